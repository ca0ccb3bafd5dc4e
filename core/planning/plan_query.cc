// The planning façade: the query's rules on the stored map, then inflation,
// the radius rules and the search on the planning grid.
#include "core/planning/plan_query.h"

#include <optional>
#include <string>
#include <utility>

#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "core/kinematics/smoother.h"
#include "core/map/clearance.h"
#include "core/map/cost_model.h"
#include "core/map/inflation.h"
#include "core/postprocess/path_simplify.h"
#include "core/postprocess/plan_through.h"
#include "core/search/endpoints.h"
#include "core/search/registry.h"
#include "core/status_macros.h"

namespace pathd {
namespace {

// The planning grid: the stored one, or the one shaped for the robot.
absl::StatusOr<std::shared_ptr<const Grid>> PlanningGrid(const PlanQuery& query,
                                                         const PlanSnapshot& snapshot,
                                                         const PlanEngine& engine) {
  const GridShape shape = PlanningShape(query);
  if (!shape.shaped()) return snapshot.grid;
  if (engine.inflate) return engine.inflate(snapshot.grid, shape);
  PATHD_ASSIGN_OR_RETURN(Grid shaped, ShapeGrid(*snapshot.grid, shape));
  return std::make_shared<const Grid>(std::move(shaped));
}

// The goal on the inflated map. Inflation only blocks cells, so the stored
// map's choice, when still free, is also the nearest free cell of the
// inflated map (NearestTraversableCell orders by distance, then y, then x):
// the tolerance search runs again only when the radius made it inscribed.
absl::StatusOr<Cell> GoalOnInflated(const PlanQuery& query, const Grid& inflated) {
  const Cell chosen = query.request.goal;
  if (inflated.InBounds(chosen) &&
      Traversable(inflated.cost(chosen), query.request.cost.unknown_is_free)) {
    return chosen;
  }
  return GoalWithinTolerance(inflated, query.requested_goal,
                             query.goal_tolerance_cells, query.request.cost,
                             query.robot_radius_cells);
}

// The start to plan from with snap_start: the requested one when it is off
// the grid (ValidateEndpoints reports it) or the robot centre may occupy it
// on `grid`, else the nearest cell within snap_start_max_cells it may occupy,
// else INVALID_ARGUMENT naming the option with kStartBlocked. `grid` is the
// planning grid: inflated when radius_cells > 0.
absl::StatusOr<Cell> SnapStart(const Grid& grid, const PlanQuery& query,
                               double radius_cells) {
  const Cell requested = query.requested_start;
  const bool unknown_is_free = query.request.cost.unknown_is_free;
  if (!grid.InBounds(requested) || Traversable(grid.cost(requested), unknown_is_free)) {
    return requested;
  }
  if (std::optional<Cell> nearest = NearestTraversableCell(
          grid, requested, query.snap_start_max_cells, query.request.cost)) {
    return *nearest;
  }
  return WithEndpointFault(
      absl::InvalidArgumentError(absl::StrFormat(
          "start %s is on a blocked cell (cost %d) and options.snap_start found no "
          "cell within snap_start_max (%g cells) that is free%s",
          CellToString(requested), grid.cost(requested), query.snap_start_max_cells,
          radius_cells > 0.0
              ? absl::StrFormat(" for the robot radius (%g cells)", radius_cells)
              : std::string())),
      EndpointFault::kStartBlocked);
}

// INVALID_ARGUMENT for the first endpoint (start, goal, via[i]) the radius
// made inscribed.
absl::Status CheckInscribed(const PlanQuery& query, Cell start, Cell goal,
                            const Grid& stored, const Grid& inflated) {
  const double radius = query.robot_radius_cells;
  PATHD_RETURN_IF_ERROR(CheckRadiusEndpoints(
      stored, inflated, radius, {{start, "start"}, {goal, "goal"}}));
  for (size_t i = 0; i < query.via.size(); ++i) {
    const std::string what = absl::StrFormat("via[%d]", i);
    PATHD_RETURN_IF_ERROR(
        CheckRadiusEndpoints(stored, inflated, radius, {{query.via[i], what}}));
  }
  return absl::OkStatus();
}

}  // namespace

void SetSingleLeg(PlanAnswer* answer) {
  answer->leg_end_indices.clear();
  answer->reached_goal_index = answer->result.found() ? 0 : -1;
  if (answer->result.found()) {
    answer->leg_end_indices.push_back(
        static_cast<int32_t>(answer->result.path.size()) - 1);
  }
}

void ReportClearance(const PlanQuery& query, PlanAnswer* answer) {
  if (query.min_clearance_cells <= 0.0 || answer->result.path.empty()) return;
  answer->result.min_clearance =
      PathClearance(*answer->source.grid, answer->result.path,
                    query.request.cost.unknown_is_free);
}

// PlanQuery::smooth_for: the found path's points (the polyline, or the cell
// centres) as smoothed poses on the stored map, and the first pose where the
// footprint does not fit. Skipped when a stateful search answered on a newer
// version than `stored` (its poses would be checked on the wrong map).
absl::Status SmoothForRobot(const PlanQuery& query, const PlanSnapshot& snapshot,
                            PlanAnswer* answer) {
  PlanResult& result = answer->result;
  if (query.smooth_for == nullptr || !result.found() || !result.poses.empty() ||
      answer->source.map_version != snapshot.version) {
    return absl::OkStatus();
  }
  std::vector<CellPoint> points = result.polyline;
  if (points.empty()) {
    points.reserve(result.path.size());
    for (const Cell& c : result.path) points.push_back(CellPoint{c.x + 0.5, c.y + 0.5});
  }
  SmootherOptions options;
  options.min_turning_radius = query.smooth_min_turning_radius_cells;
  PATHD_ASSIGN_OR_RETURN(result.poses,
                         SmoothPolyline(*snapshot.grid, points, query.smooth_for,
                                        query.request.cost.unknown_is_free, options));
  for (size_t i = 0; i < result.poses.size(); ++i) {
    if (query.smooth_for->CollidesExactly(*snapshot.grid, result.poses[i].pose,
                                          query.request.cost.unknown_is_free)) {
      answer->footprint_collision = static_cast<int64_t>(i);
      break;
    }
  }
  return absl::OkStatus();
}

GridShape PlanningShape(const PlanQuery& query) {
  return GridShape::Of(query.robot_radius_cells, query.inflation_radius_cells,
                       query.cost_scaling_per_cell, query.min_clearance_cells,
                       query.request.cost.unknown_is_free, query.inflation_inscribed_cells);
}

absl::Status CheckCostShaping(const PlanQuery& query) {
  // Named as the client sets them; the first one asked for is reported.
  const char* option = nullptr;
  const char* what = nullptr;
  if (query.inflation_radius_cells > 0.0) {
    option = "options.inflation_radius_m/_cells";
    what = "inflation costs work";
  } else if (query.min_clearance_cells > 0.0) {
    option = "options.min_clearance_m/_cells";
    what = "a minimum clearance works";
  } else {
    return absl::OkStatus();
  }
  if (const Planner* planner = PlannerRegistry::Default().Get(query.planner);
      planner != nullptr && planner->traits().needs_uniform_cost) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "%s: planner %s plans on uniform-cost maps and %s through cell costs; "
        "use a grid planner (astar, theta_star, ...), voronoi to stay as far "
        "from obstacles as the map allows, or robot_radius for a hard limit",
        option, query.planner, what));
  }
  if (query.request.cost.cost_weight == 0.0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "%s: %s through cell costs, and cost_weight 0 ignores them", option, what));
  }
  return absl::OkStatus();
}

