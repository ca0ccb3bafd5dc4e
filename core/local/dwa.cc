#include "core/local/dwa.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string_view>

#include "absl/strings/str_format.h"
#include "core/status_macros.h"

namespace pathd {
namespace {

// n values evenly across [lo, hi], both ends included (the middle for n = 1).
std::vector<double> Samples(double lo, double hi, int32_t n) {
  std::vector<double> out;
  if (n <= 1 || hi <= lo) {
    out.push_back(0.5 * (lo + hi));
    return out;
  }
  for (int32_t i = 0; i < n; ++i) out.push_back(lo + (hi - lo) * i / (n - 1));
  return out;
}

// The smallest distance from `p` to the path's segments first..last-1.
double DistanceToPath(absl::Span<const CellPoint> path, size_t first,
                      size_t last, CellPoint p) {
  if (path.size() == 1) return std::hypot(path[0].x - p.x, path[0].y - p.y);
  double best = std::numeric_limits<double>::infinity();
  for (size_t i = first; i < last && i + 1 < path.size(); ++i) {
    const CellPoint a = path[i], b = path[i + 1];
    const double dx = b.x - a.x, dy = b.y - a.y;
    const double len2 = dx * dx + dy * dy;
    const double t =
        len2 > 0
            ? std::clamp(((p.x - a.x) * dx + (p.y - a.y) * dy) / len2, 0.0, 1.0)
            : 0.0;
    best = std::min(best, std::hypot(a.x + t * dx - p.x, a.y + t * dy - p.y));
  }
  return best;
}

double Clamp01(double x) { return std::clamp(x, 0.0, 1.0); }

}  // namespace

absl::Status ValidateDwaOptions(const DwaOptions& o) {
  if (o.v_samples < 1 || o.v_samples > 1000 || o.w_samples < 1 ||
      o.w_samples > 1000 || o.vy_samples < 1 || o.vy_samples > 1000) {
    return absl::InvalidArgumentError(
        "dwa options: v_samples, w_samples and vy_samples must be in 1..1000");
  }
  if (o.max_sub_steps < 1 || o.max_sub_steps > 10000) {
    return absl::InvalidArgumentError(
        "dwa options: max_sub_steps must be in 1..10000");
  }
  PATHD_RETURN_IF_ERROR(
      CheckOptionValues("dwa",
                        {{"horizon", o.horizon},
                         {"sub_step", o.sub_step},
                         {"lookahead", o.lookahead},
                         {"clearance_limit", o.clearance_limit},
                         {"goal_tolerance", o.goal_tolerance},
                         {"window_seconds", o.window_seconds}},
                        /*zero_ok=*/false));
  PATHD_RETURN_IF_ERROR(
      CheckOptionValues("dwa",
                        {{"min_progress", o.min_progress},
                         {"path_distance_weight", o.path_distance_weight},
                         {"goal_distance_weight", o.goal_distance_weight},
                         {"heading_weight", o.heading_weight},
                         {"obstacle_weight", o.obstacle_weight},
                         {"speed_weight", o.speed_weight},
                         {"twirling_weight", o.twirling_weight}},
                        /*zero_ok=*/true));
  return absl::OkStatus();
}

DynamicWindow ComputeDynamicWindow(const RobotState& s, const VelocityLimits& l,
                                   double period) {
  const auto axis = [period](double current, double acc, double lo, double hi,
                             double* wlo, double* whi) {
    const double reach = acc * period;
    *wlo = std::max(lo, current - reach);
    *whi = std::min(hi, current + reach);
    if (*wlo > *whi) {
      *wlo = *whi = current > hi ? current - reach : current + reach;
    }
  };
  DynamicWindow w;
  axis(s.v, l.acc_v, l.min_v, l.max_v, &w.v_lo, &w.v_hi);
  axis(s.w, l.acc_w, -l.max_w, l.max_w, &w.w_lo, &w.w_hi);
  if (l.holonomic) {
    axis(s.vy, l.acc_vy, -l.max_vy, l.max_vy, &w.vy_lo, &w.vy_hi);
  }
  return w;
}

absl::StatusOr<LocalPlan> DwaStep(const DwaMap& map, const RobotState& state,
                                  const VelocityLimits& limits,
                                  absl::Span<const MovingObstacle> obstacles,
                                  absl::Span<const CellPoint> path,
                                  double period, const DwaOptions& options,
                                  std::vector<DwaRollout>* rollouts,
                                  ProgressWindow* progress) {
  if (absl::Status s = ValidateDwaOptions(options); !s.ok()) return s;
  if (absl::Status s = ValidateVelocityLimits(limits); !s.ok()) return s;
  if (map.grid == nullptr || map.checker == nullptr) {
    return absl::InvalidArgumentError(
        "dwa: the map needs a grid and a footprint checker");
  }
  if (!(std::isfinite(period) && period > 0)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "dwa: control period must be positive (got %g)", period));
  }
  if (path.empty())
    return absl::InvalidArgumentError("dwa: the global path is empty");
  if (rollouts != nullptr) rollouts->clear();

  const Grid& grid = *map.grid;
  const FootprintChecker& checker = *map.checker;
  const double r_circ = checker.footprint().circumscribed_radius();
  const double margin = checker.options().margin_cells;
  const CellPoint position = state.pose.point();
  const PathTarget target = FindPathTarget(path, position, options.lookahead);
  const bool at_goal = target.distance_to_goal <= options.goal_tolerance;
  // The path critic reads the segments from the robot's nearest one to as
  // far as the robot can get within the horizon (bounded work on long paths).
  const double reach =
      options.lookahead +
      options.horizon * std::max({std::fabs(limits.max_v),
                                  std::fabs(limits.min_v), limits.max_vy}) +
      1.0;
  size_t path_last = target.nearest_segment + 1;
  for (double along = 0; path_last < path.size(); ++path_last) {
    const CellPoint a = path[path_last - 1], b = path[path_last];
    along += std::hypot(b.x - a.x, b.y - a.y);
    if (along > reach) {
      ++path_last;
      break;
    }
  }
  path_last = std::min(path_last, path.size());

  const DynamicWindow window = ComputeDynamicWindow(state, limits, period);
  const std::vector<double> vs =
      Samples(window.v_lo, window.v_hi, options.v_samples);
  const std::vector<double> ws =
      Samples(window.w_lo, window.w_hi, options.w_samples);
  const std::vector<double> vys =
      limits.holonomic ? Samples(window.vy_lo, window.vy_hi, options.vy_samples)
                       : std::vector<double>{0.0};

  LocalPlan plan;
  // A start that already touches an obstacle (with the checker's margin)
  // rejects every rollout; say so rather than count them.
  const bool start_collides =
      checker.Collides(grid, state.pose, options.unknown_is_free, map.distance);
  double best_score = std::numeric_limits<double>::infinity();
  std::vector<Pose> best_poses;
  int64_t map_rejects = 0, obstacle_rejects = 0;
  std::vector<Pose> poses;
  for (double v : vs) {
    for (double vy : vys) {
      for (double w : ws) {
        ++plan.samples;
        // Sub-steps: no footprint point moves more than 2 * margin per step.
        const double motion = std::hypot(v, vy) + std::fabs(w) * r_circ;
        double h = options.sub_step;
        if (margin > 0 && motion > 0) h = std::min(h, 2.0 * margin / motion);
        int32_t steps =
            static_cast<int32_t>(std::ceil(options.horizon / h - 1e-9));
        steps = std::clamp(steps, 1, options.max_sub_steps);
        h = options.horizon / steps;
        poses.clear();
        poses.push_back(state.pose);
        const char* rejected = nullptr;
        double clearance = std::numeric_limits<double>::infinity();
        double moving_clearance = std::numeric_limits<double>::infinity();
        int32_t worst_cost = 0;
        for (int32_t i = 0; i <= steps; ++i) {
          if (i > 0)
            poses.push_back(IntegrateVelocity(poses.back(), v, vy, w, h, 1));
          const Pose& p = poses.back();
          if (checker.Collides(grid, p, options.unknown_is_free,
                               map.distance)) {
            rejected = "map";
            break;
          }
          const double t = i * h;
          for (const MovingObstacle& o : obstacles) {
            const double ox = o.position.x + o.velocity.x * t;
            const double oy = o.position.y + o.velocity.y * t;
            const double gap =
                std::hypot(ox - p.x, oy - p.y) - o.radius - r_circ;
            if (gap < 0) {
              rejected = "moving obstacle";
              break;
            }
            moving_clearance = std::min(moving_clearance, gap);
          }
          if (rejected != nullptr) break;
          const Cell c = p.cell();
          if (map.distance != nullptr) {
            clearance = std::min(
                clearance,
                static_cast<double>(map.distance[grid.Index(c)]) - r_circ);
          } else {
            worst_cost =
                std::max<int32_t>(worst_cost, checker.MaxCost(grid, p));
          }
        }
        DwaRollout* out = nullptr;
        if (rollouts != nullptr) {
          rollouts->push_back(DwaRollout{v, vy, w, poses, rejected == nullptr,
                                         rejected == nullptr ? "" : rejected,
                                         0.0});
          out = &rollouts->back();
        }
        if (rejected != nullptr) {
          (std::string_view(rejected) == "map" ? map_rejects
                                               : obstacle_rejects)++;
          continue;
        }
        const Pose& end = poses.back();
        const CellPoint end_point = end.point();
        double score = 0;
        score += options.path_distance_weight *
                 Clamp01(DistanceToPath(path, target.nearest_segment, path_last,
                                        end_point) /
                         options.lookahead);
        score +=
            options.goal_distance_weight *
            Clamp01(std::hypot(target.point.x - end.x, target.point.y - end.y) /
                    (options.lookahead + 1.0));
        if (std::hypot(target.point.x - end.x, target.point.y - end.y) > 1e-6) {
          score += options.heading_weight *
                   AngleBetween(end.yaw, std::atan2(target.point.y - end.y,
                                                    target.point.x - end.x)) /
                   3.141592653589793;
        }
        const double obstacle =
            map.distance != nullptr
                ? Clamp01((options.clearance_limit - clearance) /
                          options.clearance_limit)
                : worst_cost / static_cast<double>(kMaxTraversableCost);
        // Moving obstacles count with their predicted positions, so robots
        // start giving way before the rollouts toward each other collide.
        const double moving =
            Clamp01((options.clearance_limit - moving_clearance) /
                    options.clearance_limit);
        score += options.obstacle_weight * std::max(Clamp01(obstacle), moving);
        const double top = std::max(limits.max_v, 1e-9);
        score +=
            options.speed_weight * Clamp01((top - std::hypot(v, vy)) / top);
        if (limits.max_w > 0)
          score +=
              options.twirling_weight * Clamp01(std::fabs(w) / limits.max_w);
        if (out != nullptr) out->score = score;
        if (score < best_score) {
          best_score = score;
          plan.v = v;
          plan.vy = vy;
          plan.w = w;
          best_poses = poses;
        }
      }
    }
  }

  const auto brake = [&] {
    plan.v = std::clamp(0.0, window.v_lo, window.v_hi);
    plan.vy =
        limits.holonomic ? std::clamp(0.0, window.vy_lo, window.vy_hi) : 0.0;
    plan.w = std::clamp(0.0, window.w_lo, window.w_hi);
    plan.trajectory.clear();
    plan.trajectory.push_back(state.pose);
    const int32_t steps = std::max(
        1, static_cast<int32_t>(std::ceil(options.horizon / options.sub_step)));
    for (int32_t i = 0; i < steps; ++i) {
      plan.trajectory.push_back(IntegrateVelocity(plan.trajectory.back(),
                                                  plan.v, plan.vy, plan.w,
                                                  options.horizon / steps, 1));
    }
  };
  if (at_goal) {
    brake();
    plan.status = LocalStatus::kGoalReached;
    plan.reason = absl::StrFormat("within %g cells of the path's end",
                                  options.goal_tolerance);
  } else if (start_collides) {
    brake();
    plan.status = LocalStatus::kBlocked;
    plan.reason =
        "the footprint at the current pose already touches an obstacle (the "
        "checker's margin included); braking";
  } else if (std::isinf(best_score)) {
    brake();
    plan.status = LocalStatus::kBlocked;
    plan.reason = absl::StrFormat(
        "every one of %d velocity samples collides within %g s (%d with the "
        "map, %d with moving "
        "obstacles); braking",
        static_cast<int>(plan.samples), options.horizon,
        static_cast<int>(map_rejects), static_cast<int>(obstacle_rejects));
  } else {
    plan.trajectory = std::move(best_poses);
  }
  if (at_goal && progress != nullptr) progress->remaining.clear();
  if (!at_goal) {
    ReportStall(progress, target, period, options.window_seconds,
                options.min_progress, &plan);
  }
  return plan;
}

}  // namespace pathd
