// Breadth-first search: the path with the fewest moves (cell costs only decide
// what is blocked). The reported cost is still measured under the cost model.
#include <memory>

#include "core/planners/planners.h"
#include "core/search/grid_planner.h"
#include "core/search/grid_view.h"

namespace pathd {
namespace {

using internal::GridView;

// Breadth-first search from `start` until `goal` is taken off the queue;
// each expanded cell goes to `listener`. The caller has called
// scratch.BeginSearch().
template <typename Listener>
PlanOutcome BreadthFirst(const GridView& view, uint32_t start, uint32_t goal,
                         const StopCondition& stop, SearchScratch& scratch,
                         int64_t& expansions, Listener listener) {
  std::vector<uint32_t>& queue = scratch.fifo();
  scratch.At(start);  // marks the start seen
  queue.push_back(start);
  // A vector used as a FIFO: every cell enters at most once, so it never
  // holds more than the map and needs no wrap-around.
  for (size_t head = 0; head < queue.size();) {
    if (const PlanOutcome why = stop.Check(expansions);
        why != PlanOutcome::kFound) {
      return why;
    }
    const uint32_t current = queue[head++];
    ++expansions;
    listener.OnExpand(current);
    if (current == goal) return PlanOutcome::kFound;
    const Cell at = view.CellOf(current);
    view.ForEachNeighbor(at.x, at.y,
                         [&](uint32_t next, int32_t, int32_t, double) {
                           if (scratch.Seen(next)) return;
                           SearchScratch::Node& node = scratch.At(next);
                           node.parent = current;
                           queue.push_back(next);
                         });
  }
  return PlanOutcome::kNoPath;
}

class BfsPlanner final : public GridPlanner {
 public:
  BfsPlanner()
      : GridPlanner("bfs",
                    PlannerTraits{.fewest_moves = true,
                                  .description = "breadth-first search; fewest "
                                                 "moves, ignores cell costs "
                                                 "except for blocking"}) {}

 protected:
  absl::StatusOr<PlanResult> Search(const GridQuery& q) const override {
    [[maybe_unused]] const Grid& grid = q.grid;
    [[maybe_unused]] const PlanRequest& request = q.request;
    [[maybe_unused]] const StopCondition& stop = q.stop;
    [[maybe_unused]] SearchScratch& scratch = q.scratch;
    const GridView view(grid, request.cost);
    scratch.BeginSearch(grid.size());
    const uint32_t start = view.Index(request.start.x, request.start.y);
    const uint32_t goal = view.Index(request.goal.x, request.goal.y);
    PlanResult result;
    result.outcome = internal::WithExpansionListener(
        request.expansion_recorder, view, [&](auto listener) {
          return BreadthFirst(view, start, goal, stop, scratch,
                              result.expansions, listener);
        });
    if (result.found()) {
      internal::SetMeasuredPath(
          grid, request.cost,
          internal::TracePath(view, scratch, goal, grid.size()), &result);
    }
    return result;
  }
};

}  // namespace

std::unique_ptr<Planner> MakeBfsPlanner() {
  return std::make_unique<BfsPlanner>();
}

}  // namespace pathd
