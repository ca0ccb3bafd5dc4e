// Depth-first search: the forward search of LaValle's Planning Algorithms
// (ch. 2.2) with a LIFO queue. Each cell is marked when pushed, so the stack
// never holds more than the map; an explicit stack rather than recursion,
// because maps have millions of cells. Complete, not optimal.
#include <cstdint>
#include <memory>

#include "absl/time/clock.h"
#include "core/search/endpoints.h"
#include "core/planners/planners.h"
#include "core/search/grid_view.h"
#include "core/status_macros.h"

namespace pathd {
namespace {

class DfsPlanner final : public Planner {
 public:
  std::string_view name() const override { return "dfs"; }
  const PlannerTraits& traits() const override {
    static const PlannerTraits kTraits{
        .description = "depth-first search, nearest-to-goal neighbour first; "
                       "complete, not optimal"};
    return kTraits;
  }

  absl::StatusOr<PlanResult> Plan(const Grid& grid, const PlanRequest& request,
                                  const StopCondition& stop,
                                  SearchScratch& scratch) const override {
    PATHD_RETURN_IF_ERROR(ValidateRequest(grid, request, name(), traits()));
    const absl::Time started = absl::Now();
    const internal::GridView view(grid, request.cost);
    scratch.BeginSearch(grid.size());
    std::vector<uint32_t>& stack = scratch.fifo();

    const uint32_t start = view.Index(request.start.x, request.start.y);
    const uint32_t goal = view.Index(request.goal.x, request.goal.y);
    scratch.At(start).g = 0.0;
    stack.push_back(start);

    PlanResult result;
    result.outcome = PlanOutcome::kNoPath;
    int64_t expansions = 0;
    // The unvisited neighbours of one cell, pushed farthest from the goal
    // first so the nearest is popped next: still depth-first, but on open
    // ground it runs straight at the goal instead of sweeping the map.
    struct Child {
      uint32_t index;
      double h;
    };
    Child children[8];
    while (!stack.empty()) {
      if (const PlanOutcome why = stop.Check(expansions); why != PlanOutcome::kFound) {
        result.outcome = why;
        break;
      }
      const uint32_t current = stack.back();
      stack.pop_back();
      ++expansions;
      internal::RecordExpansion(request, view, current);
      if (current == goal) {
        result.outcome = PlanOutcome::kFound;
        break;
      }
      const Cell at = view.CellOf(current);
      const double g = scratch.Raw(current).g;
      int count = 0;
      view.ForEachNeighbor(at.x, at.y, [&](uint32_t next, int32_t nx, int32_t ny,
                                           double move_length) {
        if (scratch.Seen(next)) return;
        SearchScratch::Node& node = scratch.At(next);
        node.parent = current;
        node.g = g + move_length * view.Factor(next);
        // Insertion sort, descending h: at most eight entries.
        const double h =
            GridDistance(Cell{nx, ny}, request.goal, request.cost.connectivity);
        int i = count++;
        for (; i > 0 && children[i - 1].h < h; --i) children[i] = children[i - 1];
        children[i] = Child{next, h};
      });
      for (int i = 0; i < count; ++i) stack.push_back(children[i].index);
    }

    result.expansions = expansions;
    if (result.found()) {
      result.path = internal::TracePath(view, scratch, goal, grid.size());
      result.cost = scratch.Raw(goal).g;
      result.length = internal::PathLength(result.path);
    }
    result.planning_time = absl::Now() - started;
    return result;
  }
};

}  // namespace

std::unique_ptr<Planner> MakeDfsPlanner() { return std::make_unique<DfsPlanner>(); }

}  // namespace pathd
