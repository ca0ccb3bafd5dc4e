// pathctl fleet plan: conflict-free timed paths for the robots of a file
// (one "SX SY GX GY [RADIUS_M]" line each; cells, or metres with --world).
// The table shows each robot's cost in steps and length in metres; --output
// json prints the response (paths[i].cells[t] is robot i's cell at step t),
// csv one row per robot and time step.
#include <cmath>
#include <string>
#include <vector>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "client/pathctl/command.h"
#include "client/pathctl/files.h"
#include "client/pathctl/fleet_plan.h"
#include "core/status_macros.h"

namespace pathd::pathctl {
namespace {

// The robots of `text` (the --robots file): '#' starts a comment, blank
// lines are skipped. INVALID_ARGUMENT naming the line.
absl::StatusOr<std::vector<v1::FleetRobot>> ParseRobots(const std::string& text,
                                                        const std::string& path, bool world) {
  std::vector<v1::FleetRobot> robots;
  int line_number = 0;
  for (absl::string_view line : absl::StrSplit(text, '\n')) {
    ++line_number;
    line = line.substr(0, line.find('#'));
    const std::vector<std::string> fields =
        absl::StrSplit(line, absl::ByAnyChar(" \t,\r"), absl::SkipWhitespace());
    if (fields.empty()) continue;
    const std::string where = absl::StrFormat("%s:%d", path, line_number);
    if (fields.size() != 4 && fields.size() != 5) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "%s: expected 'SX SY GX GY [RADIUS_M]', got %d fields", where, fields.size()));
    }
    static constexpr const char* kStart[] = {"SX", "SY"};
    static constexpr const char* kGoal[] = {"GX", "GY"};
    const Args all(fields);
    absl::StatusOr<v1::Position> start = PositionFromPair(all.subspan(0, 2), world, kStart);
    if (!start.ok()) {
      return absl::InvalidArgumentError(absl::StrCat(where, ": ", start.status().message()));
    }
    absl::StatusOr<v1::Position> goal = PositionFromPair(all.subspan(2, 2), world, kGoal);
    if (!goal.ok()) {
      return absl::InvalidArgumentError(absl::StrCat(where, ": ", goal.status().message()));
    }
    v1::FleetRobot robot;
    *robot.mutable_start() = *start;
    *robot.mutable_goal() = *goal;
    if (fields.size() == 5) {
      double radius = 0.0;
      if (!absl::SimpleAtod(fields[4], &radius) || !std::isfinite(radius) || radius < 0.0) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "%s: RADIUS_M '%s' is not a distance >= 0 in metres", where, fields[4]));
      }
      robot.set_radius_m(radius);
    }
    robots.push_back(std::move(robot));
  }
  if (robots.empty()) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": no robots (one 'SX SY GX GY' line each)"));
  }
  return robots;
}

std::string SolverName(v1::FleetSolver solver) {
  switch (solver) {
    case v1::FLEET_SOLVER_PRIORITIZED:
      return "prioritized";
    case v1::FLEET_SOLVER_CBS:
      return "cbs";
    case v1::FLEET_SOLVER_PIBT:
      return "pibt";
    default:
      return "lacam";
  }
}

}  // namespace

absl::StatusOr<v1::FleetSolver> SolverFromName(const std::string& name) {
  if (name.empty() || name == "lacam") return v1::FLEET_SOLVER_LACAM;
  if (name == "pibt") return v1::FLEET_SOLVER_PIBT;
  if (name == "prioritized") return v1::FLEET_SOLVER_PRIORITIZED;
  if (name == "cbs") return v1::FLEET_SOLVER_CBS;
  return absl::InvalidArgumentError(
      absl::StrCat("--solver must be lacam, pibt, prioritized or cbs, not '", name, "'"));
}

absl::StatusOr<v1::PlanFleetRequest> FleetPlanRequest(const Options& options,
                                                      const std::string& map) {
  const FleetOptions& o = options.fleet;
  v1::PlanFleetRequest request;
  request.set_map(map);
  PATHD_ASSIGN_OR_RETURN(const std::string text, ReadTextFile(o.robots));
  PATHD_ASSIGN_OR_RETURN(std::vector<v1::FleetRobot> robots,
                           ParseRobots(text, o.robots, o.world));
  for (v1::FleetRobot& r : robots) *request.add_robots() = std::move(r);
  PATHD_ASSIGN_OR_RETURN(const v1::FleetSolver solver, SolverFromName(o.solver));
  request.set_solver(solver);
  if (o.time_limit_s) {
    if (!std::isfinite(*o.time_limit_s) || *o.time_limit_s <= 0.0) {
      return absl::InvalidArgumentError(
          absl::StrFormat("--time_limit %g must be > 0 seconds", *o.time_limit_s));
    }
    request.set_time_limit_ms(
        std::max<int64_t>(1, static_cast<int64_t>(std::llround(*o.time_limit_s * 1000.0))));
  }
  if (o.suboptimality) request.set_suboptimality(*o.suboptimality);
  if (o.restarts) request.set_restarts(*o.restarts);
  if (o.max_steps) request.set_max_steps(*o.max_steps);
  request.set_refine(o.refine);
  request.set_seed(o.seed);
  if (absl::Status s = SetCostOptions(options.cost, request.mutable_options()); !s.ok()) {
    return s;
  }
  return request;
}

