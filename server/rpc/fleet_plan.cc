// PlanFleet: the robots decoded and checked on the gRPC thread (each start
// and goal named robots[i].start / robots[i].goal, radii, distinct cells);
// on a worker, one planning grid per distinct radius from the inflation
// cache, core/fleet/mapf under the solver's time limit, the timed paths
// with world points.
#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "core/fleet/mapf.h"
#include "core/planning/plan_query.h"
#include "core/search/endpoints.h"
#include "core/status_macros.h"
#include "server/rpc/fleet_common.h"
#include "server/rpc/fleet_queries.h"

namespace pathd::server {
namespace {

// The solver's time limit when the request sets none.
constexpr int64_t kDefaultTimeLimitMs = 10'000;
// Of the time left before the call's deadline, the share the solver may use
// (the rest builds and sends the answer).
constexpr double kDeadlineShare = 0.9;

// "robots[3]" or "robots[3] ('forklift-2')".
std::string RobotName(const v1::PlanFleetRequest& r, int i) {
  const std::string& name = r.robots(i).name();
  return name.empty() ? absl::StrFormat("robots[%d]", i)
                      : absl::StrFormat("robots[%d] ('%s')", i, name);
}

struct FleetCall : UnaryCall<v1::PlanFleetRequest, v1::PlanFleetResponse> {
  static constexpr char kRpc[] = "PlanFleet";
  std::optional<FleetQuery> q;
  std::vector<Cell> starts;
  std::vector<Cell> goals;
  // Each robot's radius in cells.
  std::vector<double> radii;
  FleetOptions options;
  absl::Duration time_limit;
};

// Two robots on one cell, named; OK when all cells differ.
absl::Status CheckDistinct(const v1::PlanFleetRequest& r, const std::vector<Cell>& cells,
                           const char* what) {
  std::map<std::pair<int32_t, int32_t>, int> seen;
  for (int i = 0; i < static_cast<int>(cells.size()); ++i) {
    const auto [it, inserted] = seen.emplace(std::make_pair(cells[i].x, cells[i].y), i);
    if (!inserted) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "%s.%s (%d, %d) is the %s of %s too: robots need distinct %ss",
          RobotName(r, i), what, cells[i].x, cells[i].y, what, RobotName(r, it->second),
          what));
    }
  }
  return absl::OkStatus();
}

absl::Status PrepareFleet(const PlanDeps& deps, FleetCall& call) {
  const v1::PlanFleetRequest& r = *call.request;
  if (r.robots_size() == 0) return absl::InvalidArgumentError("robots: give at least one");
  if (r.robots_size() > deps.limits.max_fleet_robots) {
    return absl::ResourceExhaustedError(
        absl::StrFormat("%d robots; the limit is %d (--max_fleet_robots)", r.robots_size(),
                        deps.limits.max_fleet_robots));
  }
  PATHD_ASSIGN_OR_RETURN(call.q, DecodeFleetQuery(deps, r.map(), r.options()));
  const Grid& grid = call.q->stored();
  const CostParams& cost = call.q->query().request.cost;
  for (int i = 0; i < r.robots_size(); ++i) {
    const v1::FleetRobot& robot = r.robots(i);
    const std::string name = RobotName(r, i);
    for (const bool start : {true, false}) {
      const std::string what = absl::StrFormat("%s.%s", name, start ? "start" : "goal");
      PATHD_ASSIGN_OR_RETURN(
          const Cell c, CellFromPosition(start ? robot.start() : robot.goal(), grid, what));
      PATHD_RETURN_IF_ERROR(ValidateEndpoint(grid, c, what, cost));
      (start ? call.starts : call.goals).push_back(c);
    }
    if (!std::isfinite(robot.radius_m()) || robot.radius_m() < 0.0) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "%s.radius_m %g must be finite and >= 0", name, robot.radius_m()));
    }
    const double diagonal = std::hypot(grid.width(), grid.height());
    const double radius = robot.radius_m() > 0.0
                              ? std::min(robot.radius_m() / grid.resolution(), diagonal)
                              : call.q->query().robot_radius_cells;
    call.radii.push_back(radius);
  }
  PATHD_RETURN_IF_ERROR(CheckDistinct(r, call.starts, "start"));
  PATHD_RETURN_IF_ERROR(CheckDistinct(r, call.goals, "goal"));

  FleetOptions& o = call.options;
  PATHD_RETURN_IF_ERROR(CheckFleetSolver(r.solver(), "solver"));
  o.solver = FleetSolverFromProto(r.solver());
  if (r.restarts() < 0) {
    return absl::InvalidArgumentError(
        absl::StrFormat("restarts %d must be >= 0", r.restarts()));
  }
  if (r.restarts() > 0) o.restarts = r.restarts();
  if (!std::isfinite(r.suboptimality()) || r.suboptimality() < 0.0 ||
      (r.suboptimality() > 0.0 && r.suboptimality() < 1.0)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "suboptimality %g must be 0 (optimal), 1 (optimal) or above 1 (ECBS)",
        r.suboptimality()));
  }
  o.suboptimality = std::max(1.0, r.suboptimality());
  if (r.seed() != 0) o.seed = r.seed();
  if (r.max_steps() < 0) {
    return absl::InvalidArgumentError(
        absl::StrFormat("max_steps %d must be >= 0", r.max_steps()));
  }
  o.max_steps = r.max_steps();
  o.refine = r.refine();
  if (r.time_limit_ms() < 0) {
    return absl::InvalidArgumentError(
        absl::StrFormat("time_limit_ms %d must be >= 0", r.time_limit_ms()));
  }
  call.time_limit =
      absl::Milliseconds(r.time_limit_ms() > 0 ? r.time_limit_ms() : kDefaultTimeLimitMs);
  return absl::OkStatus();
}

