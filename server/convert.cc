// proto <-> core translation of planning requests and responses: positions,
// options, the one DecodePlanQuery and the one PlanResponse builder.
#include "server/convert.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <utility>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "core/map/inflation_cost.h"
#include "core/planners/nature/ant_colony.h"
#include "core/planners/nature/reaction_diffusion.h"
#include "core/postprocess/plan_through.h"
#include "core/search/endpoints.h"
#include "core/status_macros.h"
#include "proto/path_codec.h"
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
    case v1::Position::kWorldPose:
    case v1::Position::kCellPose: {
      PATHD_ASSIGN_OR_RETURN(const PositionPose pose, PoseFromPosition(position, grid, what));
      return pose.pose.cell();
    }
    case v1::Position::KIND_NOT_SET:
      break;
  }
  return absl::InvalidArgumentError(
      absl::StrFormat("%s is not set (give a cell, a world point or a pose)", what));
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

// A distance option given as NAME_m or NAME_cells (a oneof: `metres` and
// `cells` say which, at most one set), in cells, capped at the map's
// diagonal: beyond it every cell is that close to any obstacle and the
// map's outside, so a larger value means nothing more and would only slow
// the transform. 0 when neither is set.
absl::StatusOr<double> DistanceCells(std::string_view name, std::optional<double> metres,
                                     std::optional<double> cells, const Grid& grid) {
  if (!metres.has_value() && !cells.has_value()) return 0.0;
  double value = metres.has_value() ? *metres : *cells;
  if (!std::isfinite(value) || value < 0.0) {
    return absl::InvalidArgumentError(
        absl::StrFormat("options.%s_%s %s must be finite and >= 0", name,
                        metres.has_value() ? "m" : "cells", Num(value)));
  }
  if (metres.has_value()) value /= grid.resolution();
  return std::min(value, std::hypot(grid.width(), grid.height()));
}

}  // namespace

namespace {

// The core validators name parameters "ant_colony.rho"; on the wire they are
// options.ant_colony.rho.
absl::Status AsOption(absl::Status status) {
  if (status.ok()) return status;
  return absl::Status(status.code(), absl::StrFormat("options.%s", status.message()));
}

}  // namespace

absl::Status AntColonyFromOptions(const v1::AntColonyOptions& options,
                                  AntColonyParams* params) {
  if (options.has_ants()) params->ants = options.ants();
  if (options.has_iterations()) params->iterations = options.iterations();
  if (options.has_stall_iterations()) params->stall_iterations = options.stall_iterations();
  if (options.has_alpha()) params->alpha = options.alpha();
  if (options.has_beta()) params->beta = options.beta();
  if (options.has_rho()) params->rho = options.rho();
  if (options.has_xi()) params->xi = options.xi();
  if (options.has_q0()) params->q0 = options.q0();
  if (options.has_tau0()) {
    if (!(options.tau0() > 0.0)) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "options.ant_colony.tau0 %s must be > 0 (unset: the default)",
          Num(options.tau0())));
    }
    params->tau0 = options.tau0();
  }
  if (options.has_max_steps()) {
    if (options.max_steps() <= 0) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "options.ant_colony.max_steps %d must be > 0 (unset: the default)",
          options.max_steps()));
    }
    params->max_steps = options.max_steps();
  }
  if (options.has_seed()) params->seed = options.seed();
  return AsOption(ValidateAntColonyParams(*params));
}

absl::Status ReactionDiffusionFromOptions(const v1::ReactionDiffusionOptions& options,
                                          ReactionDiffusionParams* params) {
  if (options.has_diffusion()) params->diffusion = options.diffusion();
  if (options.has_reaction_rate()) params->reaction_rate = options.reaction_rate();
  if (options.has_threshold()) params->threshold = options.threshold();
  if (options.has_time_step()) params->time_step = options.time_step();
  if (options.has_max_steps()) {
    if (options.max_steps() <= 0) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "options.reaction_diffusion.max_steps %d must be > 0 (unset: the "
          "default)",
          options.max_steps()));
    }
    params->max_steps = options.max_steps();
  }
  return AsOption(ValidateReactionDiffusionParams(*params));
}

absl::StatusOr<std::string_view> PlannerName(int planner) {
  if (planner == v1::PLANNER_UNSPECIFIED) return std::string_view("astar");
  if (std::optional<std::string_view> name = WirePlannerName(planner)) return *name;
  return absl::InvalidArgumentError(absl::StrFormat("unknown planner %d", planner));
}

