// proto <-> core translation.
#include "server/convert.h"

#include "proto/planner_names.h"

#include <cmath>
#include <optional>
#include <utility>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "core/search/endpoints.h"
#include "core/status_macros.h"
#include "proto/planner_names.h"

namespace pathd::server {
namespace {

// Formats a double so NaN and infinities read as such in messages.
std::string Num(double v) { return absl::StrFormat("%g", v); }

}  // namespace

absl::StatusOr<Cell> CellFromPosition(const v1::Position& position,
                                      const Grid& grid, std::string_view what) {
  switch (position.kind_case()) {
    case v1::Position::kCell:
      return FromProto(position.cell());
    case v1::Position::kWorld: {
      const WorldPoint p{position.world().x(), position.world().y()};
      if (!std::isfinite(p.x) || !std::isfinite(p.y)) {
        return absl::InvalidArgumentError(
            absl::StrFormat("%s world point (%s, %s) is not finite", what,
                            Num(p.x), Num(p.y)));
      }
      absl::StatusOr<Cell> cell = grid.WorldToCell(p);
      if (!cell.ok()) {
        absl::Status outside = absl::InvalidArgumentError(absl::StrFormat(
            "%s world point (%s, %s) is outside the map: %s", what, Num(p.x),
            Num(p.y), cell.status().message()));
        if (const auto fault = EndpointFaultFor(what, /*outside=*/true)) {
          return WithEndpointFault(std::move(outside), *fault);
        }
        return outside;
      }
      return *cell;
    }
    case v1::Position::KIND_NOT_SET:
      break;
  }
  return absl::InvalidArgumentError(
      absl::StrFormat("%s is not set (give a cell or a world point)", what));
}

absl::StatusOr<CostParams> CostParamsFromOptions(const v1::PlanOptions& options) {
  CostParams params;
  switch (options.connectivity()) {
    case v1::CONNECTIVITY_UNSPECIFIED:
    case v1::CONNECTIVITY_EIGHT:
      params.connectivity = Connectivity::kEight;
      break;
    case v1::CONNECTIVITY_FOUR:
      params.connectivity = Connectivity::kFour;
      break;
    default:
      return absl::InvalidArgumentError(absl::StrFormat(
          "options.connectivity: unknown connectivity %d",
          static_cast<int>(options.connectivity())));
  }
  if (options.has_cost_weight()) {
    const double w = options.cost_weight();
    if (!std::isfinite(w) || w < 0.0) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "options.cost_weight %s must be finite and >= 0", Num(w)));
    }
    params.cost_weight = w;
  } else {
    params.cost_weight = 1.0;
  }
  params.unknown_is_free = options.unknown_is_free();
  return params;
}

absl::StatusOr<int64_t> EffectiveMaxExpansions(const v1::PlanOptions& options,
                                               int64_t server_limit) {
  const int64_t requested = options.max_expansions();
  if (requested < 0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "options.max_expansions %d must be >= 0", requested));
  }
  if (server_limit <= 0) return requested;
  if (requested == 0) return server_limit;
  return std::min(requested, server_limit);
}

namespace {

// Checks a potential-field option: 0 (unset) keeps the default, otherwise it
// must be finite and > 0.
absl::Status SetPositive(double value, std::string_view field, double* out) {
  if (value == 0.0) return absl::OkStatus();
  if (!std::isfinite(value) || value < 0.0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "options.potential_field.%s %s must be finite and > 0", field, Num(value)));
  }
  *out = value;
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<std::string_view> PlannerName(int planner) {
  if (planner == v1::PLANNER_UNSPECIFIED) return std::string_view("astar");
  if (std::optional<std::string_view> name = WirePlannerName(planner)) return *name;
  return absl::InvalidArgumentError(absl::StrFormat("unknown planner %d", planner));
}