// The grids of the problem, one per distinct radius, and each robot's index;
// every start and goal checked against its robot's radius.
absl::StatusOr<FleetProblem> BuildProblem(
    InflationCache& inflation, const FleetCall& call,
    std::vector<std::shared_ptr<const Grid>>* keep_alive) {
  const FleetQuery& q = *call.q;
  const v1::PlanFleetRequest& r = *call.request;
  FleetProblem problem;
  problem.connectivity = q.query().request.cost.connectivity;
  problem.unknown_is_free = q.query().request.cost.unknown_is_free;
  std::map<double, int32_t> grid_of_radius;
  for (size_t i = 0; i < call.radii.size(); ++i) {
    const double radius = call.radii[i];
    auto [it, inserted] =
        grid_of_radius.emplace(radius, static_cast<int32_t>(keep_alive->size()));
    if (inserted) {
      PlanQuery shaped = q.query();
      shaped.robot_radius_cells = radius;
      const GridShape shape = PlanningShape(shaped);
      if (shape.shaped()) {
        PATHD_ASSIGN_OR_RETURN(std::shared_ptr<const Grid> grid,
                               inflation.Get(*q.decoded.snapshot, shape));
        keep_alive->push_back(std::move(grid));
      } else {
        keep_alive->push_back(q.decoded.snapshot->grid);
      }
      problem.grids.push_back(keep_alive->back().get());
    }
    if (radius > 0.0) {
      const std::string name = RobotName(r, static_cast<int>(i));
      const std::string start = name + ".start";
      const std::string goal = name + ".goal";
      PATHD_RETURN_IF_ERROR(CheckRadiusEndpoints(q.stored(), *problem.grids[it->second], radius,
                                                 {{call.starts[i], start},
                                                  {call.goals[i], goal}}));
    }
    problem.robots.push_back(FleetRobot{call.starts[i], call.goals[i], it->second});
  }
  return problem;
}

