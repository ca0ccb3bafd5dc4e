// The nearest place a robot may stand: the cell nearest to a target whose
// centre passes a test (on the inflated map for a circular robot: the cell
// is free; for a polygon footprint: the footprint placed there touches no
// blocked cell). Pure functions; thread-compatible.
#ifndef PATHD_CORE_FLEET_NEAREST_H_
#define PATHD_CORE_FLEET_NEAREST_H_

#include <cstdint>
#include <functional>
#include <optional>

#include "core/kinematics/footprint.h"
#include "core/map/grid.h"
#include "core/search/endpoints.h"

namespace pathd {

// NearestCell and NearestAllowedCell (the ring search) live in
// core/search/endpoints.h, where the goal tolerance uses them too.

// The test for a polygon footprint at heading `yaw` (grid frame): the
// footprint placed at the cell's centre touches no cell that is not
// traversable under unknown_is_free, nor the map's outside
// (FootprintChecker::CollidesExactly).
std::function<bool(Cell)> FootprintFits(const Grid& grid, const FootprintChecker& checker,
                                        double yaw, bool unknown_is_free);

}  // namespace pathd

#endif  // PATHD_CORE_FLEET_NEAREST_H_
