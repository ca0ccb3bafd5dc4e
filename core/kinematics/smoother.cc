#include "core/kinematics/smoother.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

#include "core/kinematics/obstacle_heuristic.h"
#include "core/kinematics/pose_path.h"

namespace pathd {
namespace {

// Longest piece a result may have, cells (the planners' half cell, and what
// the motion checks' sample spacing assumes of a changed piece).
constexpr double kMaxPiece = 0.5 + 1e-9;

bool SamePose(const Pose& a, const Pose& b) {
  return a.x == b.x && a.y == b.y && a.yaw == b.yaw;
}

// The smoothing of one path: the original, the current poses, which are
// held fixed, and the checks.
class Smoothing {
 public:
  Smoothing(const std::vector<PathPose>& original, const MotionChecker& checker,
            const SmootherOptions& options)
      : original_(original),
        poses_(original),
        fixed_(original.size(), false),
        checker_(checker),
        options_(options) {}

  std::vector<PathPose> Run() {
    const size_t n = original_.size();
    fixed_[0] = fixed_[n - 1] = true;
    for (size_t i = 1; i < n; ++i) {
      // A cusp: the pose where the direction changes belongs to both
      // motions and keeps its place and heading.
      if (original_[i].reverse != original_[i - 1].reverse && i > 1) fixed_[i - 1] = true;
    }
    // Each cusp-free segment is smoothed on its own.
    size_t begin = 0;
    for (size_t i = 1; i < n; ++i) {
      if (!fixed_[i]) continue;
      SmoothSegment(begin, i);
      begin = i;
    }
    return poses_;
  }

 private:
  // Smooths the segment between fixed poses `begin` and `end` (no cusp
  // inside), pinning original poses where the result fails, reverting the
  // whole segment after options_.max_pins pins.
  void SmoothSegment(size_t begin, size_t end) {
    std::vector<std::pair<size_t, size_t>> work = {{begin, end}};
    int32_t pins = 0;
    while (!work.empty()) {
      const auto [a, b] = work.back();
      work.pop_back();
      if (b - a < 2) continue;
      Descend(a, b);
      const size_t failed = FirstFailure(a, b);
      if (failed == kNone) continue;
      if (++pins > options_.max_pins) {
        for (size_t i = begin; i <= end; ++i) poses_[i] = original_[i];
        return;
      }
      // Pin the original pose at the failing piece (one of its ends is not
      // fixed, or the piece would be original and pass) and smooth the two
      // sides again.
      const size_t pin = fixed_[failed] ? failed + 1 : failed;
      fixed_[pin] = true;
      for (size_t i = a + 1; i < b; ++i) poses_[i] = original_[i];
      work.push_back({a, pin});
      work.push_back({pin, b});
    }
  }

  // Gradient descent of the positions strictly between a and b from the
  // original, then headings along the result.
  void Descend(size_t a, size_t b) {
    for (size_t i = a + 1; i < b; ++i) poses_[i] = original_[i];
    const double wd = options_.w_data;
    const double ws = options_.w_smooth;
    // A fixed pose keeps its heading, so the pose next to it is also pulled
    // to where that heading points (one original spacing along it): the
    // smoothness term of a point before the fixed one on its tangent.
    // Without it the neighbours of every fixed pose bend away from its
    // heading and fail the curvature and direction checks.
    const auto along = [this](size_t fixed, size_t next) {
      const Pose& f = original_[fixed].pose;
      const Pose& n = original_[next].pose;
      const double spacing = std::hypot(n.x - f.x, n.y - f.y);
      // The direction of travel between the two, as the fixed heading has
      // it: backwards when reversing, towards `fixed` when it comes after.
      double sign = original_[std::max(fixed, next)].reverse ? -1.0 : 1.0;
      if (next < fixed) sign = -sign;
      return CellPoint{f.x + sign * spacing * std::cos(f.yaw),
                       f.y + sign * spacing * std::sin(f.yaw)};
    };
    const CellPoint after_a = along(a, a + 1);
    const CellPoint before_b = along(b, b - 1);
    for (int32_t it = 0; it < options_.max_iterations; ++it) {
      double change = 0.0;
      for (size_t i = a + 1; i < b; ++i) {
        Pose& p = poses_[i].pose;
        const Pose& o = original_[i].pose;
        const Pose& prev = poses_[i - 1].pose;
        const Pose& next = poses_[i + 1].pose;
        double x = p.x + wd * (o.x - p.x) + ws * (prev.x + next.x - 2.0 * p.x);
        double y = p.y + wd * (o.y - p.y) + ws * (prev.y + next.y - 2.0 * p.y);
        if (i == a + 1) {
          x += ws * (after_a.x - p.x);
          y += ws * (after_a.y - p.y);
        }
        if (i + 1 == b) {
          x += ws * (before_b.x - p.x);
          y += ws * (before_b.y - p.y);
        }
        change += std::fabs(x - p.x) + std::fabs(y - p.y);
        p.x = x;
        p.y = y;
      }
      if (change < options_.tolerance) break;
    }
    // The heading of the direction of travel through each moved pose.
    for (size_t i = a + 1; i < b; ++i) {
      const Pose& prev = poses_[i - 1].pose;
      const Pose& next = poses_[i + 1].pose;
      double yaw = std::atan2(next.y - prev.y, next.x - prev.x);
      if (poses_[i].reverse) yaw += std::numbers::pi;
      poses_[i].pose.yaw = NormalizeAngle(yaw);
    }
  }