absl::StatusOr<double> RobotRadiusCells(const v1::PlanOptions& options,
                                        const Grid& grid) {
  using Case = v1::PlanOptions::RobotRadiusCase;
  const Case c = options.robot_radius_case();
  return DistanceCells(
      "robot_radius",
      c == Case::kRobotRadiusM ? std::optional(options.robot_radius_m()) : std::nullopt,
      c == Case::kRobotRadiusCells ? std::optional(options.robot_radius_cells())
                                   : std::nullopt,
      grid);
}

absl::StatusOr<double> MinClearanceCells(const v1::PlanOptions& options,
                                         const Grid& grid) {
  using Case = v1::PlanOptions::MinClearanceCase;
  const Case c = options.min_clearance_case();
  return DistanceCells(
      "min_clearance",
      c == Case::kMinClearanceM ? std::optional(options.min_clearance_m()) : std::nullopt,
      c == Case::kMinClearanceCells ? std::optional(options.min_clearance_cells())
                                    : std::nullopt,
      grid);
}

absl::Status DecodeInflationCost(const v1::PlanOptions& options, const Grid& grid,
                                 PlanQuery* query) {
  double factor = kDefaultCostScalingFactor;
  if (options.has_cost_scaling_factor()) {
    factor = options.cost_scaling_factor();
    if (!std::isfinite(factor) || factor <= 0.0) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "options.cost_scaling_factor %s must be finite and > 0 (per metre)",
          Num(factor)));
    }
  }
  using Case = v1::PlanOptions::InflationRadiusCase;
  const Case c = options.inflation_radius_case();
  const bool metres = c == Case::kInflationRadiusM;
  PATHD_ASSIGN_OR_RETURN(
      const double radius,
      DistanceCells(
          "inflation_radius",
          metres ? std::optional(options.inflation_radius_m()) : std::nullopt,
          c == Case::kInflationRadiusCells
              ? std::optional(options.inflation_radius_cells())
              : std::nullopt,
          grid));
  if (radius <= 0.0) return absl::OkStatus();
  // As given (before the diagonal's cap, which the robot radius may have had).
  const double given = metres ? options.inflation_radius_m() / grid.resolution()
                              : options.inflation_radius_cells();
  if (given < query->robot_radius_cells) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "options.inflation_radius_%s %s is smaller than the robot radius (%s "
        "cells%s); inflation costs apply between the robot radius and the "
        "inflation radius",
        metres ? "m" : "cells",
        Num(metres ? options.inflation_radius_m() : options.inflation_radius_cells()),
        Num(query->robot_radius_cells),
        options.robot_radius_case() == v1::PlanOptions::ROBOT_RADIUS_NOT_SET
            ? ", the footprint's inscribed radius"
            : ""));
  }
  query->inflation_radius_cells = radius;
  // Nav2's factor is per metre; core decays per cell.
  query->cost_scaling_per_cell = factor * grid.resolution();
  return absl::OkStatus();
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

absl::Status DecodeSnapStart(const v1::PlanOptions& options, const Grid& grid,
                             PlanQuery* query) {
  query->requested_start = query->request.start;
  query->snap_start = options.snap_start();
  double limit = 0.0;
  std::string_view field;
  switch (options.snap_start_max_case()) {
    case v1::PlanOptions::kSnapStartMaxM:
      field = "snap_start_max_m";
      limit = options.snap_start_max_m();
      break;
    case v1::PlanOptions::kSnapStartMaxCells:
      field = "snap_start_max_cells";
      limit = options.snap_start_max_cells();
      break;
    case v1::PlanOptions::SNAP_START_MAX_NOT_SET:
      break;
  }
  if (!std::isfinite(limit) || limit < 0.0) {
    return absl::InvalidArgumentError(
        absl::StrFormat("options.%s %s must be finite and >= 0", field, Num(limit)));
  }
  double cells = options.snap_start_max_case() == v1::PlanOptions::kSnapStartMaxM
                     ? limit / grid.resolution()
                     : limit;
  if (cells > kMaxGoalToleranceCells) {
    return absl::InvalidArgumentError(
        absl::StrFormat("options.%s %s is %s cells; the limit is %s cells", field,
                        Num(limit), Num(cells), Num(kMaxGoalToleranceCells)));
  }
  if (cells == 0.0) {
    cells = std::min(kMaxGoalToleranceCells,
                     std::max(kDefaultSnapStartCells, 2.0 * query->robot_radius_cells));
  }
  query->snap_start_max_cells = cells;
  return absl::OkStatus();
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
  PATHD_RETURN_IF_ERROR(AntColonyFromOptions(options.ant_colony(), &request->ant_colony));
  return ReactionDiffusionFromOptions(options.reaction_diffusion(),
                                      &request->reaction_diffusion);
}

