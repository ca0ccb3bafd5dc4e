// pathctl: the command-line client of pathd. Defines the flags, fills each
// command's option struct (client/pathctl/options.h) from them and hands the
// command to pathd::pathctl::Run (client/pathctl/command.h); the commands live
// one per file in client/pathctl/<cmd>_cmd.cc.
#include <unistd.h>

#include <cstdlib>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "absl/synchronization/mutex.h"
#include "absl/time/time.h"
#include "client/pathctl/pathctl.h"
#include "client/pathctl/progress.h"

ABSL_FLAG(std::string, server, "",
          "pathd address; default $PATHD_SERVER, else 127.0.0.1:50051");
ABSL_FLAG(absl::Duration, timeout, pathd::client::kDefaultTimeout,
          "deadline of each call");
ABSL_FLAG(std::string, tls_ca, "",
          "PEM CA certificate of the server; turns TLS on");
ABSL_FLAG(std::string, tls_cert, "",
          "PEM client certificate for mutual TLS (needs --tls_key, --tls_ca)");
ABSL_FLAG(std::string, tls_key, "", "PEM key of --tls_cert");
ABSL_FLAG(std::string, tls_server_name, "",
          "name the server certificate carries, if not the --server host");
ABSL_FLAG(std::string, token, "",
          "bearer token sent on every call; default $PATHD_TOKEN");
ABSL_FLAG(std::string, token_file, "",
          "file holding the bearer token (preferred over --token)");
ABSL_FLAG(bool, json, false, "print the response message as JSON");
ABSL_FLAG(std::string, output, "",
          "output format: table (default), json or csv (--json = --output=json)");
ABSL_FLAG(bool, no_progress, false,
          "no progress bars on stderr (batch, bench, maps create --from)");
ABSL_FLAG(std::string, from, "", "maps create: the .map or .yaml/.yml file");
ABSL_FLAG(bool, replace, false, "maps create: replace an existing map");
ABSL_FLAG(double, resolution, 0.0, "maps create: metres per cell (.map files)");
ABSL_FLAG(bool, cells, false, "maps get: print the cells as ASCII");
ABSL_FLAG(std::optional<uint64_t>, expected_version, std::nullopt,
          "maps set/rect: apply only at this map version");
ABSL_FLAG(uint64_t, from_version, 0,
          "maps watch: the version already held (0: start with the whole map)");
ABSL_FLAG(int64_t, count, 0, "maps watch: stop after N events (0: no limit)");
ABSL_FLAG(std::string, planner, "", "plan: planner name (default: server's)");
ABSL_FLAG(int, connectivity, 0, "plan, navigate, cost-to-go: 4 or 8 (default 8)");
ABSL_FLAG(std::optional<double>, cost_weight, std::nullopt,
          "plan, navigate, cost-to-go: cell cost weight (default 1)");
ABSL_FLAG(bool, world, false, "plan, cost-to-go: coordinates are world metres");
ABSL_FLAG(bool, unknown_is_free, false, "plan, navigate, cost-to-go: unknown cells are free");
ABSL_FLAG(int64_t, max_expansions, 0, "plan: expansion budget (0: server's)");
ABSL_FLAG(std::optional<double>, heuristic_weight, std::nullopt,
          "plan: weighted_astar heuristic weight w >= 1 (default 1.5)");
ABSL_FLAG(std::optional<double>, robot_radius, std::nullopt,
          "plan, navigate, cost-to-go: robot radius in metres");
ABSL_FLAG(std::optional<double>, robot_radius_cells, std::nullopt,
          "plan, navigate, cost-to-go: robot radius in cells");
ABSL_FLAG(std::optional<double>, min_clearance, std::nullopt,
          "plan, navigate, cost-to-go: keep this many metres from obstacles "
          "where the map allows (a cost, not a rule)");
ABSL_FLAG(std::optional<double>, min_clearance_cells, std::nullopt,
          "plan, navigate, cost-to-go: the minimum clearance in cells");
