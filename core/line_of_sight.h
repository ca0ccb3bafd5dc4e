// Line of sight on the grid with the same no-corner-cutting rule as moves,
// and the cost of a straight segment: shared by the any-angle planners, path
// simplification and the potential field's collision check.
//
// A segment is clear when every cell whose closed square meets it is
// traversable. For single moves this is exactly the move rule: a straight move
// touches only its two cells, a diagonal move also touches the two side cells
// at the shared corner.
#ifndef PATHD_CORE_LINE_OF_SIGHT_H_
#define PATHD_CORE_LINE_OF_SIGHT_H_

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>

#include "core/cost_model.h"
#include "core/grid.h"

namespace pathd {

// Calls visit(x, y, corner_only) for every cell whose closed square meets the
// segment between the centres of a and b, in order from a to b (a first, b
// last). corner_only is true for cells the segment only touches at a corner
// point. Stops and returns false as soon as visit returns false. Exact: the
// walk runs on doubled integer coordinates, so corner crossings are never
// missed by rounding. Every visited cell lies in the bounding box of a and b.
template <typename Visit>
bool ForEachCellOnSegment(Cell a, Cell b, Visit&& visit) {
  int32_t cx = a.x;
  int32_t cy = a.y;
  if (!visit(cx, cy, false)) return false;
  const int64_t adx = std::abs(static_cast<int64_t>(b.x) - a.x);
  const int64_t ady = std::abs(static_cast<int64_t>(b.y) - a.y);
  const int32_t sx = b.x > a.x ? 1 : -1;
  const int32_t sy = b.y > a.y ? 1 : -1;
  // In doubled coordinates the start is at the centre (offset 1 from its cell
  // edge) and the next boundary along x is 1 + 2 * (steps taken along x) away.
  // Crossing times compare as dist_x / adx vs dist_y / ady.
  int64_t dist_x = 1;
  int64_t dist_y = 1;
  while (cx != b.x || cy != b.y) {
    // Infinite time for an axis the segment does not move along.
    const bool step_x_first =
        ady == 0 || (adx != 0 && dist_x * ady < dist_y * adx);
    const bool step_y_first =
        adx == 0 || (ady != 0 && dist_y * adx < dist_x * ady);
    if (step_x_first) {
      cx += sx;
      dist_x += 2;
      if (!visit(cx, cy, false)) return false;
    } else if (step_y_first) {
      cy += sy;
      dist_y += 2;
      if (!visit(cx, cy, false)) return false;
    } else {
      // Through a corner: the two side cells are touched at one point.
      if (!visit(cx + sx, cy, true)) return false;
      if (!visit(cx, cy + sy, true)) return false;
      cx += sx;
      cy += sy;
      dist_x += 2;
      dist_y += 2;
      if (!visit(cx, cy, false)) return false;
    }
  }
  return true;
}

// The same walk for a segment between arbitrary points in cell coordinates
// (CellPoint). A crossing within 1e-9 cells of a corner counts as a corner
// crossing, so the test errs towards "blocked". Cells may be out of bounds
// when the points are near the edge; visit must check.
template <typename Visit>
bool ForEachCellOnSegment(CellPoint p, CellPoint q, Visit&& visit) {
  constexpr double kCornerEps = 1e-9;
  int32_t cx = static_cast<int32_t>(std::floor(p.x));
  int32_t cy = static_cast<int32_t>(std::floor(p.y));
  const int32_t ex = static_cast<int32_t>(std::floor(q.x));
  const int32_t ey = static_cast<int32_t>(std::floor(q.y));
  if (!visit(cx, cy, false)) return false;
  const double dx = q.x - p.x;
  const double dy = q.y - p.y;
  const int32_t sx = dx > 0 ? 1 : -1;
  const int32_t sy = dy > 0 ? 1 : -1;
  const double inf = std::numeric_limits<double>::infinity();
  // Parameter t in [0, 1] at the next x / y boundary, and its increment.
  const double step_tx = dx != 0 ? std::abs(1.0 / dx) : inf;
  const double step_ty = dy != 0 ? std::abs(1.0 / dy) : inf;
  double tx = dx != 0 ? ((dx > 0 ? cx + 1 - p.x : p.x - cx) * step_tx) : inf;
  double ty = dy != 0 ? ((dy > 0 ? cy + 1 - p.y : p.y - cy) * step_ty) : inf;
  // Bounded by the number of boundaries crossed, so rounding cannot loop.
  const int64_t max_steps =
      std::abs(static_cast<int64_t>(ex) - cx) + std::abs(static_cast<int64_t>(ey) - cy);
  for (int64_t i = 0; i < max_steps && (cx != ex || cy != ey); ++i) {
    if (std::abs(tx - ty) <= kCornerEps * (step_tx < step_ty ? step_tx : step_ty) &&
        tx <= 1.0) {
      if (!visit(cx + sx, cy, true)) return false;
      if (!visit(cx, cy + sy, true)) return false;
      cx += sx;
      cy += sy;
      tx += step_tx;
      ty += step_ty;
      ++i;
    } else if (tx < ty) {
      cx += sx;
      tx += step_tx;
    } else {
      cy += sy;
      ty += step_ty;
    }
    if (!visit(cx, cy, false)) return false;
  }
  return true;
}

// True when every cell the segment between the centres of a and b touches is
// on the grid and traversable under `cost`.
inline bool LineOfSight(const Grid& grid, Cell a, Cell b, const CostParams& cost) {
  return ForEachCellOnSegment(a, b, [&](int32_t x, int32_t y, bool) {
    return grid.InBounds(x, y) && Traversable(grid.cost(x, y), cost.unknown_is_free);
  });
}

// Cost of following the segment from the centre of a to the centre of b:
// Euclidean length times the largest cell factor among the cells it passes
// through (corner-only touches and a itself excluded). Equals the move cost of
// every single move and the plain length when all cells cost the same.
// Precondition: LineOfSight(grid, a, b, cost).
inline double SegmentCost(const Grid& grid, Cell a, Cell b, const CostParams& cost) {
  double factor = 1.0;
  bool first = true;
  ForEachCellOnSegment(a, b, [&](int32_t x, int32_t y, bool corner_only) {
    if (!first && !corner_only) {
      const double f = CellFactor(grid.cost(x, y), cost.cost_weight);
      if (f > factor) factor = f;
    }
    first = false;
    return true;
  });
  return std::hypot(static_cast<double>(b.x - a.x), static_cast<double>(b.y - a.y)) *
         factor;
}

}  // namespace pathd

#endif  // PATHD_CORE_LINE_OF_SIGHT_H_
