// What a pathctl command runs with: its options, its output streams, a
// lazily made client (so usage errors never touch the network), and the
// ways a command ends (usage error, failed call, JSON or CSV output). Plus
// the request-building helpers several commands share: planner names, cost
// options, positions, via points, fetching a map's cells.
#ifndef PATHD_CLIENT_PATHCTL_COMMAND_ENV_H_
#define PATHD_CLIENT_PATHCTL_COMMAND_ENV_H_

#include <memory>
#include <optional>
#include <ostream>
#include <span>
#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "client/client.h"
#include "client/pathctl/exit_codes.h"
#include "client/pathctl/options.h"
#include "client/pathctl/output.h"
#include "client/pathctl/text.h"
#include "core/map/grid.h"
#include "google/protobuf/message.h"
#include "pathd/v1/planner_service.pb.h"

namespace pathd::pathctl {

struct Command;  // command.h

// One command run's state. Not thread-safe; commands that start threads
// (batch, bench) keep them off it.
class CommandEnv {
 public:
  CommandEnv(const Options& options, std::ostream& out, std::ostream& err)
      : options_(options), out_(out), err_(err) {}

  const Options& options() const { return options_; }
  const GlobalOptions& global() const { return options_.global; }
  std::ostream& out() { return out_; }
  std::ostream& err() { return err_; }

  // The command being run (its short usage follows a usage error); null
  // before dispatch, when a usage error prints the whole synopsis.
  const Command* command() const { return command_; }
  void set_command(const Command* command) { command_ = command; }

  // The client for --server, made on first use with the loaded credentials.
  const client::PathdClient& client();

  // Reads the TLS and token files once, before any command connects; a
  // message on `err` and the exit code when they are unusable.
  std::optional<int> LoadCredentials();
  const client::ClientCredentials& credentials() const { return credentials_; }

  // "error: PROBLEM", then the command's short usage (the whole synopsis
  // before a command is known); kExitUsage.
  int Usage(absl::string_view problem);

  // "error: CODE: message" and the exit code of the code. A plaintext call
  // that failed UNAVAILABLE the way a TLS port answers plaintext ("Socket
  // closed") adds a hint suggesting --tls_ca.
  int Fail(const absl::Status& status);

  bool json() const { return options_.global.json; }
  bool csv() const { return options_.global.output == OutputFormat::kCsv; }

  // Prints `message` with protobuf's canonical proto3 JSON mapping, default
  // values included, so `"found": false` is visible to scripts.
  int PrintJson(const google::protobuf::Message& message);
  int PrintCsv(const Table& table);

  // The usage error of a command asked for a format it cannot print; `why`
  // says what it prints instead.
  int Unsupported(absl::string_view command, absl::string_view why);

 private:
  const Options& options_;
  std::ostream& out_;
  std::ostream& err_;
  const Command* command_ = nullptr;
  std::unique_ptr<client::PathdClient> client_;
  client::ClientCredentials credentials_;
};

// Whether an UNAVAILABLE message is what gRPC says when a plaintext client
// reaches a TLS port (the server drops the connection at the first bytes).
bool LooksLikeTlsPort(absl::string_view message);

// "astar, dijkstra, ..." from proto/planner_names.h.
std::string PlannerNames();
// Looks up a planner by CLI name; INVALID_ARGUMENT listing the valid names.
absl::StatusOr<v1::Planner> PlannerFromName(absl::string_view name);

// Sets connectivity, cost weight, unknown cells and robot radius;
// INVALID_ARGUMENT (a usage error) for a bad combination.
absl::Status SetCostOptions(const CostOptions& options, v1::PlanOptions* plan_options);

// Sets options.path_encoding from --path_encoding: "" or "packed" PACKED
// (what the client unpacks, the default), "readable" READABLE, "both" BOTH;
// INVALID_ARGUMENT naming the flag otherwise.
absl::Status SetPathEncoding(absl::string_view flag, v1::PlanOptions* plan_options);

// Sets the robot's footprint, turning radius, motion model, penalties, goal
// heading tolerance, lattice and smoothing on request->options, and turns
// the start and goal into poses when --start_yaw / --goal_yaw give their
// headings (a cell becomes its centre). INVALID_ARGUMENT (a usage error)
// naming the flag for a bad value or a flag pair given twice.
absl::Status SetRobotOptions(const RobotOptions& robot, v1::PlanRequest* request);

// Sets options->footprint from --footprint (metres) or --footprint_cells;
// INVALID_ARGUMENT naming the flag.
absl::Status SetFootprint(const RobotOptions& robot, v1::PlanOptions* options);

// Whether the planner that answered (PlanResponse.planner) is kinematic: its
// poses are the path.
bool IsKinematicPlanner(std::string_view name);

// Nav2's footprint syntax "[[x, y], [x, y], ...]" (a YAML flow sequence of
// points; at least 3). INVALID_ARGUMENT naming `flag`.
absl::StatusOr<std::vector<std::pair<double, double>>> ParseFootprint(
    std::string_view flag, const std::string& text);

// One position from two arguments (`names` word the errors): a cell, or
// with `world` a point in metres.
absl::StatusOr<v1::Position> PositionFromPair(Args xy, bool world,
                                              std::span<const char* const> names);

// Adds "X,Y;X,Y..." (--via) to request.via: cells, or world metres with
// `world`. INVALID_ARGUMENT (a usage error) naming the bad point.
absl::Status AddViaPoints(const std::string& via, bool world, v1::PlanRequest* request);

// The map's current cells as a Grid with its resolution and origin.
absl::StatusOr<Grid> FetchGrid(CommandEnv& env, const std::string& name);

}  // namespace pathd::pathctl

#endif  // PATHD_CLIENT_PATHCTL_COMMAND_ENV_H_
