// A* (Hart, Nilsson & Raphael 1968), Dijkstra's algorithm, weighted A* (Pohl
// 1970) and greedy best-first search: one planner class on the best-first
// loop of core/search/best_first.h, each algorithm an open-list priority
// over the octile (8-connected) or Manhattan (4-connected) heuristic.
#include <memory>

#include "core/planners/planners.h"
#include "core/search/best_first.h"
#include "core/search/grid_planner.h"
#include "core/search/heuristics.h"

namespace pathd {
namespace {

using internal::GridDistanceHeuristic;
using internal::ZeroHeuristic;

// Which priority a BestFirstPlanner searches with.
enum class Order { kAStar, kDijkstra, kWeighted, kGreedy };

class BestFirstPlanner final : public GridPlanner {
 public:
  BestFirstPlanner(std::string_view name, Order order, PlannerTraits traits)
      : GridPlanner(name, traits), order_(order) {}

 protected:
  absl::StatusOr<PlanResult> Search(const GridQuery& q) const override {
    [[maybe_unused]] const Grid& grid = q.grid;
    [[maybe_unused]] const PlanRequest& request = q.request;
    [[maybe_unused]] const StopCondition& stop = q.stop;
    [[maybe_unused]] SearchScratch& scratch = q.scratch;
    const GridDistanceHeuristic h{request.goal, request.cost.connectivity};
    switch (order_) {
      case Order::kAStar:
        return internal::GridBestFirstSearch(
            grid, request, stop, scratch,
            internal::AStarPriority<GridDistanceHeuristic>{h});
      case Order::kDijkstra:
        // f = g never decreases along the search: the radix heap, which
        // pops in the binary heap's order (same costs, same paths).
        return internal::GridBestFirstSearch<internal::MonotoneOpenList>(
            grid, request, stop, scratch,
            internal::AStarPriority<ZeroHeuristic>{});
      case Order::kWeighted:
        return internal::GridBestFirstSearch(
            grid, request, stop, scratch,
            internal::WeightedPriority<GridDistanceHeuristic>{
                h, request.heuristic_weight});
      case Order::kGreedy:
        return internal::GridBestFirstSearch(
            grid, request, stop, scratch,
            internal::GreedyPriority<GridDistanceHeuristic>{h});
    }
    return absl::InternalError("unknown best-first order");
  }

 private:
  Order order_;
};

}  // namespace

std::unique_ptr<Planner> MakeAStarPlanner() {
  return std::make_unique<BestFirstPlanner>(
      "astar", Order::kAStar,
      PlannerTraits{.optimal = true,
                    .description =
                        "A* with the octile (8-connected) or Manhattan "
                        "(4-connected) heuristic; optimal"});
}
std::unique_ptr<Planner> MakeDijkstraPlanner() {
  return std::make_unique<BestFirstPlanner>(
      "dijkstra", Order::kDijkstra,
      PlannerTraits{.optimal = true,
                    .description =
                        "Dijkstra's uniform-cost search; optimal, the "
                        "reference every other planner is checked "
                        "against"});
}
std::unique_ptr<Planner> MakeWeightedAStarPlanner() {
  return std::make_unique<BestFirstPlanner>(
      "weighted_astar", Order::kWeighted,
      PlannerTraits{.bounded = true,
                    .description =
                        "weighted A* (f = g + w * h, w = "
                        "heuristic_weight); cost at most w times the "
                        "optimum, fewer expansions"});
}
std::unique_ptr<Planner> MakeGreedyPlanner() {
  return std::make_unique<BestFirstPlanner>(
      "greedy", Order::kGreedy,
      PlannerTraits{.description =
                        "greedy best-first search on the heuristic "
                        "alone (f = h); complete, fast, not optimal"});
}

}  // namespace pathd
