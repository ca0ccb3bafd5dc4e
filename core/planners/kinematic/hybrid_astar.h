// Hybrid A* (Dolgov, Thrun, Montemerlo & Diebel, "Path Planning for
// Autonomous Vehicles in Unknown Semi-structured Environments", IJRR 2010),
// as ROS 2 Nav2's Smac Hybrid-A* planner runs it: A* over continuous poses
// (x, y, yaw), pruned to the best pose per lattice state (cell x heading
// bin of the footprint checker), expanded by driving short arcs at the
// largest curvature and straight, forward only (Dubins) or both ways
// (Reeds-Shepp); every few expansions, and at each one near the goal, an
// analytic expansion tries the shortest Dubins / Reeds-Shepp curve (OMPL)
// to the exact goal pose. The heuristic is the larger of the curve length
// without obstacles and the holonomic cost-to-go with obstacles
// (core/kinematics/obstacle_heuristic.h). Motions are checked over their
// whole sweep (core/kinematics/motion_check.h); the path is smoothed
// (core/kinematics/smoother.h) when the query asks.
//
// The planner "hybrid_astar" is registered in core/search/registry.cc;
// PlanHybridAStar is the same search with options for tests and benchmarks.
#ifndef PATHD_CORE_PLANNERS_KINEMATIC_HYBRID_ASTAR_H_
#define PATHD_CORE_PLANNERS_KINEMATIC_HYBRID_ASTAR_H_

#include "absl/status/statusor.h"
#include "core/map/grid.h"
#include "core/search/plan_types.h"
#include "core/search/stop_condition.h"

namespace pathd {

// The motions the search drives from each pose, derived from the query as
// Nav2's HybridMotionTable does: a turn of the fewest heading bins whose
// chord is at least sqrt(2) cells long (so it leaves the cell; a quarter
// turn when the radius is below sqrt(2)/2), and a straight motion of that
// chord (at least sqrt(2)).
struct HybridMotions {
  // Heading change of one turning motion, radians (a whole number of bins).
  double turn = 0.0;
  // Length of a turning motion (radius x turn) and of a straight one, cells.
  double turn_length = 0.0;
  double straight_length = 0.0;
};
HybridMotions HybridMotionsFor(double min_turning_radius_cells, int32_t heading_bins);

struct HybridAStarOptions {
  // Nav2's analytic_expansion_ratio: an analytic expansion is tried every
  // max(1, floor(h / ratio)) expansions, h the heuristic (cells) of the
  // state expanded, so every expansion near the goal.
  double analytic_expansion_ratio = 3.5;
  // Off: the lattice alone must reach the goal tolerance (tests compare it
  // with a brute-force search over the same motions).
  bool analytic_expansion = true;
  // An analytic expansion ends the search when its path costs at most this
  // times the estimate of the state it starts from (g + non_straight_penalty
  // x h: h is a length, the curve pays for its turns), as it usually does; a
  // dearer one (a long way round, or backing up most of the way) is kept
  // while the search goes on, and taken once nothing left on the open list
  // is expected within this factor of it. Nav2 takes the first one
  // (infinity here). On 250 random maps of 12-20 cells (hybrid_astar_test's
  // brute-force comparison on larger maps) taking the shortest curve first
  // made 9 of 149 paths cost over 1.5 times the brute force's, mostly by
  // backing up most of the way; pricing the candidates (Dubins beside
  // Reeds-Shepp) left 4, mean 0.93 of the brute force's cost; with this
  // slack 3, mean 0.91 (docs/decisions.md).
  double analytic_slack = 1.2;
  // Off: the heuristic is the curve length alone (benchmarks).
  bool obstacle_heuristic = true;
  // Off: the straight-line distance instead of the curve length.
  bool curve_heuristic = true;
  // Within this many turning radii of the goal the curve heuristic is the
  // Dubins / Reeds-Shepp length (a Reeds-Shepp length from OMPL costs 5-10
  // us, hence curve_table); farther, the straight-line distance, a lower
  // bound of it, and there the obstacle heuristic dominates anyway. On the
  // benchmark's warehouse a wider window made searches slower, not faster
  // (RS, field from the store, p90: 78 ms at 0, 2 and 4 radii, 255 ms at 8,
  // 390 ms at 16; docs/performance.md): the final approach is where a
  // heading matters.
  double curve_heuristic_radii = 2.0;
  // Read the curve length from the shared table (TabledCurveLength in
  // core/kinematics/curves.h, Nav2's lookup table) instead of computing it.
  bool curve_table = true;
  // Smooth when the query asks (KinematicQuery::smooth); off: never.
  bool smooth = true;
  // When the lattice (one cell x one heading bin per state) is exhausted
  // without reaching the goal, the search starts again with states of half
  // a cell, then a quarter, ..., down to 1 / max_subdivisions (a power of
  // two; 1: no retry). A query without a path costs about 1 + 4 + 16 + ...
  // times an exhausted lattice; one whose goal cell the obstacle heuristic
  // shows unreachable is answered at once.
  int32_t max_subdivisions = 4;
};

// Plans request.kinematic (DefaultKinematicQuery of request.start/goal when
// null) on `grid`. INVALID_ARGUMENT for a bad request: endpoints off the map
// or blocked ("start"/"goal" named, with their EndpointFault), a start or
// goal pose whose footprint collides, a motion model other than dubins or
// reeds_shepp, a turning radius, tolerance or penalty out of range, or
// request.start/goal not the cells of the query's poses. A search that ends
// without a path is an OK result (kNoPath when the lattice is exhausted).
absl::StatusOr<PlanResult> PlanHybridAStar(const Grid& grid, const PlanRequest& request,
                                           const StopCondition& stop,
                                           const HybridAStarOptions& options = {});

}  // namespace pathd

#endif  // PATHD_CORE_PLANNERS_KINEMATIC_HYBRID_ASTAR_H_
