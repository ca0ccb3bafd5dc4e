// A* (Hart, Nilsson & Raphael 1968) and Dijkstra's algorithm on the shared
// best-first loop.
#include <memory>

#include "absl/status/status.h"
#include "core/planners/best_first.h"
#include "core/planners/planners.h"
#include "core/status_macros.h"

namespace pathd {
namespace {

using internal::BestFirstSearch;

// Octile distance (8-connected) or Manhattan distance (4-connected) to the
// goal. Every step costs at least its length (cell factors are >= 1), so both
// are admissible and consistent.
struct GridHeuristic {
  Cell goal;
  Connectivity connectivity;
  double operator()(int32_t x, int32_t y) const {
    return GridDistance(Cell{x, y}, goal, connectivity);
  }
};

struct ZeroHeuristic {
  double operator()(int32_t, int32_t) const { return 0.0; }
};

class AStarPlanner final : public Planner {
 public:
  std::string_view name() const override { return "astar"; }
  const PlannerTraits& traits() const override {
    static const PlannerTraits kTraits{
        .optimal = true,
        .description = "A* with the octile (8-connected) or Manhattan "
                       "(4-connected) heuristic; optimal"};
    return kTraits;
  }
  absl::StatusOr<PlanResult> Plan(const Grid& grid, const PlanRequest& request,
                                  const StopCondition& stop,
                                  SearchScratch& scratch) const override {
    PATHD_RETURN_IF_ERROR(ValidateRequest(grid, request, name(), traits()));
    const GridHeuristic h{request.goal, request.cost.connectivity};
    return BestFirstSearch(grid, request, stop, scratch, h);
  }
};

class DijkstraPlanner final : public Planner {
 public:
  std::string_view name() const override { return "dijkstra"; }
  const PlannerTraits& traits() const override {
    static const PlannerTraits kTraits{
        .optimal = true,
        .description = "Dijkstra's uniform-cost search; optimal, the reference "
                       "every other planner is checked against"};
    return kTraits;
  }
  absl::StatusOr<PlanResult> Plan(const Grid& grid, const PlanRequest& request,
                                  const StopCondition& stop,
                                  SearchScratch& scratch) const override {
    PATHD_RETURN_IF_ERROR(ValidateRequest(grid, request, name(), traits()));
    return BestFirstSearch(grid, request, stop, scratch, ZeroHeuristic{});
  }
};

}  // namespace

std::unique_ptr<Planner> MakeAStarPlanner() { return std::make_unique<AStarPlanner>(); }
std::unique_ptr<Planner> MakeDijkstraPlanner() {
  return std::make_unique<DijkstraPlanner>();
}

}  // namespace pathd
