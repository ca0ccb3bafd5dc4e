// The continuous free space of a grid, as the geometric planners see it
// (visibility graph, minimal construct, navigation mesh, trapezoidal cells,
// Euclidean shortest path maps), and the exact segment test they share.
//
// Cell (x, y) is the closed square [x, x+1] x [y, y+1] in cell coordinates
// (CellPoint). Blocked cells (not Traversable under the request) and
// everything outside the grid are obstacles. A point is in free space unless
// it lies
//  - in the open interior of a blocked cell,
//  - on an edge between two blocked cells, or
//  - on a grid corner whose four cells are blocked, or of which exactly two,
//    diagonally opposite, are blocked (a pinch: two obstacles touching at a
//    point). With three blocked, the corner is on the boundary of the free
//    one (a map corner is such a point).
// So a path may touch obstacle boundaries (run along a wall, turn at an
// obstacle corner), which is what makes Euclidean shortest paths polylines
// through obstacle corners, but never squeezes between two blocked cells
// that share only a corner: the no-corner-cutting rule of moves and line of
// sight. Touching is the one relaxation against line_of_sight.h, whose
// segments keep off blocked squares altogether; every line-of-sight segment
// is clear here too, so a geometric shortest path is never longer than
// Theta*'s.
//
// Coordinates are exact: every point a geometric planner puts in a path is a
// cell centre (start, goal) or a grid corner (a bend), so in doubled cell
// coordinates (LatticePoint) all of them are integers and every test below
// is integer arithmetic.
#ifndef PATHD_CORE_GEOMETRY_FREE_SPACE_H_
#define PATHD_CORE_GEOMETRY_FREE_SPACE_H_

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "absl/types/span.h"
#include "core/map/grid.h"
#include "core/search/derived.h"
#include "core/search/plan_types.h"

namespace pathd {

// A point in doubled cell coordinates: (x2 / 2, y2 / 2) in cell coordinates.
// Even components lie on grid lines; the centre of cell (x, y) is
// (2x + 1, 2y + 1), the corner (x, y) is (2x, 2y).
struct LatticePoint {
  int64_t x2 = 0;
  int64_t y2 = 0;
  friend bool operator==(const LatticePoint&, const LatticePoint&) = default;
};

inline LatticePoint CentreOf(Cell c) {
  return LatticePoint{2 * static_cast<int64_t>(c.x) + 1,
                      2 * static_cast<int64_t>(c.y) + 1};
}
inline LatticePoint CornerAt(int64_t x, int64_t y) {
  return LatticePoint{2 * x, 2 * y};
}
inline CellPoint ToCellPoint(LatticePoint p) {
  return CellPoint{static_cast<double>(p.x2) / 2.0,
                   static_cast<double>(p.y2) / 2.0};
}
// The lattice point at `p`, or nullopt when a coordinate is not a multiple
// of 1/2 (or too large to be a grid point).
inline std::optional<LatticePoint> ToLatticePoint(CellPoint p) {
  const double x2 = p.x * 2.0;
  const double y2 = p.y * 2.0;
  if (!(std::abs(x2) < 1e15 && std::abs(y2) < 1e15) || x2 != std::floor(x2) ||
      y2 != std::floor(y2)) {
    return std::nullopt;
  }
  return LatticePoint{static_cast<int64_t>(x2), static_cast<int64_t>(y2)};
}
// Euclidean distance in cells. The squared doubled distance is an exact
// integer in a double (coordinates < 2^18), so this is correctly rounded.
inline double Distance(LatticePoint a, LatticePoint b) {
  const double dx = static_cast<double>(b.x2 - a.x2);
  const double dy = static_cast<double>(b.y2 - a.y2);
  return std::sqrt(dx * dx + dy * dy) / 2.0;
}
// Euclidean length of a polyline, in cells.
double PolylineLength(absl::Span<const LatticePoint> polyline);

// The blocked/free state of a grid's cells under one traversability rule,
// padded by one blocked cell on every side so the outside reads as blocked
// without bounds checks. A value type, O(width * height) bytes; built once
// per map version and shared (core/search/derived.h), or updated in place
// for changed cells.
class FreeSpace {
 public:
  FreeSpace() = default;
  FreeSpace(const Grid& grid, bool unknown_is_free);