namespace {

bool IsKinematic(std::string_view planner) {
  const Planner* p = PlannerRegistry::Default().Get(planner);
  return p != nullptr && p->traits().kinematic;
}

// The rules of a kinematic planner's query: it plans between exact poses for
// a footprint, so the grid planners' goal substitution, radius and
// simplification do not apply (the decoder folds the radius into the
// footprint and the tolerance into the kinematic query).
absl::Status CheckKinematicQuery(const Grid& stored, PlanQuery* query) {
  if (query->simplify) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "options.simplify: planner %s returns motions the robot can drive; "
        "simplifying would cut its turns (options.smooth smooths them within "
        "the footprint and the turning radius)",
        query->planner));
  }
  if (query->request.want_cost_to_go) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "options.return_cost_to_go: planner %s searches poses, not cells, and "
        "has no cost-to-go field",
        query->planner));
  }
  if (query->snap_start) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "options.snap_start: planner %s plans from an exact pose checked with "
        "its footprint; find a free pose with Nearest and plan from it",
        query->planner));
  }
  if (query->robot_radius_cells > 0.0 || query->goal_tolerance_cells > 0.0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "planner %s takes the robot's shape as a footprint and the goal "
        "tolerance in its kinematic query (PlanRequest::kinematic), not as a "
        "robot radius or a blocked-goal tolerance",
        query->planner));
  }
  PATHD_RETURN_IF_ERROR(ValidateEndpoints(stored, query->request));
  PATHD_RETURN_IF_ERROR(CheckCostShaping(*query));
  // Each via leg ends at its cell's centre with any heading and the next
  // starts where it ended (PlanThrough); the planner names a colliding one.
  return ValidateVia(stored, query->via, query->request.cost);
}

}  // namespace

