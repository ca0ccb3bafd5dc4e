#include "client/pathctl/simulate.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "yaml-cpp/yaml.h"

namespace pathd::pathctl {
namespace {

// The server's documented defaults (proto VelocityLimits, ControlOptions),
// made explicit so that the referee knows every limit.
constexpr double kDefaultMaxV = 0.5;
constexpr double kDefaultMaxW = 1.5;
constexpr double kDefaultAccV = 1.0;
constexpr double kDefaultAccW = 3.0;

// Reads scenario values with errors that name the key.
class Reader {
 public:
  explicit Reader(std::string source) : source_(std::move(source)) {}

  absl::Status Error(const std::string& where, const std::string& what) const {
    return absl::InvalidArgumentError(absl::StrCat(source_, ": ", where, ": ", what));
  }

  // A finite number; `positive`: > 0, else >= `min`.
  absl::StatusOr<double> Number(const YAML::Node& node, const std::string& where,
                                bool positive, double min = -1e300) const {
    if (!node.IsScalar()) return Error(where, "expected a number");
    double value = 0.0;
    try {
      value = node.as<double>();
    } catch (const YAML::Exception&) {
      return Error(where, absl::StrCat("'", node.Scalar(), "' is not a number"));
    }
    if (!std::isfinite(value)) return Error(where, "must be finite");
    if (positive && value <= 0.0) return Error(where, absl::StrCat("must be > 0 (got ", node.Scalar(), ")"));
    if (!positive && value < min) {
      return Error(where, absl::StrFormat("must be >= %g (got %s)", min, node.Scalar()));
    }
    return value;
  }

  // [x, y] or, with `yaw_ok`, [x, y, yaw].
  absl::StatusOr<std::vector<double>> Point(const YAML::Node& node, const std::string& where,
                                            bool yaw_ok) const {
    if (!node.IsSequence() || node.size() < 2 || node.size() > (yaw_ok ? 3u : 2u)) {
      return Error(where, yaw_ok ? "expected [x, y] or [x, y, yaw] (metres, radians)"
                                 : "expected [x, y] (metres)");
    }
    std::vector<double> out;
    for (size_t i = 0; i < node.size(); ++i) {
      absl::StatusOr<double> v = Number(node[i], absl::StrCat(where, "[", i, "]"), false);
      if (!v.ok()) return v.status();
      out.push_back(*v);
    }
    return out;
  }

