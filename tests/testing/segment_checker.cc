#include "tests/testing/segment_checker.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>

#include "absl/strings/str_format.h"
#include "core/map/cost_model.h"

namespace pathd::testing {
namespace {

// floor(n / 2) for any sign.
int64_t FloorHalf(int64_t n) { return n >= 0 ? n / 2 : -((-n + 1) / 2); }

// t = num / den with den > 0, as a bound on the segment parameter.
struct Bound {
  int64_t num = 0;
  int64_t den = 1;
  bool strict = false;
};

// l < u (or l <= u when neither is strict), exactly.
bool Below(const Bound& l, const Bound& u) {
  const __int128 lhs = static_cast<__int128>(l.num) * u.den;
  const __int128 rhs = static_cast<__int128>(u.num) * l.den;
  return (l.strict || u.strict) ? lhs < rhs : lhs <= rhs;
}

// One axis of a feature, in doubled coordinates: lo < p < hi (open) or
// p == lo (equal).
struct AxisCondition {
  bool equal = false;
  int64_t lo = 0;
  int64_t hi = 0;
};
AxisCondition Open(int64_t lo, int64_t hi) { return {false, lo, hi}; }
AxisCondition Equal(int64_t v) { return {true, v, v}; }

// Collects the bounds on t that one axis condition puts on a + t d; false
// when the axis alone rules every t out (d == 0 and a fails the condition).
bool AddAxis(int64_t a, int64_t d, const AxisCondition& c, Bound* lowers,
             int* n_lower, Bound* uppers, int* n_upper) {
  if (d == 0) {
    return c.equal ? a == c.lo : (c.lo < a && a < c.hi);
  }
  // Normalise to a positive denominator: a + t d op v <=> t op' (v - a) / d.
  auto fraction = [&](int64_t v, bool strict) {
    return d > 0 ? Bound{v - a, d, strict} : Bound{a - v, -d, strict};
  };
  if (c.equal) {
    lowers[(*n_lower)++] = fraction(c.lo, false);
    uppers[(*n_upper)++] = fraction(c.lo, false);
    return true;
  }
  // lo < a + t d < hi.
  if (d > 0) {
    lowers[(*n_lower)++] = fraction(c.lo, true);
    uppers[(*n_upper)++] = fraction(c.hi, true);
  } else {
    lowers[(*n_lower)++] = fraction(c.hi, true);
    uppers[(*n_upper)++] = fraction(c.lo, true);
  }
  return true;
}

// Some point of the closed segment a-b satisfies both axis conditions.
bool Meets(LatticePoint a, LatticePoint b, const AxisCondition& cx,
           const AxisCondition& cy) {
  std::array<Bound, 3> lowers;
  std::array<Bound, 3> uppers;
  int n_lower = 0, n_upper = 0;
  lowers[n_lower++] = Bound{0, 1, false};
  uppers[n_upper++] = Bound{1, 1, false};
  if (!AddAxis(a.x2, b.x2 - a.x2, cx, lowers.data(), &n_lower, uppers.data(),
               &n_upper)) {
    return false;
  }
  if (!AddAxis(a.y2, b.y2 - a.y2, cy, lowers.data(), &n_lower, uppers.data(),
               &n_upper)) {
    return false;
  }
  for (int i = 0; i < n_lower; ++i) {
    for (int j = 0; j < n_upper; ++j) {
      if (!Below(lowers[i], uppers[j])) return false;
    }
  }
  return true;
}

std::string CellString(Cell c) { return absl::StrFormat("(%d, %d)", c.x, c.y); }

}  // namespace

std::string SegmentDefect::ToString() const {
  switch (kind) {
    case Kind::kNotOnLattice:
      return "a vertex is not on the half-cell lattice";
    case Kind::kCrossesBlockedCell:
      return "crosses the interior of blocked cell " + CellString(cell);
    case Kind::kAlongBlockedEdge:
      return "runs along the edge between blocked cells " + CellString(cell) +
             " and " + CellString(other);
    case Kind::kThroughClosedCorner:
      return "passes through closed corner " + CellString(corner) +
             " (a pinch or enclosed)";
  }
  return "?";
}

std::string PolylineDefect::ToString() const {
  return absl::StrFormat("segment %d (%.1f, %.1f) -> (%.1f, %.1f) %s", index,
                         from.x, from.y, to.x, to.y, defect.ToString());
}

SegmentChecker::SegmentChecker(const Grid& grid, bool unknown_is_free)
    : width_(grid.width()), height_(grid.height()), blocked_(grid.size()) {
  for (size_t i = 0; i < grid.size(); ++i) {
    blocked_[i] = Traversable(grid.cells()[i], unknown_is_free) ? 0 : 1;
  }
}

bool SegmentChecker::Blocked(int64_t x, int64_t y) const {
  if (x < 0 || y < 0 || x >= width_ || y >= height_) return true;
  return blocked_[static_cast<size_t>(y) * static_cast<size_t>(width_) +
                  static_cast<size_t>(x)] != 0;
}

bool SegmentChecker::ClosedCorner(int64_t x, int64_t y) const {
  // The cells around corner (x, y): lower-left (x-1, y-1), lower-right
  // (x, y-1), upper-left (x-1, y), upper-right (x, y).
  const bool ll = Blocked(x - 1, y - 1), lr = Blocked(x, y - 1);
  const bool ul = Blocked(x - 1, y), ur = Blocked(x, y);
  const int count = ll + lr + ul + ur;
  if (count == 4) return true;
  return count == 2 && ((ll && ur) || (lr && ul));
}

std::optional<SegmentDefect> SegmentChecker::CellFeatures(LatticePoint a,
                                                          LatticePoint b,
                                                          int64_t x,
                                                          int64_t y) const {
  const int64_t x2 = 2 * x, y2 = 2 * y;
  const Cell cell{static_cast<int32_t>(x), static_cast<int32_t>(y)};
  if (Blocked(x, y)) {
    if (Meets(a, b, Open(x2, x2 + 2), Open(y2, y2 + 2))) {
      return SegmentDefect{SegmentDefect::Kind::kCrossesBlockedCell, cell, {}, {}};
    }
    if (Blocked(x + 1, y) && Meets(a, b, Equal(x2 + 2), Open(y2, y2 + 2))) {
      return SegmentDefect{SegmentDefect::Kind::kAlongBlockedEdge, cell,
                           Cell{cell.x + 1, cell.y}, {}};
    }
    if (Blocked(x, y + 1) && Meets(a, b, Open(x2, x2 + 2), Equal(y2 + 2))) {
      return SegmentDefect{SegmentDefect::Kind::kAlongBlockedEdge, cell,
                           Cell{cell.x, cell.y + 1}, {}};
    }
  }
  if (ClosedCorner(x, y) && Meets(a, b, Equal(x2), Equal(y2))) {
    return SegmentDefect{SegmentDefect::Kind::kThroughClosedCorner, {}, {}, cell};
  }
  return std::nullopt;
}

std::optional<SegmentDefect> SegmentChecker::FindDefect(LatticePoint a,
                                                        LatticePoint b,
                                                        bool exhaustive) const {
  // Every feature of cell (x, y) lies in its closed square [x, x+1] x
  // [y, y+1], which the segment can touch only for columns floor(min x) - 1
  // .. floor(max x), and likewise rows.
  const int64_t min_x2 = std::min(a.x2, b.x2), max_x2 = std::max(a.x2, b.x2);
  const int64_t min_y2 = std::min(a.y2, b.y2), max_y2 = std::max(a.y2, b.y2);
  const int64_t x_first = FloorHalf(min_x2) - 1, x_last = FloorHalf(max_x2);
  const int64_t y_first = FloorHalf(min_y2) - 1, y_last = FloorHalf(max_y2);
  for (int64_t x = x_first; x <= x_last; ++x) {
    int64_t row_first = y_first, row_last = y_last;
    if (!exhaustive && a.x2 != b.x2) {
      // Rows the segment can reach over columns x .. x + 1 (a superset: the
      // y range over [x - 1, x + 2], widened by one row for rounding).
      const double ax = a.x2 / 2.0, ay = a.y2 / 2.0;
      const double slope = static_cast<double>(b.y2 - a.y2) /
                           static_cast<double>(b.x2 - a.x2);
      const double lo = std::max<double>(static_cast<double>(x - 1), min_x2 / 2.0);
      const double hi = std::min<double>(static_cast<double>(x + 2), max_x2 / 2.0);
      const double y0 = ay + (lo - ax) * slope, y1 = ay + (hi - ax) * slope;
      row_first = std::max(y_first, static_cast<int64_t>(std::floor(std::min(y0, y1))) - 2);
      row_last = std::min(y_last, static_cast<int64_t>(std::floor(std::max(y0, y1))) + 1);
    }
    for (int64_t y = row_first; y <= row_last; ++y) {
      if (auto d = CellFeatures(a, b, x, y)) return d;
    }
  }
  return std::nullopt;
}

std::optional<PolylineDefect> PolylineChecker::FirstDefect(
    absl::Span<const CellPoint> polyline) const {
  auto on_lattice = [](CellPoint p) -> std::optional<LatticePoint> {
    const double x2 = p.x * 2.0, y2 = p.y * 2.0;
    if (!(std::abs(x2) < 1e9 && std::abs(y2) < 1e9) || x2 != std::floor(x2) ||
        y2 != std::floor(y2)) {
      return std::nullopt;
    }
    return LatticePoint{static_cast<int64_t>(x2), static_cast<int64_t>(y2)};
  };
  for (size_t i = 0; i < polyline.size(); ++i) {
    const size_t j = polyline.size() == 1 ? i : i + 1;
    if (j >= polyline.size()) break;
    const auto a = on_lattice(polyline[i]);
    const auto b = on_lattice(polyline[j]);
    if (!a || !b) {
      return PolylineDefect{i, polyline[i], polyline[j],
                            SegmentDefect{SegmentDefect::Kind::kNotOnLattice, {}, {}, {}}};
    }
    if (auto d = segments_.FindDefect(*a, *b)) {
      return PolylineDefect{i, polyline[i], polyline[j], *d};
    }
  }
  return std::nullopt;
}

double LatticePolylineLength(absl::Span<const CellPoint> polyline) {
  long double sum = 0;
  for (size_t i = 0; i + 1 < polyline.size(); ++i) {
    const long double dx = static_cast<long double>(polyline[i + 1].x) - polyline[i].x;
    const long double dy = static_cast<long double>(polyline[i + 1].y) - polyline[i].y;
    sum += std::sqrt(dx * dx + dy * dy);
  }
  return static_cast<double>(sum);
}

}  // namespace pathd::testing
