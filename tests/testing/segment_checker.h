// An independent checker of geometric paths: decides whether a straight
// segment between two points of the half-cell lattice lies in the free space
// of core/geometry/free_space.h, written from that rule alone and not from
// FreeSpace's method, so the tests can hold the planners (and FreeSpace
// itself) to it.
//
// The rule, restated: cell (x, y) is the closed square [x, x+1] x [y, y+1];
// cells that are not Traversable and every cell outside the grid are
// blocked. A point is NOT free when it lies in the open interior of a blocked
// cell, in the relative interior of an edge shared by two blocked cells, or
// on a closed grid corner: exactly two diagonally opposite cells blocked (a
// pinch) or all four. Equivalently: a point is free when it lies in some
// free cell's closed square and is not a pinch. So a corner with three
// blocked cells (a concave corner of the obstacles, e.g. the corners of the
// map) is free: it is a corner of the one free square, and touching it
// squeezes between nothing. (free_space.h's "include two diagonally opposite
// blocked cells ..., or four" read this way; the "or four" would be
// redundant otherwise. FreeSpace agrees, see segment_checker_test.)
// A segment is clear when every point of it, endpoints included, is free.
//
// Method: every obstacle feature (open square, open edge, corner point) is a
// product of two per-axis conditions, each either an open interval or an
// equality. For the segment P(t) = a + t (b - a), t in [0, 1], each condition
// bounds t from below and/or above, strictly or not; the segment meets the
// feature exactly when every lower bound is below every upper bound (strictly
// when either is strict). All of it in doubled integer coordinates, as
// fractions compared by cross-multiplication: exact, no floating point in
// any decision. Features are enumerated per column over the cells the
// segment's column span can touch (a superset, widened by a margin; the
// exhaustive mode scans the whole bounding box instead, and the tests check
// that both agree).
#ifndef PATHD_TESTS_TESTING_SEGMENT_CHECKER_H_
#define PATHD_TESTS_TESTING_SEGMENT_CHECKER_H_

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "absl/types/span.h"
#include "core/geometry/free_space.h"
#include "core/map/grid.h"

namespace pathd::testing {

// Why a segment is not clear: the first obstacle feature found.
struct SegmentDefect {
  enum class Kind {
    // A coordinate is not a multiple of 1/2 (polylines only).
    kNotOnLattice,
    // The segment meets the open interior of blocked cell `cell`.
    kCrossesBlockedCell,
    // The segment meets the open edge between blocked cells `cell` and
    // `other`.
    kAlongBlockedEdge,
    // The segment contains grid corner `corner`, a pinch (exactly two
    // diagonally opposite cells blocked) or enclosed (all four blocked).
    kThroughClosedCorner,
  };
  Kind kind = Kind::kCrossesBlockedCell;
  Cell cell;
  Cell other;
  // Grid corner (x, y), in cell units (kThroughClosedCorner).
  Cell corner;
  std::string ToString() const;
};

// Checks segments on one grid (copied: the blocked state is taken when the
// checker is made). Thread-compatible: const methods may run concurrently.
class SegmentChecker {
 public:
  SegmentChecker(const Grid& grid, bool unknown_is_free);

  // The segment a-b (doubled cell coordinates) is clear.
  bool Clear(LatticePoint a, LatticePoint b) const {
    return !FindDefect(a, b).has_value();
  }
  // The first obstacle feature the closed segment a-b meets, or nullopt when
  // it is clear. `exhaustive` scans every feature of the bounding box (slow
  // on long segments; the reference for the windowed scan).
  std::optional<SegmentDefect> FindDefect(LatticePoint a, LatticePoint b,
                                          bool exhaustive = false) const;

  // Cell (x, y) is blocked; any x, y (outside the grid: blocked).
  bool Blocked(int64_t x, int64_t y) const;
  // Grid corner (x, y) is not free: exactly two diagonally opposite cells
  // around it are blocked, or all four.
  bool ClosedCorner(int64_t x, int64_t y) const;

  int32_t width() const { return width_; }
  int32_t height() const { return height_; }

 private:
  // Checks the features owned by cell (x, y): its open square, the open
  // edges to its right (x+1, y) and upper (x, y+1) neighbours, and its lower
  // left corner (x, y).
  std::optional<SegmentDefect> CellFeatures(LatticePoint a, LatticePoint b,
                                            int64_t x, int64_t y) const;

  int32_t width_ = 0;
  int32_t height_ = 0;
  std::vector<uint8_t> blocked_;
};

// A bad polyline segment: segment `index` runs from vertex index to
// index + 1.
struct PolylineDefect {
  size_t index = 0;
  CellPoint from;
  CellPoint to;
  SegmentDefect defect;
  std::string ToString() const;
};

// Checks whole polylines (PlanResult::polyline) with a SegmentChecker.
class PolylineChecker {
 public:
  explicit PolylineChecker(const SegmentChecker& segments) : segments_(segments) {}

  // The first segment that is not clear (or whose vertices are not on the
  // half-cell lattice), or nullopt. A single vertex is checked as a point.
  std::optional<PolylineDefect> FirstDefect(
      absl::Span<const CellPoint> polyline) const;

 private:
  const SegmentChecker& segments_;
};

// Exact Euclidean length of a polyline whose vertices are on the half-cell
// lattice, summed in long double; for length comparisons in tests.
double LatticePolylineLength(absl::Span<const CellPoint> polyline);

}  // namespace pathd::testing

#endif  // PATHD_TESTS_TESTING_SEGMENT_CHECKER_H_
