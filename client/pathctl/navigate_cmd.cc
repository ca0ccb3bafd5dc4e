// pathctl navigate: a Navigate session opened from SX SY to GX GY, with an
// optional robot script replayed through it (navigate_session.cc).
#include <string>
#include <utility>
#include <vector>

#include "client/pathctl/command.h"
#include "client/pathctl/files.h"
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
  absl::StatusOr<std::vector<int32_t>> p = ParseInts(args.subspan(1), kNames);
  if (!p.ok()) return env.Usage(p.status().message());
  v1::NavigateOpen open;
  open.set_map(args[0]);
  open.mutable_start()->mutable_cell()->set_x((*p)[0]);
  open.mutable_start()->mutable_cell()->set_y((*p)[1]);
  open.mutable_goal()->mutable_cell()->set_x((*p)[2]);
  open.mutable_goal()->mutable_cell()->set_y((*p)[3]);
  if (absl::Status s = SetCostOptions(env.options().cost, open.mutable_options()); !s.ok()) {
    return env.Usage(s.message());
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
          RunNavigateSession(env.client(), open, script, env.json(), env.out());
      !s.ok()) {
    return env.Fail(s);
  }
  return kExitOk;
}

constexpr absl::string_view kNavigateFlags[] = {
    "script", "connectivity", "cost_weight", "unknown_is_free", "robot_radius",
    "robot_radius_cells", "min_clearance",
    "min_clearance_cells", "inflation_radius",
    "inflation_radius_cells", "cost_scaling_factor"};

}  // namespace

const Command kNavigateCommand = {
    .name = "navigate",
    .synopsis = "NAME SX SY GX GY [--script FILE] [cost options]",
    .help = "Opens a Navigate session (D* Lite) on map NAME from cell (SX, SY) to\n"
            "(GX, GY) and prints its path; --script replays a robot run through it\n"
            "(format in 'pathctl --help'). Cells only: a script moves the robot cell\n"
            "by cell. --timeout bounds each wait for an answer, not the session.",
    .flags = kNavigateFlags,
    .run = Navigate,
    .map_arg = MapArg::kExisting,
};

}  // namespace pathd::pathctl