const char* ExpansionLimitSource(const v1::PlanOptions& options,
                                 int64_t server_limit) {
  const bool server_binds =
      server_limit > 0 &&
      (options.max_expansions() == 0 || options.max_expansions() >= server_limit);
  return server_binds ? "--max_expansions" : "options.max_expansions";
}

WireQuery WireQueryOf(const v1::PlanRequest& request) {
  return WireQuery{.map = &request.map(),
                   .planner = request.planner(),
                   .start = &request.start(),
                   .goal = &request.goal(),
                   .via = &request.via(),
                   .options = &request.options(),
                   .allow_partial = request.allow_partial(),
                   .search_options = true,
                   .goal_tolerance = true,
                   .expansion_budget = true};
}

WireQuery WireQueryOf(const v1::CostToGoRequest& request) {
  return WireQuery{.map = &request.map(),
                   .goal = &request.goal(),
                   .options = &request.options(),
                   .expansion_budget = true};
}

WireQuery WireQueryOf(const v1::IsPathValidRequest& request) {
  return WireQuery{.map = &request.map(), .options = &request.options()};
}

WireQuery WireQueryOf(const v1::NavigateOpen& open) {
  // A session whose options give the robot kinematics but name no planner
  // plans for them with hybrid_astar; otherwise D* Lite, which the façade
  // sees as a grid planner (the name only words messages).
  int planner = open.planner();
  if (planner == v1::PLANNER_UNSPECIFIED) {
    const v1::PlanOptions& options = open.options();
    const bool kinematic =
        options.min_turning_radius_case() !=
            v1::PlanOptions::MIN_TURNING_RADIUS_NOT_SET ||
        options.motion_model() != v1::MOTION_MODEL_UNSPECIFIED;
    planner = kinematic ? v1::PLANNER_HYBRID_ASTAR : v1::PLANNER_DSTAR_LITE;
  }
  return WireQuery{.map = &open.map(),
                   .planner = planner,
                   .start = &open.start(),
                   .goal = &open.goal(),
                   .options = &open.options(),
                   .search_options = true,
                   .expansion_budget = true};
}

absl::StatusOr<DecodedQuery> DecodePlanQuery(const WireQuery& wire,
                                             const MapStore& store,
                                             const QueryLimits& limits) {
  DecodedQuery decoded;
  PlanQuery& query = decoded.query;
  PlanRequest& request = query.request;
  const v1::PlanOptions& options = *wire.options;
  PATHD_ASSIGN_OR_RETURN(query.planner, PlannerName(wire.planner));
  PATHD_ASSIGN_OR_RETURN(decoded.snapshot, store.Get(*wire.map));
  const Grid& grid = *decoded.snapshot->grid;
  if (wire.start != nullptr) {
    PATHD_ASSIGN_OR_RETURN(request.start, CellFromPosition(*wire.start, grid, "start"));
  }
  if (wire.goal != nullptr) {
    PATHD_ASSIGN_OR_RETURN(request.goal, CellFromPosition(*wire.goal, grid, "goal"));
  }
  query.requested_goal = request.goal;
  if (!v1::PathEncoding_IsValid(options.path_encoding())) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "options.path_encoding: unknown value %d", options.path_encoding()));
  }
  decoded.path_encoding = options.path_encoding();
  if (wire.search_options) {
    PATHD_RETURN_IF_ERROR(PlanOptionsToRequest(options, &request));
    query.simplify = options.simplify();
    decoded.return_expansions = options.return_expansions();
  } else {
    PATHD_ASSIGN_OR_RETURN(request.cost, CostParamsFromOptions(options));
  }
  PATHD_ASSIGN_OR_RETURN(query.robot_radius_cells, RobotRadiusCells(options, grid));
  PATHD_ASSIGN_OR_RETURN(query.min_clearance_cells, MinClearanceCells(options, grid));
  // A whole field is 8 bytes per cell in a Plan message.
  if (limits.max_cost_to_go_cells.has_value() && request.want_cost_to_go &&
      grid.size() > static_cast<size_t>(*limits.max_cost_to_go_cells)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "options.return_cost_to_go: the map has %d cells; whole cost-to-go "
        "fields are returned for maps of up to %d cells (--max_cost_to_go_cells)",
        grid.size(), *limits.max_cost_to_go_cells));
  }
  if (wire.expansion_budget) {
    PATHD_ASSIGN_OR_RETURN(query.max_expansions,
                           EffectiveMaxExpansions(options, limits.max_expansions));
    decoded.expansion_limit_source =
        ExpansionLimitSource(options, limits.max_expansions);
  }
  if (wire.goal_tolerance) {
    PATHD_ASSIGN_OR_RETURN(query.goal_tolerance_cells, GoalToleranceCells(options, grid));
  }
  PATHD_RETURN_IF_ERROR(DecodeKinematics(wire, grid, &query));
  // After the footprint, whose inscribed radius is then the robot radius.
  PATHD_RETURN_IF_ERROR(DecodeInflationCost(options, grid, &query));
  if (wire.goal_tolerance) {  // Plan's options: snap_start too
    PATHD_RETURN_IF_ERROR(DecodeSnapStart(options, grid, &query));
  }
  if (wire.via != nullptr && !wire.via->empty()) {
    // Counted before anything is sized by the request.
    PATHD_RETURN_IF_ERROR(CheckViaCount(static_cast<size_t>(wire.via->size())));
    query.via.reserve(wire.via->size());
    for (int i = 0; i < wire.via->size(); ++i) {
      PATHD_ASSIGN_OR_RETURN(
          const Cell cell,
          CellFromPosition(wire.via->Get(i), grid, absl::StrFormat("via[%d]", i)));
      query.via.push_back(cell);
    }
    query.allow_partial = wire.allow_partial;
  }
  return decoded;
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