absl::Status CheckPlanQuery(const Grid& stored, bool stateful, PlanQuery* query) {
  if (IsKinematic(query->planner)) return CheckKinematicQuery(stored, query);
  PlanRequest& request = query->request;
  // Substituted before anything keys on the goal, so every planner (and a
  // stateful search's cache entry) sees the cell actually planned to.
  PATHD_ASSIGN_OR_RETURN(
      request.goal, GoalWithinTolerance(stored, query->requested_goal,
                                        query->goal_tolerance_cells, request.cost,
                                        /*radius_cells=*/0.0));
  if (query->snap_start) {
    PATHD_ASSIGN_OR_RETURN(request.start, SnapStart(stored, *query, /*radius_cells=*/0.0));
  }
  PATHD_RETURN_IF_ERROR(ValidateEndpoints(stored, request));
  PATHD_RETURN_IF_ERROR(CheckCostShaping(*query));
  if (query->via.empty()) return absl::OkStatus();
  if (stateful) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "via: planner %s keeps cached state for one goal and may answer on a "
        "newer map version, so it cannot plan through via points; use a "
        "planner such as astar or dijkstra",
        query->planner));
  }
  if (request.want_cost_to_go) {
    return absl::InvalidArgumentError(
        "options.return_cost_to_go: a cost-to-go field belongs to one goal, "
        "and a plan through via points has several");
  }
  return ValidateVia(stored, query->via, request.cost);
}

absl::StatusOr<PlanAnswer> RunPlanQuery(const PlanQuery& query,
                                        const PlanSnapshot& snapshot,
                                        const PlanEngine& engine,
                                        const StopCondition& stop,
                                        SearchScratch& scratch) {
  if ((engine.planner == nullptr) == (engine.stateful == nullptr)) {
    return absl::InternalError("a plan engine needs exactly one of planner, stateful");
  }
  PlanAnswer answer;
  answer.goal = query.request.goal;
  answer.start = query.request.start;
  answer.source = PlanSource{snapshot.grid, snapshot.version};
  PATHD_ASSIGN_OR_RETURN(answer.source.grid, PlanningGrid(query, snapshot, engine));
  // Clearance costs block nothing: only the radius moves or refuses endpoints.
  if (query.robot_radius_cells > 0.0) {
    PATHD_ASSIGN_OR_RETURN(answer.goal, GoalOnInflated(query, *answer.source.grid));
    if (query.snap_start) {
      // As the goal: the stored map's choice stands while still free.
      const Grid& inflated = *answer.source.grid;
      if (!inflated.InBounds(answer.start) ||
          !Traversable(inflated.cost(answer.start), query.request.cost.unknown_is_free)) {
        PATHD_ASSIGN_OR_RETURN(answer.start,
                               SnapStart(inflated, query, query.robot_radius_cells));
      }
    }
    PATHD_RETURN_IF_ERROR(CheckInscribed(query, answer.start, answer.goal, *snapshot.grid,
                                         *answer.source.grid));
  }
  // The query as searched: with the goal the radius may have moved.
  const PlanQuery* settled = &query;
  PlanQuery moved;
  if (!(answer.goal == query.request.goal) || !(answer.start == query.request.start)) {
    moved = query;
    moved.request.goal = answer.goal;
    moved.request.start = answer.start;
    settled = &moved;
  }
  std::unique_ptr<DerivedStore> derived;
  if (engine.derived && engine.planner != nullptr) {
    derived = engine.derived(answer.source.grid, query.robot_radius_cells);
    if (settled == &query) {
      moved = query;
      settled = &moved;
    }
    moved.request.derived = derived.get();
  }
  const Grid& grid = *answer.source.grid;
  if (!settled->via.empty()) {
    // One grid for every leg: the snapshot (or its inflation) taken once.
    // CheckPlanQuery refused via points for a stateful engine.
    PATHD_ASSIGN_OR_RETURN(
        ThroughResult through,
        PlanThrough(*engine.planner, grid, settled->request, settled->via, stop,
                    scratch,
                    ThroughOptions{.allow_partial = settled->allow_partial,
                                   .simplify = settled->simplify}));
    answer.result = std::move(through.plan);
    answer.reached_goal_index = through.reached_goal_index;
    answer.leg_end_indices = std::move(through.leg_end_indices);
    answer.failed_leg = through.failed_leg;
    ReportClearance(query, &answer);
    PATHD_RETURN_IF_ERROR(SmoothForRobot(query, snapshot, &answer));
    return answer;
  }
  if (engine.stateful != nullptr) {
    PATHD_RETURN_IF_ERROR(engine.stateful->Plan(*settled, stop, &answer));
  } else {
    PATHD_ASSIGN_OR_RETURN(answer.result,
                           engine.planner->Plan(grid, settled->request, stop, scratch));
  }
  if (settled->simplify && answer.result.found()) {
    // The grid the stateful search answered on, which may be newer.
    SimplifyPath(*answer.source.grid, settled->request.cost, &answer.result);
  }
  SetSingleLeg(&answer);
  ReportClearance(query, &answer);
  PATHD_RETURN_IF_ERROR(SmoothForRobot(query, snapshot, &answer));
  return answer;
}

absl::StatusOr<PlanAnswer> PlanOnce(PlanQuery query, const PlanSnapshot& snapshot,
                                    const PlanEngine& engine,
                                    const StopCondition& stop,
                                    SearchScratch& scratch) {
  PATHD_RETURN_IF_ERROR(
      CheckPlanQuery(*snapshot.grid, engine.stateful != nullptr, &query));
  return RunPlanQuery(query, snapshot, engine, stop, scratch);
}

}  // namespace pathd