ABSL_FLAG(std::optional<double>, inflation_radius, std::nullopt,
          "plan, navigate, cost-to-go, render: Nav2 inflation costs out to this "
          "many metres from lethal cells (Nav2's default is 0.55)");
ABSL_FLAG(std::optional<double>, inflation_radius_cells, std::nullopt,
          "plan, navigate, cost-to-go, render: the inflation radius in cells");
ABSL_FLAG(std::optional<double>, cost_scaling_factor, std::nullopt,
          "plan, navigate, cost-to-go, render: Nav2's cost_scaling_factor, per "
          "metre (default 10)");
ABSL_FLAG(std::optional<double>, goal_tolerance, std::nullopt,
          "plan: substitute the nearest free cell within this many metres for "
          "a blocked goal (kinematic planners: end this close to the goal)");
ABSL_FLAG(std::optional<double>, goal_tolerance_cells, std::nullopt,
          "plan: the goal tolerance in cells");
ABSL_FLAG(std::string, footprint, "",
          "plan, batch, render: the robot's outline in metres, Nav2's syntax "
          "\"[[x,y],[x,y],...]\" (x forward, y left)");
ABSL_FLAG(std::string, footprint_cells, "", "plan, batch, render: the outline in cells");
ABSL_FLAG(std::optional<double>, min_turning_radius, std::nullopt,
          "plan, batch, render: kinematic planners' smallest turning radius, metres "
          "(default 0.4)");
ABSL_FLAG(std::optional<double>, min_turning_radius_cells, std::nullopt,
          "plan, batch, render: the turning radius in cells");
ABSL_FLAG(std::string, motion_model, "",
          "plan, batch, render: dubins, reeds_shepp, differential or omnidirectional");
ABSL_FLAG(std::optional<double>, reverse_penalty, std::nullopt,
          "plan: kinematic planners' reversing cost multiplier (default 2)");
ABSL_FLAG(std::optional<double>, change_penalty, std::nullopt,
          "plan: cost added per change of direction (default 0)");
ABSL_FLAG(std::optional<double>, non_straight_penalty, std::nullopt,
          "plan: turning cost multiplier (default 1.2)");
ABSL_FLAG(std::optional<double>, cost_penalty, std::nullopt,
          "plan: weight of cell costs along motions (default 2)");
ABSL_FLAG(std::optional<double>, start_yaw, std::nullopt,
          "plan, render: the start's heading, radians");
ABSL_FLAG(std::optional<double>, goal_yaw, std::nullopt,
          "plan, render: the goal's heading, radians");
ABSL_FLAG(std::optional<double>, goal_yaw_tolerance, std::nullopt,
          "plan, render: how far (radians) a kinematic path may end from the goal's "
          "heading");
ABSL_FLAG(std::string, lattice, "",
          "plan, batch, render: state_lattice's control set (a shipped name or a "
          "file on the server)");
ABSL_FLAG(bool, no_smooth, false, "plan, batch, render: do not smooth kinematic paths");
ABSL_FLAG(bool, smooth, false,
          "plan, batch, render: also return a grid or geometric planner's path as poses "
          "smoothed for the robot (footprint or radius)");
ABSL_FLAG(std::string, via, "",
          "plan: via points X,Y[;X,Y...] visited in order before the goal");
ABSL_FLAG(bool, allow_partial, false,
          "plan: with --via, return the path to the last reached goal when a "
          "leg finds no path");
ABSL_FLAG(bool, expansions, false,
          "plan: return the expanded cells (prints the count; --json: the cells)");
ABSL_FLAG(std::string, path_file, "", "check: the path, one \"X Y\" per line");
ABSL_FLAG(bool, simplify, false, "plan: simplify the path by ray-shooting");
ABSL_FLAG(int, lookahead, 0, "plan: rtaa_star/lrta_star look-ahead (0: 64)");
ABSL_FLAG(std::string, cost_to_go_file, "",
          "plan, cost-to-go: write the cost-to-go field as CSV");
