// The fleet RPCs' shared decoding, planning grid and stopped statuses.
#include "server/rpc/fleet_common.h"

#include "core/planning/plan_query.h"
#include "core/search/endpoints.h"
#include "core/status_macros.h"

namespace pathd::server {

absl::StatusOr<FleetQuery> DecodeFleetQuery(const PlanDeps& deps, const std::string& map,
                                            const v1::PlanOptions& options,
                                            int planner) {
  WireQuery wire;
  wire.map = &map;
  wire.planner = planner;
  wire.options = &options;
  wire.expansion_budget = true;
  FleetQuery out;
  PATHD_ASSIGN_OR_RETURN(out.decoded,
                         DecodePlanQuery(wire, deps.store,
                                         QueryLimits{.max_expansions = deps.limits.max_expansions}));
  PATHD_RETURN_IF_ERROR(CheckCostShaping(out.decoded.query));
  return out;
}

absl::StatusOr<std::vector<Cell>> DecodeCells(
    const google::protobuf::RepeatedPtrField<v1::Position>& positions,
    const std::string& field, const FleetQuery& q) {
  std::vector<Cell> cells;
  cells.reserve(positions.size());
  for (int i = 0; i < positions.size(); ++i) {
    const std::string what = absl::StrFormat("%s[%d]", field, i);
    PATHD_ASSIGN_OR_RETURN(const Cell c, CellFromPosition(positions[i], q.stored(), what));
    PATHD_RETURN_IF_ERROR(ValidateEndpoint(q.stored(), c, what, q.query().request.cost));
    cells.push_back(c);
  }
  return cells;
}

absl::StatusOr<std::shared_ptr<const Grid>> PlanningGridFor(
    InflationCache& inflation, const FleetQuery& q, const std::vector<Cell>& cells,
    const std::string& field, bool indexed) {
  const GridShape shape = PlanningShape(q.query());
  if (!shape.shaped()) return q.decoded.snapshot->grid;
  PATHD_ASSIGN_OR_RETURN(std::shared_ptr<const Grid> grid,
                         inflation.Get(*q.decoded.snapshot, shape));
  if (q.query().robot_radius_cells > 0.0) {
    for (size_t i = 0; i < cells.size(); ++i) {
      const std::string what = indexed ? absl::StrFormat("%s[%d]", field, i) : field;
      PATHD_RETURN_IF_ERROR(CheckRadiusEndpoints(q.stored(), *grid,
                                                 q.query().robot_radius_cells,
                                                 {{cells[i], what}}));
    }
  }
  return grid;
}

absl::Status StoppedStatus(PlanOutcome outcome, const char* what, int64_t budget,
                           const char* budget_source) {
  switch (outcome) {
    case PlanOutcome::kCancelled:
      return absl::CancelledError(absl::StrFormat("cancelled while computing the %s", what));
    case PlanOutcome::kExpansionLimit:
      return absl::ResourceExhaustedError(
          absl::StrFormat("expansion limit of %d (%s) reached while computing the %s", budget,
                          budget_source, what));
    default:
      return absl::DeadlineExceededError(
          absl::StrFormat("deadline passed while computing the %s", what));
  }
}

absl::Status CheckFleetSolver(v1::FleetSolver solver, std::string_view field) {
  if (v1::FleetSolver_IsValid(solver)) return absl::OkStatus();
  return absl::InvalidArgumentError(absl::StrFormat(
      "%s %d is not a FleetSolver value (lacam, pibt, prioritized or cbs)", field,
      static_cast<int>(solver)));
}

FleetSolver FleetSolverFromProto(v1::FleetSolver solver) {
  switch (solver) {
    case v1::FLEET_SOLVER_PRIORITIZED:
      return FleetSolver::kPrioritized;
    case v1::FLEET_SOLVER_CBS:
      return FleetSolver::kCbs;
    case v1::FLEET_SOLVER_PIBT:
      return FleetSolver::kPibt;
    default:
      return FleetSolver::kLacam;
  }
}

v1::FleetSolver FleetSolverToProto(FleetSolver solver) {
  switch (solver) {
    case FleetSolver::kPrioritized:
      return v1::FLEET_SOLVER_PRIORITIZED;
    case FleetSolver::kCbs:
      return v1::FLEET_SOLVER_CBS;
    case FleetSolver::kPibt:
      return v1::FLEET_SOLVER_PIBT;
    case FleetSolver::kLacam:
      break;
  }
  return v1::FLEET_SOLVER_LACAM;
}

double StepsLength(const std::vector<Cell>& cells) {
  double length = 0.0;
  for (size_t t = 1; t < cells.size(); ++t) {
    const bool diagonal = cells[t].x != cells[t - 1].x && cells[t].y != cells[t - 1].y;
    const bool moved = cells[t].x != cells[t - 1].x || cells[t].y != cells[t - 1].y;
    length += diagonal ? kSqrt2 : (moved ? 1.0 : 0.0);
  }
  return length;
}

void FillFleetPath(const std::vector<Cell>& cells, const Grid& stored, v1::FleetPath* path) {
  for (const Cell c : cells) {
    *path->add_cells() = ToProto(c);
    const WorldPoint w = stored.CellCenter(c);
    v1::WorldPoint* p = path->add_world();
    p->set_x(w.x);
    p->set_y(w.y);
  }
  int64_t cost = static_cast<int64_t>(cells.size()) - 1;
  while (cost > 0 && cells[cost - 1] == cells.back()) --cost;
  path->set_cost(cost);
  const double length = StepsLength(cells);
  path->set_length(length);
  path->set_length_m(length * stored.resolution());
}

}  // namespace pathd::server
