// Obstacle inflation by the robot radius: marks every cell whose centre is
// within the radius of a lethal cell's centre as inscribed (253), so planners
// that treat the robot as a point at its centre keep the whole disc clear.
#ifndef PATHD_CORE_MAP_INFLATION_H_
#define PATHD_CORE_MAP_INFLATION_H_

#include "absl/status/statusor.h"
#include "core/map/grid.h"

namespace pathd {

// Returns a copy of `grid` where every cell whose centre lies within
// radius_cells (Euclidean, inclusive) of the centre of a lethal (254) cell
// becomes kInscribedCost, unless it is lethal or unknown (255) already; other
// cells keep their cost, and resolution and origin are kept. Radius 0 returns
// an identical copy. Exact (core/map/euclidean_distance.h) and O(cells).
// INVALID_ARGUMENT naming the robot radius when it is negative or not finite.
absl::StatusOr<Grid> InflateObstacles(const Grid& grid, double radius_cells);

}  // namespace pathd

#endif  // PATHD_CORE_MAP_INFLATION_H_
