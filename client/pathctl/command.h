// pathctl's command table: one Command per command (`maps create`, `plan`,
// ...), defined beside its code in <cmd>_cmd.cc and listed once in
// command.cc. Dispatch, the synopsis, each command's short usage and
// `pathctl help CMD`, the flag check and bash completion are all generated
// from it, so they cannot disagree.
#ifndef PATHD_CLIENT_PATHCTL_COMMAND_H_
#define PATHD_CLIENT_PATHCTL_COMMAND_H_

#include <ostream>
#include <span>
#include <string>
#include "absl/strings/string_view.h"
#include <vector>

#include "client/pathctl/command_env.h"
#include "client/pathctl/completion.h"
#include "client/pathctl/options.h"
#include "client/pathctl/text.h"

namespace pathd::pathctl {

// What a command's first positional argument is.
enum class MapArg {
  kNone,
  kExisting,  // the name of a map on the server (completed from maps list)
  kNew,       // the name of a map to make (maps create, maps import)
};

struct Command {
  // The words that select it: "plan", "maps create".
  absl::string_view name;
  // Its arguments and flags after the name. '\n' separates lines: a line
  // starting with a space continues the one before, any other is a second
  // form of the command ("pathctl [flags] NAME" is put before it).
  absl::string_view synopsis;
  // What it does, for `pathctl help NAME` (a few lines of prose).
  absl::string_view help;
  // The flags it reads, without "--", besides the global ones (kGlobalFlags).
  std::span<const absl::string_view> flags;
  // Runs it on the positional arguments after its name; returns an ExitCode.
  int (*run)(CommandEnv& env, Args args);
  // Whether its first argument is a map name: Run checks such a name by the
  // map name rule (map_name.h) before any call, and completion offers the
  // server's map names for kExisting.
  MapArg map_arg = MapArg::kNone;
  // Its next argument is a local file (completion).
  bool file_first = false;
  // It calls pathd, so the TLS and token files are read first (metrics and
  // help do not).
  bool connects = true;
  // It prints --output geojson (the others refuse it).
  bool geojson = false;
};

// The flags every command takes.
inline constexpr absl::string_view kGlobalFlags[] = {
    "server",   "timeout",    "tls_ca", "tls_cert", "tls_key",    "tls_server_name",
    "token",    "token_file", "json",   "output",   "no_progress"};

// The commands, in synopsis order.
std::span<const Command* const> Commands();
// The command named `name` (words joined by one space); null when none is.
const Command* FindCommand(absl::string_view name);
// Commands of a group ("maps" -> maps create, maps list, ...); empty when
// `group` is not the first word of a two-word command.
std::vector<const Command*> CommandsOfGroup(absl::string_view group);

// "usage: pathctl [flags] NAME SYNOPSIS...\nrun 'pathctl help NAME' ...\n".
std::string ShortUsage(const Command& command);
// The short usage of every command of a group ("maps").
std::string GroupUsage(absl::string_view group);
// `pathctl help NAME`: the short usage, the help text, and the command's
// flags with their one-line descriptions.
std::string CommandHelp(const Command& command);
// The whole synopsis, shown after a usage error that names no command.
std::string SynopsisText();
// The full --help text: synopsis, flags, formats, glyphs and exit codes.
std::string UsageText();
// "pathctl VERSION\n", from the CMake project version.
std::string VersionText();

// What `pathctl completion bash` completes: the table's commands, the flags
// registered in pathctl/main.cc, planner names and output formats.
CompletionSpec PathctlCompletionSpec();

// Runs the command in `args` (positional arguments, e.g. {"maps", "list"}).
// Output goes to `out`; errors ("error: <CODE>: <message>") and usage go to
// `err`. A flag in options.given_flags that is neither global nor in the
// command's list is a usage error naming it. Returns an ExitCode.
int Run(const Options& options, const std::vector<std::string>& args,
        std::ostream& out, std::ostream& err);

// The commands, one object each in its <cmd>_cmd.cc.
extern const Command kMapsCreateCommand;
extern const Command kMapsListCommand;
extern const Command kMapsGetCommand;
extern const Command kMapsDeleteCommand;
extern const Command kMapsSetCommand;
extern const Command kMapsRectCommand;
extern const Command kMapsWatchCommand;
extern const Command kMapsImportCommand;
extern const Command kMapsExportCommand;
extern const Command kMapsStatsCommand;
extern const Command kPlanCommand;
extern const Command kBatchCommand;
extern const Command kNavigateCommand;
extern const Command kCostToGoCommand;
extern const Command kTableCommand;
extern const Command kNearestCommand;
extern const Command kTripCommand;
extern const Command kIsochroneCommand;
extern const Command kFleetPlanCommand;
extern const Command kSimulateCommand;
extern const Command kCheckCommand;
extern const Command kCacheStatsCommand;
extern const Command kSessionsCommand;
extern const Command kHealthCommand;
extern const Command kMetricsCommand;
extern const Command kBenchCommand;
extern const Command kRenderCommand;
extern const Command kCompletionCommand;
extern const Command kHelpCommand;

}  // namespace pathd::pathctl

#endif  // PATHD_CLIENT_PATHCTL_COMMAND_H_
