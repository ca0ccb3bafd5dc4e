// Inflation costs as Nav2's costmap_2d inflation layer computes them
// (PlanOptions.inflation_radius_m, cost_scaling_factor): beyond the robot's
// inscribed radius a cell's cost decays exponentially with its distance to
// the nearest lethal cell, so paths keep away from walls where there is
// room, by the same costs a planner tuned on Nav2's costmaps sees.
//
// Units: core works in cells. Nav2's parameters are metres and 1/metres;
// inflation_radius_cells = inflation_radius_m / resolution and
// cost_scaling_per_cell = cost_scaling_factor * resolution, so
// exp(-factor * (d_m - r_m)) = exp(-per_cell * (d_cells - r_cells)).
// Distances are exact Euclidean distances between cell centres
// (core/map/euclidean_distance.h), like the robot radius's.
#ifndef PATHD_CORE_MAP_INFLATION_COST_H_
#define PATHD_CORE_MAP_INFLATION_COST_H_

#include <cstdint>

#include "absl/status/status.h"
#include "core/map/euclidean_distance.h"
#include "core/map/grid.h"

namespace pathd {

// Nav2's default cost_scaling_factor, per metre (an unset factor).
inline constexpr double kDefaultCostScalingFactor = 10.0;

// Nav2's InflationLayer::computeCost for a cell whose centre is
// `distance_cells` from the nearest lethal cell's centre: kLethalCost at 0,
// kInscribedCost up to the inscribed radius (inclusive), beyond it
// (kInscribedCost - 1) * exp(-cost_scaling_per_cell * (distance -
// inscribed)) truncated to an integer as Nav2's static_cast does (so 252 is
// never reached, and far cells cost 0).
uint8_t InflationCost(double distance_cells, double inscribed_radius_cells,
                      double cost_scaling_per_cell);

// OK when the parameters describe inflation costs: inflation_radius_cells
// finite and >= robot_radius_cells, cost_scaling_per_cell finite and > 0.
// Otherwise INVALID_ARGUMENT naming the value at fault ("inflation radius",
// "cost scaling").
absl::Status CheckInflationCost(double robot_radius_cells, double inflation_radius_cells,
                                double cost_scaling_per_cell);

// The distance (cells) beyond which no cell gets a cost: the inflation
// radius, or less when the decay reaches 0 before it (252 * exp(-s * (d -
// r)) < 1 from d = r + ln(252) / s; this keeps a margin of one more unit of
// the exponent, so rounding never matters). Parameters as CheckInflationCost
// accepts.
double InflationCostReach(double robot_radius_cells, double inflation_radius_cells,
                          double cost_scaling_per_cell);

// Raises every cell whose centre lies at a distance d with robot_radius <
// d <= inflation_radius from the nearest lethal (254) cell's centre to
// InflationCost(d, robot_radius, cost_scaling_per_cell) when that is higher
// than its own cost. Cells within the robot radius are left to the radius's
// inflation (InflateObstacles makes them inscribed); lethal and inscribed
// cells keep their cost.
//
// Sources are lethal cells only, as in Nav2: unknown cells and the map's
// outside are not obstacles to inflate (Nav2 inflates LETHAL_OBSTACLE cells
// only, and a costmap's edge is not one). Unknown cells themselves: blocked
// (unknown_is_free false) they stay unknown, as Nav2 with its default
// inflate_unknown false keeps them; traversed as free they take the cost
// like a free cell, as Nav2 with inflate_unknown true does, and so stop
// being unknown in this planning copy (as clearance costs do).
//
// O(cells): a distance transform bounded by InflationCostReach.
// INVALID_ARGUMENT as CheckInflationCost.
absl::Status ApplyInflationCost(double robot_radius_cells, double inflation_radius_cells,
                                double cost_scaling_per_cell, bool unknown_is_free,
                                Grid* grid);
// The same with the caller's transform, reused across calls (ShapeGrid's
// steps share one), writing only the cells of `area` (a rectangle of the
// grid; distances still count every lethal cell of the grid), with the
// costs decaying from `decay_radius_cells` (>= robot_radius_cells; cells
// between the two cost 252, the most a traversable cell costs: a footprint
// checked cell by cell decides collisions there, GridShape). Precondition:
// CheckInflationCost(decay_radius_cells, ...) is OK.
void ApplyInflationCost(double robot_radius_cells, double decay_radius_cells,
                        double inflation_radius_cells, double cost_scaling_per_cell,
                        bool unknown_is_free, EuclideanDistanceField& transform,
                        const CellRect& area, Grid* grid);

}  // namespace pathd

#endif  // PATHD_CORE_MAP_INFLATION_COST_H_
