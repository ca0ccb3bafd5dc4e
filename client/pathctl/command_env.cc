// Implementation of the command environment and the shared request helpers.
#include "client/pathctl/command_env.h"

#include <optional>
#include <string_view>
#include <utility>
#include <vector>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "client/pathctl/command.h"
#include "core/status_macros.h"
#include "proto/planner_names.h"

namespace pathd::pathctl {

const client::PathdClient& CommandEnv::client() {
  if (client_ == nullptr) {
    client_ = std::make_unique<client::PathdClient>(
        client::MakeChannel(global().server, credentials_), global().timeout);
  }
  return *client_;
}

std::optional<int> CommandEnv::LoadCredentials() {
  absl::StatusOr<client::ClientCredentials> credentials =
      client::LoadClientCredentials(global().credentials);
  if (!credentials.ok()) {
    return absl::IsInvalidArgument(credentials.status())
               ? Usage(credentials.status().message())
               : Fail(credentials.status());
  }
  credentials_ = *std::move(credentials);
  if (!credentials_.token.empty() && credentials_.tls_ca_pem.empty() &&
      !client::IsLoopbackAddress(global().server)) {
    err_ << "warning: sending the token without TLS: anyone on the network "
            "path to "
         << global().server << " can read it; use --tls_ca\n";
  }
  return std::nullopt;
}

int CommandEnv::Usage(absl::string_view problem) {
  err_ << "error: " << problem << "\n\n"
       << (command_ != nullptr ? ShortUsage(*command_)
                               : absl::StrCat(SynopsisText(),
                                              "run 'pathctl --help' for details\n"));
  return kExitUsage;
}

bool LooksLikeTlsPort(absl::string_view message) {
  return absl::StrContains(message, "Socket closed") ||
         absl::StrContains(message, "Connection reset by peer") ||
         absl::StrContains(message, "End of TCP stream");
}

int CommandEnv::Fail(const absl::Status& status) {
  err_ << "error: " << absl::StatusCodeToString(status.code()) << ": "
       << status.message() << "\n";
  if (absl::IsUnavailable(status) && global().credentials.tls_ca.empty() &&
      LooksLikeTlsPort(status.message())) {
    err_ << "hint: " << global().server
         << " closed a plaintext connection; if it serves TLS, give --tls_ca "
            "FILE (its CA, or its self-signed certificate)\n";
  }
  return ExitCodeForStatus(status.code());
}

int CommandEnv::PrintJson(const google::protobuf::Message& message) {
  absl::StatusOr<std::string> json = MessageToJson(message, false);
  if (!json.ok()) return Fail(json.status());
  out_ << *json;
  return kExitOk;
}

int CommandEnv::PrintCsv(const Table& table) {
  out_ << table.Csv();
  return kExitOk;
}

int CommandEnv::Unsupported(absl::string_view command, absl::string_view why) {
  err_ << "error: " << command << " has no --output "
       << OutputFormatName(global().output) << ": " << why << "\n";
  return kExitUsage;
}

std::string PlannerNames() {
  std::vector<absl::string_view> names;
  for (const WirePlanner& p : WirePlanners()) names.push_back(p.name);
  return absl::StrJoin(names, ", ");
}

absl::StatusOr<v1::Planner> PlannerFromName(absl::string_view name) {
  if (std::optional<v1::Planner> planner =
          WirePlannerFromName(std::string_view(name.data(), name.size()))) {
    return *planner;
  }
  return absl::InvalidArgumentError(absl::StrCat(
      "--planner: unknown planner '", name, "'; valid planners: ", PlannerNames()));
}

namespace {

// A distance flag pair: --NAME in metres or --NAME_cells, not both.
template <typename SetMetres, typename SetCells>
absl::Status SetDistance(std::string_view name, std::optional<double> metres,
                         std::optional<double> cells, SetMetres set_metres,
                         SetCells set_cells) {
  if (metres.has_value() && cells.has_value()) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "give --%s (metres) or --%s_cells, not both", name, name));
  }
  if (metres.has_value()) set_metres(*metres);
  if (cells.has_value()) set_cells(*cells);
  return absl::OkStatus();
}

}  // namespace

