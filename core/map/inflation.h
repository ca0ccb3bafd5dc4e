// Obstacle inflation by the robot radius: marks every cell whose centre is
// within the radius of a lethal cell's centre as inscribed (253), so planners
// that treat the robot as a point at its centre keep the whole disc clear;
// and the planning grid's shape (GridShape): that inflation, inflation and
// clearance costs, computed in full or advanced from the previous version.
#ifndef PATHD_CORE_MAP_INFLATION_H_
#define PATHD_CORE_MAP_INFLATION_H_

#include <algorithm>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/types/span.h"
#include "core/map/grid.h"

namespace pathd {

// Returns a copy of `grid` where every cell whose centre lies within
// radius_cells (Euclidean, inclusive) of the centre of a lethal (254) cell
// becomes kInscribedCost, unless it is lethal or unknown (255) already; other
// cells keep their cost, and resolution and origin are kept. Radius 0 returns
// an identical copy. Exact (core/map/euclidean_distance.h) and O(cells).
// INVALID_ARGUMENT naming the robot radius when it is negative or not finite.
absl::StatusOr<Grid> InflateObstacles(const Grid& grid, double radius_cells);

// How a stored map becomes the grid one robot plans on, in this order: its
// obstacles inflated by the robot radius (InflateObstacles), Nav2's
// inflation costs around its lethal cells (core/map/inflation_cost.h), then
// clearance costs around what is left blocked (core/map/clearance.h).
// Everything in cells: the server converts metres with the map's
// resolution. The server caches one shaped grid per (map version, shape).
struct GridShape {
  double robot_radius_cells = 0.0;
  // 0: no inflation costs. Otherwise >= robot_radius_cells: cells between
  // the two get Nav2's exponentially decaying costs.
  double inflation_radius_cells = 0.0;
  // Nav2's cost_scaling_factor (per metre) times the map's resolution
  // (metres per cell): the decay per cell. Kept 0 without inflation costs.
  double cost_scaling_per_cell = 0.0;
  // > robot_radius_cells: the inflation costs decay from this radius, as
  // Nav2's do from the inscribed radius, but nothing within it is blocked:
  // cells between the robot radius and it cost 252, the most a traversable
  // cell costs (the kinematic planners, whose footprint check decides
  // collisions: the footprint's inscribed radius with a robot radius of 0).
  // Kept 0 without inflation costs or when not above the robot radius; at
  // most the inflation radius (a footprint wider than the inflation: every
  // cell within the inflation radius costs 252, as Nav2's are inscribed).
  double cost_inscribed_cells = 0.0;
  // 0: no clearance costs.
  double min_clearance_cells = 0.0;
  // Only the inflation and clearance costs read it (an unknown cell
  // traversed as free takes their costs; the clearance measures from unknown
  // cells unless they are free); kept false without them so equal shapes
  // compare equal.
  bool unknown_is_free = false;

  // The shape with the fields that do not apply cleared, so that two
  // requests planning on the same grid have equal shapes.
  static GridShape Of(double robot_radius_cells, double inflation_radius_cells,
                      double cost_scaling_per_cell, double min_clearance_cells,
                      bool unknown_is_free, double cost_inscribed_cells = 0.0) {
    const bool inflation = inflation_radius_cells != 0.0;
    return GridShape{robot_radius_cells, inflation ? inflation_radius_cells : 0.0,
                     inflation ? cost_scaling_per_cell : 0.0,
                     inflation && cost_inscribed_cells > robot_radius_cells
                         ? std::min(cost_inscribed_cells, inflation_radius_cells)
                         : 0.0,
                     min_clearance_cells,
                     (inflation || min_clearance_cells > 0.0) && unknown_is_free};
  }
  // The radius the inflation costs decay from.
  double decay_radius_cells() const {
    return cost_inscribed_cells > robot_radius_cells ? cost_inscribed_cells
                                                     : robot_radius_cells;
  }
  bool has_inflation_cost() const { return inflation_radius_cells != 0.0; }
  // False: the stored map is the planning grid. (A nonsensical inflation
  // radius counts, so ShapeGrid reports it.)
  bool shaped() const {
    return robot_radius_cells > 0.0 || has_inflation_cost() || min_clearance_cells > 0.0;
  }
  friend bool operator==(const GridShape&, const GridShape&) = default;
};

// OK when ShapeGrid accepts the shape; otherwise INVALID_ARGUMENT naming
// the value at fault (robot radius, inflation radius, cost scaling, minimum
// clearance).
absl::Status CheckGridShape(const GridShape& shape);

// InflateObstacles by the radius, then ApplyInflationCost, then
// ApplyClearanceCost, each when the shape asks for it. Errors as
// CheckGridShape.
absl::StatusOr<Grid> ShapeGrid(const Grid& grid, const GridShape& shape);

// A shaped grid brought to a new map version.
struct ShapedGridAdvance {
  Grid grid;
  // True when only windows around the changed cells were recomputed; false
  // when the changes covered too much and the grid was shaped in full.
  bool advanced = false;
  // Cells of the padded windows read (the map's when shaped in full); the
  // work is about proportional to them.
  int64_t window_cells = 0;
};

// ShapeGrid(stored, shape), computed from the previous version's shaped
// grid without an O(map) recomputation: `previous_shaped` must be
// ShapeGrid(previous stored grid, shape) (or this function's result for
// it), of stored's dimensions, and `changed_cells` every cell whose cost
// differs between the previous stored grid and `stored` (more is harmless).
//
// A changed cell can change the shaped grid only within the shape's reach
// of it (ShapeReach: the larger of the inflation costs' reach and the robot
// radius plus the clearance), and within that only when it became or stopped
// being lethal (otherwise only the cell itself, and with clearance costs the
// cells within the clearance of it, can change). Those boxes are merged where
// merging saves work, each is shaped again from `stored` over the box padded
// by the reach (a cell's shaping reads sources up to the reach away; the
// padded window's own edges then lie beyond every bound that matters), and
// the rest is copied from previous_shaped. Falls back to ShapeGrid when the
// padded windows would cover more than half the map, or when the
// dimensions differ or a changed cell is off the map. The result equals
// ShapeGrid(stored, shape) byte for byte. Errors as CheckGridShape.
absl::StatusOr<ShapedGridAdvance> AdvanceShapedGrid(const Grid& previous_shaped,
                                                    const Grid& stored,
                                                    absl::Span<const Cell> changed_cells,
                                                    const GridShape& shape);

// How far (cells) a change of a lethal cell reaches into a grid shaped by a
// valid `shape`: the largest distance at which its shaping reads the stored
// map.
double ShapeReach(const GridShape& shape);

}  // namespace pathd

#endif  // PATHD_CORE_MAP_INFLATION_H_