absl::Status AnswerFleet(FleetCall& call, InflationCache& inflation,
                         int64_t max_message_bytes) {
  const absl::Time started = absl::Now();
  std::vector<std::shared_ptr<const Grid>> grids;
  PATHD_ASSIGN_OR_RETURN(const FleetProblem problem, BuildProblem(inflation, call, &grids));
  const absl::Time deadline =
      std::min(started + call.time_limit,
               started + (call.deadline - started) * kDeadlineShare);
  const StopCondition stop(deadline, &call.cancelled, /*max_expansions=*/0);
  const absl::Time solve_started = absl::Now();
  PATHD_ASSIGN_OR_RETURN(const FleetPlan plan, PlanFleet(problem, call.options, stop));
  const int64_t solver_us = absl::ToInt64Microseconds(absl::Now() - solve_started);
  if (plan.outcome == PlanOutcome::kCancelled) {
    return absl::CancelledError("cancelled while planning the fleet");
  }

  v1::PlanFleetResponse& out = *call.response;
  const Grid& stored = call.q->stored();
  const double res = stored.resolution();
  out.set_map_version(call.q->decoded.snapshot->version);
  out.set_solver(FleetSolverToProto(call.options.solver));
  out.set_solver_time_us(solver_us);
  out.set_expansions(plan.expansions);
  out.set_iterations(plan.iterations);
  out.set_lower_bound(plan.lower_bound);
  out.set_frame_id(kFrameId);
  // The stop condition has no expansion budget, so kExpansionLimit is a
  // solver's own limit: an incomplete one giving up (prioritized after every
  // order, pibt at max_steps) or lacam / cbs at their memory cap.
  const bool gave_up = plan.outcome == PlanOutcome::kExpansionLimit;
  const bool stopped = plan.outcome == PlanOutcome::kTimeout;
  out.set_stopped_early(stopped);
  out.set_found(plan.complete && !plan.paths.empty());
  if (!out.found()) {
    if (stopped) {
      out.set_reason(absl::StrFormat("no conflict-free plan within the time limit of %d ms",
                                     absl::ToInt64Milliseconds(deadline - started)));
    } else if (gave_up) {
      const bool incomplete = call.options.solver == FleetSolver::kPrioritized ||
                              call.options.solver == FleetSolver::kPibt;
      const std::string_view solver = FleetSolverName(call.options.solver);
      out.set_reason(
          incomplete
              ? absl::StrFormat("%s gave up after %d iterations: it is incomplete; lacam "
                                "finds a plan when one exists",
                                solver, plan.iterations)
              : absl::StrFormat("%s stopped at its memory cap after %d iterations without a "
                                "plan",
                                solver, plan.iterations));
    } else {
      out.set_reason(
          "no conflict-free plan exists: a robot's goal is unreachable on its map, or the "
          "robots cannot all reach their goals");
    }
    return absl::OkStatus();
  }
  out.set_optimal(plan.optimal);
  out.set_makespan(plan.makespan);
  out.set_sum_of_costs(plan.sum_of_costs);
  const v1::PlanFleetRequest& r = *call.request;
  for (size_t i = 0; i < plan.paths.size(); ++i) {
    const std::vector<Cell>& cells = plan.paths[i];
    v1::FleetPath* path = out.add_paths();
    FillFleetPath(cells, stored, path);
    path->set_name(r.robots(static_cast<int>(i)).name());
    path->set_radius_m(call.radii[i] * res);
  }
  if (absl::Status s = CheckResponseSize(out, "fleet plan", max_message_bytes); !s.ok()) {
    out.Clear();
    return s;
  }
  return absl::OkStatus();
}

}  // namespace

grpc::ServerUnaryReactor* ServePlanFleet(const PlanDeps& deps,
                                         grpc::CallbackServerContext* context,
                                         const v1::PlanFleetRequest* request,
                                         v1::PlanFleetResponse* response) {
  auto call = StartUnaryCall<FleetCall>(context, request, response);
  const absl::Status prepared = PrepareFleet(deps, *call);
  auto job = std::make_unique<CallJob<FleetCall>>(
      call,
      [inflation = &deps.inflation, bytes = deps.limits.max_message_bytes](
          FleetCall& c, SearchScratch&) -> Verdict {
        absl::Status s = AnswerFleet(c, *inflation, bytes);
        if (!s.ok()) return {s, "ERROR"};
        const v1::PlanFleetResponse& out = *c.response;
        return {s, out.found() ? (out.stopped_early() ? "FOUND_STOPPED" : "FOUND")
                               : (out.stopped_early() ? "STOPPED" : "NO_PLAN")};
      },
      &FinishFleetCall<FleetCall>, JobFailureText{"out of memory", "fleet plan failed"});
  return AdmitUnaryCall(deps.pool, std::move(call), prepared, std::move(job),
                        &FinishFleetCall<FleetCall>);
}

}  // namespace pathd::server
