// A* (Hart, Nilsson & Raphael 1968), Dijkstra's algorithm, weighted A* (Pohl
// 1970) and greedy best-first search on the shared best-first loop: each is
// an open-list priority policy.
#include <memory>

#include "absl/status/status.h"
#include "core/search/endpoints.h"
#include "core/search/best_first.h"
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

// Open-list keys for BestFirstSearch.
struct AStarPriority {
  GridHeuristic h;
  double operator()(double g, int32_t x, int32_t y) const { return g + h(x, y); }
};

struct DijkstraPriority {
  double operator()(double g, int32_t, int32_t) const { return g; }
};

// f = g + w * h: w > 1 trades path cost (at most w times the optimum) for
// fewer expansions, as the search is pulled towards the goal.
struct WeightedAStarPriority {
  GridHeuristic h;
  double w;
  double operator()(double g, int32_t x, int32_t y) const { return g + w * h(x, y); }
};

// f = h: expands whatever looks closest to the goal, whatever it cost to
// reach. Ties on h still go to the larger g, the search's current direction.
struct GreedyPriority {
  GridHeuristic h;
  double operator()(double, int32_t x, int32_t y) const { return h(x, y); }
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
    const AStarPriority priority{{request.goal, request.cost.connectivity}};
    return BestFirstSearch(grid, request, stop, scratch, priority);
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
    return BestFirstSearch(grid, request, stop, scratch, DijkstraPriority{});
  }
};

class WeightedAStarPlanner final : public Planner {
 public:
  std::string_view name() const override { return "weighted_astar"; }
  const PlannerTraits& traits() const override {
    static const PlannerTraits kTraits{
        .bounded = true,
        .description = "weighted A* (f = g + w * h, w = heuristic_weight); cost "
                       "at most w times the optimum, fewer expansions"};
    return kTraits;
  }
  absl::StatusOr<PlanResult> Plan(const Grid& grid, const PlanRequest& request,
                                  const StopCondition& stop,
                                  SearchScratch& scratch) const override {
    PATHD_RETURN_IF_ERROR(ValidateRequest(grid, request, name(), traits()));
    const WeightedAStarPriority priority{{request.goal, request.cost.connectivity},
                                         request.heuristic_weight};
    return BestFirstSearch(grid, request, stop, scratch, priority);
  }
};

class GreedyPlanner final : public Planner {
 public:
  std::string_view name() const override { return "greedy"; }
  const PlannerTraits& traits() const override {
    static const PlannerTraits kTraits{
        .description = "greedy best-first search on the heuristic alone (f = h); "
                       "complete, fast, not optimal"};
    return kTraits;
  }
  absl::StatusOr<PlanResult> Plan(const Grid& grid, const PlanRequest& request,
                                  const StopCondition& stop,
                                  SearchScratch& scratch) const override {
    PATHD_RETURN_IF_ERROR(ValidateRequest(grid, request, name(), traits()));
    const GreedyPriority priority{{request.goal, request.cost.connectivity}};
    return BestFirstSearch(grid, request, stop, scratch, priority);
  }
};

}  // namespace

std::unique_ptr<Planner> MakeAStarPlanner() { return std::make_unique<AStarPlanner>(); }
std::unique_ptr<Planner> MakeDijkstraPlanner() {
  return std::make_unique<DijkstraPlanner>();
}
std::unique_ptr<Planner> MakeWeightedAStarPlanner() {
  return std::make_unique<WeightedAStarPlanner>();
}
std::unique_ptr<Planner> MakeGreedyPlanner() { return std::make_unique<GreedyPlanner>(); }

}  // namespace pathd