ABSL_FLAG(std::string, pf_attractive, "",
          "plan: potential_field attractive potential, quadratic or conic");
ABSL_FLAG(double, pf_attractive_gain, 0.0, "plan: potential_field k_att");
ABSL_FLAG(double, pf_switch_distance, 0.0,
          "plan: potential_field quadratic-to-conic distance, cells");
ABSL_FLAG(double, pf_repulsive_gain, 0.0, "plan: potential_field eta");
ABSL_FLAG(double, pf_influence, 0.0,
          "plan: potential_field obstacle influence distance, cells");
ABSL_FLAG(double, pf_step, 0.0, "plan: potential_field descent step, cells");
ABSL_FLAG(int64_t, pf_max_steps, 0, "plan: potential_field step limit");
ABSL_FLAG(std::string, ant_colony, "",
          "plan: ant_colony parameters KEY=VALUE[,KEY=VALUE...] (ants, "
          "iterations, stall_iterations, alpha, beta, rho, xi, q0, tau0, "
          "max_steps, seed)");
ABSL_FLAG(std::string, reaction_diffusion, "",
          "plan: reaction_diffusion parameters KEY=VALUE[,KEY=VALUE...] "
          "(diffusion, reaction_rate, threshold, time_step, max_steps)");
ABSL_FLAG(std::string, script, "", "navigate: the robot run to replay");
ABSL_FLAG(std::string, fleet, "",
          "navigate: join this fleet group of the map (robots planned together)");
ABSL_FLAG(std::string, window, "", "cost-to-go: X,Y,W,H part of the field");
ABSL_FLAG(std::string, sources, "", "table: source points X,Y[;X,Y...]");
ABSL_FLAG(std::string, destinations, "", "table: destination points X,Y[;X,Y...]");
ABSL_FLAG(std::string, waypoints, "", "trip: the stops X,Y[;X,Y...], the first where it starts");
ABSL_FLAG(std::string, method, "", "table: auto (default), backward or forward");
ABSL_FLAG(std::string, end, "", "trip: round_trip (default), fixed_last or any");
ABSL_FLAG(std::optional<double>, yaw, std::nullopt,
          "nearest: heading (radians) of a polygon footprint");
ABSL_FLAG(std::optional<double>, max_distance, std::nullopt,
          "nearest: farthest answer, metres");
ABSL_FLAG(std::optional<double>, max_distance_cells, std::nullopt,
          "nearest: farthest answer, cells");
ABSL_FLAG(std::optional<double>, budget, std::nullopt, "isochrone: cost budget, metres");
ABSL_FLAG(std::optional<double>, budget_cells, std::nullopt,
          "isochrone: cost budget, cells");
ABSL_FLAG(std::string, robots, "",
          "fleet plan: file with one 'SX SY GX GY [RADIUS_M]' line per robot (cells; "
          "metres with --world)");
ABSL_FLAG(std::string, solver, "",
          "fleet plan, navigate --fleet: lacam (default), pibt, prioritized or cbs");
ABSL_FLAG(std::optional<double>, time_limit, std::nullopt,
          "fleet plan: the solver's time limit, seconds (then it answers with the best "
          "plan so far; default 10)");
ABSL_FLAG(std::optional<double>, suboptimality, std::nullopt,
          "fleet plan --solver cbs: above 1, ECBS within this factor of optimal");
ABSL_FLAG(std::optional<int32_t>, restarts, std::nullopt,
          "fleet plan --solver prioritized: priority orders tried after the first");
ABSL_FLAG(std::optional<int32_t>, max_steps, std::nullopt,
          "fleet plan: longest timed path, steps");
ABSL_FLAG(bool, refine, false,
          "fleet plan --solver lacam: improve the first plan (LaCAM*) until --time_limit");