namespace {

// The result part of a response; `request` gives the start and the goal
// planned to.
void FillResult(const PlanResult& result, const PlanRequest& request,
                const Grid& grid, int64_t max_expansions,
                v1::PathEncoding path_encoding, v1::PlanResponse* response) {
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
  if (!result.found() && !result.reason.empty()) response->set_reason(result.reason);
  if (const std::optional<AntColonyStats>& aco = result.ant_colony) {
    v1::AntColonyReport* report = response->mutable_ant_colony();
    report->set_iterations_run(aco->iterations_run);
    report->set_best_iteration(aco->best_iteration);
    report->set_ants_reached_goal(aco->ants_reached_goal);
    report->set_ants_died(aco->ants_died);
    report->set_stopped_by(aco->stopped_by);
  }
  if (const std::optional<ReactionDiffusionStats>& rd = result.reaction_diffusion) {
    v1::ReactionDiffusionReport* report = response->mutable_reaction_diffusion();
    report->set_steps(rd->steps);
    report->set_reached_cells(rd->reached_cells);
    report->set_front_speed(rd->front_speed);
    report->set_max_relative_error(rd->max_relative_error);
    report->set_mean_relative_error(rd->mean_relative_error);
    report->set_optimal_cost(rd->optimal_cost);
    report->set_cost_ratio(rd->cost_ratio);
    report->set_escapes(rd->escapes);
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
  response->set_cost_m(result.cost * grid.resolution());
  response->set_length_m(result.length * grid.resolution());
  response->set_frame_id(kFrameId);
  FillPoses(result, grid, response);
  if (path_encoding != v1::PATH_ENCODING_PACKED) {
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
  if (path_encoding == v1::PATH_ENCODING_PACKED || path_encoding == v1::PATH_ENCODING_BOTH) {
    const std::vector<Cell>& path = result.path;
    response->set_packed_path(EncodePackedPath(
        static_cast<int64_t>(path.size()),
        [&path](int64_t i) { return PackedCell{path[i].x, path[i].y}; }));
    // What PathFrameCellCenter needs to redo grid.CellCenter.
    v1::PathFrame* frame = response->mutable_path_frame();
    frame->set_resolution(grid.resolution());
    frame->mutable_origin()->set_x(grid.origin().x);
    frame->mutable_origin()->set_y(grid.origin().y);
    frame->mutable_origin()->set_yaw(grid.frame_yaw());
  }
  if (result.min_clearance >= 0.0) {
    response->set_has_clearance(true);
    response->set_min_clearance_cells(result.min_clearance);
    response->set_min_clearance_m(result.min_clearance * grid.resolution());
  }
  response->mutable_polyline()->Reserve(static_cast<int>(result.polyline.size()));
  response->mutable_world_polyline()->Reserve(
      static_cast<int>(result.polyline.size()));
  for (const CellPoint& p : result.polyline) {
    v1::CellPoint* out = response->add_polyline();
    out->set_x(p.x);
    out->set_y(p.y);
    const WorldPoint w = grid.CellPointToWorld(p);
    v1::WorldPoint* world = response->add_world_polyline();
    world->set_x(w.x);
    world->set_y(w.y);
  }
}

}  // namespace

void FillPlanResponse(const PlanResult& result, const PlanRequest& request,
                      const Grid& grid, int64_t max_expansions,
                      v1::PathEncoding path_encoding, v1::PlanResponse* response) {
  FillResult(result, request, grid, max_expansions, path_encoding, response);
}

void BuildPlanResponse(const PlanQuery& query, const PlanAnswer& answer,
                       std::string_view expansion_limit_source,
                       v1::PathEncoding path_encoding, v1::PlanResponse* response) {
  const PlanResult& result = answer.result;
  const Grid& grid = *answer.source.grid;
  // answer.start is RunPlanQuery's; callers that build an answer themselves
  // (Navigate sessions) plan from the query's start and never snap.
  const Cell start = query.snap_start ? answer.start : query.request.start;
  PlanRequest planned = PlanRequest::Between(start, answer.goal);
  FillResult(result, planned, grid, query.max_expansions, path_encoding, response);
  if (answer.cost_to_go_field != nullptr && query.request.want_cost_to_go) {
    // Widened float -> double once, into the message (the wire type).
    const absl::Span<const float> field = answer.cost_to_go_field->field();
    response->set_cost_to_go_width(grid.width());
    response->mutable_cost_to_go()->Reserve(static_cast<int>(field.size()));
    response->mutable_cost_to_go()->Add(field.begin(), field.end());
  }
  // A planner's own reason (PlanResult::reason) is not the budget's.
  if (result.outcome == PlanOutcome::kExpansionLimit &&
      !expansion_limit_source.empty() && result.reason.empty()) {
    response->set_reason(
        absl::StrFormat("%s (%s)", response->reason(), expansion_limit_source));
  }
  if (answer.footprint_collision >= 0) {
    response->set_footprint_collision(answer.footprint_collision);
  }
  response->set_robot_radius_cells(query.robot_radius_cells);
  response->set_robot_radius_m(query.robot_radius_cells * grid.resolution());
  response->set_map_version(answer.source.map_version);
  response->set_planner(std::string(query.planner));
  response->set_cache_hit(answer.source.cache_hit);
  response->set_repaired_cells(answer.source.repaired_cells);
  *response->mutable_requested_goal() = ToProto(query.requested_goal);
  response->set_goal_substituted(!(answer.goal == query.requested_goal));
  if (query.snap_start) {
    *response->mutable_requested_start() = ToProto(query.requested_start);
    if (!(answer.start == query.requested_start)) {
      const double dx = answer.start.x - query.requested_start.x;
      const double dy = answer.start.y - query.requested_start.y;
      const double cells = std::sqrt(dx * dx + dy * dy);
      response->set_start_snapped(true);
      response->set_snap_distance_cells(cells);
      response->set_snap_distance_m(cells * grid.resolution());
    }
  }
  response->set_reached_goal_index(answer.reached_goal_index);
  response->mutable_leg_end_indices()->Add(answer.leg_end_indices.begin(),
                                           answer.leg_end_indices.end());
  if (answer.failed_leg >= 0) {
    const auto n = static_cast<int32_t>(query.via.size());
    const Cell to = answer.failed_leg == n ? answer.goal : query.via[answer.failed_leg];
    const Cell from =
        answer.failed_leg == 0 ? query.request.start : query.via[answer.failed_leg - 1];
    // FillResult's "no path" names the whole plan's ends.
    const std::string why =
        result.outcome == PlanOutcome::kNoPath
            ? absl::StrFormat("no path from %s to %s", CellToString(from),
                              CellToString(to))
            : response->reason();
    response->set_reason(absl::StrFormat("%s: %s", LegName(answer.failed_leg, n), why));
  }
  if (const ExpansionRecorder* recorder = query.request.expansion_recorder) {
    auto* expanded = response->mutable_expanded();
    expanded->Reserve(static_cast<int>(recorder->cells().size()));
    for (const Cell& c : recorder->cells()) *expanded->Add() = ToProto(c);
    response->set_expanded_truncated(recorder->truncated());
  }
}

}  // namespace pathd::server
