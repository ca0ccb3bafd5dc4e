// Breadth-first search: the path with the fewest moves (cell costs only decide
// what is blocked). The reported cost is still measured under the cost model.
#include <memory>

#include "absl/time/clock.h"
#include "core/search/endpoints.h"
#include "core/planners/planners.h"
#include "core/search/grid_view.h"
#include "core/status_macros.h"

namespace pathd {
namespace {

class BfsPlanner final : public Planner {
 public:
  std::string_view name() const override { return "bfs"; }
  const PlannerTraits& traits() const override {
    static const PlannerTraits kTraits{
        .fewest_moves = true,
        .description = "breadth-first search; fewest moves, ignores cell costs "
                       "except for blocking"};
    return kTraits;
  }

  absl::StatusOr<PlanResult> Plan(const Grid& grid, const PlanRequest& request,
                                  const StopCondition& stop,
                                  SearchScratch& scratch) const override {
    PATHD_RETURN_IF_ERROR(ValidateRequest(grid, request, name(), traits()));
    const absl::Time started = absl::Now();
    const internal::GridView view(grid, request.cost);
    scratch.BeginSearch(grid.size());
    std::vector<uint32_t>& queue = scratch.fifo();

    const uint32_t start = view.Index(request.start.x, request.start.y);
    const uint32_t goal = view.Index(request.goal.x, request.goal.y);
    scratch.At(start);  // marks the start seen
    queue.push_back(start);

    PlanResult result;
    result.outcome = PlanOutcome::kNoPath;
    int64_t expansions = 0;
    // A vector used as a FIFO: every cell enters at most once, so it never
    // holds more than the map and needs no wrap-around.
    for (size_t head = 0; head < queue.size();) {
      if (const PlanOutcome why = stop.Check(expansions); why != PlanOutcome::kFound) {
        result.outcome = why;
        break;
      }
      const uint32_t current = queue[head++];
      ++expansions;
      internal::RecordExpansion(request, view, current);
      if (current == goal) {
        result.outcome = PlanOutcome::kFound;
        break;
      }
      const Cell at = view.CellOf(current);
      view.ForEachNeighbor(at.x, at.y, [&](uint32_t next, int32_t, int32_t, double) {
        if (scratch.Seen(next)) return;
        SearchScratch::Node& node = scratch.At(next);
        node.parent = current;
        queue.push_back(next);
      });
    }

    result.expansions = expansions;
    if (result.found()) {
      internal::SetMeasuredPath(grid, request.cost,
                                internal::TracePath(view, scratch, goal, grid.size()),
                                &result);
    }
    result.planning_time = absl::Now() - started;
    return result;
  }
};

}  // namespace

std::unique_ptr<Planner> MakeBfsPlanner() { return std::make_unique<BfsPlanner>(); }

}  // namespace pathd
