#include "core/local/local_types.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "absl/strings/str_format.h"

namespace pathd {

absl::Status ValidateVelocityLimits(const VelocityLimits& l) {
  const struct {
    const char* name;
    double value;
    bool signed_ok;
  } fields[] = {{"min_v", l.min_v, true},    {"max_v", l.max_v, true},
                {"max_vy", l.max_vy, false}, {"max_w", l.max_w, false},
                {"acc_v", l.acc_v, false},   {"acc_vy", l.acc_vy, false},
                {"acc_w", l.acc_w, false}};
  for (const auto& f : fields) {
    if (!std::isfinite(f.value)) {
      return absl::InvalidArgumentError(
          absl::StrFormat("velocity limits: %s is not finite", f.name));
    }
    if (!f.signed_ok && f.value < 0) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "velocity limits: %s is negative (%g)", f.name, f.value));
    }
  }
  if (l.min_v > l.max_v) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "velocity limits: min_v (%g) is greater than max_v (%g)", l.min_v,
        l.max_v));
  }
  return absl::OkStatus();
}

absl::Status CheckOptionValues(const char* owner,
                               std::initializer_list<OptionValue> values,
                               bool zero_ok) {
  for (const OptionValue& f : values) {
    if (!(std::isfinite(f.value) && (zero_ok ? f.value >= 0 : f.value > 0))) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "%s options: %s must be %s and finite (got %g)", owner, f.name,
          zero_ok ? ">= 0" : "positive", f.value));
    }
  }
  return absl::OkStatus();
}

const char* LocalStatusName(LocalStatus status) {
  switch (status) {
    case LocalStatus::kOk:
      return "ok";
    case LocalStatus::kBlocked:
      return "blocked";
    case LocalStatus::kLocalMinimum:
      return "local_minimum";
    case LocalStatus::kGoalReached:
      return "goal_reached";
  }
  return "unknown";
}

Pose IntegrateVelocity(const Pose& pose, double v, double vy, double w,
                       double seconds, int32_t steps) {
  Pose p = pose;
  if (steps < 1) steps = 1;
  const double h = seconds / steps;
  for (int32_t i = 0; i < steps; ++i) {
    const double mid = p.yaw + 0.5 * w * h;
    const double c = std::cos(mid), s = std::sin(mid);
    p.x += (v * c - vy * s) * h;
    p.y += (v * s + vy * c) * h;
    p.yaw = NormalizeAngle(p.yaw + w * h);
  }
  return p;
}

PathTarget FindPathTarget(absl::Span<const CellPoint> path, CellPoint position,
                          double lookahead) {
  PathTarget target;
  const CellPoint& last = path.back();
  target.distance_to_goal =
      std::hypot(last.x - position.x, last.y - position.y);
  if (path.size() == 1) {
    target.point = last;
    target.distance_to_path = target.distance_to_goal;
    target.remaining = 0.0;
    return target;
  }
  // The nearest point over all segments, and where along its segment it is.
  double best = std::numeric_limits<double>::infinity();
  double best_t = 0.0;
  for (size_t i = 0; i + 1 < path.size(); ++i) {
    const CellPoint a = path[i], b = path[i + 1];
    const double dx = b.x - a.x, dy = b.y - a.y;
    const double len2 = dx * dx + dy * dy;
    double t = 0.0;
    if (len2 > 0) {
      t = std::clamp(((position.x - a.x) * dx + (position.y - a.y) * dy) / len2,
                     0.0, 1.0);
    }
    const double d =
        std::hypot(a.x + t * dx - position.x, a.y + t * dy - position.y);
    // "<=" prefers the later segment at a tie: at a corner the robot is
    // past the earlier one.
    if (d <= best) {
      best = d;
      best_t = t;
      target.nearest_segment = i;
    }
  }
  target.distance_to_path = best;
  // Walk `lookahead` along the path from the nearest point.
  size_t i = target.nearest_segment;
  CellPoint from{path[i].x + best_t * (path[i + 1].x - path[i].x),
                 path[i].y + best_t * (path[i + 1].y - path[i].y)};
  double left = lookahead;
  target.point = last;
  bool placed = false;
  double remaining = 0.0;
  for (size_t j = i; j + 1 < path.size(); ++j) {
    const CellPoint to = path[j + 1];
    const double seg = std::hypot(to.x - from.x, to.y - from.y);
    remaining += seg;
    if (!placed && seg >= left) {
      const double f = seg > 0 ? left / seg : 0.0;
      target.point =
          CellPoint{from.x + f * (to.x - from.x), from.y + f * (to.y - from.y)};
      placed = true;
    } else if (!placed) {
      left -= seg;
    }
    from = to;
  }
  target.remaining = remaining;
  return target;
}

void FollowVelocityDiffDrive(CellPoint desired, double yaw, double turn_gain,
                             const VelocityLimits& limits, double* v,
                             double* w) {
  const double speed = std::hypot(desired.x, desired.y);
  if (speed < 1e-9) {
    *v = 0.0;
    *w = 0.0;
    return;
  }
  const double error = NormalizeAngle(std::atan2(desired.y, desired.x) - yaw);
  *w = std::clamp(turn_gain * error, -limits.max_w, limits.max_w);
  const double forward =
      std::fabs(error) < std::numbers::pi / 2 ? speed * std::cos(error) : 0.0;
  *v = std::clamp(forward, std::max(limits.min_v, 0.0),
                  std::max(limits.max_v, 0.0));
}

std::optional<double> RecordProgress(ProgressWindow& window, double remaining,
                                     double period, double window_seconds) {
  if (!window.remaining.empty() && remaining > window.remaining.back() + 1.0) {
    window.remaining.clear();
  }
  const size_t cycles = static_cast<size_t>(
      std::clamp(std::ceil(window_seconds / period), 1.0, 10000.0));
  window.remaining.push_back(remaining);
  while (window.remaining.size() > cycles + 1) window.remaining.pop_front();
  if (window.remaining.size() < cycles + 1) return std::nullopt;
  return window.remaining.front() - window.remaining.back();
}

void ReportStall(ProgressWindow* window, const PathTarget& target,
                 double period, double window_seconds, double min_progress,
                 LocalPlan* plan) {
  if (window == nullptr) return;
  const std::optional<double> progress =
      RecordProgress(*window, target.remaining, period, window_seconds);
  plan->progress = progress;
  if (progress.has_value() && *progress < min_progress &&
      plan->status == LocalStatus::kOk) {
    plan->status = LocalStatus::kLocalMinimum;
    plan->reason = absl::StrFormat(
        "%.3g cells of progress along the path in the last %g s (stalled, "
        "oscillating or circling)",
        *progress, window_seconds);
  }
}

double ClampToWindow(double target, double current, double acceleration,
                     double period, double lo, double hi) {
  const double reach = acceleration * period;
  double wlo = std::max(lo, current - reach);
  double whi = std::min(hi, current + reach);
  if (wlo > whi) {
    // The current velocity is outside [lo, hi] by more than one period can
    // change: physics wins, the nearest reachable value toward the range.
    return current > hi ? current - reach : current + reach;
  }
  return std::clamp(target, wlo, whi);
}

}  // namespace pathd
