#include "core/kinematics/motion_check.h"

#include <utility>

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

}  // namespace pathd
