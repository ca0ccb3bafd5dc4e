// Clearance as a cell cost: PlanOptions.min_clearance_m for the grid
// planners. Cells closer than the requested clearance to anything the robot
// centre may not occupy (lethal, inscribed and, unless traversed as free,
// unknown cells, and the outside of the map) cost more the closer they are,
// so every cost-aware planner keeps that far from walls where the map allows
// and passes closer only where a detour would cost more. A preference, not a
// rule: the hard rule is the robot radius (core/map/inflation.h), whose
// inscribed cells these distances are measured from.
//
// Distances are exact Euclidean distances between cell centres
// (core/map/euclidean_distance.h), like the robot radius's.
#ifndef PATHD_CORE_MAP_CLEARANCE_H_
#define PATHD_CORE_MAP_CLEARANCE_H_

#include <cstdint>

#include "absl/status/status.h"
#include "absl/types/span.h"
#include "core/map/euclidean_distance.h"
#include "core/map/grid.h"

namespace pathd {

// The cost a traversable cell at `distance` cells from the nearest
// obstacle gets (at least; a costlier cell keeps its cost): a linear ramp
// from kMaxTraversableCost at distance 0 to 0 at min_clearance, rounded up,
// so every cell short of the clearance costs something. With the cost
// model's step = length * (1 + w * c / 252) a step beside a wall (distance
// 1) of a 10-cell clearance costs 1.9 times a free step at w = 1, which
// cost_weight scales.
uint8_t ClearanceCost(double distance, double min_clearance_cells);

// Raises the cost of every traversable cell of `grid` closer than
// min_clearance_cells (> 0) to an obstacle to ClearanceCost. Unknown cells
// traversed as free (unknown_is_free) near obstacles take the ramp's cost
// and so stop being unknown in this planning copy. O(cells): a distance
// transform bounded by the clearance. INVALID_ARGUMENT naming the clearance
// when it is not finite or not positive.
absl::Status ApplyClearanceCost(double min_clearance_cells, bool unknown_is_free,
                                Grid* grid);
// The same with the caller's transform, reused across calls (ShapeGrid's
// steps share one), writing only the cells of `area` (a rectangle of the
// grid; distances still count every obstacle of the grid). Precondition:
// min_clearance_cells finite and > 0.
void ApplyClearanceCost(double min_clearance_cells, bool unknown_is_free,
                        EuclideanDistanceField& transform, const CellRect& area,
                        Grid* grid);

// The smallest clearance of the path's cells: the exact Euclidean distance
// (cells) from a cell's centre to the centre of the nearest cell the robot
// centre may not occupy, the map's outside included. Infinity for an empty
// path. Each cell's nearest obstacle is searched in growing square rings,
// bounded by the smallest found so far, and cells the path reaches within
// less than (their distance - smallest) of a measured cell are skipped
// (clearance changes by at most the length walked), so open stretches cost
// little.
double PathClearance(const Grid& grid, absl::Span<const Cell> path,
                     bool unknown_is_free);

}  // namespace pathd

#endif  // PATHD_CORE_MAP_CLEARANCE_H_