  int32_t width() const { return width_; }
  int32_t height() const { return height_; }
  bool unknown_is_free() const { return unknown_is_free_; }

  // Re-reads `changed` cells from `grid` (same size as the one built from).
  void Update(const Grid& grid, absl::Span<const Cell> changed);

  // Cell (x, y) is blocked; any x, y (outside the grid: blocked).
  bool Blocked(int64_t x, int64_t y) const {
    if (x < -1 || y < -1 || x > width_ || y > height_) return true;
    return blocked_[static_cast<size_t>(y + 1) * stride_ +
                    static_cast<size_t>(x + 1)] != 0;
  }
  // The four cells around grid corner (x, y): bit 0 cell (x-1, y-1), bit 1
  // (x, y-1), bit 2 (x-1, y), bit 3 (x, y).
  int CornerMask(int64_t x, int64_t y) const {
    return (Blocked(x - 1, y - 1) ? 1 : 0) | (Blocked(x, y - 1) ? 2 : 0) |
           (Blocked(x - 1, y) ? 4 : 0) | (Blocked(x, y) ? 8 : 0);
  }
  // Grid corner (x, y) is in free space (not a pinch, not enclosed).
  bool CornerFree(int64_t x, int64_t y) const;
  // Grid corner (x, y) is a convex obstacle corner: exactly one of its four
  // cells is blocked. The only points where a Euclidean shortest path bends.
  bool IsBendCorner(int64_t x, int64_t y) const;
  // Every bend corner, row by row (y, then x), corners 0..width x 0..height.
  std::vector<LatticePoint> BendCorners() const;

  // `p` is in free space.
  bool PointFree(LatticePoint p) const;
  // Every point of the closed segment a-b is in free space. Exact; O(cells
  // the segment crosses).
  bool SegmentClear(LatticePoint a, LatticePoint b) const;
  // Every segment of the polyline is clear.
  bool PolylineClear(absl::Span<const LatticePoint> polyline) const;

  // Calls visit(Cell) for each cell whose interior the segment a-b meets, in
  // order from a to b; for a piece running along a grid line, the free cell
  // beside it (the one below or left when both are free). Cells may be
  // outside the grid when the segment is not clear.
  template <typename Visit>
  void ForEachCellCrossed(LatticePoint a, LatticePoint b, Visit&& visit) const;

  size_t bytes() const { return blocked_.capacity(); }

 private:
  void Set(int64_t x, int64_t y, bool blocked) {
    blocked_[static_cast<size_t>(y + 1) * stride_ + static_cast<size_t>(x + 1)] =
        blocked ? 1 : 0;
  }

