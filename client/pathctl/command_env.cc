// Implementation of the command environment and the shared request helpers.
#include "client/pathctl/command_env.h"

#include <algorithm>
#include <iterator>
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
#include "core/search/registry.h"
#include "core/status_macros.h"
#include "proto/planner_names.h"
#include "yaml-cpp/yaml.h"

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

absl::Status SetPathEncoding(absl::string_view flag, v1::PlanOptions* plan_options) {
  if (flag.empty() || flag == "packed") {
    plan_options->set_path_encoding(v1::PATH_ENCODING_PACKED);
  } else if (flag == "readable") {
    plan_options->set_path_encoding(v1::PATH_ENCODING_READABLE);
  } else if (flag == "both") {
    plan_options->set_path_encoding(v1::PATH_ENCODING_BOTH);
  } else {
    return absl::InvalidArgumentError(
        absl::StrCat("--path_encoding must be readable, packed or both, not '", flag, "'"));
  }
  return absl::OkStatus();
}

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

bool IsKinematicPlanner(std::string_view name) {
  const Planner* planner = PlannerRegistry::Default().Get(name);
  return planner != nullptr && planner->traits().kinematic;
}

absl::StatusOr<std::vector<std::pair<double, double>>> ParseFootprint(
    std::string_view flag, const std::string& text) {
  const auto bad = [&](std::string_view why) {
    return absl::InvalidArgumentError(absl::StrCat(
        "--", std::string(flag), ": ", std::string(why),
        "; expected \"[[x, y], [x, y], [x, y], ...]\" as in Nav2's footprint parameter"));
  };
  YAML::Node node;
  try {
    node = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    return bad(absl::StrCat("cannot parse '", text, "': ", e.msg));
  }
  if (!node.IsSequence() || node.size() < 3) return bad("give at least 3 points");
  std::vector<std::pair<double, double>> points;
  for (size_t i = 0; i < node.size(); ++i) {
    const YAML::Node& p = node[i];
    if (!p.IsSequence() || p.size() != 2) {
      return bad(absl::StrFormat("point %d is not a pair [x, y]", i + 1));
    }
    try {
      points.emplace_back(p[0].as<double>(), p[1].as<double>());
    } catch (const YAML::Exception&) {
      return bad(absl::StrFormat("point %d is not two numbers", i + 1));
    }
  }
  return points;
}

namespace {

// The position as a pose facing `yaw`: a world point keeps its metres, a
// cell becomes its centre in cell coordinates.
void SetYaw(double yaw, v1::Position* position) {
  if (position->has_world()) {
    const v1::WorldPoint w = position->world();
    v1::WorldPose* pose = position->mutable_world_pose();
    pose->set_x(w.x());
    pose->set_y(w.y());
    pose->set_yaw(yaw);
  } else if (position->has_cell()) {
    const v1::Cell c = position->cell();
    v1::CellPose* pose = position->mutable_cell_pose();
    pose->set_x(c.x() + 0.5);
    pose->set_y(c.y() + 0.5);
    pose->set_yaw(yaw);
  }
}

}  // namespace

absl::Status SetFootprint(const RobotOptions& robot, v1::PlanOptions* options) {
  if (!robot.footprint_m.empty() && !robot.footprint_cells.empty()) {
    return absl::InvalidArgumentError("give --footprint (metres) or --footprint_cells, not both");
  }
  if (!robot.footprint_m.empty()) {
    PATHD_ASSIGN_OR_RETURN(const auto points, ParseFootprint("footprint", robot.footprint_m));
    for (const auto& [x, y] : points) {
      v1::WorldPoint* p = options->mutable_footprint()->add_polygon_m();
      p->set_x(x);
      p->set_y(y);
    }
  }
  if (!robot.footprint_cells.empty()) {
    PATHD_ASSIGN_OR_RETURN(const auto points,
                           ParseFootprint("footprint_cells", robot.footprint_cells));
    for (const auto& [x, y] : points) {
      v1::CellPoint* p = options->mutable_footprint()->add_polygon_cells();
      p->set_x(x);
      p->set_y(y);
    }
  }
  return absl::OkStatus();
}

absl::Status SetRobotOptions(const RobotOptions& robot, v1::PlanRequest* request) {
  v1::PlanOptions* options = request->mutable_options();
  PATHD_RETURN_IF_ERROR(SetFootprint(robot, options));
  PATHD_RETURN_IF_ERROR(SetDistance(
      "min_turning_radius", robot.min_turning_radius_m, robot.min_turning_radius_cells,
      [&](double m) { options->set_min_turning_radius_m(m); },
      [&](double c) { options->set_min_turning_radius_cells(c); }));
  if (!robot.motion_model.empty()) {
    static constexpr std::pair<const char*, v1::MotionModel> kModels[] = {
        {"dubins", v1::MOTION_MODEL_DUBINS},
        {"reeds_shepp", v1::MOTION_MODEL_REEDS_SHEPP},
        {"differential", v1::MOTION_MODEL_DIFFERENTIAL},
        {"omnidirectional", v1::MOTION_MODEL_OMNIDIRECTIONAL},
    };
    const auto* found = std::find_if(std::begin(kModels), std::end(kModels), [&](const auto& m) {
      return robot.motion_model == m.first;
    });
    if (found == std::end(kModels)) {
      return absl::InvalidArgumentError(absl::StrCat(
          "--motion_model must be dubins, reeds_shepp, differential or omnidirectional, not '",
          robot.motion_model, "'"));
    }
    options->set_motion_model(found->second);
  }
  v1::KinematicPenalties* penalties = options->mutable_penalties();
  if (robot.reverse_penalty) penalties->set_reverse(*robot.reverse_penalty);
  if (robot.change_penalty) penalties->set_change(*robot.change_penalty);
  if (robot.non_straight_penalty) penalties->set_non_straight(*robot.non_straight_penalty);
  if (robot.cost_penalty) penalties->set_cost(*robot.cost_penalty);
  if (robot.goal_yaw_tolerance) options->set_goal_yaw_tolerance(*robot.goal_yaw_tolerance);
  options->set_lattice(robot.lattice);
  if (robot.no_smooth && robot.smooth) {
    return absl::InvalidArgumentError("--smooth and --no_smooth contradict each other; give one");
  }
  if (robot.no_smooth) options->set_smooth(false);
  if (robot.smooth) options->set_smooth(true);
  if (robot.start_yaw) SetYaw(*robot.start_yaw, request->mutable_start());
  if (robot.goal_yaw) SetYaw(*robot.goal_yaw, request->mutable_goal());
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
  // Always the stream: one path for every size, and no message holds more
  // than 1 MiB of cells, whatever the server's --max_message_bytes.
  PATHD_ASSIGN_OR_RETURN(v1::GetMapResponse response, env.client().DownloadMap(name));
  const v1::MapInfo& info = response.info();
  std::string& cells = *response.mutable_cells();
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
