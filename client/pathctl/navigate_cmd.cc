// pathctl navigate: a Navigate session opened from SX SY to GX GY, with an
// optional robot script replayed through it (navigate_session.cc).
#include <string>
#include <utility>
#include <vector>

#include "client/pathctl/command.h"
#include "client/pathctl/files.h"
#include "client/pathctl/fleet_plan.h"
#include "client/pathctl/navigate_script.h"
#include "client/pathctl/navigate_session.h"

namespace pathd::pathctl {
namespace {

int Navigate(CommandEnv& env, Args args) {
  if (args.size() != 5) return env.Usage("navigate takes NAME SX SY GX GY");
  if (env.csv()) {
    return env.Unsupported("navigate",
                           "it prints a log of script steps and pushed paths; "
                           "use --output table, or json for one NavigateResponse "
                           "per line");
  }
  static constexpr const char* kNames[] = {"SX", "SY", "GX", "GY"};
  const bool world = env.options().plan.world;
  v1::NavigateOpen open;
  open.set_map(args[0]);
  absl::StatusOr<v1::Position> start = PositionFromPair(args.subspan(1, 2), world, {kNames, 2});
  if (!start.ok()) return env.Usage(start.status().message());
  absl::StatusOr<v1::Position> goal = PositionFromPair(args.subspan(3, 2), world, {kNames + 2, 2});
  if (!goal.ok()) return env.Usage(goal.status().message());
  *open.mutable_start() = *std::move(start);
  *open.mutable_goal() = *std::move(goal);
  if (absl::Status s = SetCostOptions(env.options().cost, open.mutable_options()); !s.ok()) {
    return env.Usage(s.message());
  }
  // The robot (plan's flags): the footprint, and for a kinematic session its
  // turning radius, motion model, penalties and headings.
  v1::PlanRequest robot;
  *robot.mutable_start() = open.start();
  *robot.mutable_goal() = open.goal();
  if (absl::Status s = SetRobotOptions(env.options().robot, &robot); !s.ok()) {
    return env.Usage(s.message());
  }
  *open.mutable_start() = robot.start();
  *open.mutable_goal() = robot.goal();
  open.mutable_options()->MergeFrom(robot.options());
  const PlanFlags& plan = env.options().plan;
  if (!plan.planner.empty()) {
    absl::StatusOr<v1::Planner> planner = PlannerFromName(plan.planner);
    if (!planner.ok()) return env.Usage(planner.status().message());
    if (*planner != v1::PLANNER_DSTAR_LITE && !IsKinematicPlanner(plan.planner)) {
      return env.Usage(absl::StrCat("--planner: navigate plans with dstar_lite or a kinematic "
                                    "planner (hybrid_astar, state_lattice), not ",
                                    plan.planner));
    }
    open.set_planner(*planner);
  }
  if (plan.max_expansions < 0) {
    return env.Usage("--max_expansions must be >= 0");
  }
  // The cap of each D* Lite plan, and the budget of each kinematic replan.
  open.mutable_options()->set_max_expansions(plan.max_expansions);
  open.set_replan_max_expansions(plan.max_expansions);
  const NavigateOptions& navigate = env.options().navigate;
  if (!navigate.fleet.empty()) {
    open.mutable_fleet()->set_group(navigate.fleet);
    if (!navigate.solver.empty()) {
      absl::StatusOr<v1::FleetSolver> solver = SolverFromName(navigate.solver);
      if (!solver.ok()) return env.Usage(solver.status().message());
      open.mutable_fleet()->set_solver(*solver);
    }
  } else if (!navigate.solver.empty()) {
    return env.Usage("--solver: navigate takes it with --fleet GROUP");
  }
  std::vector<ScriptStep> script;
  const std::string& script_file = env.options().navigate.script;
  if (!script_file.empty()) {
    absl::StatusOr<std::string> text = ReadTextFile(script_file);
    if (!text.ok()) return env.Fail(text.status());
    absl::StatusOr<std::vector<ScriptStep>> parsed =
        ParseNavigateScript(*text, script_file);
    if (!parsed.ok()) {
      // The message already says where; the command synopsis would not help.
      env.err() << "error: " << parsed.status().message() << "\n";
      return kExitUsage;
    }
    script = *std::move(parsed);
  }
  if (absl::Status s =
          RunNavigateSession(env.client(), open, script, env.json(), env.out(), world);
      !s.ok()) {
    return env.Fail(s);
  }
  return kExitOk;
}

constexpr absl::string_view kNavigateFlags[] = {
    "script", "world", "planner", "max_expansions", "connectivity", "cost_weight", "unknown_is_free",
    "robot_radius", "robot_radius_cells", "min_clearance", "min_clearance_cells",
    "inflation_radius", "inflation_radius_cells", "cost_scaling_factor", "footprint",
    "footprint_cells", "min_turning_radius", "min_turning_radius_cells", "motion_model",
    "reverse_penalty", "change_penalty", "non_straight_penalty", "cost_penalty", "start_yaw",
    "goal_yaw", "goal_yaw_tolerance", "lattice", "no_smooth", "fleet", "solver"};

}  // namespace

const Command kNavigateCommand = {
    .name = "navigate",
    .synopsis = "NAME SX SY GX GY [--world] [--script FILE] [cost options]\n"
                " [--planner dstar_lite|hybrid_astar|state_lattice] [--max_expansions N]\n"
                " [--footprint \"[[x,y],...]\"] [--min_turning_radius M]\n"
                " [--motion_model dubins|reeds_shepp] [--start_yaw R] [--goal_yaw R]\n"
                " [--fleet GROUP [--solver lacam|pibt|prioritized|cbs]]",
    .help = "Opens a Navigate session on map NAME from cell (SX, SY) to (GX, GY) and\n"
            "prints its path; --script replays a robot run through it (format in\n"
            "'pathctl --help'). D* Lite by default; --planner hybrid_astar or\n"
            "state_lattice (or --min_turning_radius / --motion_model) opens a\n"
            "kinematic session for the robot of --footprint, which answers poses\n"
            "and replans from each reported pose within --max_expansions (default\n"
            "20000). --fleet GROUP opens a fleet session: the robots of the group's\n"
            "sessions on the map are planned together (one cell per robot per time\n"
            "step) and each is released along its timed path as the others pass;\n"
            "a script's 'follow' drives only as far as released, waiting for the\n"
            "pushes that release more. --world: SX SY GX GY in metres, and poses\n"
            "printed in metres.\n"
            "--timeout bounds each wait for an answer, not the session.",
    .flags = kNavigateFlags,
    .run = Navigate,
    .map_arg = MapArg::kExisting,
};

}  // namespace pathd::pathctl