absl::StatusOr<double> RobotRadiusCells(const v1::PlanOptions& options,
                                        const Grid& grid) {
  double radius = 0.0;
  std::string_view field;
  switch (options.robot_radius_case()) {
    case v1::PlanOptions::kRobotRadiusM:
      field = "robot_radius_m";
      radius = options.robot_radius_m();
      break;
    case v1::PlanOptions::kRobotRadiusCells:
      field = "robot_radius_cells";
      radius = options.robot_radius_cells();
      break;
    case v1::PlanOptions::ROBOT_RADIUS_NOT_SET:
      return 0.0;
  }
  if (!std::isfinite(radius) || radius < 0.0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "options.%s %s must be finite and >= 0", field, Num(radius)));
  }
  if (options.robot_radius_case() == v1::PlanOptions::kRobotRadiusM) {
    radius /= grid.resolution();
  }
  // Beyond the map's diagonal every cell is within the radius of any obstacle;
  // a bigger value means nothing more and would only slow the transform.
  const double diagonal = std::hypot(grid.width(), grid.height());
  if (radius > diagonal) radius = diagonal;
  return radius;
}

absl::StatusOr<double> GoalToleranceCells(const v1::PlanOptions& options,
                                          const Grid& grid) {
  double tolerance = 0.0;
  std::string_view field;
  switch (options.goal_tolerance_case()) {
    case v1::PlanOptions::kGoalToleranceM:
      field = "goal_tolerance_m";
      tolerance = options.goal_tolerance_m();
      break;
    case v1::PlanOptions::kGoalToleranceCells:
      field = "goal_tolerance_cells";
      tolerance = options.goal_tolerance_cells();
      break;
    case v1::PlanOptions::GOAL_TOLERANCE_NOT_SET:
      return 0.0;
  }
  if (!std::isfinite(tolerance) || tolerance < 0.0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "options.%s %s must be finite and >= 0", field, Num(tolerance)));
  }
  const double cells =
      options.goal_tolerance_case() == v1::PlanOptions::kGoalToleranceM
          ? tolerance / grid.resolution()
          : tolerance;
  if (cells > kMaxGoalToleranceCells) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "options.%s %s is %s cells; the limit is %s cells", field,
        Num(tolerance), Num(cells), Num(kMaxGoalToleranceCells)));
  }
  return cells;
}

absl::Status PlanOptionsToRequest(const v1::PlanOptions& options,
                                  PlanRequest* request) {
  PATHD_ASSIGN_OR_RETURN(request->cost, CostParamsFromOptions(options));
  request->heuristic_weight =
      options.has_heuristic_weight() ? options.heuristic_weight() : 1.5;
  if (!std::isfinite(request->heuristic_weight) || request->heuristic_weight < 1.0) {
    return absl::InvalidArgumentError(
        absl::StrFormat("options.heuristic_weight %s must be finite and >= 1",
                        Num(request->heuristic_weight)));
  }
  if (options.lookahead() < 0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "options.lookahead %d must be >= 0", options.lookahead()));
  }
  request->lookahead = options.lookahead();
  request->want_cost_to_go = options.return_cost_to_go();
  const v1::PotentialFieldOptions& pf = options.potential_field();
  PotentialFieldParams& params = request->potential;
  switch (pf.attractive()) {
    case v1::ATTRACTIVE_POTENTIAL_UNSPECIFIED:
    case v1::ATTRACTIVE_POTENTIAL_QUADRATIC:
      params.attractive = AttractiveShape::kQuadratic;
      break;
    case v1::ATTRACTIVE_POTENTIAL_CONIC:
      params.attractive = AttractiveShape::kConic;
      break;
    default:
      return absl::InvalidArgumentError(absl::StrFormat(
          "options.potential_field.attractive: unknown shape %d",
          static_cast<int>(pf.attractive())));
  }
  PATHD_RETURN_IF_ERROR(
      SetPositive(pf.attractive_gain(), "attractive_gain", &params.attractive_gain));
  PATHD_RETURN_IF_ERROR(
      SetPositive(pf.switch_distance(), "switch_distance", &params.switch_distance));
  PATHD_RETURN_IF_ERROR(
      SetPositive(pf.repulsive_gain(), "repulsive_gain", &params.repulsive_gain));
  PATHD_RETURN_IF_ERROR(SetPositive(pf.influence_distance(), "influence_distance",
                                    &params.influence_distance));
  PATHD_RETURN_IF_ERROR(SetPositive(pf.step_size(), "step_size", &params.step_size));
  if (pf.max_steps() < 0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "options.potential_field.max_steps %d must be >= 0", pf.max_steps()));
  }
  params.max_steps = pf.max_steps();
  return absl::OkStatus();
}

