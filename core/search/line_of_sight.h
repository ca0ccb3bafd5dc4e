// Line of sight on the grid with the same no-corner-cutting rule as moves,
// and the cost of a straight segment: shared by the any-angle planners, path
// simplification and the potential field's collision check.
//
// A segment is clear when every cell whose closed square meets it is
// traversable. For single moves this is exactly the move rule: a straight move
// touches only its two cells, a diagonal move also touches the two side cells
// at the shared corner.
#ifndef PATHD_CORE_SEARCH_LINE_OF_SIGHT_H_
#define PATHD_CORE_SEARCH_LINE_OF_SIGHT_H_

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>

#include "core/map/cost_model.h"
#include "core/map/grid.h"

namespace pathd {

// Calls visit(x, y, corner_only) for every cell whose closed square meets the
// segment between the centres of a and b (the supercover), in order from a to
// b: a first, b last, the two cells at a corner the segment passes through
// between the cells before and after it. corner_only is true exactly for cells
// the segment meets in a single point (such a corner). Stops and returns false
// as soon as visit returns false. Exact: in doubled coordinates the centres
// are odd integers, so crossings compare in integer arithmetic. Every visited
// cell lies in the bounding box of a and b; a == b visits a once.
template <typename Visit>
bool ForEachCellOnSegment(Cell a, Cell b, Visit&& visit);

// The same walk, also passing each cell's row-major index in a grid `width`
// cells wide: visit(x, y, index, corner_only). For hot loops (the any-angle
// planners), which read cells by index and let the compiler drop x and y.
template <typename Visit>
bool ForEachCellOnSegmentIndexed(Cell a, Cell b, int64_t width, Visit&& visit) {
  int32_t cx = a.x;
  int32_t cy = a.y;
  int64_t index = static_cast<int64_t>(a.y) * width + a.x;
  if (!visit(cx, cy, index, false)) return false;
  const int64_t adx = std::abs(static_cast<int64_t>(b.x) - a.x);
  const int64_t ady = std::abs(static_cast<int64_t>(b.y) - a.y);
  const int32_t sx = b.x > a.x ? 1 : -1;
  const int32_t sy = b.y > a.y ? 1 : -1;
  const int64_t step_y = sy * width;
  // With the segment scaled to run from t = 0 to 2 * adx * ady, the next
  // vertical boundary is crossed at dist_x * ady and the next horizontal one
  // at dist_y * adx, where dist_x = 1, 3, 5, ... is the doubled distance to
  // it. error = dist_x * ady - dist_y * adx says which comes first (negative:
  // x; zero: both, a corner), updated Bresenham-style without multiplying.
  // An axis without motion never crosses: ady == 0 keeps error = -adx < 0 and
  // adx == 0 keeps it = ady > 0.
  int64_t error = ady - adx;
  // Every step crosses one boundary, a corner two.
  for (int64_t crossings = adx + ady; crossings > 0; --crossings) {
    if (error < 0) {
      cx += sx;
      index += sx;
      error += 2 * ady;
    } else if (error > 0) {
      cy += sy;
      index += step_y;
      error -= 2 * adx;
    } else {
      if (!visit(cx + sx, cy, index + sx, true)) return false;
      if (!visit(cx, cy + sy, index + step_y, true)) return false;
      cx += sx;
      cy += sy;
      index += sx + step_y;
      error += 2 * (ady - adx);
      --crossings;
    }
    if (!visit(cx, cy, index, false)) return false;
  }
  return true;
}

template <typename Visit>
bool ForEachCellOnSegment(Cell a, Cell b, Visit&& visit) {
  return ForEachCellOnSegmentIndexed(
      a, b, 0, [&](int32_t x, int32_t y, int64_t, bool corner_only) {
        return visit(x, y, corner_only);
      });
}

// The same walk for a segment between arbitrary points in cell coordinates
// (CellPoint; precondition: finite). Visits every cell whose closed square
// meets the segment, in order from p to q, starting with the cell the segment
// occupies as it leaves p. corner_only is true for cells it meets in a single
// point: the side cells of a corner it passes through, and cells touched only
// at p or q when p or q lies on a cell boundary. A segment running along a
// boundary (p.x == q.x an integer, or p.y == q.y) touches the cells on both
// sides. A crossing within 1e-9 cells of a corner counts as a corner
// crossing, and a boundary within 1e-9 cells past q as reached, so floating
// point rounding errs towards visiting extra cells ("blocked"), never fewer.
// Cells may be out of bounds when the points are near the edge; visit must
// check.
template <typename Visit>
bool ForEachCellOnSegment(CellPoint p, CellPoint q, Visit&& visit) {
  constexpr double kEps = 1e-9;
  const double dx = q.x - p.x;
  const double dy = q.y - p.y;
  const int32_t sx = dx < 0 ? -1 : 1;
  const int32_t sy = dy < 0 ? -1 : 1;
  const double fx = std::floor(p.x);
  const double fy = std::floor(p.y);
  const bool on_x = p.x == fx;  // p on a vertical cell boundary
  const bool on_y = p.y == fy;
  // The cell the segment is in just after leaving p.
  int32_t cx = static_cast<int32_t>(fx) - (on_x && dx < 0 ? 1 : 0);
  int32_t cy = static_cast<int32_t>(fy) - (on_y && dy < 0 ? 1 : 0);
  // Staying on a boundary: the column (row) below cx (cy) is touched too.
  const bool twin_x = on_x && dx == 0;
  const bool twin_y = on_y && dy == 0;
  auto visit_with_twins = [&](int32_t x, int32_t y, bool corner_only,
                              bool twin_corner_only) {
    if (!visit(x, y, corner_only)) return false;
    if (twin_x && !visit(x - 1, y, twin_corner_only)) return false;
    if (twin_y && !visit(x, y - 1, twin_corner_only)) return false;
    if (twin_x && twin_y && !visit(x - 1, y - 1, twin_corner_only))
      return false;
    return true;
  };
  const bool is_point = dx == 0 && dy == 0;
  if (!visit_with_twins(cx, cy, false, is_point)) return false;
  // Leaving a boundary, the cells behind it meet the segment at p only.
  const bool behind_x = on_x && dx != 0;
  const bool behind_y = on_y && dy != 0;
  if (behind_x && !visit_with_twins(cx - sx, cy, true, true)) return false;
  if (behind_y && !visit_with_twins(cx, cy - sy, true, true)) return false;
  if (behind_x && behind_y && !visit(cx - sx, cy - sy, true)) return false;
  if (is_point) return true;

  constexpr double kInf = std::numeric_limits<double>::infinity();
  // Segment parameter t in [0, 1] at the next boundary crossed along each
  // axis, computed afresh each time (no accumulated rounding).
  auto next_tx = [&] {
    return dx == 0 ? kInf : ((sx > 0 ? cx + 1 : cx) - p.x) / dx;
  };
  auto next_ty = [&] {
    return dy == 0 ? kInf : ((sy > 0 ? cy + 1 : cy) - p.y) / dy;
  };
  // kEps cells along the faster axis, as a parameter interval.
  const double eps_t = kEps / std::max(std::abs(dx), std::abs(dy));
  double tx = next_tx();
  double ty = next_ty();
  while (true) {
    const double t = std::min(tx, ty);
    if (!(t <= 1.0 + eps_t)) break;
    // A boundary reached at q: the new cell meets the segment at q only.
    const bool at_end = t >= 1.0 - eps_t;
    if (std::abs(tx - ty) <= eps_t) {
      if (!visit(cx + sx, cy, true)) return false;
      if (!visit(cx, cy + sy, true)) return false;
      cx += sx;
      cy += sy;
      // Both coordinates move, so there are no twins.
      if (!visit(cx, cy, at_end)) return false;
      tx = next_tx();
      ty = next_ty();
    } else if (tx < ty) {
      cx += sx;
      if (!visit_with_twins(cx, cy, at_end, at_end)) return false;
      tx = next_tx();
    } else {
      cy += sy;
      if (!visit_with_twins(cx, cy, at_end, at_end)) return false;
      ty = next_ty();
    }
  }
  return true;
}

// Euclidean distance between the centres of a and b. The sum of squares is an
// exact integer in a double, so this is the correctly rounded length and the
// same on every platform (std::hypot only promises 1 ulp).
inline double SegmentLength(Cell a, Cell b) {
  const double dx = static_cast<double>(b.x) - a.x;
  const double dy = static_cast<double>(b.y) - a.y;
  return std::sqrt(dx * dx + dy * dy);
}

// True when every cell the segment between the centres of a and b touches is
// on the grid and traversable under `cost`.
inline bool LineOfSight(const Grid& grid, Cell a, Cell b,
                        const CostParams& cost) {
  return ForEachCellOnSegment(a, b, [&](int32_t x, int32_t y, bool) {
    return grid.InBounds(x, y) &&
           Traversable(grid.cost(x, y), cost.unknown_is_free);
  });
}

// Cost of following the segment from the centre of a to the centre of b:
// Euclidean length times the largest cell factor among the cells it passes
// through (corner-only touches and a itself excluded, as a move pays for the
// cell it enters). Equals the move cost of every single move, and the
// Euclidean length when cost_weight is 0 or every cell on the way is free.
// Never less than the Euclidean length, so it keeps the Euclidean heuristic
// admissible. Precondition: LineOfSight(grid, a, b, cost).
inline double SegmentCost(const Grid& grid, Cell a, Cell b,
                          const CostParams& cost) {
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
  return SegmentLength(a, b) * factor;
}

}  // namespace pathd

#endif  // PATHD_CORE_SEARCH_LINE_OF_SIGHT_H_
