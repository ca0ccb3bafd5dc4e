// Goal-rooted cost-to-go fields (the "shortest path map" of DESIGN.md) and the
// descent that turns one into a path: the raster distance transform (Jarvis
// 2004) and an exact Dijkstra sweep from the goal. The planners
// "distance_transform" and "distance_transform_exact" are built on these.
#ifndef PATHD_CORE_PLANNERS_COST_TO_GO_H_
#define PATHD_CORE_PLANNERS_COST_TO_GO_H_

#include <cstdint>
#include <vector>

#include "core/search/path_measure.h"
#include "core/search/endpoints.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/search/open_list.h"
#include "core/search/planner.h"
#include "core/search/radix_heap.h"
#include "core/search/search_scratch.h"

namespace pathd {

// A cost-to-go field and how its computation ended.
struct CostToGoField {
  // Row-major: the cost of the cheapest path from each cell to the goal under
  // the cost model (moving u -> v costs move length * CellFactor(v)); +inf for
  // blocked cells and cells that cannot reach the goal. Meaningful only when
  // outcome == kFound.
  std::vector<double> values;
  // kFound when the field is complete, else the stop condition's outcome.
  PlanOutcome outcome = PlanOutcome::kFound;
  // Raster transform: cells in the rows swept, at most passes x cells (rows
  // whose inputs did not change are skipped). Dijkstra sweep: cells settled.
  int64_t expansions = 0;
  // Raster transform only: raster passes made, forward and backward each
  // counting one.
  int32_t passes = 0;
};

// "Distance Transform for Path Planning" (Algorithm 1 of Faigl's lecture "Path
// Planning", B4M36UIR Lecture 03, after Jarvis 2004): 0 at the
// goal and infinity elsewhere, then alternating forward raster passes
// (top-left to bottom-right, each cell taking the best of its already visited
// neighbours W, N, NW, NE) and backward passes (bottom-right to top-left: E,
// S, SE, SW) until a pass changes nothing. Only the straight neighbours with
// 4-connectivity; a diagonal only without corner cutting. Converges to the
// exact cost-to-go; the number of passes grows with how often shortest paths
// turn against the raster directions (mazes need hundreds). Skips rows whose
// sweep could change nothing (same values, same passes, less work). Polls
// `stop` between rows. Precondition: the grid passes ValidateEndpoints with
// `goal` as goal.
CostToGoField RasterDistanceTransform(const Grid& grid, Cell goal, const CostParams& cost,
                                      const StopCondition& stop);

// The same field by Dijkstra's algorithm from the goal over reversed moves, in
// O(n log n) whatever the map's shape (a radix heap: keys never decrease).
// Polls `stop` every settled cell. Same precondition. Settled cells go to
// `recorder` unless it is null.
CostToGoField DijkstraCostToGo(const Grid& grid, Cell goal, const CostParams& cost,
                               const StopCondition& stop, SearchScratch& scratch,
                               ExpansionRecorder* recorder = nullptr);

namespace internal {
// DijkstraCostToGo on a chosen open list: MonotoneOpenList (what it uses) or
// the binary heap OpenList (what it used before), both instantiated, so a
// benchmark can compare the two in one binary. The fields are bit-identical.
template <typename Open>
CostToGoField DijkstraCostToGoOn(const Grid& grid, Cell goal, const CostParams& cost,
                                 const StopCondition& stop, SearchScratch& scratch,
                                 ExpansionRecorder* recorder = nullptr);
extern template CostToGoField DijkstraCostToGoOn<OpenList>(
    const Grid&, Cell, const CostParams&, const StopCondition&, SearchScratch&,
    ExpansionRecorder*);
extern template CostToGoField DijkstraCostToGoOn<MonotoneOpenList>(
    const Grid&, Cell, const CostParams&, const StopCondition&, SearchScratch&,
    ExpansionRecorder*);
}  // namespace internal

// Follows a complete field from `start` to the cell where it is 0 (the goal),
// each step to the neighbour v minimising move length * CellFactor(v) +
// field(v), the first in the cost model's move order on ties. Returns the path
// start..goal, or an empty path when the field is +inf at the start. For a
// field from the functions above, the path's cost (MeasurePath) equals the
// field at the start up to rounding. Precondition: `field` has one value per
// grid cell and `start` is on the grid.
std::vector<Cell> DescendCostToGo(const Grid& grid, const CostParams& cost,
                                  const std::vector<double>& field, Cell start);

}  // namespace pathd

#endif  // PATHD_CORE_PLANNERS_COST_TO_GO_H_
