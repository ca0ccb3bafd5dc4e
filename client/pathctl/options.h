// What pathctl's flags hold once parsed, grouped by the commands that read
// them: one small struct per command (or per group of commands sharing
// flags), filled by pathctl/main.cc. A command reads only its own structs
// and GlobalOptions; its entry in the command table (command.cc) lists the
// flags it reads, and any other flag on its line is a usage error.
#ifndef PATHD_CLIENT_PATHCTL_OPTIONS_H_
#define PATHD_CLIENT_PATHCTL_OPTIONS_H_

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "absl/time/time.h"
#include "client/client.h"
#include "client/pathctl/output.h"

namespace pathd::pathctl {

// Where `pathctl metrics` looks when --metrics_address is not given: the
// address docs/service.md runs `pathd --metrics_address` with.
inline constexpr char kDefaultMetricsAddress[] = "127.0.0.1:9464";

// Flags every command takes: the server, deadlines, TLS and token, output.
struct GlobalOptions {
  std::string server = client::kDefaultServerAddress;
  // --tls_ca, --tls_cert, --tls_key, --tls_server_name, --token,
  // --token_file (or $PATHD_TOKEN); read when a command first connects.
  client::CredentialSources credentials;
  absl::Duration timeout = client::kDefaultTimeout;
  // --output (--json is --output=json).
  OutputFormat output = OutputFormat::kTable;
  // output == kJson, which the commands' JSON branches test.
  bool json = false;
  // Draw progress bars on stderr (ProgressBarsWanted: a person is watching).
  bool progress_bars = false;
  // stderr is a terminal: plan --progress rewrites one line in place.
  bool stderr_is_terminal = false;
};

// The cost options of every planning command (plan, batch, navigate,
// cost-to-go, check, bench, render).
struct CostOptions {
  int connectivity = 0;  // 0: the server's default (8)
  std::optional<double> cost_weight;
  bool unknown_is_free = false;
  std::optional<double> robot_radius_m;
  std::optional<double> robot_radius_cells;
  std::optional<double> min_clearance_m;
  std::optional<double> min_clearance_cells;
  std::optional<double> inflation_radius_m;
  std::optional<double> inflation_radius_cells;
  std::optional<double> cost_scaling_factor;
};

// The robot's shape and motion (plan, batch, render): the kinematic
// planners read all of it, the others the footprint (planned for by its
// inscribed radius).
struct RobotOptions {
  // Nav2's footprint syntax, "[[x, y], [x, y], ...]": metres, or cells.
  std::string footprint_m;
  std::string footprint_cells;
  std::optional<double> min_turning_radius_m;
  std::optional<double> min_turning_radius_cells;
  // dubins, reeds_shepp, differential, omnidirectional; empty: the planner's.
  std::string motion_model;
  std::optional<double> reverse_penalty;
  std::optional<double> change_penalty;
  std::optional<double> non_straight_penalty;
  std::optional<double> cost_penalty;
  // Headings of the start and the goal, radians (the goal's: unset lets a
  // kinematic path end at any heading).
  std::optional<double> start_yaw;
  std::optional<double> goal_yaw;
  std::optional<double> goal_yaw_tolerance;
  std::string lattice;
  bool no_smooth = false;
  bool smooth = false;
};

// maps create / import / get / set / rect / watch.
struct MapsOptions {
  std::string from;          // create: the .map or .yaml file
  bool replace = false;      // create, import
  double resolution = 0.0;   // create, import; 0: the server's default
  bool cells = false;        // get: print the cells
  std::optional<uint64_t> expected_version;  // set, rect
  // watch: the version already held (0: none) and how many events to print
  // (0: until the map is deleted).
  uint64_t from_version = 0;
  int64_t count = 0;
  // import of a .png: map_server's thresholds (unset: 0.65 / 0.196) and
  // colour inversion.
  std::optional<double> occupied_thresh;
  std::optional<double> free_thresh;
  bool negate = false;
};

// The search options of plan; batch, bench and render read a subset (see
// their flag lists in the command table).
struct PlanFlags {
  bool world = false;  // coordinates are world metres
  std::string planner;  // empty: the server's default
  int64_t max_expansions = 0;
  std::optional<double> heuristic_weight;
  bool simplify = false;
  int lookahead = 0;
  // --path_encoding: readable, packed or both (empty: packed).
  std::string path_encoding;
  // Via points "X,Y;X,Y..." visited in order before the goal; empty: none.
  std::string via;
  bool allow_partial = false;
  // Ask for the expanded cells.
  bool expansions = false;
  // Goal tolerance in metres or cells (at most one).
  std::optional<double> goal_tolerance_m;
  std::optional<double> goal_tolerance_cells;
  // Non-empty: request the cost-to-go field and write it here as CSV.
  std::string cost_to_go_file;
  // Potential field; empty / 0 keep the server's defaults.
  std::string pf_attractive;
  double pf_attractive_gain = 0.0;
  double pf_switch_distance = 0.0;
  double pf_repulsive_gain = 0.0;
  double pf_influence = 0.0;
  double pf_step = 0.0;
  int64_t pf_max_steps = 0;
  // ant_colony / reaction_diffusion parameters as KEY=VALUE[,KEY=VALUE...]
  // (the AntColonyOptions / ReactionDiffusionOptions field names); empty:
  // the server's defaults.
  std::string ant_colony;
  std::string reaction_diffusion;
  // Use PlanStream and show its progress on stderr.
  bool progress = false;
  // Start in an obstacle or the inflated zone: plan from the nearest free
  // cell within the limit (metres or cells; unset: the server's default).
  bool snap_start = false;
  std::optional<double> snap_start_max_m;
  std::optional<double> snap_start_max_cells;
};

struct CheckOptions {
  bool world = false;
  // Read the poses from this file ("X Y" per line) instead of the line.
  std::string path_file;
};

struct NavigateOptions {
  // The script to replay; empty: open, print the path, close.
  std::string script;
  // --fleet: the fleet group to join; empty: not a fleet session. --solver:
  // the group's solver (empty: the group's, lacam for a new group).
  std::string fleet;
  std::string solver;
};

struct CostToGoOptions {
  bool world = false;
  std::string window;  // "X,Y,W,H"; empty: the whole map
  std::string cost_to_go_file;
};

// table, nearest, trip, isochrone.
struct FleetOptions {
  bool world = false;  // coordinates are world metres
  // "X,Y;X,Y..." lists.
  std::string sources;
  std::string destinations;
  std::string waypoints;
  // table: auto, backward, forward.
  std::string method;
  // trip: round_trip, fixed_last, any; the legs' planner.
  std::string end;
  std::string planner;
  // nearest: the heading for a polygon footprint, the farthest answer.
  std::optional<double> yaw;
  std::optional<double> max_distance_m;
  std::optional<double> max_distance_cells;
  // isochrone: the budget.
  std::optional<double> budget_m;
  std::optional<double> budget_cells;
  // fleet plan: the robots file, the solver and its options (unset: the
  // server's defaults).
  std::string robots;
  std::string solver;
  std::optional<double> time_limit_s;
  std::optional<double> suboptimality;
  std::optional<int32_t> restarts;
  std::optional<int32_t> max_steps;
  bool refine = false;
  uint64_t seed = 1;
};

// simulate: where to write the run's trajectories (the picture takes
// render's --out, --scale and --y_up).
struct SimulateOptions {
  std::string trajectory;  // CSV
  std::string log_json;
};

struct MetricsOptions {
  std::string metrics_address = kDefaultMetricsAddress;
};

// bench: closed-loop load of Plan calls. Workers (one request in flight
// each), connections they share, the measured time and / or request count
// (0: no count bound), the unmeasured warm-up before it, the Moving AI map
// to load (queries from its .scen file), and the seed of the random queries
// and of the shuffle.
struct BenchOptions {
  int concurrency = 4;
  int channels = 1;
  absl::Duration duration = absl::Seconds(10);
  absl::Duration warmup = absl::Seconds(1);
  int64_t requests = 0;
  std::string movingai;
  uint64_t seed = 1;
};

// render: --plan (SX SY GX GY follow NAME), the PNG to write (-o / --out;
// empty: none), text instead of or as well as the PNG, pixels per cell (0:
// automatic) and row 0 at the bottom.
struct RenderFlags {
  bool plan = false;
  std::string out;
  bool ascii = false;
  int scale = 0;
  bool y_up = false;
  // A structure kind to draw under the plan (core/geometry/structure.h).
  std::string overlay;
};

// Everything main.cc parsed. `given_flags` names the flags on the command
// line (without "--", "no" stripped from a negated boolean), which Run
// checks against the command's flag list.
struct Options {
  GlobalOptions global;
  CostOptions cost;
  RobotOptions robot;
  MapsOptions maps;
  PlanFlags plan;
  CheckOptions check;
  NavigateOptions navigate;
  CostToGoOptions cost_to_go;
  FleetOptions fleet;
  SimulateOptions simulate;
  MetricsOptions metrics;
  BenchOptions bench;
  RenderFlags render;
  std::vector<std::string> given_flags;
};

}  // namespace pathd::pathctl

#endif  // PATHD_CLIENT_PATHCTL_OPTIONS_H_