std::string FleetPlanSummary(const v1::PlanFleetResponse& response) {
  if (!response.found()) return absl::StrCat("no fleet plan: ", response.reason());
  return absl::StrFormat("fleet plan (%s): %d robots, makespan %d, sum of costs %d (lower bound %d)%s%s",
                         SolverName(response.solver()), response.paths_size(),
                         response.makespan(), response.sum_of_costs(), response.lower_bound(),
                         response.optimal() ? ", optimal" : "",
                         response.stopped_early() ? ", stopped early (best so far)" : "");
}

namespace {

int RunFleetPlan(CommandEnv& env, Args args) {
  const FleetOptions& o = env.options().fleet;
  if (args.size() != 1) return env.Usage("fleet plan takes NAME and --robots FILE");
  if (o.robots.empty()) return env.Usage("fleet plan needs --robots FILE");
  absl::StatusOr<v1::PlanFleetRequest> request = FleetPlanRequest(env.options(), args[0]);
  if (!request.ok()) {
    return request.status().code() == absl::StatusCode::kInvalidArgument
               ? env.Usage(request.status().message())
               : env.Fail(request.status());
  }
  absl::StatusOr<v1::PlanFleetResponse> response = env.client().PlanFleet(*request);
  if (!response.ok()) return env.Fail(response.status());
  const int code = response->found() ? kExitOk : kExitNoPath;
  if (env.json()) {
    const int printed = env.PrintJson(*response);
    return printed != kExitOk ? printed : code;
  }
  if (env.csv()) {
    Table table({"robot", "t", "x", "y", "world_x", "world_y"});
    for (int i = 0; i < response->paths_size(); ++i) {
      const v1::FleetPath& p = response->paths(i);
      for (int t = 0; t < p.cells_size(); ++t) {
        table.AddRow({absl::StrCat(i), absl::StrCat(t), absl::StrCat(p.cells(t).x()),
                      absl::StrCat(p.cells(t).y()), absl::StrFormat("%.3f", p.world(t).x()),
                      absl::StrFormat("%.3f", p.world(t).y())});
      }
    }
    const int printed = env.PrintCsv(table);
    return printed != kExitOk ? printed : code;
  }
  std::ostream& out = env.out();
  out << absl::StrFormat("map version:  %d\nsolver:       %s (%.3f ms, %d expansions, %d iterations)\n",
                         response->map_version(), SolverName(response->solver()),
                         response->solver_time_us() / 1000.0, response->expansions(),
                         response->iterations());
  if (!response->found()) {
    out << "no plan: " << response->reason() << "\n"
        << absl::StrFormat("lower bound:  %d steps (sum of costs)\n", response->lower_bound());
    return code;
  }
  const int64_t bound = response->lower_bound();
  out << absl::StrFormat(
      "robots:       %d\nmakespan:     %d steps\nsum of costs: %d steps (lower bound %d, %+.1f%%)%s%s\n\n",
      response->paths_size(), response->makespan(), response->sum_of_costs(), bound,
      bound > 0 ? 100.0 * static_cast<double>(response->sum_of_costs() - bound) /
                      static_cast<double>(bound)
                : 0.0,
      response->optimal() ? ", optimal" : "",
      response->stopped_early() ? "\nstopped early: the time limit ran out; best plan so far"
                                : "");
  Table table({"robot", "start", "goal", "cost (steps)", "length (m)"});
  for (int i = 0; i < response->paths_size(); ++i) {
    const v1::FleetPath& p = response->paths(i);
    table.AddRow({absl::StrCat(i), FormatCell(p.cells(0)), FormatCell(p.cells(p.cells_size() - 1)),
                  absl::StrCat(p.cost()), absl::StrFormat("%.3f", p.length_m())});
  }
  out << table.Aligned();
  return code;
}

constexpr absl::string_view kFleetPlanFlags[] = {
    "robots", "solver", "time_limit", "refine", "suboptimality", "restarts", "max_steps",
    "seed", "world", "connectivity", "unknown_is_free", "robot_radius", "robot_radius_cells"};

}  // namespace

const Command kFleetPlanCommand = {
    .name = "fleet plan",
    .synopsis = "NAME --robots FILE [--solver lacam|pibt|prioritized|cbs]\n"
                " [--time_limit S] [--refine] [--suboptimality W] [--restarts N] [--seed N]\n"
                " [--max_steps N]\n"
                " [--world] [--robot_radius M] [--connectivity 4|8]",
    .help = "Plans conflict-free timed paths for the robots of FILE on map NAME: one\n"
            "'SX SY GX GY [RADIUS_M]' line per robot (cells; metres with --world). At\n"
            "each time step every robot waits or moves one cell, and no two robots\n"
            "sweep one cell in one step (no vertex, swap or following conflicts).\n"
            "lacam (default) scales to hundreds of robots (--refine: LaCAM*, improving\n"
            "its first plan until --time_limit); cbs is optimal for small\n"
            "teams (--suboptimality W > 1: ECBS); prioritized is fast but may fail.\n"
            "--output json prints paths[i].cells[t], robot i's cell at step t (it\n"
            "stays at its goal after its last entry). Exit code 3 when no plan.",
    .flags = kFleetPlanFlags,
    .run = RunFleetPlan,
    .map_arg = MapArg::kExisting,
};

}  // namespace pathd::pathctl