 private:
  std::string source_;
};

absl::StatusOr<v1::LocalPlanner> LocalPlannerOf(const std::string& name) {
  if (name == "orca") return v1::LOCAL_PLANNER_ORCA;
  if (name == "dwa") return v1::LOCAL_PLANNER_DWA;
  if (name == "firas") return v1::LOCAL_PLANNER_FIRAS;
  return absl::InvalidArgumentError(absl::StrCat("'", name, "' is not dwa, orca or firas"));
}

// Applies the robot keys of `node` (a robot or the defaults) to `robot`.
// `where` names the node in errors; `is_robot` allows name, start and goal.
absl::Status ApplyRobotKeys(const Reader& r, const YAML::Node& node, const std::string& where,
                            bool is_robot, SimRobotSpec& robot, bool& has_start,
                            bool& has_goal) {
  if (!node.IsMap()) return r.Error(where, "expected a mapping of robot keys");
  for (const auto& entry : node) {
    const std::string key = entry.first.as<std::string>();
    const YAML::Node& value = entry.second;
    const std::string at = absl::StrCat(where, ".", key);
    const auto number = [&](double& out, bool positive, double min = 0.0) -> absl::Status {
      absl::StatusOr<double> v = r.Number(value, at, positive, min);
      if (!v.ok()) return v.status();
      out = *v;
      return absl::OkStatus();
    };
    absl::Status s;
    if (is_robot && key == "name") {
      if (!value.IsScalar()) return r.Error(at, "expected a string");
      robot.name = value.Scalar();
    } else if (is_robot && key == "start") {
      absl::StatusOr<std::vector<double>> p = r.Point(value, at, true);
      if (!p.ok()) return p.status();
      robot.start_x = (*p)[0];
      robot.start_y = (*p)[1];
      robot.start_yaw = p->size() > 2 ? (*p)[2] : 0.0;
      has_start = true;
    } else if (is_robot && key == "goal") {
      absl::StatusOr<std::vector<double>> p = r.Point(value, at, false);
      if (!p.ok()) return p.status();
      robot.goal_x = (*p)[0];
      robot.goal_y = (*p)[1];
      has_goal = true;
    } else if (key == "radius") {
      s = number(robot.radius, true);
    } else if (key == "inflation_radius") {
      s = number(robot.inflation_radius, false, 0.0);
    } else if (key == "goal_tolerance") {
      s = number(robot.goal_tolerance, true);
    } else if (key == "drive") {
      if (!value.IsScalar() || (value.Scalar() != "diff" && value.Scalar() != "omni")) {
        return r.Error(at, "must be diff (differential drive) or omni (omnidirectional)");
      }
      robot.limits.set_holonomic(value.Scalar() == "omni");
    } else if (key == "local_planner") {
      absl::StatusOr<v1::LocalPlanner> p =
          value.IsScalar() ? LocalPlannerOf(value.Scalar())
                           : absl::InvalidArgumentError("expected dwa, orca or firas");
      if (!p.ok()) return r.Error(at, std::string(p.status().message()));
      robot.local_planner = *p;
    } else if (key == "max_v" || key == "max_vy" || key == "max_w" || key == "acc_v" ||
               key == "acc_vy" || key == "acc_w") {
      double v = 0.0;
      s = number(v, true);
      if (key == "max_v") robot.limits.set_max_v(v);
      if (key == "max_vy") robot.limits.set_max_vy(v);
      if (key == "max_w") robot.limits.set_max_w(v);
      if (key == "acc_v") robot.limits.set_acc_v(v);
      if (key == "acc_vy") robot.limits.set_acc_vy(v);
      if (key == "acc_w") robot.limits.set_acc_w(v);
    } else if (key == "min_v") {
      double v = 0.0;
      s = number(v, false, -1e300);
      if (v > 0.0) return r.Error(at, "must be <= 0 (negative lets the robot reverse)");
      robot.limits.set_min_v(v);
    } else if (key == "options") {
      if (!value.IsMap()) return r.Error(at, "expected a mapping of local planner options");
      for (const auto& option : value) {
        const std::string name = option.first.as<std::string>();
        absl::StatusOr<double> v = r.Number(option.second, absl::StrCat(at, ".", name), false);
        if (!v.ok()) return v.status();
        robot.local_options[name] = *v;  // the server names a bad one
      }
    } else {
      return r.Error(at, is_robot ? "unknown robot key (name, start, goal, radius, "
                                    "inflation_radius, goal_tolerance, drive, local_planner, max_v, min_v, "
                                    "max_vy, max_w, acc_v, acc_vy, acc_w, options)"
                                  : "unknown key in defaults (radius, inflation_radius, goal_tolerance, drive, "
                                    "local_planner, max_v, min_v, max_vy, max_w, acc_v, "
                                    "acc_vy, acc_w, options)");
    }
    if (!s.ok()) return s;
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<SimScenario> ParseScenario(const std::string& yaml_text,
                                          const std::string& source) {
  const Reader r(source);
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    return absl::InvalidArgumentError(absl::StrCat(source, ": not YAML: ", e.what()));
  }
  if (!root.IsMap()) return r.Error("document", "expected a mapping with map and robots");
  SimScenario scenario;
  SimRobotSpec defaults;
  defaults.limits.set_max_v(kDefaultMaxV);
  defaults.limits.set_max_w(kDefaultMaxW);
  defaults.limits.set_acc_v(kDefaultAccV);
  defaults.limits.set_acc_vy(kDefaultAccV);
  defaults.limits.set_acc_w(kDefaultAccW);
  // Defaults first: robots listed before them still take them.
  if (root["defaults"]) {
    bool unused_start = false, unused_goal = false;
    if (absl::Status s = ApplyRobotKeys(r, root["defaults"], "defaults", false, defaults,
                                        unused_start, unused_goal);
        !s.ok()) {
      return s;
    }
  }
  for (const auto& entry : root) {
    const std::string key = entry.first.as<std::string>();
    const YAML::Node& value = entry.second;
    const auto number = [&](double& out) -> absl::Status {
      absl::StatusOr<double> v = r.Number(value, key, true);
      if (!v.ok()) return v.status();
      out = *v;
      return absl::OkStatus();
    };
    absl::Status s;
    if (key == "map") {
      if (!value.IsScalar() || value.Scalar().empty()) return r.Error(key, "expected a map name");
      scenario.map = value.Scalar();
    } else if (key == "map_file") {
      if (!value.IsScalar() || value.Scalar().empty()) return r.Error(key, "expected a file name");
      scenario.map_file = value.Scalar();
      const size_t slash = source.rfind('/');
      if (scenario.map_file[0] != '/' && slash != std::string::npos) {
        scenario.map_file = absl::StrCat(source.substr(0, slash + 1), scenario.map_file);
      }
    } else if (key == "map_resolution") {
      s = number(scenario.map_resolution);
    } else if (key == "step") {
      s = number(scenario.step);
    } else if (key == "control_period") {
      s = number(scenario.control_period);
    } else if (key == "duration") {
      s = number(scenario.duration);
    } else if (key == "deadlock_window") {
      s = number(scenario.deadlock_window);
    } else if (key == "deadlock_distance") {
      s = number(scenario.deadlock_distance);
    } else if (key == "sensor_range") {
      s = number(scenario.sensor_range);
    } else if (key == "defaults" || key == "robots" || key == "obstacles") {
      continue;
    } else {
      return r.Error(key, "unknown key (map, map_file, map_resolution, step, control_period, duration, deadlock_window, "
                          "deadlock_distance, sensor_range, defaults, robots, obstacles)");
    }
    if (!s.ok()) return s;
  }
  if (scenario.map.empty()) return r.Error("map", "missing: the name of a map on the server");
  if (scenario.control_period < scenario.step) {
    return r.Error("control_period", absl::StrFormat("%g s is shorter than step %g s",
                                                     scenario.control_period, scenario.step));
  }
  if (scenario.duration > 3600.0) return r.Error("duration", "at most 3600 simulated seconds");
  if (scenario.duration / scenario.step > 1e7) {
    return r.Error("step", "more than 10 million steps: use a longer step or a shorter duration");
  }

  const YAML::Node robots = root["robots"];
  if (!robots || !robots.IsSequence() || robots.size() == 0) {
    return r.Error("robots", "missing: a list of robots (start and goal each)");
  }
  for (size_t i = 0; i < robots.size(); ++i) {
    SimRobotSpec robot = defaults;
    robot.name = absl::StrCat("r", i);
    bool has_start = false, has_goal = false;
    const std::string where = absl::StrCat("robots[", i, "]");
    if (absl::Status s = ApplyRobotKeys(r, robots[i], where, true, robot, has_start, has_goal);
        !s.ok()) {
      return s;
    }
    if (!has_start) return r.Error(absl::StrCat(where, " (", robot.name, ")"), "start missing");
    if (!has_goal) return r.Error(absl::StrCat(where, " (", robot.name, ")"), "goal missing");
    if (robot.limits.holonomic() && robot.limits.max_vy() == 0.0) {
      robot.limits.set_max_vy(robot.limits.max_v());
    }
    scenario.robots.push_back(std::move(robot));
  }
  for (size_t i = 0; i < scenario.robots.size(); ++i) {
    for (size_t j = 0; j < i; ++j) {
      if (scenario.robots[i].name == scenario.robots[j].name) {
        return r.Error(absl::StrCat("robots[", i, "].name"),
                       absl::StrCat("'", scenario.robots[i].name, "' is also robots[", j, "]'s"));
      }
    }
  }
  if (const YAML::Node obstacles = root["obstacles"]) {
    if (!obstacles.IsSequence()) return r.Error("obstacles", "expected a list");
    for (size_t i = 0; i < obstacles.size(); ++i) {
      const std::string where = absl::StrCat("obstacles[", i, "]");
      const YAML::Node& node = obstacles[i];
      if (!node.IsMap() || !node["start"] || !node["velocity"]) {
        return r.Error(where, "expected start: [x, y], velocity: [vx, vy], radius: R");
      }
      SimObstacleSpec o;
      absl::StatusOr<std::vector<double>> p = r.Point(node["start"], where + ".start", false);
      if (!p.ok()) return p.status();
      absl::StatusOr<std::vector<double>> v = r.Point(node["velocity"], where + ".velocity", false);
      if (!v.ok()) return v.status();
      o.x = (*p)[0];
      o.y = (*p)[1];
      o.vx = (*v)[0];
      o.vy = (*v)[1];
      if (node["radius"]) {
        absl::StatusOr<double> radius = r.Number(node["radius"], where + ".radius", true);
        if (!radius.ok()) return radius.status();
        o.radius = *radius;
      }
      scenario.obstacles.push_back(o);
    }
  }
  return scenario;
}

SimPose IntegrateBody(const SimPose& pose, double v, double vy, double w, double seconds) {
  SimPose out = pose;
  if (std::abs(w) < 1e-9) {
    const double c = std::cos(pose.yaw), s = std::sin(pose.yaw);
    out.x += (v * c - vy * s) * seconds;
    out.y += (v * s + vy * c) * seconds;
    return out;
  }
  // The body velocity turns with the heading: integrate
  // R(yaw0 + w t) (v, vy) exactly.
  const double yaw1 = pose.yaw + w * seconds;
  const double s0 = std::sin(pose.yaw), c0 = std::cos(pose.yaw);
  const double s1 = std::sin(yaw1), c1 = std::cos(yaw1);
  out.x += (v * (s1 - s0) + vy * (c1 - c0)) / w;
  out.y += (-v * (c1 - c0) + vy * (s1 - s0)) / w;
  out.yaw = std::remainder(yaw1, 2.0 * M_PI);
  return out;
}

std::string LimitViolation(const v1::VelocityLimits& limits, double v, double vy, double w,
                           double prev_v, double prev_vy, double prev_w, double period) {
  constexpr double kSlack = 1e-6;
  if (v > limits.max_v() + kSlack || v < limits.min_v() - kSlack) {
    return absl::StrFormat("v %.4f m/s outside [%g, %g]", v, limits.min_v(), limits.max_v());
  }
  if (std::abs(vy) > (limits.holonomic() ? limits.max_vy() : 0.0) + kSlack) {
    return absl::StrFormat("vy %.4f m/s beyond %g", vy, limits.holonomic() ? limits.max_vy() : 0.0);
  }
  if (std::abs(w) > limits.max_w() + kSlack) {
    return absl::StrFormat("w %.4f rad/s beyond %g", w, limits.max_w());
  }
  if (std::abs(v - prev_v) > limits.acc_v() * period + kSlack) {
    return absl::StrFormat("v changed by %.4f m/s in one period (acc_v allows %.4f)",
                           v - prev_v, limits.acc_v() * period);
  }
  if (std::abs(vy - prev_vy) > limits.acc_vy() * period + kSlack) {
    return absl::StrFormat("vy changed by %.4f m/s in one period (acc_vy allows %.4f)",
                           vy - prev_vy, limits.acc_vy() * period);
  }
  if (std::abs(w - prev_w) > limits.acc_w() * period + kSlack) {
    return absl::StrFormat("w changed by %.4f rad/s in one period (acc_w allows %.4f)",
                           w - prev_w, limits.acc_w() * period);
  }
  return "";
}

const char* SimEndName(SimEnd end) {
  switch (end) {
    case SimEnd::kArrived:
      return "arrived";
    case SimEnd::kUnreachable:
      return "unreachable";
    case SimEnd::kDeadlocked:
      return "deadlock";
    case SimEnd::kTimedOut:
      return "timed out";
  }
  return "?";
}

SimReferee::SimReferee(const SimScenario& scenario, const Grid& grid)
    : scenario_(scenario),
      grid_(grid),
      results_(scenario.robots.size()),
      last_(scenario.robots.size()),
      history_(scenario.robots.size()),
      last_sample_t_(scenario.robots.size(), -1e300),
      prev_command_(scenario.robots.size(), {0.0, 0.0, 0.0}) {
  for (size_t i = 0; i < scenario.robots.size(); ++i) {
    const SimRobotSpec& r = scenario.robots[i];
    last_[i] = {r.start_x, r.start_y, r.start_yaw};
  }
}

bool SimReferee::TouchesMap(const SimPose& pose, double radius) const {
  // The disc in cell coordinates (world frame = grid frame up to the
  // origin's translation: Nav2's convention, which pathd follows unless
  // --honour_origin_yaw; simulate_cmd refuses a rotated frame).
  const CellPoint c = grid_.WorldToCellPoint({pose.x, pose.y});
  const double rc = radius / grid_.resolution();
  const int32_t x0 = static_cast<int32_t>(std::floor(c.x - rc));
  const int32_t x1 = static_cast<int32_t>(std::floor(c.x + rc));
  const int32_t y0 = static_cast<int32_t>(std::floor(c.y - rc));
  const int32_t y1 = static_cast<int32_t>(std::floor(c.y + rc));
  for (int32_t y = y0; y <= y1; ++y) {
    for (int32_t x = x0; x <= x1; ++x) {
      // Outside the map counts as an obstacle: the robot left it.
      const bool blocked = !grid_.InBounds(x, y) || grid_.cost(x, y) >= kLethalCost;
      if (!blocked) continue;
      // Distance from the centre to the cell's square [x, x+1] x [y, y+1].
      const double dx = std::max({x - c.x, 0.0, c.x - (x + 1.0)});
      const double dy = std::max({y - c.y, 0.0, c.y - (y + 1.0)});
      if (dx * dx + dy * dy < rc * rc - 1e-9) return true;
    }
  }
  return false;
}

void SimReferee::Observe(double t, const std::vector<SimPose>& robots,
                         const std::vector<SimPose>& obstacles) {
  const size_t n = robots.size();
  // Pair keys: (i, j) robots, (i, -1) the map, (i, -2 - k) obstacle k.
  const auto touch = [&](int64_t a, int64_t b, bool now, const std::string& what) {
    bool& was = touching_[{a, b}];
    if (now && !was) contacts_.push_back({t, what});
    was = now;
  };
  for (size_t i = 0; i < n; ++i) {
    const SimRobotSpec& ri = scenario_.robots[i];
    results_[i].distance += std::hypot(robots[i].x - last_[i].x, robots[i].y - last_[i].y);
    last_[i] = robots[i];
    for (size_t j = i + 1; j < n; ++j) {
      const SimRobotSpec& rj = scenario_.robots[j];
      const double gap = std::hypot(robots[i].x - robots[j].x, robots[i].y - robots[j].y) -
                         ri.radius - rj.radius;
      results_[i].min_clearance = std::min(results_[i].min_clearance, gap);
      results_[j].min_clearance = std::min(results_[j].min_clearance, gap);
      if (gap < min_separation_) {
        min_separation_ = gap;
        min_pair_ = absl::StrCat(ri.name, " and ", rj.name);
        min_time_ = t;
      }
      touch(static_cast<int64_t>(i), static_cast<int64_t>(j), gap < 0.0,
            absl::StrFormat("%s and %s collide at (%.2f, %.2f)", ri.name, rj.name,
                            (robots[i].x + robots[j].x) / 2, (robots[i].y + robots[j].y) / 2));
    }
    touch(static_cast<int64_t>(i), -1, TouchesMap(robots[i], ri.radius),
          absl::StrFormat("%s touches an obstacle cell at (%.2f, %.2f)", ri.name, robots[i].x,
                          robots[i].y));
    for (size_t k = 0; k < obstacles.size(); ++k) {
      const double gap = std::hypot(robots[i].x - obstacles[k].x, robots[i].y - obstacles[k].y) -
                         ri.radius - scenario_.obstacles[k].radius;
      touch(static_cast<int64_t>(i), -2 - static_cast<int64_t>(k), gap < 0.0,
            absl::StrFormat("%s hits moving obstacle %d at (%.2f, %.2f)", ri.name, k,
                            robots[i].x, robots[i].y));
    }
    if (t - last_sample_t_[i] >= scenario_.control_period - 1e-9) {
      history_[i].push_back({t, robots[i].x, robots[i].y});
      last_sample_t_[i] = t;
      // Keep a little more than one window.
      const double keep_from = t - scenario_.deadlock_window - scenario_.control_period;
      auto& h = history_[i];
      size_t drop = 0;
      while (drop + 1 < h.size() && h[drop + 1].t <= keep_from) ++drop;
      if (drop > 64) h.erase(h.begin(), h.begin() + static_cast<ptrdiff_t>(drop));
    }
  }
}

void SimReferee::ReportGoalReached(size_t robot, double t, const SimPose& pose) {
  SimRobotResult& r = results_[robot];
  if (r.arrival_time >= 0.0) return;
  const SimRobotSpec& spec = scenario_.robots[robot];
  const double d = std::hypot(pose.x - spec.goal_x, pose.y - spec.goal_y);
  const double allowed = spec.goal_tolerance + grid_.resolution() * M_SQRT1_2;
  if (d <= allowed + 1e-9) {
    r.arrival_time = t;
    r.end = SimEnd::kArrived;
  } else if (r.detail.empty()) {
    r.detail = absl::StrFormat("the server said GOAL_REACHED %.3f m from the goal (allowed %.3f)",
                               d, allowed);
  }
}

void SimReferee::SetUnreachable(size_t robot, const std::string& why) {
  results_[robot].end = SimEnd::kUnreachable;
  results_[robot].detail = why;
}

void SimReferee::SetPathLength(size_t robot, double metres) { results_[robot].path_length = metres; }

void SimReferee::CheckCommand(size_t robot, double v, double vy, double w) {
  std::array<double, 3>& prev = prev_command_[robot];
  SimRobotResult& r = results_[robot];
  if (r.limit_violation.empty()) {
    r.limit_violation = LimitViolation(scenario_.robots[robot].limits, v, vy, w, prev[0],
                                       prev[1], prev[2], scenario_.control_period);
  }
  prev = {v, vy, w};
}

bool SimReferee::Stuck(size_t robot, double t) const {
  const auto& h = history_[robot];
  if (h.empty() || t < scenario_.deadlock_window) return false;
  // The sample at or before t - window, and every one since, within the
  // distance of the latest.
  const Sample& now = h.back();
  bool covered = false;
  for (auto it = h.rbegin(); it != h.rend(); ++it) {
    if (std::hypot(it->x - now.x, it->y - now.y) >= scenario_.deadlock_distance) return false;
    if (it->t <= t - scenario_.deadlock_window + 1e-9) {
      covered = true;
      break;
    }
  }
  return covered;
}

bool SimReferee::AllSettled(double t) const {
  for (size_t i = 0; i < results_.size(); ++i) {
    if (arrived(i) || results_[i].end == SimEnd::kUnreachable) continue;
    if (!Stuck(i, t)) return false;
  }
  return true;
}

void SimReferee::Finish(double t) {
  for (size_t i = 0; i < results_.size(); ++i) {
    SimRobotResult& r = results_[i];
    if (arrived(i) || r.end == SimEnd::kUnreachable) continue;
    const SimRobotSpec& spec = scenario_.robots[i];
    const double d = std::hypot(last_[i].x - spec.goal_x, last_[i].y - spec.goal_y);
    if (Stuck(i, t)) {
      r.end = SimEnd::kDeadlocked;
      // The robots nearest it: who it is stuck with.
      std::string near;
      for (size_t j = 0; j < results_.size(); ++j) {
        if (j == i) continue;
        const double gap = std::hypot(last_[i].x - last_[j].x, last_[i].y - last_[j].y) -
                           spec.radius - scenario_.robots[j].radius;
        if (gap < 2.0 * spec.radius) {
          absl::StrAppend(&near, near.empty() ? "" : ", ", scenario_.robots[j].name);
        }
      }
      r.detail = absl::StrFormat(
          "moved less than %g m in the last %g s, %.2f m from its goal%s%s", scenario_.deadlock_distance,
          scenario_.deadlock_window, d, near.empty() ? "" : "; next to ", near);
    } else {
      r.end = SimEnd::kTimedOut;
      r.detail = absl::StrFormat("still moving after %g s, %.2f m from its goal", t, d);
    }
  }
}

}  // namespace pathd::pathctl
