#include "core/kinematics/motion_check.h"

#include <cmath>
#include <utility>
#include <vector>

#include "core/kinematics/vehicle.h"
#include "core/status_macros.h"

namespace pathd {

absl::StatusOr<MotionChecker> MotionChecker::Create(
    std::shared_ptr<const FootprintChecker> footprint, const Grid& grid, bool unknown_is_free,
    const float* distance) {
  MotionChecker checker;
  FootprintCheckerOptions options = footprint->options();
  const double margin = options.margin_cells;
  options.margin_cells = margin + kMotionMargin;
  PATHD_ASSIGN_OR_RETURN(checker.coarse_,
                         SharedFootprintChecker(footprint->footprint(), options));
  options.margin_cells = margin + kMotionMargin / 4.0;
  PATHD_ASSIGN_OR_RETURN(checker.fine_, SharedFootprintChecker(footprint->footprint(), options));
  // A circle about the reference point covers the same cells at every
  // heading: turning moves none of it.
  checker.reach_ = footprint->footprint().is_circle()
                       ? 0.0
                       : footprint->footprint().circumscribed_radius() + margin;
  checker.exact_ = std::move(footprint);
  checker.grid_ = &grid;
  checker.unknown_is_free_ = unknown_is_free;
  checker.distance_ = distance;
  return checker;
}

int64_t FirstBlockedPiece(const MotionChecker& checker, const std::vector<PathPose>& poses) {
  if (poses.empty()) return -1;
  if (poses.size() == 1) return checker.PoseFree(poses[0].pose) ? -1 : 0;
  const size_t last = poses.size() - 1;
  for (size_t i = 0; i < last; ++i) {
    const Pose& p = poses[i].pose;
    const Pose& q = poses[i + 1].pose;
    if (i == 0 && !checker.PoseFree(p)) return 0;
    if (i + 1 == last && !checker.PoseFree(q)) return static_cast<int64_t>(i);
    const double turn = NormalizeAngle(q.yaw - p.yaw);
    const double sweep = std::hypot(q.x - p.x, q.y - p.y) + checker.reach() * std::fabs(turn);
    const auto lerp = [&](double t) {
      return Pose{p.x + t * (q.x - p.x), p.y + t * (q.y - p.y), p.yaw + t * turn};
    };
    // Each interior pose is tested as the end of one piece and the start of
    // the next; kProven for the second saves the repeat.
    const MotionEnd from = i == 0 ? MotionEnd::kExact : MotionEnd::kProven;
    const MotionEnd to = i + 1 == last ? MotionEnd::kExact : MotionEnd::kSample;
    if (!checker.MotionFree(lerp, sweep, kMotionDeviation, from, to)) {
      return static_cast<int64_t>(i);
    }
  }
  return -1;
}

}  // namespace pathd
