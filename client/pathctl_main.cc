// pathctl: the command-line client of pathd. Defines the flags and hands the
// parsed command to pathd::pathctl::Run (client/pathctl.h), where the commands
// live.
#include <cstdlib>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "client/pathctl.h"

ABSL_FLAG(std::string, server, "",
          "pathd address; default $PATHD_SERVER, else 127.0.0.1:50051");
ABSL_FLAG(absl::Duration, timeout, pathd::client::kDefaultTimeout,
          "deadline of each call");
ABSL_FLAG(bool, json, false, "print the response message as JSON");
ABSL_FLAG(std::string, from, "", "maps create: the .map or .yaml/.yml file");
ABSL_FLAG(bool, replace, false, "maps create: replace an existing map");
ABSL_FLAG(double, resolution, 0.0, "maps create: metres per cell (.map files)");
ABSL_FLAG(bool, cells, false, "maps get: print the cells as ASCII");
ABSL_FLAG(std::optional<uint64_t>, expected_version, std::nullopt,
          "maps set/rect: apply only at this map version");
ABSL_FLAG(std::string, planner, "", "plan: planner name (default: server's)");
ABSL_FLAG(int, connectivity, 0, "plan: 4 or 8 (default: server's, 8)");
ABSL_FLAG(std::optional<double>, cost_weight, std::nullopt,
          "plan: cell cost weight (default: server's, 1)");
ABSL_FLAG(bool, world, false, "plan: coordinates are world metres");
ABSL_FLAG(bool, unknown_is_free, false, "plan: unknown cells are free");
ABSL_FLAG(int64_t, max_expansions, 0, "plan: expansion budget (0: server's)");

int main(int argc, char** argv) {
  namespace pathctl = pathd::pathctl;
  absl::SetProgramUsageMessage(pathctl::UsageText());

  absl::StatusOr<pathctl::CommandLine> line =
      pathctl::SplitCommandLine(argc, argv);
  if (!line.ok()) {
    std::cerr << "error: " << line.status().message() << "\n\n"
              << pathctl::SynopsisText()
              << "run 'pathctl --help' for details\n";
    return pathctl::kExitUsage;
  }
  if (line->help) {
    std::cout << pathctl::UsageText();
    return pathctl::kExitOk;
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
  options.server = pathctl::ResolveServerAddress(
      absl::GetFlag(FLAGS_server), std::getenv(pathctl::kServerEnvVar));
  options.timeout = absl::GetFlag(FLAGS_timeout);
  options.json = absl::GetFlag(FLAGS_json);
  options.from = absl::GetFlag(FLAGS_from);
  options.replace = absl::GetFlag(FLAGS_replace);
  options.resolution = absl::GetFlag(FLAGS_resolution);
  options.cells = absl::GetFlag(FLAGS_cells);
  options.expected_version = absl::GetFlag(FLAGS_expected_version);
  options.planner = absl::GetFlag(FLAGS_planner);
  options.connectivity = absl::GetFlag(FLAGS_connectivity);
  options.cost_weight = absl::GetFlag(FLAGS_cost_weight);
  options.world = absl::GetFlag(FLAGS_world);
  options.unknown_is_free = absl::GetFlag(FLAGS_unknown_is_free);
  options.max_expansions = absl::GetFlag(FLAGS_max_expansions);

  return pathctl::Run(
      options,
      std::vector<std::string>(positional.begin() + 1, positional.end()),
      std::cout, std::cerr);
}
