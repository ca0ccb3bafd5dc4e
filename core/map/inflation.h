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

// How a stored map becomes the grid one robot plans on: its obstacles
// inflated by the robot radius, then clearance costs around what is left
// blocked (core/map/clearance.h). The server caches one shaped grid per (map
// version, shape).
struct GridShape {
  double robot_radius_cells = 0.0;
  // 0: no clearance costs.
  double min_clearance_cells = 0.0;
  // Only the clearance costs read it (unknown cells are obstacles to measure
  // from unless traversed as free); kept false without them so equal shapes
  // compare equal.
  bool unknown_is_free = false;

  static GridShape Of(double robot_radius_cells, double min_clearance_cells,
                      bool unknown_is_free) {
    return GridShape{robot_radius_cells, min_clearance_cells,
                     min_clearance_cells > 0.0 && unknown_is_free};
  }
  // False: the stored map is the planning grid.
  bool shaped() const { return robot_radius_cells > 0.0 || min_clearance_cells > 0.0; }
  friend bool operator==(const GridShape&, const GridShape&) = default;
};

// InflateObstacles by the radius, then ApplyClearanceCost. Errors name the
// value at fault.
absl::StatusOr<Grid> ShapeGrid(const Grid& grid, const GridShape& shape);

}  // namespace pathd

#endif  // PATHD_CORE_MAP_INFLATION_H_
