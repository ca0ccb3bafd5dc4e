// Validation of a query's endpoints and options before any search, the typed
// fault attached to an endpoint error, the nearest cell a robot may occupy,
// and the two endpoint rules of a query with a goal tolerance or a robot
// radius (used by the planning façade, core/planning/plan_query.h).
#ifndef PATHD_CORE_SEARCH_ENDPOINTS_H_
#define PATHD_CORE_SEARCH_ENDPOINTS_H_

#include <cstdint>
#include <functional>
#include <initializer_list>
#include <optional>
#include <string_view>
#include <utility>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/search/plan_types.h"
#include "core/search/planner.h"

namespace pathd {

// Which endpoint a rejected request got wrong. Validation attaches it to its
// INVALID_ARGUMENT status (as a payload, which survives being passed up
// unchanged), so callers can report a typed reason without parsing messages.
enum class EndpointFault {
  kStartOutsideMap,
  kGoalOutsideMap,
  kStartBlocked,
  kGoalBlocked,
};

// `status` with `fault` attached.
absl::Status WithEndpointFault(absl::Status status, EndpointFault fault);
// The fault attached to `status`, nullopt when none is.
std::optional<EndpointFault> EndpointFaultOf(const absl::Status& status);
// The fault of endpoint `what` ("start" or "goal"; nullopt for any other
// name) being outside the map or blocked.
std::optional<EndpointFault> EndpointFaultFor(std::string_view what, bool outside);

// INVALID_ARGUMENT naming `what` when `cell` is off the grid ("goal (9, 0) is
// outside the 4 x 2 map") or on a cell that is not traversable under `cost`
// ("... is on a blocked cell (cost 254)"), with its EndpointFault when `what`
// is "start" or "goal".
absl::Status ValidateEndpoint(const Grid& grid, Cell cell, std::string_view what,
                              const CostParams& cost);

// INVALID_ARGUMENT naming "start" or "goal" when one is off the grid or on a
// cell that is not traversable under request.cost, or naming the field when
// the cost parameters are invalid (weight negative or not finite,
// connectivity not 4/8, heuristic_weight < 1, lookahead < 0, potential-field
// parameters not positive and finite) or the grid is empty or too large to
// search. Endpoint errors carry their EndpointFault.
absl::Status ValidateEndpoints(const Grid& grid, const PlanRequest& request);

// ValidateEndpoints plus the planner's own preconditions from its traits:
// FAILED_PRECONDITION naming the planner and the first weighted cell when it
// needs uniform cost, or when it needs 8-connectivity. Every planner's Plan()
// calls this first.
absl::Status ValidateRequest(const Grid& grid, const PlanRequest& request,
                             std::string_view planner, const PlannerTraits& traits);

struct NearestCell {
  Cell cell;
  // Euclidean distance between the target's centre and the cell's, cells.
  double distance = 0.0;
  // Cells tested.
  int64_t tested = 0;
};

// The cell nearest to `target` (Euclidean distance between cell centres, at
// most `max_distance` inclusive; ties to the smaller y, then the smaller x)
// for which `allowed` is true; nullopt when none is. Visits rings of growing
// Chebyshev radius around the target and stops once no further ring can be
// nearer, so the work is O(d^2) for the answer's distance d,
// O(max_distance^2) when there is none; `allowed` runs only for candidates
// that would win. `target` may be off the grid; only cells on it are tested.
std::optional<NearestCell> NearestAllowedCell(const Grid& grid, Cell target,
                                              double max_distance,
                                              const std::function<bool(Cell)>& allowed);

// NearestAllowedCell for the robot centre under `cost`: the nearest cell on
// the grid that is Traversable.
std::optional<Cell> NearestTraversableCell(const Grid& grid, Cell target,
                                           double max_distance,
                                           const CostParams& cost);

// The goal to plan to: `requested` when the tolerance is 0, the cell is off
// the grid (ValidateEndpoints reports it) or the robot centre may occupy it;
// otherwise the nearest cell within the tolerance that it may occupy
// (NearestTraversableCell), or INVALID_ARGUMENT naming the tolerance (and the
// radius, when radius_cells > 0) with EndpointFault::kGoalBlocked when there
// is none. `grid` is the planning grid: inflated when radius_cells > 0.
absl::StatusOr<Cell> GoalWithinTolerance(const Grid& grid, Cell requested,
                                         double tolerance_cells,
                                         const CostParams& cost,
                                         double radius_cells);

// INVALID_ARGUMENT "<what> (x, y) is within the robot radius (r cells) of an
// obstacle" for the first of `endpoints` that the inflation made inscribed
// (traversable on `stored`, kInscribedCost on `inflated`), with the
// EndpointFault of "start"/"goal". Endpoints off the grid are not checked.
absl::Status CheckRadiusEndpoints(
    const Grid& stored, const Grid& inflated, double radius_cells,
    std::initializer_list<std::pair<Cell, std::string_view>> endpoints);

}  // namespace pathd

#endif  // PATHD_CORE_SEARCH_ENDPOINTS_H_
