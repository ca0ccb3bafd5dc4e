// Depth-first search: the forward search of LaValle's Planning Algorithms
// (ch. 2.2) with a LIFO queue. Each cell is marked when pushed, so the stack
// never holds more than the map; an explicit stack rather than recursion,
// because maps have millions of cells. Complete, not optimal.
#include <cstdint>
#include <memory>

#include "core/planners/planners.h"
#include "core/search/grid_planner.h"
#include "core/search/grid_view.h"
#include "core/search/heuristics.h"

namespace pathd {
namespace {

using internal::GridView;

// Depth-first search from `start` until `goal` is popped; each expanded cell
// goes to `listener`. The caller has called scratch.BeginSearch().
template <typename Listener>
PlanOutcome DepthFirst(const GridView& view, uint32_t start, uint32_t goal,
                       const internal::GridDistanceHeuristic& h,
                       const StopCondition& stop, SearchScratch& scratch,
                       int64_t& expansions, Listener listener) {
  std::vector<uint32_t>& stack = scratch.fifo();
  scratch.At(start).g = 0.0;
  stack.push_back(start);
  // The unvisited neighbours of one cell, pushed farthest from the goal
  // first so the nearest is popped next: still depth-first, but on open
  // ground it runs straight at the goal instead of sweeping the map.
  struct Child {
    uint32_t index;
    double h;
  };
  Child children[8];
  while (!stack.empty()) {
    if (const PlanOutcome why = stop.Check(expansions);
        why != PlanOutcome::kFound) {
      return why;
    }
    const uint32_t current = stack.back();
    stack.pop_back();
    ++expansions;
    listener.OnExpand(current);
    if (current == goal) return PlanOutcome::kFound;
    const Cell at = view.CellOf(current);
    const double g = scratch.Raw(current).g;
    int count = 0;
    view.ForEachNeighbor(
        at.x, at.y,
        [&](uint32_t next, int32_t nx, int32_t ny, double move_length) {
          if (scratch.Seen(next)) return;
          SearchScratch::Node& node = scratch.At(next);
          node.parent = current;
          node.g = g + move_length * view.Factor(next);
          // Insertion sort, descending h: at most eight entries.
          const double hn = h(nx, ny);
          int i = count++;
          for (; i > 0 && children[i - 1].h < hn; --i)
            children[i] = children[i - 1];
          children[i] = Child{next, hn};
        });
    for (int i = 0; i < count; ++i) stack.push_back(children[i].index);
  }
  return PlanOutcome::kNoPath;
}

class DfsPlanner final : public GridPlanner {
 public:
  DfsPlanner()
      : GridPlanner("dfs", PlannerTraits{.description =
                                             "depth-first search, "
                                             "nearest-to-goal neighbour "
                                             "first; complete, not optimal"}) {}

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
    const internal::GridDistanceHeuristic h{request.goal,
                                            request.cost.connectivity};
    PlanResult result;
    result.outcome = internal::WithExpansionListener(
        request.expansion_recorder, view, [&](auto listener) {
          return DepthFirst(view, start, goal, h, stop, scratch,
                            result.expansions, listener);
        });
    if (result.found()) {
      result.path = internal::TracePath(view, scratch, goal, grid.size());
      result.cost = scratch.Raw(goal).g;
      result.length = internal::PathLength(result.path);
    }
    return result;
  }
};

}  // namespace

std::unique_ptr<Planner> MakeDfsPlanner() {
  return std::make_unique<DfsPlanner>();
}

}  // namespace pathd