v1::PlanOutcome ToProto(PlanOutcome outcome) {
  switch (outcome) {
    case PlanOutcome::kFound:
      return v1::PLAN_OUTCOME_FOUND;
    case PlanOutcome::kNoPath:
      return v1::PLAN_OUTCOME_NO_PATH;
    case PlanOutcome::kExpansionLimit:
      return v1::PLAN_OUTCOME_EXPANSION_LIMIT;
    case PlanOutcome::kTimeout:
      return v1::PLAN_OUTCOME_TIMEOUT;
    case PlanOutcome::kCancelled:
      return v1::PLAN_OUTCOME_CANCELLED;
    case PlanOutcome::kLocalMinimum:
      return v1::PLAN_OUTCOME_LOCAL_MINIMUM;
  }
  return v1::PLAN_OUTCOME_UNSPECIFIED;
}

v1::PlanOutcome OutcomeOfStatus(const absl::Status& status) {
  if (const std::optional<EndpointFault> fault = EndpointFaultOf(status)) {
    switch (*fault) {
      case EndpointFault::kStartOutsideMap:
        return v1::PLAN_OUTCOME_START_OUTSIDE_MAP;
      case EndpointFault::kGoalOutsideMap:
        return v1::PLAN_OUTCOME_GOAL_OUTSIDE_MAP;
      case EndpointFault::kStartBlocked:
        return v1::PLAN_OUTCOME_START_OCCUPIED;
      case EndpointFault::kGoalBlocked:
        return v1::PLAN_OUTCOME_GOAL_OCCUPIED;
    }
  }
  switch (status.code()) {
    case absl::StatusCode::kInvalidArgument:
    case absl::StatusCode::kFailedPrecondition:
      return v1::PLAN_OUTCOME_INVALID_REQUEST;
    case absl::StatusCode::kNotFound:
      return v1::PLAN_OUTCOME_MAP_NOT_FOUND;
    case absl::StatusCode::kDeadlineExceeded:
      return v1::PLAN_OUTCOME_TIMEOUT;
    case absl::StatusCode::kCancelled:
      return v1::PLAN_OUTCOME_CANCELLED;
    default:
      return v1::PLAN_OUTCOME_UNSPECIFIED;
  }
}

bool IsRejectionOutcome(v1::PlanOutcome outcome) {
  return outcome >= v1::PLAN_OUTCOME_START_OUTSIDE_MAP &&
         outcome <= v1::PLAN_OUTCOME_MAP_NOT_FOUND;
}

void FillPlanResponse(const PlanResult& result, const PlanRequest& request,
                      const Grid& grid, int64_t max_expansions,
                      v1::PlanResponse* response) {
  response->set_found(result.found());
  response->set_outcome(ToProto(result.outcome));
  *response->mutable_start() = ToProto(request.start);
  *response->mutable_goal() = ToProto(request.goal);
  response->set_expansions(result.expansions);
  response->set_planning_time_us(absl::ToInt64Microseconds(result.planning_time));
  switch (result.outcome) {
    case PlanOutcome::kFound:
      break;
    case PlanOutcome::kNoPath:
      response->set_reason(absl::StrFormat("no path from %s to %s",
                                           CellToString(request.start),
                                           CellToString(request.goal)));
      break;
    case PlanOutcome::kExpansionLimit:
      response->set_reason(absl::StrFormat(
          "expansion limit of %d reached before the goal", max_expansions));
      break;
    case PlanOutcome::kTimeout:
      response->set_reason(absl::StrFormat(
          "deadline passed after %d expansions", result.expansions));
      break;
    case PlanOutcome::kCancelled:
      response->set_reason("cancelled");
      break;
    case PlanOutcome::kLocalMinimum:
      response->set_reason(absl::StrFormat(
          "potential field descent stalled in a local minimum at (%.2f, %.2f)",
          result.stall_point.x, result.stall_point.y));
      response->mutable_stall_point()->set_x(result.stall_point.x);
      response->mutable_stall_point()->set_y(result.stall_point.y);
      break;
  }
  response->set_episodes(result.episodes);
  response->mutable_trajectory()->Reserve(static_cast<int>(result.trajectory.size()));
  for (const CellPoint& p : result.trajectory) {
    v1::CellPoint* out = response->add_trajectory();
    out->set_x(p.x);
    out->set_y(p.y);
  }
  if (!result.cost_to_go.empty()) {
    response->set_cost_to_go_width(grid.width());
    response->mutable_cost_to_go()->Add(result.cost_to_go.begin(),
                                        result.cost_to_go.end());
  }
  // A result that did not find its goal may still carry a path: the path to
  // the last reached via point of a partial plan (allow_partial).
  if (!result.found() && result.path.empty()) return;
  response->set_any_angle(result.any_angle);
  response->set_cost(result.cost);
  response->set_length(result.length);
  response->mutable_path()->Reserve(static_cast<int>(result.path.size()));
  response->mutable_world_path()->Reserve(static_cast<int>(result.path.size()));
  for (const Cell& c : result.path) {
    *response->add_path() = ToProto(c);
    const WorldPoint p = grid.CellCenter(c);
    v1::WorldPoint* w = response->add_world_path();
    w->set_x(p.x);
    w->set_y(p.y);
  }
}

