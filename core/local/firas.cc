#include "core/local/firas.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "absl/strings/str_format.h"
#include "core/status_macros.h"

namespace pathd {
namespace {

bool IsObstacle(const Grid& grid, int32_t x, int32_t y, bool unknown_is_free) {
  if (!grid.InBounds(x, y)) return true;
  const uint8_t c = grid.cost(x, y);
  if (c == kUnknownCost) return !unknown_is_free;
  return c >= kInscribedCost;
}

}  // namespace

absl::Status ValidateFirasOptions(const FirasOptions& o) {
  PATHD_RETURN_IF_ERROR(
      CheckOptionValues("firas",
                        {{"attraction", o.attraction},
                         {"attraction_distance", o.attraction_distance},
                         {"influence", o.influence},
                         {"lookahead", o.lookahead},
                         {"goal_tolerance", o.goal_tolerance},
                         {"turn_gain", o.turn_gain},
                         {"window_seconds", o.window_seconds}},
                        /*zero_ok=*/false));
  PATHD_RETURN_IF_ERROR(
      CheckOptionValues("firas",
                        {{"repulsion", o.repulsion},
                         {"min_force_ratio", o.min_force_ratio},
                         {"min_progress", o.min_progress}},
                        /*zero_ok=*/true));
  if (o.influence > 100) {
    return absl::InvalidArgumentError(
        "firas options: influence must be at most 100 cells");
  }
  return absl::OkStatus();
}

absl::StatusOr<LocalPlan> FirasStep(const Grid& grid, const RobotState& state,
                                    double radius, const VelocityLimits& limits,
                                    absl::Span<const MovingObstacle> obstacles,
                                    absl::Span<const CellPoint> path,
                                    double period, const FirasOptions& options,
                                    ProgressWindow* progress) {
  if (absl::Status s = ValidateFirasOptions(options); !s.ok()) return s;
  if (absl::Status s = ValidateVelocityLimits(limits); !s.ok()) return s;
  if (!(std::isfinite(radius) && radius > 0)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("firas: radius must be positive (got %g)", radius));
  }
  if (!(std::isfinite(period) && period > 0)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "firas: control period must be positive (got %g)", period));
  }
  if (path.empty())
    return absl::InvalidArgumentError("firas: the global path is empty");

  LocalPlan plan;
  const double qx = state.pose.x, qy = state.pose.y;
  const PathTarget target =
      FindPathTarget(path, state.pose.point(), options.lookahead);
  const auto finish = [&](double fx, double fy) {
    double v, vy = 0.0, w;
    if (limits.holonomic) {
      const double c = std::cos(state.pose.yaw), s = std::sin(state.pose.yaw);
      v = std::clamp(fx * c + fy * s, limits.min_v, limits.max_v);
      vy = std::clamp(-fx * s + fy * c, -limits.max_vy, limits.max_vy);
      w = 0.0;
    } else {
      FollowVelocityDiffDrive(CellPoint{fx, fy}, state.pose.yaw,
                              options.turn_gain, limits, &v, &w);
    }
    plan.v = ClampToWindow(v, state.v, limits.acc_v, period, limits.min_v,
                           limits.max_v);
    plan.w = ClampToWindow(w, state.w, limits.acc_w, period, -limits.max_w,
                           limits.max_w);
    plan.vy = limits.holonomic
                  ? ClampToWindow(vy, state.vy, limits.acc_vy, period,
                                  -limits.max_vy, limits.max_vy)
                  : 0.0;
    plan.trajectory.push_back(state.pose);
    for (int i = 0; i < 10; ++i) {
      plan.trajectory.push_back(IntegrateVelocity(
          plan.trajectory.back(), plan.v, plan.vy, plan.w, period, 1));
    }
  };

  if (target.distance_to_goal <= options.goal_tolerance) {
    finish(0.0, 0.0);
    plan.status = LocalStatus::kGoalReached;
    plan.reason = absl::StrFormat("within %g cells of the path's end",
                                  options.goal_tolerance);
    if (progress != nullptr) progress->remaining.clear();
    return plan;
  }

  // Attraction toward the lookahead point.
  double ax = target.point.x - qx, ay = target.point.y - qy;
  const double da = std::hypot(ax, ay);
  const double scale =
      da > options.attraction_distance ? options.attraction_distance / da : 1.0;
  ax *= options.attraction * scale;
  ay *= options.attraction * scale;
  const double attraction = std::hypot(ax, ay);

  // Repulsion from the nearest point of the nearest obstacle cell (the map's
  // outside counts) within the influence distance of the robot's disc.
  const double reach = radius + options.influence;
  const int32_t x0 = static_cast<int32_t>(std::floor(qx - reach));
  const int32_t x1 = static_cast<int32_t>(std::floor(qx + reach));
  const int32_t y0 = static_cast<int32_t>(std::floor(qy - reach));
  const int32_t y1 = static_cast<int32_t>(std::floor(qy + reach));
  double nearest = std::numeric_limits<double>::infinity();
  double rx = 0, ry = 0;  // q - q_r for the nearest point
  for (int32_t y = y0; y <= y1; ++y) {
    for (int32_t x = x0; x <= x1; ++x) {
      if (!IsObstacle(grid, x, y, options.unknown_is_free)) continue;
      ++plan.constraints;
      const double px = std::clamp(qx, static_cast<double>(x), x + 1.0);
      const double py = std::clamp(qy, static_cast<double>(y), y + 1.0);
      const double d = std::hypot(qx - px, qy - py);
      if (d < nearest) {
        nearest = d;
        rx = qx - px;
        ry = qy - py;
      }
    }
  }
  double fx = ax, fy = ay;
  const auto repel = [&](double clearance, double dx, double dy, double norm) {
    // dx, dy: from the obstacle point toward the robot, length norm; the
    // lecture's (q - q_r) / d^2 with d the clearance, direction kept.
    if (clearance > options.influence || norm <= 0) return;
    const double d = std::max(clearance, 1e-3);
    const double magnitude =
        options.repulsion * (1.0 / d - 1.0 / options.influence) / d;
    fx += magnitude * dx / norm;
    fy += magnitude * dy / norm;
  };
  if (nearest - radius <= 0) {
    finish(0.0, 0.0);
    plan.v = plan.w = plan.vy = 0.0;
    plan.status = LocalStatus::kBlocked;
    plan.reason = "the robot's disc overlaps an obstacle cell";
    return plan;
  }
  if (std::isfinite(nearest)) repel(nearest - radius, rx, ry, nearest);
  for (const MovingObstacle& o : obstacles) {
    ++plan.constraints;
    const double dx = qx - o.position.x, dy = qy - o.position.y;
    const double n = std::hypot(dx, dy);
    if (n - radius - o.radius <= 0) {
      finish(0.0, 0.0);
      plan.v = plan.w = plan.vy = 0.0;
      plan.status = LocalStatus::kBlocked;
      plan.reason = "the robot's disc overlaps a moving obstacle";
      return plan;
    }
    repel(n - radius - o.radius, dx, dy, n);
  }
  plan.samples = 1;

  // The force as the desired velocity, at most max speed.
  const double force = std::hypot(fx, fy);
  const double top = std::max(limits.max_v, 0.0);
  if (force > top && force > 0) {
    fx *= top / force;
    fy *= top / force;
  }
  finish(fx, fy);

  if (attraction > 0 && force < options.min_force_ratio * attraction) {
    plan.status = LocalStatus::kLocalMinimum;
    plan.reason = absl::StrFormat(
        "the repulsion cancels the attraction (resulting force %.3g of %.3g)",
        force, attraction);
  }
  ReportStall(progress, target, period, options.window_seconds,
              options.min_progress, &plan);
  return plan;
}

}  // namespace pathd
