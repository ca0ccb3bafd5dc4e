#include "core/geometry/trapezoidal.h"

#include <algorithm>
#include <cstdint>
#include <memory>
#include <vector>

#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "core/geometry/structure.h"

namespace pathd {
namespace {

// A maximal vertical run of free cells, rows [y0, y1), in the trapezoid `id`.
struct Run {
  int32_t y0;
  int32_t y1;
  int32_t id;
};

// The free runs of column x, top to bottom, without ids.
void ColumnRuns(const FreeSpace& space, int32_t x, std::vector<Run>& runs) {
  runs.clear();
  int32_t y = 0;
  while (y < space.height()) {
    if (space.Blocked(x, y)) {
      ++y;
      continue;
    }
    const int32_t y0 = y;
    while (y < space.height() && !space.Blocked(x, y)) ++y;
    runs.push_back(Run{y0, y, TrapezoidalDecomposition::kNone});
  }
}

// Twice the signed area of triangle a, b, c; positive when c lies to the
// right of a -> b with y pointing up (the funnel's convention: it only needs
// portal ends labelled consistently, see PullString).
int64_t TriArea2(LatticePoint a, LatticePoint b, LatticePoint c) {
  return (c.x2 - a.x2) * (b.y2 - a.y2) - (b.x2 - a.x2) * (c.y2 - a.y2);
}

}  // namespace

TrapezoidalDecomposition::TrapezoidalDecomposition(const Grid& grid,
                                                   bool unknown_is_free, Unswept)
    : space_(grid, unknown_is_free), cell_trapezoid_(grid.size(), kNone) {}

TrapezoidalDecomposition::TrapezoidalDecomposition(const Grid& grid,
                                                   bool unknown_is_free)
    : TrapezoidalDecomposition(grid, unknown_is_free, Unswept{}) {
  Sweep(nullptr);
}

std::shared_ptr<const TrapezoidalDecomposition> TrapezoidalDecomposition::Build(
    const Grid& grid, bool unknown_is_free, DerivedStop& stop) {
  if (stop.Stopped()) return nullptr;
  std::shared_ptr<TrapezoidalDecomposition> d(
      new TrapezoidalDecomposition(grid, unknown_is_free, Unswept{}));
  if (!d->Sweep(&stop)) {
    stop.Note(absl::StrFormat(
        "building the trapezoidal decomposition of this map version (%d x %d "
        "cells)",
        grid.width(), grid.height()));
    return nullptr;
  }
  return d;
}

bool TrapezoidalDecomposition::Sweep(DerivedStop* stop) {
  const int32_t w = space_.width();
  std::vector<Run> previous;
  std::vector<Run> current;
  for (int32_t x = 0; x < w; ++x) {
    if (stop != nullptr && x % kPollColumns == 0 && stop->Stopped()) return false;
    ColumnRuns(space_, x, current);
    // Runs are sorted and disjoint in both columns: one merge pass pairs a
    // run with the identical run before it (the same trapezoid goes on) and
    // lists the overlaps of different ones (portals on X = x).
    size_t i = 0;
    for (Run& run : current) {
      while (i < previous.size() && previous[i].y1 <= run.y0) ++i;
      if (i < previous.size() && previous[i].y0 == run.y0 &&
          previous[i].y1 == run.y1) {
        run.id = previous[i].id;
        trapezoids_[run.id].x1 = x + 1;
      } else {
        run.id = static_cast<int32_t>(trapezoids_.size());
        trapezoids_.push_back(Trapezoid{x, x + 1, run.y0, run.y1});
      }
      for (int32_t y = run.y0; y < run.y1; ++y) {
        cell_trapezoid_[static_cast<size_t>(y) * w + x] = run.id;
      }
    }
    size_t j = 0;
    for (const Run& left : previous) {
      while (j < current.size() && current[j].y1 <= left.y0) ++j;
      for (size_t k = j; k < current.size() && current[k].y0 < left.y1; ++k) {
        if (current[k].id == left.id) continue;
        portals_.push_back(CellBoundary{x, std::max(left.y0, current[k].y0),
                                  std::min(left.y1, current[k].y1), left.id,
                                  current[k].id});
      }
    }
    std::swap(previous, current);
  }
  // CSR lists of each trapezoid's portals.
  const size_t n = trapezoids_.size();
  portal_begin_.assign(n + 1, 0);
  for (const CellBoundary& p : portals_) {
    ++portal_begin_[p.left + 1];
    ++portal_begin_[p.right + 1];
  }
  for (size_t t = 0; t < n; ++t) portal_begin_[t + 1] += portal_begin_[t];
  portal_ids_.resize(2 * portals_.size());
  std::vector<int32_t> fill(portal_begin_.begin(), portal_begin_.end() - 1);
  for (size_t p = 0; p < portals_.size(); ++p) {
    portal_ids_[fill[portals_[p].left]++] = static_cast<int32_t>(p);
    portal_ids_[fill[portals_[p].right]++] = static_cast<int32_t>(p);
  }
  return true;
}

size_t TrapezoidalDecomposition::bytes() const {
  return sizeof(*this) + space_.bytes() +
         trapezoids_.capacity() * sizeof(Trapezoid) +
         portals_.capacity() * sizeof(CellBoundary) +
         (portal_begin_.capacity() + portal_ids_.capacity() +
          cell_trapezoid_.capacity()) *
             sizeof(int32_t);
}

Gate GateOf(const CellBoundary& portal, bool left_to_right) {
  // Walking towards +x with y up, the right-hand end has the smaller y.
  const LatticePoint low = CornerAt(portal.x, portal.y0);
  const LatticePoint high = CornerAt(portal.x, portal.y1);
  return left_to_right ? Gate{low, high} : Gate{high, low};
}

std::vector<LatticePoint> PullString(LatticePoint start, LatticePoint goal,
                                     absl::Span<const Gate> gates) {
  std::vector<LatticePoint> right_end{start};
  std::vector<LatticePoint> left_end{start};
  for (const Gate& gate : gates) {
    right_end.push_back(gate.right);
    left_end.push_back(gate.left);
  }
  right_end.push_back(goal);
  left_end.push_back(goal);

  std::vector<LatticePoint> path{start};
  LatticePoint apex = start;
  LatticePoint right = start;
  LatticePoint left = start;
  size_t apex_index = 0;
  size_t right_index = 0;
  size_t left_index = 0;
  for (size_t i = 1; i < right_end.size(); ++i) {
    // Tighten the right side unless it crosses over the left one, which
    // makes the left end a bend; then restart from it.
    if (TriArea2(apex, right, right_end[i]) <= 0) {
      if (apex == right || TriArea2(apex, left, right_end[i]) > 0) {
        right = right_end[i];
        right_index = i;
      } else {
        path.push_back(left);
        apex = left;
        apex_index = left_index;
        right = left = apex;
        right_index = left_index = apex_index;
        i = apex_index;
        continue;
      }
    }
    if (TriArea2(apex, left, left_end[i]) >= 0) {
      if (apex == left || TriArea2(apex, right, left_end[i]) < 0) {
        left = left_end[i];
        left_index = i;
      } else {
        path.push_back(right);
        apex = right;
        apex_index = right_index;
        right = left = apex;
        right_index = left_index = apex_index;
        i = apex_index;
        continue;
      }
    }
  }
  if (!(path.back() == goal)) path.push_back(goal);
  return path;
}

GeometricStructure DescribeDecomposition(const Grid& grid,
                                         bool unknown_is_free) {
  GeometricStructure s;
  s.kind = "decomposition";
  const absl::Time started = absl::Now();
  const TrapezoidalDecomposition d(grid, unknown_is_free);
  s.build_time = absl::Now() - started;
  s.counts = {{"cells", static_cast<int64_t>(d.trapezoids().size())},
              {"adjacencies", static_cast<int64_t>(d.portals().size())}};
  s.bytes = d.bytes();
  for (const Trapezoid& t : d.trapezoids()) {
    const CellPoint a{static_cast<double>(t.x0), static_cast<double>(t.y0)};
    const CellPoint b{static_cast<double>(t.x1), static_cast<double>(t.y0)};
    const CellPoint c{static_cast<double>(t.x1), static_cast<double>(t.y1)};
    const CellPoint e{static_cast<double>(t.x0), static_cast<double>(t.y1)};
    s.segments.push_back({a, b});
    s.segments.push_back({b, c});
    s.segments.push_back({c, e});
    s.segments.push_back({e, a});
  }
  return s;
}

}  // namespace pathd
