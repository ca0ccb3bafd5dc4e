// Path simplification as post-processing for any planner's result: keeps
// only the "turn" cells of a ray-shooting pass over the path ("Path
// Simplification" in Faigl's lecture "Path Planning", B4M36UIR Lecture 03),
// joined by straight segments that pass LineOfSight.
#ifndef PATHD_CORE_POSTPROCESS_PATH_SIMPLIFY_H_
#define PATHD_CORE_POSTPROCESS_PATH_SIMPLIFY_H_

#include "core/search/path_measure.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/search/planner.h"

namespace pathd {

// Replaces result->path by a subsequence of its cells: from each kept cell,
// the farthest later path cell reached by a chain of valid shortcuts, where a
// shortcut is valid when its segment passes LineOfSight and its SegmentCost
// is no more than the cost of the stretch of path it replaces; repeated until
// a pass removes nothing, so simplifying again changes nothing. The result is
// any-angle (result->any_angle = true) with cost and length recomputed by
// MeasureAnyAnglePath; it is never costlier than the input (up to a relative
// 1e-12 per shortcut, for rounding of sums) and, by the triangle inequality,
// never longer. Accepts cell paths and any-angle paths; leaves results without
// a path untouched, and also geometric and kinematic results (a polyline, or
// poses) and paths that are not valid under `cost` (which no planner
// returns). A pass runs in O(path cells x segment length); passes
// after the first only see the kept cells.
void SimplifyPath(const Grid& grid, const CostParams& cost, PlanResult* result);

}  // namespace pathd

#endif  // PATHD_CORE_POSTPROCESS_PATH_SIMPLIFY_H_
