// The pathctl commands: command-line splitting, the planner-name table, cell
// rendering, and Run(), which executes one command against a pathd server and
// returns the process exit code. pathctl/main.cc only defines the flags and
// wires them in, so everything here can be driven from tests.
#ifndef PATHD_CLIENT_PATHCTL_PATHCTL_H_
#define PATHD_CLIENT_PATHCTL_PATHCTL_H_

#include <cstdint>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "absl/time/time.h"
#include "client/client.h"
#include "client/pathctl/completion.h"
#include "client/pathctl/output.h"
#include "pathd/v1/planner_service.pb.h"

namespace pathd::pathctl {

// Process exit codes; documented in UsageText().
enum ExitCode : int {
  kExitOk = 0,
  kExitError = 1,   // the RPC or server failed, or a local file was unreadable
  kExitUsage = 2,   // bad command line
  kExitNoPath = 3,  // plan ran but found no path
  kExitInvalidPath = 4,  // check ran and the path is not valid on the map
  // Status codes scripts react to differently from a plain failure; the rest
  // exit kExitError. ExitCodeForStatus is the one place that maps them.
  kExitUnavailable = 5,  // UNAVAILABLE: server unreachable or shutting down
  kExitDeadline = 6,     // DEADLINE_EXCEEDED: --timeout ran out
  kExitNotFound = 7,     // NOT_FOUND: no such map (or local file)
  kExitDenied = 8,       // UNAUTHENTICATED or PERMISSION_DENIED
};

// The exit code of a command that failed with `code`: kExitUnavailable,
// kExitDeadline, kExitNotFound or kExitDenied for those codes, kExitOk for
// OK, kExitError for every other code.
int ExitCodeForStatus(absl::StatusCode code);

// Environment variable naming the server when --server is not given.
inline constexpr char kServerEnvVar[] = "PATHD_SERVER";
// Environment variable holding the token when neither --token nor
// --token_file is given.
inline constexpr char kTokenEnvVar[] = "PATHD_TOKEN";

// Where `pathctl metrics` looks when --metrics_address is not given: the
// address the README runs `pathd --metrics_address` with.
inline constexpr char kDefaultMetricsAddress[] = "127.0.0.1:9464";

// Looks up a planner by CLI name; INVALID_ARGUMENT listing the valid names.
absl::StatusOr<v1::Planner> PlannerFromName(absl::string_view name);

// Every option a command may read, already parsed from flags.
struct Options {
  std::string server = client::kDefaultServerAddress;
  // TLS and token: --tls_ca, --tls_cert, --tls_key, --tls_server_name,
  // --token, --token_file (or $PATHD_TOKEN); read when a command first
  // connects.
  client::CredentialSources credentials;
  absl::Duration timeout = client::kDefaultTimeout;
  // How results print (--output; --json is --output=json).
  OutputFormat output = OutputFormat::kTable;
  // output == kJson, which the commands' JSON branches test.
  bool json = false;
  // Draw progress bars on stderr (ProgressBarsWanted: a person is watching).
  bool progress_bars = false;
  // maps create
  std::string from;
  bool replace = false;
  double resolution = 0.0;  // 0: the server's default (1 m per cell)
  // maps get
  bool cells = false;
  // maps set / rect
  std::optional<uint64_t> expected_version;
  // maps watch: the version already held (0: none, start with the whole
  // map) and how many events to print before stopping (0: until deleted).
  uint64_t from_version = 0;
  int64_t count = 0;
  // plan
  std::string planner;   // empty: the server's default
  int connectivity = 0;  // 0: the server's default (8)
  std::optional<double> cost_weight;
  bool world = false;
  bool unknown_is_free = false;
  int64_t max_expansions = 0;
  std::optional<double> heuristic_weight;
  std::optional<double> robot_radius_m;
  std::optional<double> robot_radius_cells;
  // plan: goal tolerance in cells or metres (at most one).
  std::optional<double> goal_tolerance_cells;
  std::optional<double> goal_tolerance_m;
  // plan: via points "X,Y;X,Y..." (cells, or metres with --world) visited in
  // order before the goal; empty: none.
  std::string via;
  // plan: with via, return the path to the last reached goal when a leg fails.
  bool allow_partial = false;
  // plan: ask for the expanded cells (print their count; --json: the cells).
  bool expansions = false;
  // check: read the poses from this file ("X Y" per line) instead of the
  // command line.
  std::string path_file;
  bool simplify = false;
  int lookahead = 0;
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
  // navigate: the script to replay; empty: open, print the path, close.
  std::string script;
  // cost-to-go: "X,Y,W,H"; empty: the whole map.
  std::string window;
  // metrics: pathd's --metrics_address (HOST:PORT).
  std::string metrics_address = std::string(kDefaultMetricsAddress);
  // plan: use PlanStream and show its progress on `err`.
  bool progress = false;
  // `err` is a terminal: progress rewrites one line instead of printing one
  // line per event.
  bool stderr_is_terminal = false;
  // bench: closed-loop load of Plan calls. Workers (one request in flight
  // each), connections they share, the measured time and / or request count
  // (0: no count bound), the unmeasured warm-up before it, the Moving AI map
  // to load (queries from its .scen file), and the seed of the random
  // queries and of the shuffle.
  int concurrency = 4;
  int channels = 1;
  absl::Duration duration = absl::Seconds(10);
  absl::Duration warmup = absl::Seconds(1);
  int64_t requests = 0;
  std::string movingai;
  uint64_t seed = 1;
  // render: --plan (SX SY GX GY follow NAME), the PNG to write (-o / --out;
  // empty: none), text instead of or as well as the PNG, pixels per cell (0:
  // automatic) and row 0 at the bottom.
  bool plan = false;
  std::string out;
  bool ascii = false;
  int scale = 0;
  bool y_up = false;
  // maps import of a .png: map_server's thresholds (unset: 0.65 / 0.196) and
  // colour inversion.
  std::optional<double> occupied_thresh;
  std::optional<double> free_thresh;
  bool negate = false;
};

// One item of a `pathctl batch` file.
struct BatchItem {
  std::string id;
  v1::PlanRequest request;
};

// The items of a batch file: one "ID MAP SX SY GX GY [PLANNER]" per line
// (cells; world metres with `world`), fields separated by spaces or tabs,
// blank lines and lines starting with '#' skipped. INVALID_ARGUMENT
// "FILE:LINE: ..." for a malformed line. Only the positions and the planner
// are set; the caller adds the options shared by every item.
absl::StatusOr<std::vector<BatchItem>> ParseBatchFile(absl::string_view text,
                                                      absl::string_view file_name,
                                                      bool world);

// Writes a row-major cost-to-go field as CSV, one map row per line, "inf"
// for unreachable cells. DATA_LOSS when the values do not fill whole rows.
absl::Status WriteCostToGoCsv(const std::string& path, int32_t width,
                              const google::protobuf::RepeatedField<double>& field);
// The same for CostToGo's 4-byte field.
absl::Status WriteCostToGoCsv(const std::string& path, int32_t width,
                              const google::protobuf::RepeatedField<float>& field);

// A cost byte as a number 0..255 or the Nav2 name of a special value (free,
// inscribed, lethal, unknown); INVALID_ARGUMENT "COST: ..." otherwise.
absl::StatusOr<uint32_t> ParseCost(absl::string_view text);

// The poses of a path file: one "X Y" pair per line, separated by spaces,
// tabs or a comma (cells, or metres when `world`), blank lines and lines
// starting with '#' skipped. INVALID_ARGUMENT "FILE:LINE: ..." for a malformed
// line.
absl::StatusOr<std::vector<v1::Position>> ParsePathFile(
    absl::string_view text, absl::string_view file_name, bool world);

// The lines of Prometheus text `text` that belong to a metric whose name
// starts with one of `prefixes` (its samples and its # HELP / # TYPE lines);
// all of `text` when `prefixes` is empty.
std::string FilterMetricsText(absl::string_view text,
                              const std::vector<std::string>& prefixes);

// Cells as "(x,y) (x,y) ...".
std::string FormatPath(const google::protobuf::RepeatedPtrField<v1::Cell>& cells);

// What `pathctl completion bash` completes: pathctl's commands, the flags
// registered in pathctl/main.cc, planner names and output formats.
CompletionSpec PathctlCompletionSpec();

// The full --help text: commands, flags, cell glyphs and exit codes.
std::string UsageText();
// The command synopsis alone, shown after a usage error.
std::string SynopsisText();

// argv split into flag arguments (normalised to "--name=value" / "--name" /
// "--noname") and positional arguments, so flags may appear anywhere.
struct CommandLine {
  std::vector<std::string> flags;
  std::vector<std::string> positional;
  bool help = false;  // --help, -h or -help was given
};

// Splits argv using the process's registered Abseil flags, validating each
// flag name and value up front. absl::ParseCommandLine would exit(1) on a bad
// flag, but pathctl promises exit code 2 for every usage error. Arguments
// that parse as numbers (e.g. "-3") are positional, not flags; "--" ends
// flags. INVALID_ARGUMENT names the offending argument.
absl::StatusOr<CommandLine> SplitCommandLine(int argc, const char* const* argv);

// The server address: `flag_value` if non-empty, else `env_value` if non-null
// and non-empty, else client::kDefaultServerAddress.
std::string ResolveServerAddress(const std::string& flag_value,
                                 const char* env_value);

// One character per cell: '.' free (0); '1'..'9' weighted 1..252, digit d
// covering costs 28(d-1)+1 .. 28d; '#' inscribed or lethal (253, 254); '?'
// unknown (255).
char CellGlyph(uint8_t cost);
// Renders row-major cells as `height` lines of `width` glyphs, row 0 first.
// Precondition: cells.size() == width * height.
std::string RenderCells(int32_t width, int32_t height, absl::string_view cells);

// Runs the command in `args` (positional arguments, e.g. {"maps", "list"}).
// Output goes to `out`; errors ("error: <CODE>: <message>") and usage go to
// `err`. Returns an ExitCode.
int Run(const Options& options, const std::vector<std::string>& args,
        std::ostream& out, std::ostream& err);

}  // namespace pathd::pathctl

#endif  // PATHD_CLIENT_PATHCTL_PATHCTL_H_
