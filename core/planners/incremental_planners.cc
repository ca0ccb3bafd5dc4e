// LPA*, D* Lite and the shortest path map as stateless registry planners:
// each query builds the incremental object for that one query, so the typed
// planner suite and the Moving AI conformance check the incremental search
// against Dijkstra like any other planner. Sessions that keep the state
// between queries use core/incremental/incremental_search.h directly.
#include <memory>

#include "absl/status/status.h"
#include "core/incremental/engine.h"
#include "core/incremental/incremental_search.h"
#include "core/planners/planners.h"
#include "core/search/grid_planner.h"
#include "core/status_macros.h"

namespace pathd {
namespace {

// The grid outlives the query, so the objects may borrow it: a shared_ptr
// that owns nothing (the aliasing constructor with an empty owner).
std::shared_ptr<const Grid> Borrow(const Grid& grid) {
  return std::shared_ptr<const Grid>(std::shared_ptr<const Grid>(), &grid);
}

class LpaStarPlanner final : public GridPlanner {
 public:
  LpaStarPlanner()
      : GridPlanner(
            "lpa_star",
            PlannerTraits{.optimal = true,
                          .incremental = true,
                          .description =
                              "Lifelong Planning A* (Koenig, Likhachev & "
                              "Furcy 2004); optimal; repairs after map "
                              "changes in sessions"}) {}

 protected:
  absl::StatusOr<PlanResult> Search(const GridQuery& q) const override {
    PATHD_ASSIGN_OR_RETURN(std::unique_ptr<LpaStar> lpa,
                           LpaStar::Create(Borrow(q.grid), q.request.start,
                                           q.request.goal, q.request.cost));
    return lpa->Plan(q.stop);
  }
};

class DStarLitePlanner final : public GridPlanner {
 public:
  DStarLitePlanner()
      : GridPlanner(
            "dstar_lite",
            PlannerTraits{.optimal = true,
                          .incremental = true,
                          .description =
                              "D* Lite (Koenig & Likhachev 2002), backward "
                              "from the goal; optimal; repairs as the "
                              "robot moves and the map changes"}) {}

 protected:
  absl::StatusOr<PlanResult> Search(const GridQuery& q) const override {
    PATHD_ASSIGN_OR_RETURN(
        std::unique_ptr<DStarLite> dstar,
        DStarLite::Create(Borrow(q.grid), q.request.goal, q.request.cost));
    PATHD_RETURN_IF_ERROR(dstar->SetStart(q.request.start));
    return dstar->Plan(q.stop);
  }
};

class ShortestPathMapPlanner final : public GridPlanner {
 public:
  ShortestPathMapPlanner()
      : GridPlanner("spm",
                    PlannerTraits{.optimal = true,
                                  .incremental = true,
                                  .cost_to_go = true,
                                  .description =
                                      "shortest path map: the goal's full "
                                      "cost-to-go field (4-byte floats), "
                                      "descended from the start; optimal"}) {}

 protected:
  absl::StatusOr<PlanResult> Search(const GridQuery& q) const override {
    absl::StatusOr<std::unique_ptr<ShortestPathMap>> map =
        ShortestPathMap::Build(Borrow(q.grid), q.request.goal, q.request.cost,
                               q.stop);
    if (!map.ok()) {
      // Build reports a stop as a status; a planner reports it as an outcome.
      PlanResult stopped;
      switch (map.status().code()) {
        case absl::StatusCode::kDeadlineExceeded:
          stopped.outcome = PlanOutcome::kTimeout;
          break;
        case absl::StatusCode::kCancelled:
          stopped.outcome = PlanOutcome::kCancelled;
          break;
        case absl::StatusCode::kResourceExhausted:
          // The build stops exactly at the budget.
          stopped.outcome = PlanOutcome::kExpansionLimit;
          stopped.expansions = q.stop.max_expansions();
          break;
        default:
          return map.status();
      }
      return stopped;
    }
    PATHD_ASSIGN_OR_RETURN(PlanResult result,
                           (*map)->PathFrom(q.request.start));
    result.expansions += (*map)->last_stats().expansions;
    if (q.request.want_cost_to_go) {
      // What the descent's path from each cell costs, in double: the field
      // itself holds floats.
      PATHD_ASSIGN_OR_RETURN(result.cost_to_go,
                             internal::IncrementalAccess::PathCosts(**map));
    }
    return result;
  }
};

}  // namespace

std::unique_ptr<Planner> MakeLpaStarPlanner() {
  return std::make_unique<LpaStarPlanner>();
}
std::unique_ptr<Planner> MakeDStarLitePlanner() {
  return std::make_unique<DStarLitePlanner>();
}
std::unique_ptr<Planner> MakeShortestPathMapPlanner() {
  return std::make_unique<ShortestPathMapPlanner>();
}

}  // namespace pathd
