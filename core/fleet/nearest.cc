// The footprint test for the nearest place a robot may stand.
#include "core/fleet/nearest.h"

#include "core/kinematics/pose.h"

namespace pathd {

std::function<bool(Cell)> FootprintFits(const Grid& grid, const FootprintChecker& checker,
                                        double yaw, bool unknown_is_free) {
  return [&grid, &checker, yaw, unknown_is_free](Cell c) {
    return !checker.CollidesExactly(grid, Pose{c.x + 0.5, c.y + 0.5, yaw}, unknown_is_free);
  };
}

}  // namespace pathd