ABSL_FLAG(bool, snap_start, false,
          "plan: a start in an obstacle or within the robot radius of one moves "
          "to the nearest free cell");
ABSL_FLAG(std::optional<double>, snap_start_max, std::nullopt,
          "plan --snap_start: farthest move, metres");
ABSL_FLAG(std::optional<double>, snap_start_max_cells, std::nullopt,
          "plan --snap_start: farthest move, cells");
ABSL_FLAG(std::string, metrics_address, pathd::pathctl::kDefaultMetricsAddress,
          "metrics: pathd's --metrics_address (HOST:PORT)");
ABSL_FLAG(std::string, path_encoding, "packed",
          "plan, batch, bench: how the server sends paths: packed (decoded by "
          "pathctl), readable (repeated cells and points) or both");
ABSL_FLAG(bool, progress, false,
          "plan: stream the search's progress to stderr (PlanStream)");
ABSL_FLAG(int, concurrency, 4, "bench: requests in flight (closed-loop workers)");
ABSL_FLAG(int, channels, 1, "bench: gRPC connections the workers share");
ABSL_FLAG(absl::Duration, duration, absl::Seconds(10),
          "bench: measured time (0: until --requests are done)");
ABSL_FLAG(absl::Duration, warmup, absl::Seconds(1),
          "bench: unmeasured load before the measured time");
ABSL_FLAG(int64_t, requests, 0, "bench: stop after N measured requests (0: no limit)");
ABSL_FLAG(std::string, movingai, "",
          "bench: load this Moving AI .map and take queries from its .scen");
ABSL_FLAG(uint64_t, seed, 1,
          "bench: seed of the random queries and the shuffle; fleet plan: seed of the "
          "solver's random choices");
ABSL_FLAG(bool, plan, false,
          "render: plan from SX SY to GX GY and draw the path");
ABSL_FLAG(std::string, out, "", "render, simulate: write the picture to this PNG file");
ABSL_FLAG(std::string, trajectory, "",
          "simulate: write the trajectories to this CSV file (one row per robot and control period)");
ABSL_FLAG(std::string, log_json, "",
          "simulate: write the summary and the trajectories to this JSON file");
// -o is --out's short spelling; Abseil flags have no aliases.
ABSL_FLAG(std::string, o, "", "render: the same as --out");
ABSL_FLAG(bool, ascii, false, "render: print the picture as text");
ABSL_FLAG(int, scale, 0, "render: pixels per cell, 1..64 (0: automatic)");
ABSL_FLAG(bool, y_up, false, "render: draw row 0 at the bottom (world y up)");
ABSL_FLAG(std::string, overlay, "",
          "render: draw what a geometric planner builds from the map under the "
          "plan: polygons, visibility, mesh, decomposition or voronoi");
ABSL_FLAG(std::optional<double>, occupied_thresh, std::nullopt,
          "maps import of a .png: occupied above this (default 0.65)");
ABSL_FLAG(std::optional<double>, free_thresh, std::nullopt,
          "maps import of a .png: free below this (default 0.196)");
ABSL_FLAG(bool, negate, false, "maps import of a .png: dark is free");

namespace {

namespace pathctl = pathd::pathctl;

// A usage error before any command is known: the problem and the synopsis.
int UsageError(absl::string_view problem) {
  std::cerr << "error: " << problem << "\n\n"
            << pathctl::SynopsisText() << "run 'pathctl --help' for details\n";
  return pathctl::kExitUsage;
}

}  // namespace

