// The planner interface every algorithm implements and the traits it declares.
// Request/result types: plan_types.h; stopping: stop_condition.h; validation:
// endpoints.h; path checks: path_measure.h; creation by name: registry.h.
#ifndef PATHD_CORE_SEARCH_PLANNER_H_
#define PATHD_CORE_SEARCH_PLANNER_H_

#include <string_view>

#include "absl/status/statusor.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/search/plan_types.h"
#include "core/search/search_scratch.h"
#include "core/search/stop_condition.h"

namespace pathd {

// What a planner guarantees, so callers and tests can treat it correctly.
struct PlannerTraits {
  // Returns minimum-cost paths under the cost model.
  bool optimal = false;
  // Minimises the number of moves instead of cost (BFS).
  bool fewest_moves = false;
  // Paths may connect non-adjacent cells (any-angle).
  bool any_angle = false;
  // Keeps state between queries (explicit session objects).
  bool incremental = false;
  // Cost at most heuristic_weight times the optimum (weighted A*).
  bool bounded = false;
  // Interleaves bounded look-ahead searches with moves (RTAA*, LRTA*); the
  // path is the executed trajectory and may revisit cells.
  bool real_time = false;
  // Finds a path whenever one exists (given enough budget). False for the
  // potential field, which can stall in a local minimum.
  bool complete = true;
  // Refuses (FAILED_PRECONDITION) maps whose traversable cells do not all
  // cost the same under the request (JPS).
  bool needs_uniform_cost = false;
  // Refuses (FAILED_PRECONDITION) 4-connected requests (JPS).
  bool needs_eight_connected = false;
  // Plans in the continuous plane, not on the lattice: the answer is
  // PlanResult::polyline (core/geometry/free_space.h).
  bool geometric = false;
  // Plans oriented poses for a robot with a footprint and a motion model
  // (PlanRequest::kinematic, required): the answer is PlanResult::poses.
  bool kinematic = false;
  // Can return the full cost-to-go field (PlanRequest::want_cost_to_go).
  bool cost_to_go = false;
  // One line for --help and docs/planners.md.
  std::string_view description;
};

// "optimal", "fewest moves", "bounded", "any-angle", "real-time",
// "kinematic", "euclidean-optimal", "geometric" or "heuristic": what a planner's paths
// guarantee, for listings.
std::string_view GuaranteeName(const PlannerTraits& traits);

// A planning algorithm. Plan() is a pure function of the grid, the request and
// scratch memory: an instance holds no per-query state, so one may be shared
// by threads as long as each thread passes its own SearchScratch.
class Planner {
 public:
  virtual ~Planner() = default;
  virtual std::string_view name() const = 0;
  virtual const PlannerTraits& traits() const = 0;

  // Plans from request.start to request.goal. Returns INVALID_ARGUMENT when
  // start or goal is off the grid or not traversable (ValidateEndpoints); a
  // search that ends without a path is an OK result with outcome != kFound.
  virtual absl::StatusOr<PlanResult> Plan(const Grid& grid,
                                          const PlanRequest& request,
                                          const StopCondition& stop,
                                          SearchScratch& scratch) const = 0;
};

}  // namespace pathd

#endif  // PATHD_CORE_SEARCH_PLANNER_H_
