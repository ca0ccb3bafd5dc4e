// The planning façade: the one core entry point from a decoded query (start,
// goal, goal tolerance, robot radius, via points, planner and options) and a
// map snapshot to a plan. It holds the rules of a query that are not a
// search: goal tolerance, endpoint validation, robot-radius endpoint checks,
// via-point legs and simplification. gRPC handlers, Navigate sessions and
// batch items all call it; none re-implements a rule.
#ifndef PATHD_CORE_PLANNING_PLAN_QUERY_H_
#define PATHD_CORE_PLANNING_PLAN_QUERY_H_

#include <cstdint>
#include <functional>
#include <memory>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/incremental/incremental_search.h"
#include "core/kinematics/footprint.h"
#include "core/map/grid.h"
#include "core/map/inflation.h"
#include "core/search/plan_types.h"
#include "core/search/planner.h"
#include "core/search/search_scratch.h"
#include "core/search/stop_condition.h"

namespace pathd {

// One decoded planning query, in cells. A value type; the expansion recorder
// (request.expansion_recorder) is the caller's and must outlive the query.
struct PlanQuery {
  // Registry name of the planner, for messages.
  std::string_view planner = "astar";
  // Start, goal, cost parameters and search options. request.goal starts as
  // the goal the client asked for; CheckPlanQuery replaces it by the goal to
  // plan to when the goal tolerance substitutes one.
  PlanRequest request;
  // The goal as the client gave it.
  Cell requested_goal;
  // Ordered intermediate goals (core/postprocess/plan_through.h); empty: a
  // plain plan.
  std::vector<Cell> via;
  // Via plans: return the legs before a failed one instead of no path.
  bool allow_partial = false;
  // 0: a blocked goal is an error; otherwise the nearest cell within this
  // distance (cells) that the robot centre may occupy is planned to.
  double goal_tolerance_cells = 0.0;
  // A start the robot centre may not occupy (blocked, or inscribed by the
  // robot radius) is replaced by the nearest cell it may occupy within
  // snap_start_max_cells (the goal tolerance's rule), instead of being an
  // error. Grid planners only. requested_start is the start as asked.
  bool snap_start = false;
  double snap_start_max_cells = 0.0;
  Cell requested_start;
  // 0: plan on the map as stored; otherwise on the map with obstacles
  // inflated by this radius (cells).
  double robot_radius_cells = 0.0;
  // > 0: Nav2's inflation costs (core/map/inflation_cost.h) for cells
  // between the robot radius and this distance (cells) from a lethal cell,
  // decaying by cost_scaling_per_cell (Nav2's cost_scaling_factor per metre
  // times the resolution; must be > 0 then). Grid planners only
  // (CheckPlanQuery).
  double inflation_radius_cells = 0.0;
  double cost_scaling_per_cell = 0.0;
  // Kinematic planners: the footprint's inscribed radius, from which the
  // inflation costs decay without blocking anything (GridShape::
  // cost_inscribed_cells), as Nav2's decay from the inscribed radius.
  double inflation_inscribed_cells = 0.0;
  // > 0: cells closer than this (cells) to an obstacle of the (inflated) map
  // cost more (core/map/clearance.h), and the answer reports the path's
  // clearance. Grid planners only (CheckPlanQuery).
  double min_clearance_cells = 0.0;
  // Simplify the path (each leg's, for via plans).
  bool simplify = false;
  // Grid and geometric planners: also answer the path as poses for this
  // robot, smoothed (SmoothPolyline, core/kinematics/smoother.h) on the map
  // as stored, curving at most 1 / smooth_min_turning_radius_cells where
  // that is > 0 and the polyline allows it; null: no poses (kinematic
  // planners smooth their own, KinematicQuery::smooth).
  std::shared_ptr<const FootprintChecker> smooth_for;
  double smooth_min_turning_radius_cells = 0.0;
  // Expansion budget of the whole query (every leg); 0 = none. The caller
  // puts it into the StopCondition it passes.
  int64_t max_expansions = 0;
};

// The map a query plans on: a snapshot's grid (as stored) and its version.
struct PlanSnapshot {
  std::shared_ptr<const Grid> grid;
  uint64_t version = 0;
};

// What a query planned on and where its answer came from.
struct PlanSource {
  // The planning grid: the snapshot's, inflated for a robot radius, or a
  // newer version a stateful search had already reached.
  std::shared_ptr<const Grid> grid;
  uint64_t map_version = 0;
  // A stateful search answered from state it kept (possibly repaired).
  bool cache_hit = false;
  int64_t repaired_cells = 0;
};

// A query's answer. A search that ended without a path is an answer too
// (result.outcome says why); errors are statuses.
struct PlanAnswer {
  PlanResult result;
  // The goal planned to (query.request.goal after the tolerance).
  Cell goal;
  // The start planned from (query.request.start after snap_start); set by
  // RunPlanQuery, read by BuildPlanResponse only for a snap_start query.
  Cell start;
  PlanSource source;
  // Index into (via..., goal) of the last goal result.path reaches; -1 when
  // not even the first was reached. A plain plan is a plan with one leg.
  int32_t reached_goal_index = -1;
  // For each reached goal, the index in result.path where its leg ends.
  std::vector<int32_t> leg_end_indices;
  // The leg that ended without a path (leg i ends at goal i), -1 when none.
  int32_t failed_leg = -1;
  // When want_cost_to_go was answered from a shared field (a stateful
  // shortest path map) rather than result.cost_to_go: that field, row-major
  // over source.grid, handed out as is (neither copied nor widened here).
  std::shared_ptr<const ShortestPathMap> cost_to_go_field;
  // PlanQuery::smooth_for: the index into result.poses of the first pose at
  // which the footprint overlaps an obstacle or leaves the map (grid
  // planners plan for the footprint's inscribed disc, so a longer robot may
  // not fit where its centre does; smoothing never adds such a pose), -1
  // when every pose is free or nothing was smoothed.
  int64_t footprint_collision = -1;
};

// Fills the leg fields of a plan without via points: a plan with one leg
// (reached_goal_index 0 and one leg end when found, -1 and none when not).
void SetSingleLeg(PlanAnswer* answer);

// A search that keeps state between queries for one goal (the server's
// cached shortest path maps and D* Lite searches). It may answer on a newer
// map version than the query's snapshot, so it cannot plan through via
// points.
class StatefulSearch {
 public:
  virtual ~StatefulSearch() = default;
  // Plans query.request (goal settled, endpoints checked) for a robot of
  // query.robot_radius_cells. Sets answer->result and, when it planned on
  // something else than answer->source says (a newer version), the source;
  // sets answer->cost_to_go_field for want_cost_to_go.
  virtual absl::Status Plan(const PlanQuery& query, const StopCondition& stop,
                            PlanAnswer* answer) = 0;
};

// How a query is searched once it is settled: exactly one of `planner` (a
// registry planner, run on the planning grid) or `stateful`.
struct PlanEngine {
  const Planner* planner = nullptr;
  StatefulSearch* stateful = nullptr;
  // The snapshot's grid shaped for the robot (inflated by its radius, with
  // inflation and clearance costs): a cache's copy, or empty to compute it
  // (ShapeGrid).
  std::function<absl::StatusOr<std::shared_ptr<const Grid>>(
      const std::shared_ptr<const Grid>& stored, const GridShape& shape)>
      inflate;
  // Derived representations of the planning grid (core/search/derived.h):
  // the store for `grid`, the snapshot's grid or its inflation by
  // robot_radius_cells; empty: planners build what they need per query.
  std::function<std::unique_ptr<DerivedStore>(
      const std::shared_ptr<const Grid>& grid, double robot_radius_cells)>
      derived;
};

// With a minimum clearance, sets answer->result.min_clearance to the path's
// smallest clearance on answer->source.grid (PathClearance); otherwise does
// nothing. RunPlanQuery calls it; so do searches answered outside it
// (Navigate sessions).
void ReportClearance(const PlanQuery& query, PlanAnswer* answer);

// The shape of the grid the query plans on (robot radius, inflation costs,
// clearance costs; GridShape::Of).
GridShape PlanningShape(const PlanQuery& query);

// INVALID_ARGUMENT when the query's inflation costs or minimum clearance
// cannot act: they work through cell costs, which planners that need
// uniform cost (the geometric ones) refuse and cost_weight 0 ignores. The
// message names the option (options.inflation_radius_m/_cells first). OK
// without either.
absl::Status CheckCostShaping(const PlanQuery& query);

// The rules a query must pass on the stored map before it is worth queueing,
// in this order: the goal tolerance (substitutes query->request.goal, or
// INVALID_ARGUMENT kGoalBlocked naming the tolerance), ValidateEndpoints
// (once per query), then via points: refused for a stateful engine (naming
// the planner) and with want_cost_to_go, ValidateVia; inflation costs and a
// minimum clearance are refused for planners that need uniform cost (the
// geometric ones) and with cost_weight 0, which would ignore them
// (CheckCostShaping). Cheap: O(tolerance^2 + via points);
// never inflates. A kinematic planner's query (PlannerTraits::kinematic)
// has rules of its own: via points, simplify, return_cost_to_go, a robot
// radius and a goal tolerance are refused (its footprint and tolerances are
// in request.kinematic), then the endpoint cells are validated.
absl::Status CheckPlanQuery(const Grid& stored, bool stateful,
                            PlanQuery* query);

// Plans a query that passed CheckPlanQuery on `snapshot`: shapes the grid
// for a robot radius, inflation costs and a minimum clearance
// (engine.inflate; errors of CheckGridShape), re-chooses the goal on the inflated map only
// when the radius made the stored map's choice inscribed, checks that no
// endpoint became inscribed (INVALID_ARGUMENT "... within the robot radius
// ..."), then plans through the via points (PlanThrough, one grid for every
// leg) or once, simplifies, and with a minimum clearance sets
// result.min_clearance (PathClearance on the inflated map). A stop is an
// answer (result.outcome), not an error.
absl::StatusOr<PlanAnswer> RunPlanQuery(const PlanQuery& query,
                                        const PlanSnapshot& snapshot,
                                        const PlanEngine& engine,
                                        const StopCondition& stop,
                                        SearchScratch& scratch);

// CheckPlanQuery then RunPlanQuery, for callers that plan where they check
// (a robot linking core directly, tests).
absl::StatusOr<PlanAnswer> PlanOnce(PlanQuery query, const PlanSnapshot& snapshot,
                                    const PlanEngine& engine,
                                    const StopCondition& stop,
                                    SearchScratch& scratch);

}  // namespace pathd

#endif  // PATHD_CORE_PLANNING_PLAN_QUERY_H_