  int32_t width_ = 0;
  int32_t height_ = 0;
  size_t stride_ = 0;
  bool unknown_is_free_ = false;
  std::vector<uint8_t> blocked_;
};

// The FreeSpace of `grid` under `unknown_is_free`, shared by every geometric
// planner through `store` (key "free_space unknown_is_free=N", advanced with
// FreeSpace::Update), or built now when `store` is null.
std::shared_ptr<const FreeSpace> SharedFreeSpace(DerivedStore* store, const Grid& grid,
                                                 bool unknown_is_free);
// The same under the query's `stop`: the build (O(cells)) does not poll it,
// but a query waits for another's build of it only until `stop` fires. Null
// then, or when `stop` had fired before the build would start.
std::shared_ptr<const FreeSpace> SharedFreeSpace(DerivedStore* store, const Grid& grid,
                                                 bool unknown_is_free, DerivedStop& stop);

// The cells a polyline crosses, start to end, without repeats of the
// previous cell: the `path` of a geometric plan (PlanResult::polyline).
std::vector<Cell> CellsAlongPolyline(const FreeSpace& space,
                                     absl::Span<const LatticePoint> polyline);

// Fills `result` for a found geometric plan along `polyline` (start centre to
// goal centre): polyline, the cells it crosses, length, and cost = length x
// `cell_factor`, the one factor of every traversable cell (the geometric
// planners refuse maps with more than one).
void FillPolylineResult(const FreeSpace& space,
                        absl::Span<const LatticePoint> polyline,
                        double cell_factor, PlanResult& result);

// ---- implementation of the template ----

namespace free_space_internal {
// floor(n / d) for d > 0.
inline int64_t FloorDiv(int64_t n, int64_t d) {
  return n >= 0 ? n / d : -((-n + d - 1) / d);
}
// ceil(n / d) for d > 0.
inline int64_t CeilDiv(int64_t n, int64_t d) { return -FloorDiv(-n, d); }
}  // namespace free_space_internal

template <typename Visit>
void FreeSpace::ForEachCellCrossed(LatticePoint a, LatticePoint b,
                                   Visit&& visit) const {
  using free_space_internal::CeilDiv;
  using free_space_internal::FloorDiv;
  // The free one of two cells beside a grid-line piece (lower/left first).
  auto beside = [&](Cell first, Cell second) {
    visit(Blocked(first.x, first.y) ? second : first);
  };
  if (a.x2 == b.x2) {
    // Vertical: along a grid line (even x2) or inside one column.
    const int64_t sy = b.y2 >= a.y2 ? 1 : -1;
    const int64_t lo = std::min(a.y2, b.y2);
    const int64_t hi = std::max(a.y2, b.y2);
    // Rows j whose open span (2j, 2j + 2) meets (lo, hi); a point: its row.
    int64_t j_first = FloorDiv(lo, 2);
    int64_t j_last = lo == hi ? j_first : CeilDiv(hi, 2) - 1;
    if (sy < 0) std::swap(j_first, j_last);
    for (int64_t j = j_first;; j += sy) {
      if (a.x2 % 2 == 0) {
        const int32_t gx = static_cast<int32_t>(a.x2 / 2);
        beside(Cell{gx - 1, static_cast<int32_t>(j)},
               Cell{gx, static_cast<int32_t>(j)});
      } else {
        visit(Cell{static_cast<int32_t>((a.x2 - 1) / 2), static_cast<int32_t>(j)});
      }
      if (j == j_last) break;
    }
    return;
  }
  // Walk columns from a to b.
  const int64_t sx = b.x2 > a.x2 ? 1 : -1;
  const int64_t dx = (b.x2 - a.x2) * sx;  // > 0
  const int64_t dy = b.y2 - a.y2;
  // Scaled y (times dx) at doubled x.
  auto y_scaled = [&](int64_t x2) { return a.y2 * dx + (x2 - a.x2) * sx * dy; };
  int64_t c = sx > 0 ? FloorDiv(a.x2, 2) : CeilDiv(a.x2, 2) - 1;
  while (true) {
    const int64_t strip_lo = 2 * c;
    const int64_t strip_hi = 2 * c + 2;
    const int64_t xs = sx > 0 ? std::max(a.x2, strip_lo) : std::min(a.x2, strip_hi);
    const int64_t xe = sx > 0 ? std::min(b.x2, strip_hi) : std::max(b.x2, strip_lo);
    if ((xe - xs) * sx <= 0) break;
    const int32_t col = static_cast<int32_t>(c);
    if (dy == 0) {
      if (a.y2 % 2 == 0) {
        const int32_t gy = static_cast<int32_t>(a.y2 / 2);
        beside(Cell{col, gy - 1}, Cell{col, gy});
      } else {
        visit(Cell{col, static_cast<int32_t>((a.y2 - 1) / 2)});
      }
    } else {
      const int64_t y0 = y_scaled(xs);
      const int64_t y1 = y_scaled(xe);
      const int64_t unit = 2 * dx;
      // Rows whose open span meets the open interval between y0 and y1.
      if (y1 > y0) {
        for (int64_t j = FloorDiv(y0, unit); j <= CeilDiv(y1, unit) - 1; ++j)
          visit(Cell{col, static_cast<int32_t>(j)});
      } else {
        for (int64_t j = CeilDiv(y0, unit) - 1; j >= FloorDiv(y1, unit); --j)
          visit(Cell{col, static_cast<int32_t>(j)});
      }
    }
    c += sx;
  }
}

}  // namespace pathd

#endif  // PATHD_CORE_GEOMETRY_FREE_SPACE_H_
