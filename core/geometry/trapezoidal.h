// Vertical trapezoidal decomposition of a grid's free space (Faigl, "Path
// Planning", Lecture 03, "Cell Decomposition"; de Berg et al., "Computational
// Geometry", ch. 6) and its adjacency graph, for the `trapezoidal` planner.
//
// Free space (core/geometry/free_space.h) is a union of unit squares, so every
// obstacle edge is horizontal or vertical and the trapezoids are axis-aligned
// rectangles. A vertical extension from an obstacle vertex on grid line X = x
// cuts the free segment of that line it lies on; a free segment with no vertex
// (both ends on horizontal obstacle edges) is cut by nothing. So the cells
// are exactly the maximal runs of consecutive columns whose free vertical run
// is the same interval: a column-by-column sweep with integer comparisons,
// which is why this is hand code rather than CGAL's arrangement machinery
// (whose point location and exact kernels buy nothing on unit squares).
#ifndef PATHD_CORE_GEOMETRY_TRAPEZOIDAL_H_
#define PATHD_CORE_GEOMETRY_TRAPEZOIDAL_H_

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "absl/types/span.h"
#include "core/geometry/free_space.h"
#include "core/map/grid.h"

namespace pathd {

// One cell of the decomposition: the closed rectangle [x0, x1] x [y0, y1] in
// cell coordinates, covering grid cells x0..x1-1, y0..y1-1 (all free). Its top
// and bottom are obstacle edges or the map border.
struct Trapezoid {
  int32_t x0 = 0;
  int32_t x1 = 0;
  int32_t y0 = 0;
  int32_t y1 = 0;
  friend bool operator==(const Trapezoid&, const Trapezoid&) = default;
};

// The boundary two trapezoids share: the segment x = `x`, y in [y0, y1]
// (y1 > y0), between `left` (which ends at x) and `right` (which starts at x).
struct CellBoundary {
  int32_t x = 0;
  int32_t y0 = 0;
  int32_t y1 = 0;
  int32_t left = 0;
  int32_t right = 0;
  friend bool operator==(const CellBoundary&, const CellBoundary&) = default;

  // The midpoint, a lattice point (2x, y0 + y1).
  LatticePoint Midpoint() const {
    return LatticePoint{2 * static_cast<int64_t>(x),
                        static_cast<int64_t>(y0) + y1};
  }
};

// The decomposition of one map version under one traversability rule, with
// the free space it was built from. Immutable once built; shared between
// threads as shared_ptr<const TrapezoidalDecomposition>.
class TrapezoidalDecomposition {
 public:
  static constexpr int32_t kNone = -1;

  // O(width * height).
  TrapezoidalDecomposition(const Grid& grid, bool unknown_is_free);
  // The same, or null when `stop` fired first: one sweep, but about 2 s at
  // 4096 x 4096, so it polls `stop` every kPollColumns columns and notes in
  // it that it gave up.
  static std::shared_ptr<const TrapezoidalDecomposition> Build(const Grid& grid,
                                                               bool unknown_is_free,
                                                               DerivedStop& stop);
  static constexpr int32_t kPollColumns = 16;

  // Trapezoids in sweep order: by x0, then y0.
  const std::vector<Trapezoid>& trapezoids() const { return trapezoids_; }
  // Portals by x, then y0.
  const std::vector<CellBoundary>& portals() const { return portals_; }
  // Ids of the portals on trapezoid t's boundary.
  absl::Span<const int32_t> PortalsOf(int32_t t) const {
    return absl::MakeConstSpan(portal_ids_.data() + portal_begin_[t],
                               portal_begin_[t + 1] - portal_begin_[t]);
  }
  // The trapezoid containing free cell `c`, kNone for a blocked cell.
  int32_t TrapezoidOf(Cell c) const {
    return cell_trapezoid_[static_cast<size_t>(c.y) * space_.width() + c.x];
  }
  const FreeSpace& space() const { return space_; }

  size_t bytes() const;

 private:
  struct Unswept {};
  // The free space and an empty cell table; Sweep() fills in the rest.
  TrapezoidalDecomposition(const Grid& grid, bool unknown_is_free, Unswept);
  // False when `stop` (may be null) fired first.
  bool Sweep(DerivedStop* stop);

  FreeSpace space_;
  std::vector<Trapezoid> trapezoids_;
  std::vector<CellBoundary> portals_;
  // CSR adjacency: portal ids of trapezoid t at portal_ids_[portal_begin_[t]
  // .. portal_begin_[t + 1]).
  std::vector<int32_t> portal_begin_;
  std::vector<int32_t> portal_ids_;
  std::vector<int32_t> cell_trapezoid_;
};

// A portal as a walker crossing it sees it: its right-hand and left-hand
// ends (with y pointing up; any consistent labelling works).
struct Gate {
  LatticePoint right;
  LatticePoint left;
};
// `portal` crossed from its left trapezoid to its right one (towards +x) or
// back.
Gate GateOf(const CellBoundary& portal, bool left_to_right);

// The shortest polyline from `start` to `goal` (lattice points) inside a
// channel of convex cells joined by `gates`, in crossing order: the simple
// stupid funnel algorithm (Mononen 2010, after Lee & Preparata 1984), bending
// only at gate ends.
std::vector<LatticePoint> PullString(LatticePoint start, LatticePoint goal,
                                     absl::Span<const Gate> gates);

}  // namespace pathd

#endif  // PATHD_CORE_GEOMETRY_TRAPEZOIDAL_H_
