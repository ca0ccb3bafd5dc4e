// The control half of a Navigate session (navigate_control.h). Metres,
// seconds and world frames stop here; core/local sees cells and the grid
// frame.
#include "server/rpc/navigate_control.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <utility>

#include "absl/strings/str_format.h"
#include "core/geometry/free_space.h"
#include "core/kinematics/obstacle_heuristic.h"
#include "core/kinematics/pose.h"
#include "core/kinematics/vehicle.h"
#include "core/search/derived.h"
#include "core/status_macros.h"
#include "server/convert.h"

namespace pathd::server {
namespace {

std::string Num(double v) { return absl::StrFormat("%g", v); }

absl::Status Bad(const std::string& field, const std::string& problem) {
  return absl::InvalidArgumentError(absl::StrCat("open.control.", field, " ", problem));
}

// A limit: zero means `fallback`; else finite and positive (or >= 0).
absl::StatusOr<double> Limit(const char* name, double value, double fallback) {
  if (!std::isfinite(value) || value < 0) {
    return Bad(absl::StrCat("limits.", name),
               absl::StrCat(Num(value), " must be finite and >= 0 (0: the default ",
                            Num(fallback), ")"));
  }
  return value == 0 ? fallback : value;
}

enum class Unit { kMetres, kSeconds, kPlain, kCount, kRadians, kCubicMetres };

struct OptionSpec {
  const char* name;
  Unit unit;
  bool zero_ok;
  // Stores the value, already in core's units.
  std::function<void(ControlConfig&, double)> set;
};

std::vector<OptionSpec> DwaSpecs() {
  return {
      {"horizon", Unit::kSeconds, false, [](ControlConfig& c, double v) { c.dwa.horizon = v; }},
      {"sub_step", Unit::kSeconds, false, [](ControlConfig& c, double v) { c.dwa.sub_step = v; }},
      {"path_distance_weight", Unit::kPlain, true,
       [](ControlConfig& c, double v) { c.dwa.path_distance_weight = v; }},
      {"goal_distance_weight", Unit::kPlain, true,
       [](ControlConfig& c, double v) { c.dwa.goal_distance_weight = v; }},
      {"heading_weight", Unit::kPlain, true,
       [](ControlConfig& c, double v) { c.dwa.heading_weight = v; }},
      {"obstacle_weight", Unit::kPlain, true,
       [](ControlConfig& c, double v) { c.dwa.obstacle_weight = v; }},
      {"speed_weight", Unit::kPlain, true,
       [](ControlConfig& c, double v) { c.dwa.speed_weight = v; }},
      {"twirling_weight", Unit::kPlain, true,
       [](ControlConfig& c, double v) { c.dwa.twirling_weight = v; }},
      {"lookahead", Unit::kMetres, false, [](ControlConfig& c, double v) { c.dwa.lookahead = v; }},
      {"clearance_limit", Unit::kMetres, false,
       [](ControlConfig& c, double v) { c.dwa.clearance_limit = v; }},
      {"goal_tolerance", Unit::kMetres, false,
       [](ControlConfig& c, double v) { c.dwa.goal_tolerance = v; }},
      {"v_samples", Unit::kCount, false,
       [](ControlConfig& c, double v) { c.dwa.v_samples = static_cast<int32_t>(v); }},
      {"w_samples", Unit::kCount, false,
       [](ControlConfig& c, double v) { c.dwa.w_samples = static_cast<int32_t>(v); }},
      {"vy_samples", Unit::kCount, false,
       [](ControlConfig& c, double v) { c.dwa.vy_samples = static_cast<int32_t>(v); }},
  };
}

std::vector<OptionSpec> OrcaSpecs() {
  return {
      {"time_horizon", Unit::kSeconds, false,
       [](ControlConfig& c, double v) { c.orca.time_horizon = v; }},
      {"obstacle_time_horizon", Unit::kSeconds, false,
       [](ControlConfig& c, double v) { c.orca.obstacle_time_horizon = v; }},
      {"neighbour_range", Unit::kMetres, false,
       [](ControlConfig& c, double v) { c.orca.neighbour_range = v; }},
      {"max_neighbours", Unit::kCount, false,
       [](ControlConfig& c, double v) { c.orca.max_neighbours = static_cast<size_t>(v); }},
      {"obstacle_range", Unit::kMetres, false,
       [](ControlConfig& c, double v) { c.orca.obstacle_range = v; }},
      {"safety_margin", Unit::kMetres, true,
       [](ControlConfig& c, double v) { c.orca.safety_margin = v; }},
      {"lookahead", Unit::kMetres, false, [](ControlConfig& c, double v) { c.orca.lookahead = v; }},
      {"goal_tolerance", Unit::kMetres, false,
       [](ControlConfig& c, double v) { c.orca.goal_tolerance = v; }},
      {"keep_right", Unit::kRadians, true,
       [](ControlConfig& c, double v) { c.orca.keep_right = v; }},
      {"turn_gain", Unit::kPlain, false,
       [](ControlConfig& c, double v) { c.orca.turn_gain = v; }},
  };
}

std::vector<OptionSpec> FirasSpecs() {
  return {
      {"attraction", Unit::kPlain, false,
       [](ControlConfig& c, double v) { c.firas.attraction = v; }},
      {"attraction_distance", Unit::kMetres, false,
       [](ControlConfig& c, double v) { c.firas.attraction_distance = v; }},
      {"repulsion", Unit::kCubicMetres, true,
       [](ControlConfig& c, double v) { c.firas.repulsion = v; }},
      {"influence", Unit::kMetres, false,
       [](ControlConfig& c, double v) { c.firas.influence = v; }},
      {"lookahead", Unit::kMetres, false,
       [](ControlConfig& c, double v) { c.firas.lookahead = v; }},
      {"goal_tolerance", Unit::kMetres, false,
       [](ControlConfig& c, double v) { c.firas.goal_tolerance = v; }},
      {"turn_gain", Unit::kPlain, false,
       [](ControlConfig& c, double v) { c.firas.turn_gain = v; }},
  };
}

// Options every local planner has: the session's, not the planner's.
void AddSessionSpecs(std::vector<OptionSpec>& specs) {
  specs.push_back({"detour_range", Unit::kMetres, true,
                   [](ControlConfig& c, double v) { c.detour_range = v; }});
}

// The stall rule of the session's local planner: its window (s) and the
// least progress along the path over it (cells).
std::pair<double, double> StallRule(const ControlConfig& c) {
  switch (c.planner) {
    case LocalPlannerKind::kDwa:
      return {c.dwa.window_seconds, c.dwa.min_progress};
    case LocalPlannerKind::kOrca:
      return {c.orca.window_seconds, c.orca.min_progress};
    case LocalPlannerKind::kFiras:
      return {c.firas.window_seconds, c.firas.min_progress};
  }
  return {c.orca.window_seconds, c.orca.min_progress};
}

// What the local planner keeps between the robot's disc and the map, cells.
double SafetyMargin(const ControlConfig& c) {
  return c.planner == LocalPlannerKind::kOrca ? c.orca.safety_margin : 0.0;
}

// Distance defaults in metres (core's defaults are in cells, which depend on
// the map's resolution): what a robot of about half a metre needs.
void SetMetreDefaults(double resolution, ControlConfig& c) {
  c.dwa.lookahead = 0.4 / resolution;
  c.dwa.clearance_limit = 0.5 / resolution;
  c.dwa.goal_tolerance = 0.1 / resolution;
  c.orca.neighbour_range = 3.0 / resolution;
  c.orca.obstacle_range = 1.0 / resolution;
  c.orca.safety_margin = 0.05 / resolution;
  c.orca.lookahead = 1.0 / resolution;
  c.orca.goal_tolerance = 0.1 / resolution;
  c.firas.attraction_distance = 0.5 / resolution;
  c.firas.influence = 0.5 / resolution;
  c.firas.lookahead = 1.0 / resolution;
  c.firas.goal_tolerance = 0.1 / resolution;
  // Detours for ORCA only: DWA's and FIRAS's robots, steered sideways by a
  // detour, ran into each other more often (docs/performance.md).
  c.detour_range = c.planner == LocalPlannerKind::kOrca ? 0.5 / resolution : 0.0;
}

const char* PlannerName(LocalPlannerKind kind) {
  switch (kind) {
    case LocalPlannerKind::kDwa:
      return "dwa";
    case LocalPlannerKind::kOrca:
      return "orca";
    case LocalPlannerKind::kFiras:
      return "firas";
  }
  return "orca";
}

absl::Status ApplyLocalOptions(const v1::ControlOptions& control, double resolution,
                               ControlConfig& config) {
  std::vector<OptionSpec> specs;
  switch (config.planner) {
    case LocalPlannerKind::kDwa:
      specs = DwaSpecs();
      break;
    case LocalPlannerKind::kOrca:
      specs = OrcaSpecs();
      break;
    case LocalPlannerKind::kFiras:
      specs = FirasSpecs();
      break;
  }
  AddSessionSpecs(specs);
  // Sorted, so the first bad name reported does not depend on hashing.
  std::map<std::string, double> sorted(control.local_options().begin(),
                                       control.local_options().end());
  for (const auto& entry : sorted) {
    const std::string& name = entry.first;
    const double value = entry.second;
    const std::string field = absl::StrFormat("local_options[\"%s\"]", name);
    auto spec = std::find_if(specs.begin(), specs.end(),
                             [&](const OptionSpec& s) { return name == s.name; });
    if (spec == specs.end()) {
      std::string known;
      for (const OptionSpec& s : specs) absl::StrAppend(&known, known.empty() ? "" : ", ", s.name);
      return Bad(field, absl::StrFormat("is not an option of %s (it has: %s)",
                                        PlannerName(config.planner), known));
    }
    if (!std::isfinite(value)) return Bad(field, Num(value) + " must be finite");
    double core = value;
    switch (spec->unit) {
      case Unit::kCount:
        if (value != std::floor(value) || value < 1 || value > 1000) {
          return Bad(field, Num(value) + " must be a whole number in 1..1000");
        }
        break;
      case Unit::kRadians:
        if (std::fabs(value) >= 1.0) return Bad(field, Num(value) + " must be in (-1, 1) radians");
        break;
      default:
        if (spec->zero_ok ? value < 0 : value <= 0) {
          return Bad(field, Num(value) + (spec->zero_ok ? " must be >= 0" : " must be positive"));
        }
        break;
    }
    if (spec->unit == Unit::kMetres) core = value / resolution;
    if (spec->unit == Unit::kCubicMetres) core = value / (resolution * resolution * resolution);
    spec->set(config, core);
  }
  absl::Status valid;
  switch (config.planner) {
    case LocalPlannerKind::kDwa:
      valid = ValidateDwaOptions(config.dwa);
      break;
    case LocalPlannerKind::kOrca:
      valid = ValidateOrcaOptions(config.orca);
      break;
    case LocalPlannerKind::kFiras:
      valid = ValidateFirasOptions(config.firas);
      break;
  }
  if (!valid.ok()) {
    return absl::InvalidArgumentError(
        absl::StrCat("open.control.local_options: ", valid.message()));
  }
  return absl::OkStatus();
}

v1::LocalOutcome OutcomeOf(LocalStatus status) {
  switch (status) {
    case LocalStatus::kOk:
      return v1::LOCAL_OUTCOME_OK;
    case LocalStatus::kBlocked:
      return v1::LOCAL_OUTCOME_BLOCKED;
    case LocalStatus::kLocalMinimum:
      return v1::LOCAL_OUTCOME_LOCAL_MINIMUM;
    case LocalStatus::kGoalReached:
      return v1::LOCAL_OUTCOME_GOAL_REACHED;
  }
  return v1::LOCAL_OUTCOME_UNSPECIFIED;
}

void AddWorldPose(const Grid& grid, const Pose& pose, v1::VelocityCommand* command) {
  const WorldPoint w = grid.CellPointToWorld(pose.point());
  v1::WorldPose* out = command->add_trajectory();
  out->set_x(w.x);
  out->set_y(w.y);
  out->set_yaw(NormalizeAngle(pose.yaw + grid.frame_yaw()));
}

// A world-frame vector (m/s) in the grid frame (cells/s).
CellPoint WorldToGridVelocity(const Grid& grid, double vx, double vy) {
  const double c = std::cos(grid.frame_yaw());
  const double s = std::sin(grid.frame_yaw());
  return CellPoint{(c * vx + s * vy) / grid.resolution(),
                   (-s * vx + c * vy) / grid.resolution()};
}

}  // namespace

absl::StatusOr<ControlConfig> DecodeControlOptions(const v1::ControlOptions& control,
                                                   const v1::PlanOptions& options,
                                                   const Grid& grid) {
  const double res = grid.resolution();
  ControlConfig config;
  switch (control.local_planner()) {
    case v1::LOCAL_PLANNER_UNSPECIFIED:
    case v1::LOCAL_PLANNER_ORCA:
      config.planner = LocalPlannerKind::kOrca;
      break;
    case v1::LOCAL_PLANNER_DWA:
      config.planner = LocalPlannerKind::kDwa;
      break;
    case v1::LOCAL_PLANNER_FIRAS:
      config.planner = LocalPlannerKind::kFiras;
      break;
    default:
      return Bad("local_planner", absl::StrFormat("%d is not a LocalPlanner value",
                                                  static_cast<int>(control.local_planner())));
  }
  const v1::VelocityLimits& l = control.limits();
  PATHD_ASSIGN_OR_RETURN(const double max_v, Limit("max_v", l.max_v(), 0.5));
  if (!std::isfinite(l.min_v()) || l.min_v() > max_v) {
    return Bad("limits.min_v",
               absl::StrFormat("%s must be finite and at most max_v (%s)", Num(l.min_v()),
                               Num(max_v)));
  }
  if (!l.holonomic() && l.max_vy() != 0) {
    return Bad("limits.max_vy",
               absl::StrFormat("%s is for a holonomic robot (limits.holonomic)", Num(l.max_vy())));
  }
  PATHD_ASSIGN_OR_RETURN(const double max_vy, Limit("max_vy", l.max_vy(), max_v));
  PATHD_ASSIGN_OR_RETURN(const double max_w, Limit("max_w", l.max_w(), 1.5));
  PATHD_ASSIGN_OR_RETURN(const double acc_v, Limit("acc_v", l.acc_v(), 1.0));
  PATHD_ASSIGN_OR_RETURN(const double acc_vy, Limit("acc_vy", l.acc_vy(), 1.0));
  PATHD_ASSIGN_OR_RETURN(const double acc_w, Limit("acc_w", l.acc_w(), 3.0));
  config.limits.max_v = max_v / res;
  config.limits.min_v = l.min_v() / res;
  config.limits.max_vy = l.holonomic() ? max_vy / res : 0.0;
  config.limits.max_w = max_w;
  config.limits.acc_v = acc_v / res;
  config.limits.acc_vy = acc_vy / res;
  config.limits.acc_w = acc_w;
  config.limits.holonomic = l.holonomic();
  if (absl::Status s = ValidateVelocityLimits(config.limits); !s.ok()) {
    return absl::InvalidArgumentError(absl::StrCat("open.control.limits: ", s.message()));
  }

  const auto seconds = [](const char* name, double value, double fallback, double lo,
                          double hi) -> absl::StatusOr<double> {
    if (value == 0) return fallback;
    if (!std::isfinite(value) || value < lo || value > hi) {
      return Bad(name, absl::StrFormat("%s must be in [%s, %s] seconds (0: the default %s)",
                                       Num(value), Num(lo), Num(hi), Num(fallback)));
    }
    return value;
  };
  PATHD_ASSIGN_OR_RETURN(config.period,
                         seconds("control_period", control.control_period(), 0.1, 0.01, 2.0));
  PATHD_ASSIGN_OR_RETURN(config.stale_after,
                         seconds("stale_after", control.stale_after(), 1.0, 0.001, 3600.0));
  PATHD_ASSIGN_OR_RETURN(config.forget_after,
                         seconds("forget_after", control.forget_after(), 10.0, 0.001, 86400.0));
  config.shared_clock = control.shared_clock();
  if (config.forget_after < config.stale_after) {
    return Bad("forget_after", absl::StrFormat("%s must be at least stale_after (%s)",
                                               Num(config.forget_after),
                                               Num(config.stale_after)));
  }

  // The robot's size: its radius, else the disc around its footprint.
  PATHD_ASSIGN_OR_RETURN(std::optional<Footprint> footprint,
                         FootprintFromOptions(options, grid));
  switch (options.robot_radius_case()) {
    case v1::PlanOptions::kRobotRadiusM:
      config.radius = options.robot_radius_m() / res;
      break;
    case v1::PlanOptions::kRobotRadiusCells:
      config.radius = options.robot_radius_cells();
      break;
    default:
      if (footprint.has_value()) config.radius = footprint->circumscribed_radius();
      break;
  }
  if (!std::isfinite(config.radius) || config.radius <= 0) {
    return absl::InvalidArgumentError(
        "open.options.robot_radius: a control session needs the robot's size: a positive "
        "robot_radius_m (or _cells) or a footprint");
  }
  if (footprint.has_value()) {
    config.footprint = std::move(footprint);
  } else {
    PATHD_ASSIGN_OR_RETURN(Footprint disc, Footprint::Circle(config.radius));
    config.footprint = std::move(disc);
  }

  SetMetreDefaults(res, config);
  PATHD_RETURN_IF_ERROR(ApplyLocalOptions(control, res, config));
  return config;
}

void CycleHistogram::Observe(double seconds) {
  const size_t bucket = static_cast<size_t>(
      std::lower_bound(kBounds.begin(), kBounds.end(), seconds) - kBounds.begin());
  absl::MutexLock lock(&mu_);
  ++data_.counts[bucket];
  data_.sum += seconds;
  ++data_.count;
}

CycleHistogram::Snapshot CycleHistogram::Read() const {
  absl::MutexLock lock(&mu_);
  return data_;
}

ControlSession::ControlSession(Deps deps, ControlConfig config, std::string map,
                               uint64_t robot_id)
    : deps_(deps), config_(std::move(config)), map_(std::move(map)), robot_id_(robot_id) {
  if (config_.planner == LocalPlannerKind::kDwa) {
    FootprintCheckerOptions options;
    // DWA's rollouts check poses at most two margins of motion apart.
    options.margin_cells = 0.25;
    absl::StatusOr<std::shared_ptr<const FootprintChecker>> checker =
        SharedFootprintChecker(*config_.footprint, options);
    if (checker.ok()) checker_ = *std::move(checker);
  }
}

void ControlSession::SetPath(GlobalPath path) {
  absl::MutexLock lock(&path_mu_);
  path.generation = next_generation_++;
  path_ = std::make_shared<const GlobalPath>(std::move(path));
}

int64_t ControlSession::bytes() const {
  int64_t total = static_cast<int64_t>(sizeof(*this));
  {
    absl::MutexLock lock(&path_mu_);
    if (path_ != nullptr) {
      total += static_cast<int64_t>(path_->points.capacity() * sizeof(CellPoint) +
                                    path_->plan.SpaceUsedLong());
    }
  }
  absl::MutexLock lock(&mu_);
  total += static_cast<int64_t>(progress_.remaining.size() * sizeof(double) +
                                carried_.capacity() * sizeof(CellPoint));
  return total;
}

absl::Status ControlSession::RefreshStatics() {
  absl::StatusOr<std::shared_ptr<const MapSnapshot>> latest = deps_.store.Get(map_);
  if (!latest.ok()) {
    return absl::NotFoundError(
        absl::StrFormat("map '%s' was deleted during the navigation session", map_));
  }
  if (snapshot_ != nullptr && (*latest)->version == snapshot_->version) return absl::OkStatus();
  snapshot_ = *std::move(latest);
  const Grid& grid = *snapshot_->grid;
  std::unique_ptr<DerivedStore> store;
  if (deps_.derived != nullptr) store = deps_.derived->For(snapshot_, snapshot_->grid, 0.0);
  switch (config_.planner) {
    case LocalPlannerKind::kOrca:
      // ORCA's static lines: the boundary segments of the map's free space,
      // one set per version shared by every session on it.
      polygons_ = GetDerived<ObstaclePolygons>(
          store.get(), grid, "obstacle_polygons unknown_is_free=0",
          [](const Grid& g) { return ObstaclePolygons::Build(FreeSpace(g, false)); },
          [](const ObstaclePolygons&, const Grid&, absl::Span<const Cell>) {
            return std::shared_ptr<const ObstaclePolygons>();
          },
          [](const ObstaclePolygons& p) { return p.bytes(); });
      break;
    case LocalPlannerKind::kDwa:
      distance_ = GetObstacleDistance(store.get(), grid, /*unknown_is_free=*/false);
      break;
    case LocalPlannerKind::kFiras:
      break;
  }
  return absl::OkStatus();
}

absl::Status ControlSession::Cycle(const v1::RobotState& state,
                                   v1::NavigateResponse* response, Cell* robot_cell,
                                   std::optional<DetourRequest>* detour) {
  const SteadyTime received = std::chrono::steady_clock::now();
  std::shared_ptr<const GlobalPath> path;
  {
    absl::MutexLock lock(&path_mu_);
    path = path_;
  }
  absl::MutexLock lock(&mu_);
  PATHD_RETURN_IF_ERROR(RefreshStatics());
  const Grid& grid = *snapshot_->grid;
  const double res = grid.resolution();

  // The state, in cells and the grid frame.
  PATHD_ASSIGN_OR_RETURN(const PositionPose pose,
                         PoseFromPosition(state.pose(), grid, "state.pose"));
  for (const auto& [name, value] :
       {std::pair<const char*, double>{"v", state.v()}, {"vy", state.vy()}, {"w", state.w()},
        {"stamp", state.stamp()}}) {
    if (!std::isfinite(value)) {
      return absl::InvalidArgumentError(
          absl::StrFormat("state.%s %s must be finite", name, Num(value)));
    }
  }
  if (!config_.limits.holonomic && state.vy() != 0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "state.vy %s: the robot is not holonomic (open.control.limits.holonomic)",
        Num(state.vy())));
  }
  RobotState robot;
  robot.pose = pose.pose;
  if (!pose.has_yaw) robot.pose.yaw = last_yaw_;
  last_yaw_ = robot.pose.yaw;
  robot.v = state.v() / res;
  robot.vy = state.vy() / res;
  robot.w = state.w();
  *robot_cell = robot.pose.cell();

  // Reported obstacles: this message only, not reacting.
  std::vector<MovingObstacle> obstacles;
  obstacles.reserve(static_cast<size_t>(state.obstacles_size()));
  for (int i = 0; i < state.obstacles_size(); ++i) {
    const v1::MovingObstacleReport& report = state.obstacles(i);
    const std::string what = absl::StrFormat("state.obstacles[%d]", i);
    PATHD_ASSIGN_OR_RETURN(const PositionPose at,
                           PoseFromPosition(report.position(), grid, what + ".position"));
    if (!std::isfinite(report.vx()) || !std::isfinite(report.vy())) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "%s.vx, vy (%s, %s) must be finite", what, Num(report.vx()), Num(report.vy())));
    }
    if (!std::isfinite(report.radius()) || report.radius() < 0) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "%s.radius %s must be finite and >= 0 (metres)", what, Num(report.radius())));
    }
    MovingObstacle obstacle;
    obstacle.position = at.pose.point();
    obstacle.velocity = WorldToGridVelocity(grid, report.vx(), report.vy());
    obstacle.radius = report.radius() / res;
    obstacle.reciprocal = false;
    obstacles.push_back(obstacle);
  }

  // Published before the others are read: two robots answered at the same
  // time then see each other's newest state.
  const double c = std::cos(robot.pose.yaw);
  const double s = std::sin(robot.pose.yaw);
  RobotReport report;
  report.position = robot.pose.point();
  report.velocity = CellPoint{c * robot.v - s * robot.vy, s * robot.v + c * robot.vy};
  report.radius = config_.radius;
  report.received = received;
  report.stale_after = std::chrono::duration<double>(config_.stale_after);
  report.forget_after = std::chrono::duration<double>(config_.forget_after);
  report.stamp = state.stamp();
  report.shared_clock = config_.shared_clock;
  deps_.robots.Publish(map_, robot_id_, report);

  double range = 0.0;
  switch (config_.planner) {
    case LocalPlannerKind::kOrca:
      range = config_.orca.neighbour_range;
      break;
    case LocalPlannerKind::kDwa:
      // Whatever the rollouts may meet: both robots at full speed over the
      // horizon, plus the clearance the obstacle critic looks at.
      range = 2.0 * std::max(config_.limits.max_v, config_.limits.max_vy) * config_.dwa.horizon +
              config_.dwa.clearance_limit + config_.radius;
      break;
    case LocalPlannerKind::kFiras:
      range = config_.firas.influence + config_.radius;
      break;
  }
  std::vector<MovingObstacle> robots =
      deps_.robots.Near(map_, robot_id_, robot.pose.point(), range, received,
                        config_.shared_clock ? std::optional<double>(state.stamp())
                                             : std::nullopt);
  obstacles.insert(obstacles.end(), robots.begin(), robots.end());

  response->set_event(v1::NAVIGATE_EVENT_CONTROL);
  v1::VelocityCommand* command = response->mutable_command();
  command->set_stamp(state.stamp());
  command->set_neighbours(static_cast<int32_t>(obstacles.size()));
  if (path != nullptr) {
    command->set_map_version(path->map_version);
    if (path->generation > sent_generation_) {
      sent_generation_ = path->generation;
      // Replans published while no answer went out may end on the rest of
      // the path the client has: that is not news.
      const std::vector<CellPoint>& next = path->points;
      const bool rest_of_carried =
          !next.empty() && next.size() <= carried_.size() &&
          std::equal(next.begin(), next.end(),
                     carried_.end() - static_cast<std::ptrdiff_t>(next.size()),
                     [](const CellPoint& a, const CellPoint& b) {
                       return a.x == b.x && a.y == b.y;
                     });
      if (!rest_of_carried) {
        *response->mutable_plan() = path->plan;
        carried_ = next;
      }
    }
  }
  if (path == nullptr || path->points.empty()) {
    command->set_outcome(v1::LOCAL_OUTCOME_NO_PATH);
    command->set_reason(path == nullptr || path->plan.reason().empty()
                            ? "no global path to the goal"
                            : absl::StrCat("no global path: ", path->plan.reason()));
    AddWorldPose(grid, robot.pose, command);
    return absl::OkStatus();
  }

  absl::StatusOr<LocalPlan> plan;
  switch (config_.planner) {
    case LocalPlannerKind::kOrca: {
      const std::vector<ObstacleSegment> segments =
          ObstacleSegmentsNear(*polygons_, robot.pose.point(),
                               config_.orca.obstacle_range + config_.radius,
                               config_.orca.max_obstacle_lines);
      plan = OrcaStep(robot, config_.radius, config_.limits, obstacles, segments, path->points,
                      config_.period, config_.orca, &progress_);
      break;
    }
    case LocalPlannerKind::kDwa: {
      if (checker_ == nullptr) return absl::InternalError("DWA's footprint checker is missing");
      DwaMap map{&grid, checker_.get(), distance_->data()};
      plan = DwaStep(map, robot, config_.limits, obstacles, path->points, config_.period,
                     config_.dwa, /*rollouts=*/nullptr, &progress_);
      break;
    }
    case LocalPlannerKind::kFiras:
      plan = FirasStep(grid, robot, config_.radius, config_.limits, obstacles, path->points,
                       config_.period, config_.firas, &progress_);
      break;
  }
  if (!plan.ok()) {
    return absl::InvalidArgumentError(absl::StrCat("state: ", plan.status().message()));
  }
  if (detour != nullptr) *detour = DetourFor(robot, *plan, obstacles);
  command->set_v(plan->v * res);
  command->set_vy(plan->vy * res);
  command->set_w(plan->w);
  command->set_outcome(OutcomeOf(plan->status));
  command->set_reason(plan->reason);
  for (const Pose& p : plan->trajectory) AddWorldPose(grid, p, command);
  if (plan->trajectory.empty()) AddWorldPose(grid, robot.pose, command);
  return absl::OkStatus();
}