void FillMapInfo(const MapSnapshot& snapshot, v1::MapInfo* info) {
  const Grid& grid = *snapshot.grid;
  info->set_name(snapshot.name);
  info->set_width(grid.width());
  info->set_height(grid.height());
  info->set_resolution(grid.resolution());
  v1::Origin* origin = info->mutable_origin();
  origin->set_x(grid.origin().x);
  origin->set_y(grid.origin().y);
  origin->set_yaw(grid.origin().yaw);
  info->set_version(snapshot.version);
  info->set_free_cells(grid.CountFree());
  info->set_blocked_cells(grid.CountBlocked());
}

absl::StatusOr<std::vector<MapChange>> MapChangesFromProto(
    const google::protobuf::RepeatedPtrField<v1::CellChange>& changes) {
  std::vector<MapChange> out;
  out.reserve(static_cast<size_t>(changes.size()));
  for (int i = 0; i < changes.size(); ++i) {
    const v1::CellChange& c = changes.Get(i);
    switch (c.target_case()) {
      case v1::CellChange::kCell:
        out.push_back(MapChange::ForCell(c.cell().x(), c.cell().y(), c.cost()));
        break;
      case v1::CellChange::kRect:
        out.push_back(MapChange::ForRect(c.rect().x_min(), c.rect().y_min(),
                                         c.rect().x_max(), c.rect().y_max(),
                                         c.cost()));
        break;
      case v1::CellChange::TARGET_NOT_SET:
        return absl::InvalidArgumentError(
            absl::StrFormat("change %d: neither cell nor rect is set", i));
    }
  }
  return out;
}

absl::StatusOr<double> ResolutionFromProto(double resolution) {
  if (resolution == 0.0) return 1.0;
  if (!std::isfinite(resolution) || resolution < 0.0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "resolution %s must be finite and > 0", Num(resolution)));
  }
  return resolution;
}

absl::StatusOr<GridOrigin> OriginFromProto(const v1::Origin& origin) {
  const std::pair<const char*, double> parts[] = {
      {"origin.x", origin.x()}, {"origin.y", origin.y()}, {"origin.yaw", origin.yaw()}};
  for (const auto& [field, value] : parts) {
    if (!std::isfinite(value)) {
      return absl::InvalidArgumentError(
          absl::StrFormat("%s %s must be finite", field, Num(value)));
    }
  }
  return GridOrigin{origin.x(), origin.y(), origin.yaw()};
}

absl::StatusOr<Grid> GridFromRawCells(const v1::RawCells& raw, const MapStore& store) {
  if (raw.width() <= 0 || raw.height() <= 0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "raw: width %d and height %d must be positive", raw.width(), raw.height()));
  }
  if (absl::Status s = store.CheckSize(raw.width(), raw.height()); !s.ok()) return s;
  const int64_t expected = int64_t{raw.width()} * int64_t{raw.height()};
  if (static_cast<int64_t>(raw.cells().size()) != expected) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "raw: width %d x height %d needs %d cells, got %d", raw.width(),
        raw.height(), expected, raw.cells().size()));
  }
  std::vector<uint8_t> cells(raw.cells().begin(), raw.cells().end());
  absl::StatusOr<Grid> grid = Grid::FromCells(raw.width(), raw.height(), std::move(cells));
  if (!grid.ok()) {
    return absl::InvalidArgumentError(
        absl::StrFormat("raw: %s", grid.status().message()));
  }
  return grid;
}

}  // namespace pathd::server
