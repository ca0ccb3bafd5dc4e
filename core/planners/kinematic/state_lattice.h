// The state lattice planner: A* over (lattice point, heading) states whose
// edges are the motion primitives of a control set (core/kinematics/
// lattice.h; Pivtoraiko & Kelly, "Generating near minimal spanning control
// sets for constrained motion planning in discrete state spaces", IROS 2005;
// the "grid lattice" of the lecture "Planning I": feasible motion primitives
// chained into a plan), as ROS 2 Nav2's Smac State Lattice planner runs it.
//
// The rules, in the order a query meets them (docs/planners.md, "state_lattice"):
// - The lattice is anchored where the start's connecting motion ends:
//   lattice points are that point plus whole cells (a grid request's start
//   is a cell centre, so its lattice points are cell centres).
// - Start heading: a start whose yaw is a lattice heading is the root. Else
//   a robot that turns in place (the set has such turns and the motion model
//   allows them) turns to both neighbouring lattice headings (two roots at
//   the start's position); any other drives the shortest arc at the set's
//   turning radius to the nearer lattice heading, forward, else backward
//   when it may reverse, else to the other neighbouring heading; the first
//   of these that is free is the one root, and its end the anchor.
// - Goal: a lattice state within goal_tolerance_cells of the goal position
//   and goal_tolerance_yaw of its heading (any heading when the tolerance is
//   pi or more) ends the search; so does an analytic expansion (Nav2's): a
//   free connection from an expanded state to the exact goal pose, tried
//   every max(1, distance / 3.5) expansions within 60 cells (or six turning
//   radii) of the goal. The connection is the shortest Dubins or
//   Reeds-Shepp curve (core/kinematics/curves.h) at the set's turning radius
//   for car-like robots; turn, straight, turn for a differential robot; one
//   straight move while turning for an omnidirectional one.
// - Motions are collision-checked at samples dense enough, with a footprint
//   grown by kStateLatticeMargin, that a free verdict covers the whole motion
//   (every point of the footprint moves at most the distance driven plus its
//   reach times the heading change between samples); exact start and goal
//   poses close to an obstacle are covered by finer samples with a quarter
//   of the margin.
// - Costs are Nav2 Smac's: a primitive costs its length times (1 +
//   cost_penalty x cell cost / 252) along its poses, times
//   non_straight_penalty when it turns (non_straight_penalty +
//   change_penalty when it turns the other way or drives the other way than
//   the primitive before), times reverse_penalty when it reverses; a turn in
//   place costs kStateLatticeRotationPenalty (Nav2's rotation_penalty) per
//   heading, times the cell's cost factor.
// - The heuristic is the largest of the straight-line distance, the
//   holonomic cost-to-go with obstacles (core/kinematics/obstacle_heuristic.h:
//   a Dijkstra field from the goal cell over the 8-connected grid, closed
//   where the footprint's inscribed disc cannot fit, up to 8% above the true
//   distance, so paths may cost that much more than the lattice optimum)
//   and, for a car aiming at a heading near the goal, the shortest curve's
//   length (curves.h's table); times PlanRequest::heuristic_weight (weighted
//   A*: at most that factor more again, for far fewer expansions,
//   docs/performance.md).
#ifndef PATHD_CORE_PLANNERS_KINEMATIC_STATE_LATTICE_H_
#define PATHD_CORE_PLANNERS_KINEMATIC_STATE_LATTICE_H_

#include "absl/status/statusor.h"
#include "core/map/grid.h"
#include "core/search/plan_types.h"
#include "core/search/stop_condition.h"

namespace pathd {

// The footprint margin of motion checks, cells: samples are at most twice
// this apart in how far the footprint moves.
inline constexpr double kStateLatticeMargin = 0.125;
// Nav2's rotation_penalty: the cost of turning in place by one heading, in
// cells of straight driving.
inline constexpr double kStateLatticeRotationPenalty = 5.0;

struct StateLatticeOptions {
  // Off: only lattice states meet the goal (tests of the lattice alone).
  bool analytic_expansion = true;
  // Off: the heuristic is the straight-line distance alone (benchmarks).
  bool obstacle_heuristic = true;
  // Off: no curve length near the goal (benchmarks; docs/decisions.md says
  // what it costs and buys).
  bool curve_heuristic = true;
  // Nav2's analytic_expansion_ratio.
  double analytic_expansion_ratio = 3.5;
  // Off: no smoothing whatever KinematicQuery::smooth says (tests of the
  // lattice's own motions).
  bool smooth = true;
};

// Plans request.kinematic (DefaultKinematicQuery of request.start/goal when
// null) on `grid` with the query's control set (ControlSetForQuery).
// INVALID_ARGUMENT for a bad request: endpoints off the map or blocked
// ("start"/"goal" named, with their EndpointFault), a start or goal pose
// whose footprint collides (the goal only when goal_tolerance_cells is 0),
// request.start/goal not the cells of the query's poses, a penalty, radius
// or tolerance out of range, a control set that cannot be loaded (the file
// and line named) or turns tighter than the query's turning radius. A
// search that ends without a path is an OK result (kNoPath when the lattice
// is exhausted). Thread-safe; no state is kept between calls other than the
// process-wide control-set cache.
absl::StatusOr<PlanResult> PlanStateLattice(const Grid& grid, const PlanRequest& request,
                                            const StopCondition& stop,
                                            const StateLatticeOptions& options = {});

}  // namespace pathd

#endif  // PATHD_CORE_PLANNERS_KINEMATIC_STATE_LATTICE_H_