absl::Status SetCostOptions(const CostOptions& options, v1::PlanOptions* plan_options) {
  switch (options.connectivity) {
    case 0:
      break;
    case 4:
      plan_options->set_connectivity(v1::CONNECTIVITY_FOUR);
      break;
    case 8:
      plan_options->set_connectivity(v1::CONNECTIVITY_EIGHT);
      break;
    default:
      return absl::InvalidArgumentError(absl::StrCat(
          "--connectivity must be 4 or 8, not ", options.connectivity));
  }
  if (options.cost_weight.has_value()) {
    plan_options->set_cost_weight(*options.cost_weight);
  }
  plan_options->set_unknown_is_free(options.unknown_is_free);
  PATHD_RETURN_IF_ERROR(SetDistance(
      "robot_radius", options.robot_radius_m, options.robot_radius_cells,
      [&](double m) { plan_options->set_robot_radius_m(m); },
      [&](double c) { plan_options->set_robot_radius_cells(c); }));
  PATHD_RETURN_IF_ERROR(SetDistance(
      "min_clearance", options.min_clearance_m, options.min_clearance_cells,
      [&](double m) { plan_options->set_min_clearance_m(m); },
      [&](double c) { plan_options->set_min_clearance_cells(c); }));
  PATHD_RETURN_IF_ERROR(SetDistance(
      "inflation_radius", options.inflation_radius_m, options.inflation_radius_cells,
      [&](double m) { plan_options->set_inflation_radius_m(m); },
      [&](double c) { plan_options->set_inflation_radius_cells(c); }));
  if (options.cost_scaling_factor.has_value()) {
    plan_options->set_cost_scaling_factor(*options.cost_scaling_factor);
  }
  return absl::OkStatus();
}

absl::StatusOr<v1::Position> PositionFromPair(Args xy, bool world,
                                              std::span<const char* const> names) {
  v1::Position position;
  if (world) {
    PATHD_ASSIGN_OR_RETURN(const std::vector<double> p, ParseDoubles(xy, names));
    position.mutable_world()->set_x(p[0]);
    position.mutable_world()->set_y(p[1]);
  } else {
    PATHD_ASSIGN_OR_RETURN(const std::vector<int32_t> p, ParseInts(xy, names));
    position.mutable_cell()->set_x(p[0]);
    position.mutable_cell()->set_y(p[1]);
  }
  return position;
}

absl::Status AddViaPoints(const std::string& via, bool world, v1::PlanRequest* request) {
  if (via.empty()) return absl::OkStatus();
  const std::vector<std::string> points = absl::StrSplit(via, ';', absl::SkipWhitespace());
  for (size_t i = 0; i < points.size(); ++i) {
    const std::vector<std::string> xy = absl::StrSplit(points[i], ',');
    const std::string name = absl::StrCat("--via point ", i + 1);
    if (xy.size() != 2) {
      return absl::InvalidArgumentError(
          absl::StrCat(name, ": '", points[i], "' is not X,Y"));
    }
    static constexpr const char* kXY[] = {"X", "Y"};
    absl::StatusOr<v1::Position> point = PositionFromPair(Args(xy), world, kXY);
    if (!point.ok()) {
      return absl::InvalidArgumentError(
          absl::StrCat(name, ": ", point.status().message()));
    }
    *request->add_via() = *std::move(point);
  }
  return absl::OkStatus();
}

absl::StatusOr<Grid> FetchGrid(CommandEnv& env, const std::string& name) {
  v1::GetMapRequest request;
  request.set_name(name);
  request.set_include_cells(true);
  PATHD_ASSIGN_OR_RETURN(const v1::GetMapResponse response, env.client().GetMap(request));
  const v1::MapInfo& info = response.info();
  const std::string& cells = response.cells();
  absl::StatusOr<Grid> grid = Grid::FromCells(
      info.width(), info.height(), std::vector<uint8_t>(cells.begin(), cells.end()));
  if (!grid.ok()) {
    return absl::InternalError(absl::StrFormat("server sent %d cell bytes for a %dx%d map",
                                               cells.size(), info.width(),
                                               info.height()));
  }
  grid->set_resolution(info.resolution() > 0 ? info.resolution() : 1.0);
  grid->set_origin(GridOrigin{info.origin().x(), info.origin().y(), info.origin().yaw()});
  return grid;
}

}  // namespace pathd::pathctl
