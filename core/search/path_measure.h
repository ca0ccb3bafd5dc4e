// The move rule as a check on given paths, and the measurement (cost, length,
// validity) of grid and any-angle paths.
#ifndef PATHD_CORE_SEARCH_PATH_MEASURE_H_
#define PATHD_CORE_SEARCH_PATH_MEASURE_H_

#include <string_view>
#include <vector>

#include "core/kinematics/pose_path.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/search/plan_types.h"

namespace pathd {

// Why two consecutive cells of a path are not one legal move apart.
// Traversability of the cells themselves is not part of it.
enum class MoveFault {
  kNone,
  // The same cell twice, or cells more than one apart in x or y.
  kNotAdjacent,
  // A diagonal move on a 4-connected grid.
  kDiagonalOnFourConnected,
  // A diagonal move with a side cell off the grid or not traversable.
  kCornerCut,
};

// "not adjacent", "diagonal on a 4-connected grid", "cuts a corner" ("legal"
// for kNone), for messages.
std::string_view MoveFaultName(MoveFault fault);

// The move rule every planner's neighbour generation follows, for checking
// given paths: the fault of the move a -> b, kNone when it is legal.
MoveFault CheckMove(const Grid& grid, Cell a, Cell b, const CostParams& cost);

// Measures a cell path: every consecutive pair must be a legal move (adjacent
// under the connectivity, traversable, no corner cutting).
PathMeasure MeasurePath(const Grid& grid, const std::vector<Cell>& path,
                        const CostParams& cost);

// Measures an any-angle path: every consecutive pair must have line of sight
// (core/search/line_of_sight.h); cost sums SegmentCost, length the Euclidean lengths.
PathMeasure MeasureAnyAnglePath(const Grid& grid, const std::vector<Cell>& path,
                                const CostParams& cost);

// Measures a geometric polyline (PlanResult::polyline): every vertex a cell
// centre or grid corner, every segment clear under the free-space rule of
// core/geometry/free_space.h; first_invalid is the index of the first bad
// vertex or segment end. Length is Euclidean; cost the length of each
// segment times the largest cell factor among the cells it crosses.
PathMeasure MeasurePolyline(const Grid& grid,
                            const std::vector<CellPoint>& polyline,
                            const CostParams& cost);

// Measures a kinematic path (PlanResult::poses, with `path` its cells):
// valid when `path` is the poses' cells with consecutive duplicates removed
// (PathCells), each on the grid and traversable under `cost`, and
// consecutive poses are at most a cell apart (PlanResult::poses' contract;
// first_invalid: the index of the first bad pose or cell). Length is
// PathLength(poses) and cost PathCost(grid, poses, penalties)
// (core/kinematics/pose_path.h). Only the centre's cells are checked, not
// the footprint, and not the grid's move rule: a robot's motion is its own.
PathMeasure MeasurePosePath(const Grid& grid, const std::vector<PathPose>& poses,
                            const std::vector<Cell>& path, const CostParams& cost,
                            const MotionPenalties& penalties);

// MeasurePolyline for geometric results, MeasurePosePath for kinematic ones
// (priced with KinematicQuery's default penalties and cost_penalty =
// cost.cost_weight, what a kinematic planner uses for a request without a
// kinematic query; MeasurePosePath prices a query's own), MeasureAnyAnglePath
// when result.any_angle, else MeasurePath.
PathMeasure MeasureResultPath(const Grid& grid, const PlanResult& result,
                              const CostParams& cost);

}  // namespace pathd

#endif  // PATHD_CORE_SEARCH_PATH_MEASURE_H_