std::optional<DetourRequest> ControlSession::DetourFor(
    const RobotState& robot, const LocalPlan& plan,
    const std::vector<MovingObstacle>& obstacles) {
  ++cycles_since_detour_;
  if (config_.detour_range <= 0) return std::nullopt;
  const CellPoint at = robot.pose.point();
  if (!blockers_.empty() &&
      std::hypot(at.x - detour_origin_.x, at.y - detour_origin_.y) >= detour_clear_) {
    const bool still_there = std::any_of(
        blockers_.begin(), blockers_.end(), [&](const DetourRequest::Disc& d) {
          return std::any_of(obstacles.begin(), obstacles.end(), [&](const MovingObstacle& o) {
            return std::hypot(o.position.x - d.centre.x, o.position.y - d.centre.y) < d.radius;
          });
        });
    if (!still_there) {
      blockers_.clear();
      DetourRequest lift;
      lift.robot = at;
      lift.robot_radius = config_.radius;
      lift.lift = true;
      return lift;
    }
  }
  if (plan.status == LocalStatus::kGoalReached) return std::nullopt;
  const auto [window_seconds, min_progress] = StallRule(config_);
  const double window_cycles = std::ceil(window_seconds / config_.period);
  if (!plan.progress.has_value() || *plan.progress >= min_progress ||
      static_cast<double>(cycles_since_detour_) < window_cycles) {
    return std::nullopt;
  }
  // What stands in the way: slow discs near the robot's (a neighbour that
  // moves on is ORCA's business, not a detour's).
  DetourRequest request;
  request.robot = at;
  request.robot_radius = config_.radius;
  const double slow = 0.3 * std::max(config_.limits.max_v, config_.limits.max_vy);
  for (const MovingObstacle& o : obstacles) {
    const double gap = std::hypot(o.position.x - request.robot.x, o.position.y - request.robot.y) -
                       o.radius - config_.radius;
    if (gap > config_.detour_range) continue;
    if (std::hypot(o.velocity.x, o.velocity.y) > slow) continue;
    request.blockers.push_back(DetourRequest::Disc{o.position, o.radius});
  }
  // Gaps too tight for the robot: looked for by the replan (worker pool),
  // not here.
  request.clearance = config_.radius + SafetyMargin(config_);
  request.ahead = config_.detour_range;
  cycles_since_detour_ = 0;
  if (!request.blockers.empty()) {
    // These replace the last blockers; a stall with none keeps them.
    blockers_ = request.blockers;
    detour_origin_ = request.robot;
    double farthest = 0.0;
    for (const DetourRequest::Disc& d : request.blockers) {
      farthest = std::max(farthest, std::hypot(d.centre.x - at.x, d.centre.y - at.y) + d.radius);
    }
    // Past the farthest blocker by the robot's own size.
    detour_clear_ = farthest + 2.0 * config_.radius;
  }
  return request;
}

}  // namespace pathd::server
