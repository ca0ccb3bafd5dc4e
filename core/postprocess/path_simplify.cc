// Greedy ray-shooting simplification of planner paths (see path_simplify.h).
#include "core/search/path_measure.h"
#include "core/postprocess/path_simplify.h"

#include <cstddef>
#include <utility>
#include <vector>

#include "core/search/line_of_sight.h"

namespace pathd {
namespace {

// Two costs this close count as equal: a shortcut along a straight run of
// moves costs the same as the run, but the run's summed step costs and the
// segment's single product round differently.
constexpr double kRelativeSlack = 1e-12;

// One greedy pass: from each kept cell, the farthest later cell reachable by
// extending the shortcut one path cell at a time; prefix[k] is the cost along
// `path` from path[0] to path[k].
std::vector<Cell> SimplifyOnce(const Grid& grid, const CostParams& cost,
                               const std::vector<Cell>& path,
                               const std::vector<double>& prefix) {
  // Ray shooting as in the lecture, but with LineOfSight's supercover instead of
  // a plain Bresenham line: Bresenham picks one cell per column (or row), so
  // where the segment crosses from one row to the next inside a column it
  // never looks at the second cell and can clip the corner of an obstacle
  // there, and at an exact corner crossing it checks neither side cell. The
  // supercover checks every cell the segment touches, which for single moves
  // is the no-corner-cutting move rule. Stopping at the first failing
  // shortcut (instead of trying every later cell) keeps a pass linear in the
  // number of segment walks.
  std::vector<Cell> simplified{path[0]};
  size_t i = 0;
  while (i + 1 < path.size()) {
    size_t j = i + 1;
    while (j + 1 < path.size()) {
      const Cell from = path[i];
      const Cell to = path[j + 1];
      const double replaced = prefix[j + 1] - prefix[i];
      if (!LineOfSight(grid, from, to, cost) ||
          SegmentCost(grid, from, to, cost) >
              replaced * (1.0 + kRelativeSlack)) {
        break;
      }
      ++j;
    }
    // A path that comes back to a cell can make the turn cell the current one.
    if (path[j] != simplified.back()) simplified.push_back(path[j]);
    i = j;
  }
  return simplified;
}

// Cost along the path up to each cell, or false when a segment is blocked.
// A single move's SegmentCost is its move cost, so this holds for cell paths.
bool PrefixCosts(const Grid& grid, const CostParams& cost,
                 const std::vector<Cell>& path, std::vector<double>* prefix) {
  prefix->assign(path.size(), 0.0);
  for (size_t k = 1; k < path.size(); ++k) {
    if (!grid.InBounds(path[k]) ||
        !LineOfSight(grid, path[k - 1], path[k], cost)) {
      return false;
    }
    (*prefix)[k] =
        (*prefix)[k - 1] + SegmentCost(grid, path[k - 1], path[k], cost);
  }
  return true;
}

}  // namespace

void SimplifyPath(const Grid& grid, const CostParams& cost,
                  PlanResult* result) {
  std::vector<Cell>& path = result->path;
  // A geometric plan's polyline is its answer, and already straight; a
  // kinematic plan's poses are the robot's motion, which a shortcut between
  // cells would leave.
  if (path.empty() || !result->polyline.empty() || !result->poses.empty()) return;
  std::vector<double> prefix;
  if (!PrefixCosts(grid, cost, path, &prefix)) return;
  // A pass can leave a shortcut between two kept cells that the scan did not
  // try (it stopped at a cell in between), so repeat until nothing changes.
  // Each pass is never costlier than its input; later passes are short.
  while (true) {
    std::vector<Cell> simplified = SimplifyOnce(grid, cost, path, prefix);
    const bool changed = simplified.size() < path.size();
    path = std::move(simplified);
    if (!changed) break;
    PrefixCosts(grid, cost, path, &prefix);
  }
  result->any_angle = true;
  const PathMeasure measure = MeasureAnyAnglePath(grid, path, cost);
  result->cost = measure.cost;
  result->length = measure.length;
}

}  // namespace pathd
