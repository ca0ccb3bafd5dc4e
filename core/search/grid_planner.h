// The base of every built-in planner: its final Plan() validates the request,
// runs the planner's search, and stamps the planning time, once for all of
// them; a planner supplies its name, its traits and Search().
#ifndef PATHD_CORE_SEARCH_GRID_PLANNER_H_
#define PATHD_CORE_SEARCH_GRID_PLANNER_H_

#include <string_view>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/time/clock.h"
#include "core/map/grid.h"
#include "core/search/endpoints.h"
#include "core/search/planner.h"
#include "core/status_macros.h"

namespace pathd {

// One query as GridPlanner::Search() receives it: Plan()'s arguments, none
// owned.
// Planners name its parts as references, not with a structured binding:
// clang 14 cannot capture structured bindings in lambdas.
struct GridQuery {
  const Grid& grid;
  const PlanRequest& request;
  const StopCondition& stop;
  SearchScratch& scratch;
};

// A Planner over a Grid. Stateless like every Planner: thread-safe as long as
// each thread passes its own SearchScratch.
class GridPlanner : public Planner {
 public:
  std::string_view name() const final { return name_; }
  const PlannerTraits& traits() const final { return traits_; }

  // Validate(), then Search(); sets planning_time on the result to the time
  // Search() took. Errors are Validate()'s and Search()'s.
  absl::StatusOr<PlanResult> Plan(const Grid& grid, const PlanRequest& request,
                                  const StopCondition& stop,
                                  SearchScratch& scratch) const final {
    PATHD_RETURN_IF_ERROR(Validate(grid, request));
    const absl::Time started = absl::Now();
    absl::StatusOr<PlanResult> result =
        Search(GridQuery{grid, request, stop, scratch});
    if (result.ok()) result->planning_time = absl::Now() - started;
    return result;
  }

 protected:
  // `name` must outlive the planner (a string literal).
  GridPlanner(std::string_view name, PlannerTraits traits)
      : name_(name), traits_(traits) {}

  // The planner's search. Precondition: Validate() passed. A search that ends
  // without a path is an OK result with outcome != kFound.
  virtual absl::StatusOr<PlanResult> Search(const GridQuery& query) const = 0;

  // The check Plan() runs first: ValidateRequest against the traits. A
  // planner overrides it only to defer part of the check into Search() (JPS
  // reads every cell anyway and checks uniform cost there).
  virtual absl::Status Validate(const Grid& grid,
                                const PlanRequest& request) const {
    return ValidateRequest(grid, request, name_, traits_);
  }

 private:
  std::string_view name_;
  PlannerTraits traits_;
};

}  // namespace pathd

#endif  // PATHD_CORE_SEARCH_GRID_PLANNER_H_
