// Isochrones: the cells reachable from a start within a cost budget, and
// that region as polygons with holes. The polygons are the region's cell
// squares merged (core/geometry/obstacle_polygons.h traces the boundary
// rings; Boost.Geometry assigns each hole to the exterior around it), so
// they are exact at cell resolution: a cell's centre is inside a polygon if
// and only if the cell is reachable. Pure functions; thread-compatible.
#ifndef PATHD_CORE_FLEET_ISOCHRONE_H_
#define PATHD_CORE_FLEET_ISOCHRONE_H_

#include <cstdint>
#include <vector>

#include "absl/status/statusor.h"
#include "core/geometry/obstacle_polygons.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/search/plan_types.h"
#include "core/search/stop_condition.h"

namespace pathd {

// A polygon on cell corners: the exterior counter-clockwise and the holes
// clockwise (shoelace sign in (x, y) cell coordinates), each ring open (the
// last vertex joins the first), vertices only where the boundary turns.
struct CellPolygon {
  std::vector<GridCorner> exterior;
  std::vector<std::vector<GridCorner>> holes;
};

struct Isochrone {
  // kFound when complete, else the stop condition's outcome (nothing else
  // set then).
  PlanOutcome outcome = PlanOutcome::kFound;
  // Row-major, 1 for the cells whose cheapest cost from the start is at most
  // the budget.
  std::vector<uint8_t> reachable;
  int64_t reachable_cells = 0;
  std::vector<CellPolygon> polygons;
  int64_t expansions = 0;
};

// The isochrone of `start` (on the grid and traversable: the caller checks)
// within `budget` (>= 0, cells of cost) under `cost`: Dijkstra's search from
// the start, stopped past the budget, so the work is proportional to the
// region, not the map.
Isochrone ComputeIsochrone(const Grid& grid, const CostParams& cost, Cell start,
                           double budget, const StopCondition& stop);

// The polygons of the cells marked in `inside` (row-major, width x height):
// one per connected region (cells joined through edges; two cells touching
// only at a corner are separate polygons meeting there), holes included.
std::vector<CellPolygon> RegionPolygons(int32_t width, int32_t height,
                                        const std::vector<uint8_t>& inside);

}  // namespace pathd

#endif  // PATHD_CORE_FLEET_ISOCHRONE_H_