  static constexpr size_t kNone = static_cast<size_t>(-1);

  // The first piece between a and b that changed and fails a check, or
  // kNone.
  size_t FirstFailure(size_t a, size_t b) const {
    const size_t last = original_.size() - 1;
    bool previous_checked = false;
    for (size_t i = a; i < b; ++i) {
      const Pose& p = poses_[i].pose;
      const Pose& q = poses_[i + 1].pose;
      if (SamePose(p, original_[i].pose) && SamePose(q, original_[i + 1].pose)) {
        previous_checked = false;
        continue;
      }
      if (!PieceFits(p, q, poses_[i + 1].reverse)) return i;
      const MotionEnd from = i == 0 ? MotionEnd::kExact
                                    : (previous_checked ? MotionEnd::kProven : MotionEnd::kSample);
      const MotionEnd to = i + 1 == last ? MotionEnd::kExact : MotionEnd::kSample;
      const double turn = NormalizeAngle(q.yaw - p.yaw);
      const double sweep = std::hypot(q.x - p.x, q.y - p.y) + checker_.reach() * std::fabs(turn);
      const auto lerp = [&](double t) {
        return Pose{p.x + t * (q.x - p.x), p.y + t * (q.y - p.y), p.yaw + t * turn};
      };
      if (!checker_.MotionFree(lerp, sweep, 0.0, from, to)) return i;
      previous_checked = true;
    }
    return kNone;
  }

  // A changed piece from p to q: short, driven the way the robot faces
  // (drifting at most max_drift off the heading halfway along), and, when
  // bounded, curving no more than the turning radius allows: the circle
  // through both poses, 2 sin(|turn| / 2) / chord, is the piece's curvature.
  bool PieceFits(const Pose& p, const Pose& q, bool reverse) const {
    const double chord = std::hypot(q.x - p.x, q.y - p.y);
    if (!(chord > 0.0) || chord > kMaxPiece) return false;
    const double turn = NormalizeAngle(q.yaw - p.yaw);
    if (options_.min_turning_radius > 0.0 &&
        2.0 * std::sin(std::fabs(turn) / 2.0) / chord >
            (1.0 - 1e-9) / options_.min_turning_radius) {
      return false;
    }
    double direction = std::atan2(q.y - p.y, q.x - p.x);
    if (reverse) direction += std::numbers::pi;
    return AngleBetween(direction, p.yaw + turn / 2.0) <= options_.max_drift;
  }

  const std::vector<PathPose>& original_;
  std::vector<PathPose> poses_;
  std::vector<bool> fixed_;
  const MotionChecker& checker_;
  const SmootherOptions& options_;
};

}  // namespace

std::vector<PathPose> SmoothPath(const std::vector<PathPose>& poses, const MotionChecker& checker,
                                 const SmootherOptions& options) {
  if (poses.size() < 3) return poses;
  return Smoothing(poses, checker, options).Run();
}

std::vector<PathPose> PosesAlongPolyline(const std::vector<CellPoint>& points, double spacing) {
  std::vector<CellPoint> kept;
  for (const CellPoint& p : points) {
    if (kept.empty() || p.x != kept.back().x || p.y != kept.back().y) kept.push_back(p);
  }
  std::vector<PathPose> poses;
  if (kept.empty()) return poses;
  const auto heading = [&](size_t j) {
    return std::atan2(kept[j + 1].y - kept[j].y, kept[j + 1].x - kept[j].x);
  };
  poses.push_back(PathPose{Pose{kept[0].x, kept[0].y, kept.size() > 1 ? heading(0) : 0.0}});
  for (size_t j = 0; j + 1 < kept.size(); ++j) {
    const CellPoint a = kept[j];
    const CellPoint b = kept[j + 1];
    const double yaw = heading(j);
    const int n = std::max(
        1, static_cast<int>(std::ceil(std::hypot(b.x - a.x, b.y - a.y) / spacing - 1e-9)));
    for (int i = 1; i <= n; ++i) {
      const double t = static_cast<double>(i) / n;
      poses.push_back(PathPose{Pose{a.x + t * (b.x - a.x), a.y + t * (b.y - a.y), yaw}});
    }
  }
  return poses;
}

absl::StatusOr<std::vector<PathPose>> SmoothPolyline(
    const Grid& grid, const std::vector<CellPoint>& points,
    std::shared_ptr<const FootprintChecker> footprint, bool unknown_is_free,
    const SmootherOptions& options) {
  const std::vector<float> distance = ObstacleDistanceField(grid, unknown_is_free);
  absl::StatusOr<MotionChecker> checker =
      MotionChecker::Create(std::move(footprint), grid, unknown_is_free, distance.data());
  if (!checker.ok()) return checker.status();
  SmootherOptions polyline = options;
  // The polyline's own poses slide sideways at every bend (the heading
  // turns over the piece after it); only a car's smoothed poses are held to
  // the direction rule.
  if (polyline.min_turning_radius <= 0.0) polyline.max_drift = std::numbers::pi;
  return SmoothPath(PosesAlongPolyline(points), *checker, polyline);
}

}  // namespace pathd