int main(int argc, char** argv) {
  // Debian's Abseil checks every absl::Mutex acquisition (gRPC's too) for
  // deadlock cycles; that costs bench a few per cent of each call's CPU.
  absl::SetMutexDeadlockDetectionMode(absl::OnDeadlockCycle::kIgnore);
  absl::SetProgramUsageMessage(pathctl::UsageText());

  absl::StatusOr<pathctl::CommandLine> line =
      pathctl::SplitCommandLine(argc, argv);
  if (!line.ok()) return UsageError(line.status().message());
  if (line->version) {
    std::cout << pathctl::VersionText();
    return pathctl::kExitOk;
  }
  if (line->help) {
    // "pathctl plan --help" is "pathctl help plan".
    std::vector<std::string> args = {"help"};
    args.insert(args.end(), line->positional.begin(), line->positional.end());
    return pathctl::Run(pathctl::Options(), args, std::cout, std::cerr);
  }
  // Flags first, then "--", so positional arguments that look like flags
  // (negative numbers) stay positional.
  std::vector<char*> normalized = {argv[0]};
  for (std::string& flag : line->flags) normalized.push_back(flag.data());
  std::string end_of_flags = "--";
  normalized.push_back(end_of_flags.data());
  for (std::string& arg : line->positional) normalized.push_back(arg.data());
  std::vector<char*> positional = absl::ParseCommandLine(
      static_cast<int>(normalized.size()), normalized.data());

  pathctl::Options options;
  options.given_flags = line->names;

  pathctl::GlobalOptions& global = options.global;
  global.server = pathctl::ResolveServerAddress(absl::GetFlag(FLAGS_server),
                                                std::getenv(pathctl::kServerEnvVar));
  global.timeout = absl::GetFlag(FLAGS_timeout);
  absl::StatusOr<pathctl::OutputFormat> output = pathctl::ResolveOutputFormat(
      absl::GetFlag(FLAGS_output), absl::GetFlag(FLAGS_json));
  if (!output.ok()) return UsageError(output.status().message());
  global.output = *output;
  global.json = *output == pathctl::OutputFormat::kJson;
  global.progress_bars = pathctl::ProgressBarsWanted(
      isatty(STDOUT_FILENO) != 0, isatty(STDERR_FILENO) != 0,
      absl::GetFlag(FLAGS_no_progress));
  global.stderr_is_terminal = isatty(STDERR_FILENO) != 0;
  global.credentials.tls_ca = absl::GetFlag(FLAGS_tls_ca);
  global.credentials.tls_cert = absl::GetFlag(FLAGS_tls_cert);
  global.credentials.tls_key = absl::GetFlag(FLAGS_tls_key);
  global.credentials.tls_server_name = absl::GetFlag(FLAGS_tls_server_name);
  global.credentials.token = absl::GetFlag(FLAGS_token);
  global.credentials.token_file = absl::GetFlag(FLAGS_token_file);
  if (global.credentials.token.empty() && global.credentials.token_file.empty()) {
    if (const char* token = std::getenv(pathctl::kTokenEnvVar)) {
      global.credentials.token = token;
    }
  }

  pathctl::CostOptions& cost = options.cost;
  cost.connectivity = absl::GetFlag(FLAGS_connectivity);
  cost.cost_weight = absl::GetFlag(FLAGS_cost_weight);
  cost.unknown_is_free = absl::GetFlag(FLAGS_unknown_is_free);
  cost.robot_radius_m = absl::GetFlag(FLAGS_robot_radius);
  cost.robot_radius_cells = absl::GetFlag(FLAGS_robot_radius_cells);
  cost.min_clearance_m = absl::GetFlag(FLAGS_min_clearance);
  cost.min_clearance_cells = absl::GetFlag(FLAGS_min_clearance_cells);
  cost.inflation_radius_m = absl::GetFlag(FLAGS_inflation_radius);
  cost.inflation_radius_cells = absl::GetFlag(FLAGS_inflation_radius_cells);
  cost.cost_scaling_factor = absl::GetFlag(FLAGS_cost_scaling_factor);

  pathctl::MapsOptions& maps = options.maps;
  maps.from = absl::GetFlag(FLAGS_from);
  maps.replace = absl::GetFlag(FLAGS_replace);
  maps.resolution = absl::GetFlag(FLAGS_resolution);
  maps.cells = absl::GetFlag(FLAGS_cells);
  maps.expected_version = absl::GetFlag(FLAGS_expected_version);
  maps.from_version = absl::GetFlag(FLAGS_from_version);
  maps.count = absl::GetFlag(FLAGS_count);
  maps.occupied_thresh = absl::GetFlag(FLAGS_occupied_thresh);
  maps.free_thresh = absl::GetFlag(FLAGS_free_thresh);
  maps.negate = absl::GetFlag(FLAGS_negate);

  pathctl::PlanFlags& plan = options.plan;
  plan.world = absl::GetFlag(FLAGS_world);
  plan.planner = absl::GetFlag(FLAGS_planner);
  plan.max_expansions = absl::GetFlag(FLAGS_max_expansions);
  plan.heuristic_weight = absl::GetFlag(FLAGS_heuristic_weight);
  plan.simplify = absl::GetFlag(FLAGS_simplify);
  plan.lookahead = absl::GetFlag(FLAGS_lookahead);
  plan.path_encoding = absl::GetFlag(FLAGS_path_encoding);
  plan.via = absl::GetFlag(FLAGS_via);
  plan.allow_partial = absl::GetFlag(FLAGS_allow_partial);
  plan.expansions = absl::GetFlag(FLAGS_expansions);
  plan.goal_tolerance_m = absl::GetFlag(FLAGS_goal_tolerance);
  plan.goal_tolerance_cells = absl::GetFlag(FLAGS_goal_tolerance_cells);

  pathctl::RobotOptions& robot = options.robot;
  robot.footprint_m = absl::GetFlag(FLAGS_footprint);
  robot.footprint_cells = absl::GetFlag(FLAGS_footprint_cells);
  robot.min_turning_radius_m = absl::GetFlag(FLAGS_min_turning_radius);
  robot.min_turning_radius_cells = absl::GetFlag(FLAGS_min_turning_radius_cells);
  robot.motion_model = absl::GetFlag(FLAGS_motion_model);
  robot.reverse_penalty = absl::GetFlag(FLAGS_reverse_penalty);
  robot.change_penalty = absl::GetFlag(FLAGS_change_penalty);
  robot.non_straight_penalty = absl::GetFlag(FLAGS_non_straight_penalty);
  robot.cost_penalty = absl::GetFlag(FLAGS_cost_penalty);
  robot.start_yaw = absl::GetFlag(FLAGS_start_yaw);
  robot.goal_yaw = absl::GetFlag(FLAGS_goal_yaw);
  robot.goal_yaw_tolerance = absl::GetFlag(FLAGS_goal_yaw_tolerance);
  robot.lattice = absl::GetFlag(FLAGS_lattice);
  robot.no_smooth = absl::GetFlag(FLAGS_no_smooth);
  robot.smooth = absl::GetFlag(FLAGS_smooth);
  plan.cost_to_go_file = absl::GetFlag(FLAGS_cost_to_go_file);
  plan.pf_attractive = absl::GetFlag(FLAGS_pf_attractive);
  plan.pf_attractive_gain = absl::GetFlag(FLAGS_pf_attractive_gain);
  plan.pf_switch_distance = absl::GetFlag(FLAGS_pf_switch_distance);
  plan.pf_repulsive_gain = absl::GetFlag(FLAGS_pf_repulsive_gain);
  plan.pf_influence = absl::GetFlag(FLAGS_pf_influence);
  plan.pf_step = absl::GetFlag(FLAGS_pf_step);
  plan.pf_max_steps = absl::GetFlag(FLAGS_pf_max_steps);
  plan.ant_colony = absl::GetFlag(FLAGS_ant_colony);
  plan.reaction_diffusion = absl::GetFlag(FLAGS_reaction_diffusion);
  plan.progress = absl::GetFlag(FLAGS_progress);
  plan.snap_start = absl::GetFlag(FLAGS_snap_start);
  plan.snap_start_max_m = absl::GetFlag(FLAGS_snap_start_max);
  plan.snap_start_max_cells = absl::GetFlag(FLAGS_snap_start_max_cells);

  options.check.world = absl::GetFlag(FLAGS_world);
  options.check.path_file = absl::GetFlag(FLAGS_path_file);
  options.navigate.script = absl::GetFlag(FLAGS_script);
  options.navigate.fleet = absl::GetFlag(FLAGS_fleet);
  options.navigate.solver = absl::GetFlag(FLAGS_solver);
  options.cost_to_go.world = absl::GetFlag(FLAGS_world);
  options.cost_to_go.window = absl::GetFlag(FLAGS_window);
  options.cost_to_go.cost_to_go_file = absl::GetFlag(FLAGS_cost_to_go_file);
  options.metrics.metrics_address = absl::GetFlag(FLAGS_metrics_address);
  pathctl::FleetOptions& fleet = options.fleet;
  fleet.world = absl::GetFlag(FLAGS_world);
  fleet.sources = absl::GetFlag(FLAGS_sources);
  fleet.destinations = absl::GetFlag(FLAGS_destinations);
  fleet.waypoints = absl::GetFlag(FLAGS_waypoints);
  fleet.method = absl::GetFlag(FLAGS_method);
  fleet.end = absl::GetFlag(FLAGS_end);
  fleet.planner = absl::GetFlag(FLAGS_planner);
  fleet.yaw = absl::GetFlag(FLAGS_yaw);
  fleet.max_distance_m = absl::GetFlag(FLAGS_max_distance);
  fleet.max_distance_cells = absl::GetFlag(FLAGS_max_distance_cells);
  fleet.budget_m = absl::GetFlag(FLAGS_budget);
  fleet.budget_cells = absl::GetFlag(FLAGS_budget_cells);
  fleet.robots = absl::GetFlag(FLAGS_robots);
  fleet.solver = absl::GetFlag(FLAGS_solver);
  fleet.time_limit_s = absl::GetFlag(FLAGS_time_limit);
  fleet.suboptimality = absl::GetFlag(FLAGS_suboptimality);
  fleet.restarts = absl::GetFlag(FLAGS_restarts);
  fleet.max_steps = absl::GetFlag(FLAGS_max_steps);
  fleet.refine = absl::GetFlag(FLAGS_refine);
  fleet.seed = absl::GetFlag(FLAGS_seed);

  pathctl::BenchOptions& bench = options.bench;
  bench.concurrency = absl::GetFlag(FLAGS_concurrency);
  bench.channels = absl::GetFlag(FLAGS_channels);
  bench.duration = absl::GetFlag(FLAGS_duration);
  bench.warmup = absl::GetFlag(FLAGS_warmup);
  bench.requests = absl::GetFlag(FLAGS_requests);
  bench.movingai = absl::GetFlag(FLAGS_movingai);
  bench.seed = absl::GetFlag(FLAGS_seed);

  options.simulate.trajectory = absl::GetFlag(FLAGS_trajectory);
  options.simulate.log_json = absl::GetFlag(FLAGS_log_json);

  pathctl::RenderFlags& render = options.render;
  render.plan = absl::GetFlag(FLAGS_plan);
  const std::string out = absl::GetFlag(FLAGS_out);
  const std::string o = absl::GetFlag(FLAGS_o);
  if (!out.empty() && !o.empty() && out != o) {
    return UsageError("give -o or --out, not both");
  }
  render.out = out.empty() ? o : out;
  render.ascii = absl::GetFlag(FLAGS_ascii);
  render.scale = absl::GetFlag(FLAGS_scale);
  render.y_up = absl::GetFlag(FLAGS_y_up);
  render.overlay = absl::GetFlag(FLAGS_overlay);

  return pathctl::Run(
      options,
      std::vector<std::string>(positional.begin() + 1, positional.end()),
      std::cout, std::cerr);
}
