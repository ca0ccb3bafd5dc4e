// The text pathctl prints about itself, generated from the command table
// where it names commands: the synopsis, each command's short usage and
// help, a group's usage, the full --help reference, and the version.
#include <string>
#include <vector>

#include "absl/flags/commandlineflag.h"
#include "absl/flags/reflection.h"
#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "client/pathctl/command.h"
#include "client/pathctl/navigate_script.h"

#ifndef PATHD_VERSION
#error "PATHD_VERSION (the CMake project version) must be defined by the build"
#endif

namespace pathd::pathctl {
namespace {

// Where a synopsis's continuation lines start.
constexpr absl::string_view kContinuation = "                       ";

// The lines of `command`'s synopsis: the first form after `first_lead`,
// further forms after `lead`, continuations indented under them.
std::string SynopsisLines(const Command& command, absl::string_view first_lead,
                          absl::string_view lead) {
  std::string text;
  bool first = true;
  for (absl::string_view line : absl::StrSplit(command.synopsis, '\n')) {
    if (!line.empty() && line.front() == ' ') {
      absl::StrAppend(&text, kContinuation, absl::StripLeadingAsciiWhitespace(line),
                      "\n");
      continue;
    }
    absl::StrAppend(&text, first ? first_lead : lead, "pathctl [flags] ", command.name,
                    line.empty() ? "" : " ", line, "\n");
    first = false;
  }
  return text;
}

// A flag's help without the "plan, navigate: " prefix naming the commands
// that read it: under one command's help that list is noise (and the
// command table, not the prefix, decides who reads the flag).
std::string WithoutCommandPrefix(absl::string_view help) {
  const size_t colon = help.find(": ");
  if (colon == absl::string_view::npos) return std::string(help);
  for (char c : help.substr(0, colon)) {
    if (!absl::ascii_islower(c) && c != ' ' && c != ',' && c != '/' && c != '-') {
      return std::string(help);
    }
  }
  return std::string(help.substr(colon + 2));
}

}  // namespace

std::string ShortUsage(const Command& command) {
  return absl::StrCat(SynopsisLines(command, "usage: ", "       "),
                      "run 'pathctl help ", command.name, "' for details\n");
}

std::string GroupUsage(absl::string_view group) {
  std::string text;
  bool first = true;
  for (const Command* c : CommandsOfGroup(group)) {
    absl::StrAppend(&text, SynopsisLines(*c, first ? "usage: " : "       ", "       "));
    first = false;
  }
  absl::StrAppend(&text, "run 'pathctl help ", group, " SUBCOMMAND' for details\n");
  return text;
}

std::string CommandHelp(const Command& command) {
  std::string text = absl::StrCat(SynopsisLines(command, "usage: ", "       "), "\n",
                                  command.help, "\n");
  if (!command.flags.empty()) absl::StrAppend(&text, "\nflags:\n");
  for (absl::string_view name : command.flags) {
    const std::string flag(name);
    const absl::CommandLineFlag* registered = absl::FindCommandLineFlag(flag);
    absl::StrAppendFormat(&text, "  %-20s %s\n",
                          absl::StrCat(flag.size() == 1 ? "-" : "--", flag),
                          registered != nullptr ? WithoutCommandPrefix(registered->Help()) : "");
  }
  absl::StrAppend(&text,
                  "\nglobal flags: --server, --timeout, --output (--json), "
                  "--no_progress, --tls_ca,\n--tls_cert, --tls_key, --tls_server_name, "
                  "--token, --token_file ('pathctl --help').\n");
  return text;
}

std::string SynopsisText() {
  std::string text = "usage:\n";
  for (const Command* c : Commands()) absl::StrAppend(&text, SynopsisLines(*c, "  ", "  "));
  absl::StrAppend(&text, "  pathctl --version\n  pathctl --help\n");
  return text;
}

std::string VersionText() { return absl::StrCat("pathctl ", PATHD_VERSION, "\n"); }

std::string UsageText() {
  return absl::StrCat(
      "pathctl: command-line client of the pathd path-planning daemon.\n\n",
      SynopsisText(), R"(
'pathctl help COMMAND' (or 'pathctl COMMAND --help') prints one command's
usage, what it does and the flags it reads; 'pathctl --version' the version.

flags (anywhere on the line, as --flag=value or --flag value). The global
ones (--server, --timeout, --output, --json, --no_progress, --tls_*, --token*)
apply to every command; any other flag on a command that does not read it is
a usage error naming the flag (e.g. plan ... -o x.png):
  --server ADDR        pathd address; default $PATHD_SERVER, else 127.0.0.1:50051
  --timeout D          deadline of the call, e.g. 500ms, 30s (default 10s)
  --json               print the response message as proto3 JSON (= --output json)
  --output F           table (default: the text below), json (proto3 JSON; a
                       stream prints one object per line) or csv (a header
                       row, then rows: see "output formats")
  --no_progress        no progress bars (batch, bench, maps create --from);
                       they show only when stdout and stderr are terminals
  --tls_ca FILE        use TLS, trusting the server certificate if this PEM
                       CA (or the self-signed certificate itself) signed it
  --tls_cert FILE, --tls_key FILE
                       client certificate and key (PEM) for a pathd with
                       --tls_client_ca (mutual TLS); need --tls_ca
  --tls_server_name N  the name the server's certificate carries, when it
                       differs from the --server host (e.g. dialing an IP)
  --token_file FILE    send the token in FILE as 'authorization: Bearer ...'
                       on every call (for a pathd with --auth_tokens)
  --token T            the token itself (visible in the process list: prefer
                       --token_file); default $PATHD_TOKEN. Without --tls_ca
                       the token crosses the network in clear text (pathctl
                       warns unless the server is on this machine)
  --from FILE          maps create: .map is sent as Moving AI text; .yaml/.yml
                       as a ROS map_server map (the YAML plus the image it
                       names, relative to the YAML's folder)
  --replace            maps create, import: replace an existing map of that name
  --resolution R       maps create, import: metres per cell for .map (and
                       import's .png) files (default 1)
  --cells              maps get: also print the cells (maps up to 1024 columns)
  --expected_version V maps set/rect: apply only if the map is at version V
  --from_version V     maps watch: the version you hold; other than the current
                       one (0: none) starts with the whole map (resync)
  --count N            maps watch: stop after N events (default: until deleted)
  --planner P          plan: )",
      PlannerNames(), R"( (default: the server's, A*)
  --max_expansions N   plan: stop after N expansions (0: the server's limit)
  --world              plan, cost-to-go, check: coordinates are world metres, not cells
  --simplify           plan: keep only the turning points (ray-shooting line of
                       sight); the path becomes any-angle, never longer
  --path_encoding E    plan, batch, bench: how the server sends paths: packed
                       (default; pathctl decodes it, the output is the same),
                       readable (repeated cells and world points) or both
  --heuristic_weight W plan: weighted_astar's w >= 1 (default 1.5)
  --lookahead N        plan: rtaa_star / lrta_star expansions per episode (64)
  --cost_to_go_file F  plan (distance_transform*), cost-to-go: write the
                       cost-to-go field as CSV (one row per line, inf =
                       unreachable); cost-to-go prints a table otherwise
  --window X,Y,W,H     cost-to-go: only columns X..X+W-1, rows Y..Y+H-1
  --goal_tolerance M   plan: when the goal cell is blocked, plan to the nearest
                       free cell within M metres and say so (up to 1024 cells);
                       kinematic planners: end within M metres of the goal
  --goal_tolerance_cells C  plan: the same in cells
  --via X,Y[;X,Y...]   plan: visit these points in order before the goal (up to
                       256; metres with --world); one leg per point
  --allow_partial      plan: with --via, when a leg finds no path print the path
                       to the last reached point (exit code 3 still)
  --expansions         plan: ask for the cells the search expanded; prints how
                       many came back (--json prints them, as "expanded")
  --path_file F        check: read the path from F, one "X Y" per line ('#'
                       starts a comment line)
  --script FILE        navigate: replay this robot run (format below); without
                       it navigate prints the first path and closes
  --fleet GROUP        navigate: open a fleet session in GROUP: the group's
                       robots on the map are planned together and each is
                       released along its timed path as the others pass
                       (--solver picks the group's solver when it is new)
  --metrics_address A  metrics: pathd's --metrics_address (default
                       127.0.0.1:9464)
  --progress           plan: use PlanStream and show the search's progress
                       on stderr (one line updated in place on a terminal,
                       one line per event otherwise)
  --pf_attractive S    plan: potential_field: quadratic (default) or conic
  --pf_attractive_gain K, --pf_switch_distance D, --pf_repulsive_gain ETA,
  --pf_influence Q, --pf_step S, --pf_max_steps N
                       plan: potential_field parameters (cells; 0 = default)
  --ant_colony KEY=VALUE[,KEY=VALUE...]
                       plan: ant_colony parameters: ants, iterations,
                       stall_iterations, alpha, beta, rho, xi, q0, tau0,
                       max_steps, seed (docs/planners.md; unset = default)
  --reaction_diffusion KEY=VALUE[,KEY=VALUE...]
                       plan: reaction_diffusion parameters: diffusion,
                       reaction_rate, threshold, time_step, max_steps

  --concurrency N      bench: requests in flight; each worker sends its next
                       request when the previous answer arrives (default 4)
  --duration T         bench: measured time, e.g. 30s (default 10s; 0: until
                       --requests are done)
  --warmup T           bench: unmeasured load first (default 1s)
  --requests N         bench: stop after N measured requests (0: no limit)
  --channels K         bench: gRPC connections the workers share (default 1)
  --movingai FILE      bench: load FILE (a Moving AI .map) as NAME (default:
                       the file's stem), replacing a map of that name, and
                       take the queries from FILE.scen
  --seed S             bench: seed of the random queries and of the shuffle

  --plan               render: plan from SX SY to GX GY (given after NAME) and
                       draw the path; takes plan's options (--planner, --world,
                       --via, --simplify, --max_expansions, cost options)
  -o FILE, --out FILE  render: write the picture to FILE (PNG)
  --ascii              render: print the picture as text (maps up to 200x200)
  --scale N            render: pixels per cell, 1..64 (default: 16 for small
                       maps, less so the longer side is about 1024 pixels)
  --y_up               render: draw row 0 at the bottom (world y up), as a ROS
                       map's image shows it; default row 0 on top, as in a
                       .map file and maps get --cells
  --overlay KIND       render: draw a geometric planner's structure under the
                       plan: polygons, visibility, mesh, decomposition, voronoi
  --occupied_thresh T, --free_thresh T, --negate
                       maps import of a .png: map_server's thresholds (default
                       0.65 and 0.196) and colour inversion; see below

robot options (plan, batch, render):
  --footprint "[[x,y],...]"  the robot's outline in metres, x forward, y left
                       (Nav2's footprint syntax); kinematic planners check it
                       at every pose, the others plan for its inscribed radius
  --footprint_cells "[[x,y],...]"  the same in cells
  --min_turning_radius M  kinematic planners: smallest turning radius (0.4 m)
  --min_turning_radius_cells C  the same in cells
  --motion_model MODEL dubins (forward only, the default), reeds_shepp (with
                       reversing), differential, omnidirectional
  --start_yaw R, --goal_yaw R  headings in radians (unset goal heading: any)
  --goal_yaw_tolerance R  end within R radians of --goal_yaw
  --reverse_penalty P, --change_penalty P, --non_straight_penalty P,
  --cost_penalty P     Nav2 Smac's penalties (defaults 2, 0, 1.2, 2)
  --lattice NAME|FILE  state_lattice's control set
  --no_smooth          return kinematic paths unsmoothed
  --smooth             grid/geometric planners: also return the path as poses
                       smoothed for the footprint (or radius)

cost options (plan, navigate, cost-to-go, check):
  --connectivity N     4 or 8 (default 8)
  --cost_weight W      w in step = length * (1 + w * cost / 252) (default 1)
  --unknown_is_free    treat unknown cells (255) as free
  --robot_radius M     inflate lethal cells by the robot radius in metres
  --robot_radius_cells C  the same in cells
  --min_clearance M    prefer keeping M metres from obstacles: nearer cells
                       cost up to 252 (a preference, not a rule; not check)
  --min_clearance_cells C  the same in cells
  --inflation_radius M Nav2 inflation costs: cells up to M metres from a lethal
                       cell, beyond the robot radius, cost
                       252 * exp(-K * (distance - robot radius)) (not check)
  --inflation_radius_cells C  the same in cells
  --cost_scaling_factor K  the decay K per metre (Nav2's, default 10)

maps watch prints one line per map version: "version V updated: N cells in
R rects: (x0,y0)-(x1,y1) ...", "version V resync: whole map WxH", "version V
replaced: whole map WxH" or "version V deleted" (then it exits 0). It has no
deadline (--timeout does not apply); with --json each line is a MapEvent.

metrics prints pathd's Prometheus text (GET http://HOST:PORT/metrics, the
daemon's --metrics_address); with PREFIX arguments only the metrics whose name
starts with one of them, e.g. 'pathctl metrics pathd_requests pathd_maps'.
batch FILE (or - for stdin) sends every request of FILE through one PlanBatch
stream: one request per line, "ID MAP SX SY GX GY [PLANNER]" (cells, or
metres with --world; '#' starts a comment line). --planner is the default
for lines without one; --max_expansions, --heuristic_weight, --simplify,
--lookahead and the cost options apply to every line. It prints one line per
answer as it arrives (in finishing order), "ID found cost C length L
expansions N time T us", "ID no-path OUTCOME: reason" or "ID error CODE
OUTCOME: message", then "summary: A of N answered: F found, P no path, E
errors in S s" with the rate in plans/s. With --json each answer is a
PlanBatchResponse line and the summary goes to stderr. --timeout bounds the
whole batch. Exit code 0 when no item errored (no path is not an error), 1
when any item errored or the stream failed.
Every call about a map sends its name in the x-pathd-map header, which a load
balancer in front of several pathd replicas routes by (docs/deployment.md).
Through such a balancer a batch goes to the replica of its first line's map:
give it one map per file (lines naming a map held elsewhere answer NOT_FOUND),
and maps list, cache-stats and health reach whichever replica the balancer
picks; give --server a replica's own address to ask that one.
bench runs a closed-loop load of Plan calls. Its queries are the
scenarios of --movingai's .scen file, or 1000 random pairs of free cells of
NAME, shuffled with --seed and sent in a cycle. It prints attempts per second
and, apart, goodput (OK answers per second), latency percentiles of the OK
answers (exact, from every recorded sample), errors by status code and the
back-off waits; --json prints one object. A worker whose call was refused
(RESOURCE_EXHAUSTED) waits the server's retry-after-ms hint (plus up to 20%
jitter) before its next request; one that cannot reach the server
(UNAVAILABLE, or a refusal without a hint) backs off exponentially from 10 ms
to 1 s with jitter, so an overloaded or stopped server is not hammered. When stdout and stderr are
terminals a progress bar (elapsed of the duration, requests, current rate,
errors) is redrawn on stderr about once a second. The exit code is 0 when the run completed, whatever the
answers; scripts read the error counts.

With --json, navigate prints each NavigateResponse as one line of JSON. Its
--timeout bounds each wait for an answer and for the server's close, not the
whole session.

arguments:
  X, Y                 cells: x is the column, y the row, from 0
  COST                 0..255 (Nav2 costmap values) or free (0), inscribed (253),
                       lethal (254), unknown (255)
  X0 Y0 X1 Y1          first and last corner of a rectangle, both included,
                       X0 <= X1 and Y0 <= Y1 (inverted corners are refused)
  Numbers such as -3 are arguments, not flags; "--" ends the flags.

maps get --cells prints one character per cell, row 0 first (a .map file's
first line; a ROS map's bottom image row):
  .    free (0)
  1-9  weighted 1..252; digit d covers costs 28(d-1)+1 .. 28d
  #    inscribed or lethal (253, 254)
  ?    unknown (255)

output formats (--output csv): one header row, then
  maps create/get/list  one row per map: name,width,height,resolution,
                        origin_x,origin_y,origin_yaw,version,free_cells,
                        blocked_cells (maps get --cells has no CSV)
  maps delete           name,last_version
  maps set/rect         name,version,cells_changed
  maps watch            one row per event: version,kind,width,height,
                        changed_cells,changed_rects,rects
  plan                  one row per path cell: x,y,world_x,world_y
  batch                 one row per answer: id,status,outcome,cost,length,
                        expansions,time_us,code,message (summary on stderr)
  check                 valid,map_version,poses,cost,length,invalid_poses,
                        invalid_steps,reason
  cost-to-go            one row per cell: x,y,cost (inf: unreachable)
  cache-stats           one row per cache, then navigate_sessions
  health                service,status
  bench                 one row of the --json figures
navigate has no CSV; metrics (Prometheus text) and completion (a script)
print only as table. Asking for a format a command has not is a usage error
(exit 2) naming the command and the format.

progress bars: batch (answers of total, rate), bench (elapsed of --warmup,
then of --duration) and maps create --from (what is being sent, for how
long) draw a bar on stderr, redrawn in place at most 10 times a second and
only after half a second of work, when stdout and stderr are both terminals
and --no_progress is not given.

completion: 'source <(pathctl completion bash)' completes commands, flags,
planner names, --output formats, files and, when the server answers within a
second, map names (from 'pathctl maps list' with the line's --server).
render --ascii draws the same, then 'o' expanded cells, '*' the path, 'S'
the start and 'G' the goal. Its PNG draws free cells white, weighted cells
grey (lighter for cheaper), inscribed dark grey, lethal black, unknown
blue-grey, expanded cells tinted amber, the path as a red line, the start as
a green and the goal as a blue disc.

maps import reads .map (Moving AI) and .yaml/.yml (ROS map_server) like maps
create --from, and PNG occupancy images: a bare .png, or one a YAML names.
A PNG pixel's grey level is the mean of its R, G and B; map_server's rules
then apply: p = (255 - grey) / 255 (grey / 255 with --negate), p >
occupied_thresh lethal, p < free_thresh free, otherwise unknown. A bare
.png gets --resolution (default 1 m) and origin (0, 0); a YAML's values
come from the YAML. maps export writes FILE by its extension: .map as Moving
AI ('.' free, 'S' weighted, '@' inscribed or lethal, 'O' unknown), or
.yaml/.yml plus a .pgm of the same name (map_server trinary: 254 free or
weighted, 0 inscribed or lethal, 205 unknown). Weighted costs, inscribed and
(in a .map) unknown cells do not survive the round trip; export warns with
their counts on stderr.

exit codes:
  0  success
  1  the call failed (server error, or a local file could not be read);
     stderr says "error: <GRPC_CODE>: <message>"; health: not SERVING;
     navigate: a script's expect-push or follow failed
     (codes 5-8 below take precedence for their status codes)
  2  usage error, also a bad navigate script line (FILE:LINE: problem) and a
     format a command cannot print
  3  plan ran but found no path (the outcome says why)
     (batch: 1 when any item errored, otherwise 0)
  4  check ran and the path is not valid on the map's current version
  5  UNAVAILABLE: the server cannot be reached or is shutting down
  6  DEADLINE_EXCEEDED: the call ran past --timeout
  7  NOT_FOUND: the map (or a local file or folder named on the line) does
     not exist
  8  UNAUTHENTICATED or PERMISSION_DENIED (also a local file not writable)
     (render --plan: 3 when the plan found no path; the map is still drawn)
  9  simulate ran, and a robot collided or did not arrive

)",
      kNavigateScriptHelp);
}

}  // namespace pathd::pathctl
