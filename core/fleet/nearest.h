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

namespace pathd {

struct NearestCell {
  Cell cell;
  // Euclidean distance between the target's centre and the cell's, cells.
  double distance = 0.0;
  // Cells tested.
  int64_t tested = 0;
};

// The cell nearest to `target` (Euclidean distance between cell centres, at
// most `max_distance` inclusive; ties to the smaller y, then the smaller x:
// the rule of the goal tolerance, core/search/endpoints.h) for which
// `allowed` is true; nullopt when none is. Visits rings of growing
// Chebyshev radius around the target and stops once no further ring can be
// nearer, so the work is O(d^2) for the answer's distance d. `target` may be
// off the grid; only cells on it are tested.
std::optional<NearestCell> NearestAllowedCell(const Grid& grid, Cell target,
                                              double max_distance,
                                              const std::function<bool(Cell)>& allowed);

// The test for a polygon footprint at heading `yaw` (grid frame): the
// footprint placed at the cell's centre touches no cell that is not
// traversable under unknown_is_free, nor the map's outside
// (FootprintChecker::CollidesExactly).
std::function<bool(Cell)> FootprintFits(const Grid& grid, const FootprintChecker& checker,
                                        double yaw, bool unknown_is_free);

}  // namespace pathd

#endif  // PATHD_CORE_FLEET_NEAREST_H_
