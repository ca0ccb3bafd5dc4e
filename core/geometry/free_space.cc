#include "core/geometry/free_space.h"

#include <algorithm>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/map/cost_model.h"

namespace pathd {

using free_space_internal::CeilDiv;
using free_space_internal::FloorDiv;

double PolylineLength(absl::Span<const LatticePoint> polyline) {
  double length = 0.0;
  for (size_t i = 1; i < polyline.size(); ++i) {
    length += Distance(polyline[i - 1], polyline[i]);
  }
  return length;
}

FreeSpace::FreeSpace(const Grid& grid, bool unknown_is_free)
    : width_(grid.width()),
      height_(grid.height()),
      stride_(static_cast<size_t>(grid.width()) + 2),
      unknown_is_free_(unknown_is_free),
      blocked_(stride_ * (static_cast<size_t>(grid.height()) + 2), 1) {
  for (int32_t y = 0; y < height_; ++y) {
    for (int32_t x = 0; x < width_; ++x) {
      Set(x, y, !Traversable(grid.cost(x, y), unknown_is_free_));
    }
  }
}

void FreeSpace::Update(const Grid& grid, absl::Span<const Cell> changed) {
  for (const Cell& c : changed) {
    Set(c.x, c.y, !Traversable(grid.cost(c), unknown_is_free_));
  }
}

bool FreeSpace::CornerFree(int64_t x, int64_t y) const {
  // Closed: exactly two diagonally opposite cells blocked (0b1001 is
  // (x-1, y-1) with (x, y), 0b0110 is (x, y-1) with (x-1, y)), or all four.
  // With three blocked the corner is on the boundary of the free one.
  const int mask = CornerMask(x, y);
  return mask != 0b1001 && mask != 0b0110 && mask != 0b1111;
}

bool FreeSpace::IsBendCorner(int64_t x, int64_t y) const {
  const int mask = CornerMask(x, y);
  return mask != 0 && (mask & (mask - 1)) == 0;
}

std::vector<LatticePoint> FreeSpace::BendCorners() const {
  std::vector<LatticePoint> corners;
  for (int64_t y = 0; y <= height_; ++y) {
    for (int64_t x = 0; x <= width_; ++x) {
      if (IsBendCorner(x, y)) corners.push_back(CornerAt(x, y));
    }
  }
  return corners;
}

bool FreeSpace::PointFree(LatticePoint p) const {
  const bool x_on_line = p.x2 % 2 == 0;
  const bool y_on_line = p.y2 % 2 == 0;
  const int64_t x = FloorDiv(p.x2, 2);
  const int64_t y = FloorDiv(p.y2, 2);
  if (x_on_line && y_on_line) return CornerFree(x, y);
  if (x_on_line) return !(Blocked(x - 1, y) && Blocked(x, y));
  if (y_on_line) return !(Blocked(x, y - 1) && Blocked(x, y));
  return !Blocked(x, y);
}

// Every point of the segment is either inside a cell, on an edge or on a
// corner. Inside cells: each cell whose open interior the segment meets must
// be free. On edges: a piece running along a grid line needs one free cell
// beside it; a segment that crosses an edge meets both cells' interiors
// (checked) except at its endpoints, where it meets the cell it leaves into.
// Corners it passes through or ends at: CornerFree.
bool FreeSpace::SegmentClear(LatticePoint a, LatticePoint b) const {
  if (a == b) return PointFree(a);
  if (a.x2 > b.x2) std::swap(a, b);
  const int64_t dx = b.x2 - a.x2;
  const int64_t dy = b.y2 - a.y2;
  if (dx == 0) {
    const int64_t lo = std::min(a.y2, b.y2);
    const int64_t hi = std::max(a.y2, b.y2);
    if (a.x2 % 2 != 0) {
      const int64_t col = (a.x2 - 1) / 2;
      for (int64_t j = FloorDiv(lo, 2); j <= CeilDiv(hi, 2) - 1; ++j) {
        if (Blocked(col, j)) return false;
      }
      return true;
    }
    const int64_t gx = a.x2 / 2;
    for (int64_t j = FloorDiv(lo, 2); j <= CeilDiv(hi, 2) - 1; ++j) {
      if (Blocked(gx - 1, j) && Blocked(gx, j)) return false;
    }
    for (int64_t y2 = lo + (lo % 2 != 0 ? 1 : 0); y2 <= hi; y2 += 2) {
      if (!CornerFree(gx, y2 / 2)) return false;
    }
    return true;
  }
  // y (scaled by dx) at doubled x.
  auto y_scaled = [&](int64_t x2) { return a.y2 * dx + (x2 - a.x2) * dy; };
  const int64_t unit = 2 * dx;
  for (int64_t c = FloorDiv(a.x2, 2); 2 * c < b.x2; ++c) {
    const int64_t xs = std::max(a.x2, 2 * c);
    const int64_t xe = std::min(b.x2, 2 * c + 2);
    if (xe <= xs) continue;
    if (dy == 0) {
      if (a.y2 % 2 != 0) {
        if (Blocked(c, (a.y2 - 1) / 2)) return false;
      } else if (Blocked(c, a.y2 / 2 - 1) && Blocked(c, a.y2 / 2)) {
        return false;
      }
      continue;
    }
    const int64_t y0 = std::min(y_scaled(xs), y_scaled(xe));
    const int64_t y1 = std::max(y_scaled(xs), y_scaled(xe));
    for (int64_t j = FloorDiv(y0, unit); j <= CeilDiv(y1, unit) - 1; ++j) {
      if (Blocked(c, j)) return false;
    }
  }
  // Corners on the segment: x2 even and scaled y a multiple of 2 * dx.
  for (int64_t x2 = a.x2 + (a.x2 % 2 != 0 ? 1 : 0); x2 <= b.x2; x2 += 2) {
    const int64_t ys = y_scaled(x2);
    if (ys % unit != 0) continue;
    if (!CornerFree(x2 / 2, ys / unit)) return false;
  }
  return true;
}

bool FreeSpace::PolylineClear(absl::Span<const LatticePoint> polyline) const {
  if (polyline.size() == 1) return PointFree(polyline[0]);
  for (size_t i = 1; i < polyline.size(); ++i) {
    if (!SegmentClear(polyline[i - 1], polyline[i])) return false;
  }
  return true;
}

void FillPolylineResult(const FreeSpace& space,
                        absl::Span<const LatticePoint> polyline,
                        double cell_factor, PlanResult& result) {
  result.outcome = PlanOutcome::kFound;
  result.polyline.clear();
  for (LatticePoint p : polyline) result.polyline.push_back(ToCellPoint(p));
  result.path = CellsAlongPolyline(space, polyline);
  result.any_angle = false;
  result.length = PolylineLength(polyline);
  result.cost = result.length * cell_factor;
}

std::shared_ptr<const FreeSpace> SharedFreeSpace(DerivedStore* store, const Grid& grid,
                                                 bool unknown_is_free, DerivedStop& stop) {
  return GetDerived<FreeSpace>(
      store, grid,
      std::string("free_space unknown_is_free=") + (unknown_is_free ? "1" : "0"),
      "the free space of this map version", stop,
      [unknown_is_free](const Grid& g, DerivedStop&) {
        return std::make_shared<const FreeSpace>(g, unknown_is_free);
      },
      [](const FreeSpace& previous, const Grid& g, absl::Span<const Cell> changed,
         DerivedStop&) {
        auto next = std::make_shared<FreeSpace>(previous);
        next->Update(g, changed);
        return std::shared_ptr<const FreeSpace>(std::move(next));
      },
      [](const FreeSpace& space) { return space.bytes(); });
}

std::shared_ptr<const FreeSpace> SharedFreeSpace(DerivedStore* store, const Grid& grid,
                                                 bool unknown_is_free) {
  DerivedStop never;
  return SharedFreeSpace(store, grid, unknown_is_free, never);
}

std::vector<Cell> CellsAlongPolyline(const FreeSpace& space,
                                     absl::Span<const LatticePoint> polyline) {
  std::vector<Cell> cells;
  auto add = [&](Cell c) {
    if (cells.empty() || !(cells.back() == c)) cells.push_back(c);
  };
  if (polyline.size() == 1) {
    space.ForEachCellCrossed(polyline[0], polyline[0], add);
  }
  for (size_t i = 1; i < polyline.size(); ++i) {
    space.ForEachCellCrossed(polyline[i - 1], polyline[i], add);
  }
  return cells;
}

}  // namespace pathd
