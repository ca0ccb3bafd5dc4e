// Checks the segment walks of core/search/line_of_sight.h against a brute-force
// definition evaluated in exact rational arithmetic: a cell is visited iff its
// closed square meets the closed segment, flagged corner_only iff they meet in
// a single point, in order of where the segment first meets it. Then
// LineOfSight and SegmentCost against the move rule of the cost model.
#include "core/search/path_measure.h"
#include "core/search/line_of_sight.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/search/planner.h"
#include "gtest/gtest.h"

namespace pathd {
namespace {

using Int = __int128;

// A rational number with a positive denominator.
struct Frac {
  Int num;
  Int den;
};
bool Less(const Frac& a, const Frac& b) {
  return a.num * b.den < b.num * a.den;
}
double ToDouble(const Frac& f) {
  return static_cast<double>(f.num) / static_cast<double>(f.den);
}

// How the closed segment P + t (Q - P), t in [0, 1], meets a closed square.
struct Touch {
  bool touched = false;
  // They meet in exactly one point (P != Q).
  bool single_point = false;
  // Parameter interval of the intersection.
  Frac enter{0, 1};
  Frac leave{1, 1};
};

// Points are integers in units of 1/scale cells; the square of cell (cx, cy)
// is [cx, cx + 1] x [cy, cy + 1] cells. Liang-Barsky clipping, exactly.
Touch BruteTouch(int64_t px, int64_t py, int64_t qx, int64_t qy, int64_t scale,
                 int64_t cx, int64_t cy) {
  Touch touch;
  Frac lo{0, 1};
  Frac hi{1, 1};
  auto clip = [&](int64_t p, int64_t d, int64_t a, int64_t b) {
    if (d == 0) return a <= p && p <= b;
    Frac ta{a - p, d};
    Frac tb{b - p, d};
    if (d < 0) {
      ta = {p - a, -static_cast<Int>(d)};
      tb = {p - b, -static_cast<Int>(d)};
    }
    const Frac lower = Less(ta, tb) ? ta : tb;
    const Frac upper = Less(ta, tb) ? tb : ta;
    if (Less(lo, lower)) lo = lower;
    if (Less(upper, hi)) hi = upper;
    return true;
  };
  if (!clip(px, qx - px, scale * cx, scale * (cx + 1))) return touch;
  if (!clip(py, qy - py, scale * cy, scale * (cy + 1))) return touch;
  if (Less(hi, lo)) return touch;
  touch.touched = true;
  touch.single_point = !Less(lo, hi) && (px != qx || py != qy);
  touch.enter = lo;
  touch.leave = hi;
  return touch;
}

// Distance in cells between the segment and the square of cell (cx, cy) when
// they do not meet: attained at a corner of one or an end of the other.
double SquareDistance(int64_t px, int64_t py, int64_t qx, int64_t qy,
                      int64_t scale, int32_t cx, int32_t cy) {
  const double ax = static_cast<double>(px) / scale;
  const double ay = static_cast<double>(py) / scale;
  const double bx = static_cast<double>(qx) / scale;
  const double by = static_cast<double>(qy) / scale;
  auto point_to_segment = [&](double x, double y) {
    const double dx = bx - ax;
    const double dy = by - ay;
    const double len2 = dx * dx + dy * dy;
    const double t =
        len2 == 0
            ? 0.0
            : std::clamp(((x - ax) * dx + (y - ay) * dy) / len2, 0.0, 1.0);
    return std::hypot(ax + t * dx - x, ay + t * dy - y);
  };
  auto point_to_square = [&](double x, double y) {
    return std::hypot(x - std::clamp(x, 1.0 * cx, cx + 1.0),
                      y - std::clamp(y, 1.0 * cy, cy + 1.0));
  };
  double d = std::min(point_to_square(ax, ay), point_to_square(bx, by));
  for (const int ox : {0, 1}) {
    for (const int oy : {0, 1})
      d = std::min(d, point_to_segment(cx + ox, cy + oy));
  }
  return d;
}

struct Visited {
  int32_t x;
  int32_t y;
  bool corner_only;
};

template <typename Point>
std::vector<Visited> Walk(Point p, Point q) {
  std::vector<Visited> out;
  ForEachCellOnSegment(p, q, [&](int32_t x, int32_t y, bool corner_only) {
    out.push_back({x, y, corner_only});
    return true;
  });
  return out;
}

// Compares a walk with the brute force over every cell within one cell of the
// segment's bounding box. With exact_flags, corner_only must equal
// single_point; otherwise (floating-point input) the walk may add cells and
// flag slivers as corner touches, within kSlack cells of the segment.
void ExpectMatchesBruteForce(const std::vector<Visited>& walk, int64_t px,
                             int64_t py, int64_t qx, int64_t qy, int64_t scale,
                             bool exact_flags, const std::string& what) {
  SCOPED_TRACE(what);
  constexpr double kSlack = 1e-8;
  std::map<std::pair<int32_t, int32_t>, size_t> position;
  for (size_t i = 0; i < walk.size(); ++i) {
    const bool fresh =
        position.emplace(std::pair(walk[i].x, walk[i].y), i).second;
    ASSERT_TRUE(fresh) << "cell (" << walk[i].x << ", " << walk[i].y
                       << ") visited twice";
  }
  auto floor_div = [&](int64_t v) {
    return static_cast<int32_t>(v >= 0 ? v / scale
                                       : -((-v + scale - 1) / scale));
  };
  const int32_t x0 = floor_div(std::min(px, qx)) - 1;
  const int32_t x1 = floor_div(std::max(px, qx)) + 1;
  const int32_t y0 = floor_div(std::min(py, qy)) - 1;
  const int32_t y1 = floor_div(std::max(py, qy)) + 1;
  const double length = std::hypot(static_cast<double>(qx - px) / scale,
                                   static_cast<double>(qy - py) / scale);
  size_t matched = 0;
  std::vector<Frac> enter(walk.size(), Frac{0, 1});
  for (int32_t y = y0; y <= y1; ++y) {
    for (int32_t x = x0; x <= x1; ++x) {
      const Touch t = BruteTouch(px, py, qx, qy, scale, x, y);
      const auto it = position.find({x, y});
      if (!t.touched) {
        if (it == position.end()) continue;
        ASSERT_FALSE(exact_flags) << "visited (" << x << ", " << y
                                  << ") which the segment does not touch";
        // A near-corner crossing: allowed as a corner touch.
        EXPECT_TRUE(walk[it->second].corner_only) << x << ", " << y;
        EXPECT_LT(SquareDistance(px, py, qx, qy, scale, x, y), kSlack)
            << x << ", " << y;
        ++matched;
        enter[it->second] = Frac{-1, 1};  // unordered; skipped below
        continue;
      }
      ASSERT_NE(it, position.end()) << "missed (" << x << ", " << y << ")";
      ++matched;
      enter[it->second] = t.enter;
      if (px == qx && py == qy) continue;  // a point: flags by convention only
      if (exact_flags) {
        EXPECT_EQ(walk[it->second].corner_only, t.single_point)
            << "(" << x << ", " << y << ")";
      } else if (walk[it->second].corner_only != t.single_point) {
        // Only a sliver may be called a corner touch; never the reverse.
        EXPECT_TRUE(walk[it->second].corner_only)
            << "(" << x << ", " << y << ")";
        EXPECT_LT((ToDouble(t.leave) - ToDouble(t.enter)) * length, kSlack)
            << "(" << x << ", " << y << ")";
      }
    }
  }
  EXPECT_EQ(matched, walk.size()) << "visited cells far from the segment";
  // In order along the segment (ties: cells met at the same point).
  const Frac* last = nullptr;
  for (size_t i = 0; i < walk.size(); ++i) {
    if (enter[i].num < 0) continue;
    if (last != nullptr) {
      if (exact_flags) {
        EXPECT_FALSE(Less(enter[i], *last)) << "out of order at visit " << i;
      } else {
        EXPECT_GE(ToDouble(enter[i]) * length,
                  ToDouble(*last) * length - kSlack)
            << "out of order at visit " << i;
      }
    }
    last = &enter[i];
  }
}

// Cell centres in doubled coordinates are odd integers, so the brute force is
// exact with scale 2.
void CheckCellPair(Cell a, Cell b) {
  const std::vector<Visited> walk = Walk(a, b);
  const std::string what = CellToString(a) + " -> " + CellToString(b);
  ASSERT_FALSE(walk.empty()) << what;
  EXPECT_EQ(walk.front().x, a.x) << what;
  EXPECT_EQ(walk.front().y, a.y) << what;
  EXPECT_FALSE(walk.front().corner_only) << what;
  EXPECT_EQ(walk.back().x, b.x) << what;
  EXPECT_EQ(walk.back().y, b.y) << what;
  EXPECT_FALSE(walk.back().corner_only) << what;
  if (a == b) {
    EXPECT_EQ(walk.size(), 1u) << what;
    return;
  }
  for (const Visited& v : walk) {
    EXPECT_TRUE(v.x >= std::min(a.x, b.x) && v.x <= std::max(a.x, b.x) &&
                v.y >= std::min(a.y, b.y) && v.y <= std::max(a.y, b.y))
        << what << " left the bounding box";
  }
  ExpectMatchesBruteForce(walk, 2 * a.x + 1, 2 * a.y + 1, 2 * b.x + 1,
                          2 * b.y + 1, 2,
                          /*exact_flags=*/true, what);
}

TEST(CellSegmentTest, EveryPairInSmallWindowsMatchesBruteForce) {
  // Every ordered pair in a 9 x 9 window: all octants, slopes 0, 1/8 .. 8,
  // infinite, and a == b.
  for (int32_t ay = 0; ay < 9; ++ay) {
    for (int32_t ax = 0; ax < 9; ++ax) {
      for (int32_t by = 0; by < 9; ++by) {
        for (int32_t bx = 0; bx < 9; ++bx) {
          CheckCellPair(Cell{ax, ay}, Cell{bx, by});
          if (HasFatalFailure()) return;
        }
      }
    }
  }
}

TEST(CellSegmentTest, RandomLongSegmentsMatchBruteForce) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int32_t> coord(-40, 40);
  for (int i = 0; i < 3000; ++i) {
    const Cell a{coord(rng), coord(rng)};
    Cell b{coord(rng), coord(rng)};
    if (i % 3 == 0)
      b.y = a.y + (b.x - a.x) * ((i / 3) % 2 == 0 ? 1 : -1);  // 45 deg
    if (i % 7 == 0) b.x = a.x + 3 * (b.y - a.y);  // through many corners
    CheckCellPair(a, b);
    if (HasFatalFailure()) return;
  }
}

TEST(CellSegmentTest, HandCases) {
  auto cells = [](Cell a, Cell b) {
    std::vector<std::tuple<int, int, bool>> out;
    for (const Visited& v : Walk(a, b))
      out.emplace_back(v.x, v.y, v.corner_only);
    return out;
  };
  using V = std::vector<std::tuple<int, int, bool>>;
  EXPECT_EQ(cells({0, 0}, {3, 0}),
            (V{{0, 0, false}, {1, 0, false}, {2, 0, false}, {3, 0, false}}));
  EXPECT_EQ(cells({2, 3}, {2, 1}),
            (V{{2, 3, false}, {2, 2, false}, {2, 1, false}}));
  EXPECT_EQ(cells({0, 0}, {2, 2}), (V{{0, 0, false},
                                      {1, 0, true},
                                      {0, 1, true},
                                      {1, 1, false},
                                      {2, 1, true},
                                      {1, 2, true},
                                      {2, 2, false}}));
  // Shallow: y = 0.5 + (x - 0.5) / 2 crosses y = 1 at x = 1.5, no corner.
  EXPECT_EQ(cells({0, 0}, {2, 1}),
            (V{{0, 0, false}, {1, 0, false}, {1, 1, false}, {2, 1, false}}));
  // Slope 1/3 passes exactly through the corner (2, 1).
  EXPECT_EQ(cells({0, 0}, {3, 1}), (V{{0, 0, false},
                                      {1, 0, false},
                                      {2, 0, true},
                                      {1, 1, true},
                                      {2, 1, false},
                                      {3, 1, false}}));
  // Steep, negative direction.
  EXPECT_EQ(cells({1, 2}, {0, 0}),
            (V{{1, 2, false}, {1, 1, false}, {0, 1, false}, {0, 0, false}}));
  EXPECT_EQ(cells({4, 4}, {4, 4}), (V{{4, 4, false}}));
}

TEST(CellSegmentTest, SingleMovesReproduceTheMoveRule) {
  const Cell a{5, 5};
  for (const Move& m : kMoves) {
    const Cell b{a.x + m.dx, a.y + m.dy};
    const std::vector<Visited> walk = Walk(a, b);
    if (m.dx == 0 || m.dy == 0) {
      ASSERT_EQ(walk.size(), 2u);
      EXPECT_FALSE(walk[0].corner_only || walk[1].corner_only);
      continue;
    }
    // Diagonal: the two side cells the move rule checks, touched at the corner.
    ASSERT_EQ(walk.size(), 4u);
    EXPECT_EQ(std::tie(walk[1].x, walk[1].y), std::tie(b.x, a.y));
    EXPECT_TRUE(walk[1].corner_only);
    EXPECT_EQ(std::tie(walk[2].x, walk[2].y), std::tie(a.x, b.y));
    EXPECT_TRUE(walk[2].corner_only);
    EXPECT_EQ(std::tie(walk[3].x, walk[3].y), std::tie(b.x, b.y));
    EXPECT_FALSE(walk[3].corner_only);
  }
}

TEST(CellSegmentTest, ReversedSegmentVisitsTheSameCells) {
  std::mt19937 rng(11);
  std::uniform_int_distribution<int32_t> coord(0, 30);
  for (int i = 0; i < 2000; ++i) {
    const Cell a{coord(rng), coord(rng)};
    const Cell b{coord(rng), coord(rng)};
    std::vector<std::tuple<int, int, bool>> forward;
    std::vector<std::tuple<int, int, bool>> backward;
    for (const Visited& v : Walk(a, b))
      forward.emplace_back(v.x, v.y, v.corner_only);
    for (const Visited& v : Walk(b, a))
      backward.emplace_back(v.x, v.y, v.corner_only);
    std::sort(forward.begin(), forward.end());
    std::sort(backward.begin(), backward.end());
    EXPECT_EQ(forward, backward);
  }
}

TEST(CellSegmentTest, IndexedWalkIsTheSameWalkWithRowMajorIndices) {
  std::mt19937 rng(19);
  std::uniform_int_distribution<int32_t> coord(0, 49);
  for (int i = 0; i < 2000; ++i) {
    const Cell a{coord(rng), coord(rng)};
    const Cell b{coord(rng), coord(rng)};
    const std::vector<Visited> plain = Walk(a, b);
    size_t k = 0;
    ForEachCellOnSegmentIndexed(
        a, b, 50, [&](int32_t x, int32_t y, int64_t index, bool corner_only) {
          EXPECT_LT(k, plain.size());
          if (k >= plain.size()) return false;
          EXPECT_EQ(std::tie(x, y, corner_only),
                    std::tie(plain[k].x, plain[k].y, plain[k].corner_only));
          EXPECT_EQ(index, int64_t{y} * 50 + x);
          ++k;
          return true;
        });
    EXPECT_EQ(k, plain.size());
  }
}

TEST(CellSegmentTest, StopsWhenVisitReturnsFalse) {
  for (int stop_at = 1; stop_at <= 7; ++stop_at) {
    int calls = 0;
    const bool done = ForEachCellOnSegment(
        Cell{0, 0}, Cell{2, 2},
        [&](int32_t, int32_t, bool) { return ++calls < stop_at; });
    EXPECT_FALSE(done);
    EXPECT_EQ(calls, stop_at);
  }
  int calls = 0;
  EXPECT_TRUE(
      ForEachCellOnSegment(Cell{0, 0}, Cell{2, 2}, [&](int32_t, int32_t, bool) {
        ++calls;
        return true;
      }));
  EXPECT_EQ(calls, 7);
}

// Continuous points k / 1024 with |coordinates| < 16: every distance from a
// segment to a lattice point is 0 or far above the walk's 1e-9 corner
// tolerance, so the walk must match the brute force exactly, flags included.
TEST(PointSegmentTest, DyadicPointsMatchBruteForceExactly) {
  constexpr int64_t kScale = 1024;
  std::mt19937 rng(3);
  std::uniform_int_distribution<int64_t> any(-6 * kScale, 10 * kScale);
  std::uniform_int_distribution<int64_t> lattice(-6, 10);
  std::uniform_int_distribution<int> kind(0, 5);
  // Random coordinates, mixed with cell boundaries (integers) and centres so
  // segments start, end and run on boundaries and pass through corners.
  auto coordinate = [&]() -> int64_t {
    switch (kind(rng)) {
      case 0:
        return lattice(rng) * kScale;
      case 1:
        return lattice(rng) * kScale + kScale / 2;
      default:
        return any(rng);
    }
  };
  for (int i = 0; i < 20000; ++i) {
    const int64_t px = coordinate();
    const int64_t py = coordinate();
    int64_t qx = coordinate();
    int64_t qy = coordinate();
    if (i % 10 == 0) qx = px;  // vertical, maybe along a boundary
    if (i % 10 == 1) qy = py;
    if (i % 10 == 2) {  // exactly 45 degrees
      qy = py + (qx - px);
    }
    const CellPoint p{static_cast<double>(px) / kScale,
                      static_cast<double>(py) / kScale};
    const CellPoint q{static_cast<double>(qx) / kScale,
                      static_cast<double>(qy) / kScale};
    const std::vector<Visited> walk = Walk(p, q);
    ExpectMatchesBruteForce(walk, px, py, qx, qy, kScale, /*exact_flags=*/true,
                            absl::StrCat("case ", i));
    if (HasFatalFailure()) return;
  }
}

TEST(PointSegmentTest, CellCentresMatchTheCellWalk) {
  std::mt19937 rng(5);
  std::uniform_int_distribution<int32_t> coord(0, 25);
  for (int i = 0; i < 3000; ++i) {
    const Cell a{coord(rng), coord(rng)};
    const Cell b{coord(rng), coord(rng)};
    const std::vector<Visited> cells = Walk(a, b);
    const std::vector<Visited> points =
        Walk(CellPoint{a.x + 0.5, a.y + 0.5}, CellPoint{b.x + 0.5, b.y + 0.5});
    ASSERT_EQ(cells.size(), points.size());
    for (size_t k = 0; k < cells.size(); ++k) {
      EXPECT_EQ(std::tie(cells[k].x, cells[k].y, cells[k].corner_only),
                std::tie(points[k].x, points[k].y, points[k].corner_only));
    }
  }
}

TEST(PointSegmentTest, HandCasesOnBoundaries) {
  auto cells = [](CellPoint p, CellPoint q) {
    std::vector<std::tuple<int, int, bool>> out;
    for (const Visited& v : Walk(p, q))
      out.emplace_back(v.x, v.y, v.corner_only);
    std::sort(out.begin(), out.end());
    return out;
  };
  using V = std::vector<std::tuple<int, int, bool>>;
  // Half a cell from the centre to the boundary, either way: the neighbour is
  // touched at the end point only.
  EXPECT_EQ(cells({3.5, 2.5}, {4.0, 2.5}), (V{{3, 2, false}, {4, 2, true}}));
  EXPECT_EQ(cells({4.0, 2.5}, {3.5, 2.5}), (V{{3, 2, false}, {4, 2, true}}));
  EXPECT_EQ(cells({4.0, 2.5}, {4.5, 2.5}), (V{{3, 2, true}, {4, 2, false}}));
  // Sliding along the boundary x = 4 touches both columns.
  EXPECT_EQ(cells({4.0, 2.5}, {4.0, 3.5}),
            (V{{3, 2, false}, {3, 3, false}, {4, 2, false}, {4, 3, false}}));
  // A lattice point touches four cells.
  EXPECT_EQ(cells({4.0, 2.0}, {4.0, 2.0}),
            (V{{3, 1, true}, {3, 2, true}, {4, 1, true}, {4, 2, false}}));
  EXPECT_EQ(cells({1.25, 1.75}, {1.25, 1.75}), (V{{1, 1, false}}));
}

// Full-precision doubles in [1, 16) are integers in units of 2^-52, so the
// brute force stays exact in 128-bit arithmetic. Segments aimed through
// lattice points pass within rounding of the corner: the walk may report both
// side cells there, never fewer cells than the exact answer.
TEST(PointSegmentTest, RandomDoublesCoverTheExactAnswer) {
  constexpr double kScale = 4503599627370496.0;  // 2^52
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> coord(1.0, 15.999);
  std::uniform_int_distribution<int> lattice(2, 14);
  for (int i = 0; i < 20000; ++i) {
    const CellPoint p{coord(rng), coord(rng)};
    CellPoint q{coord(rng), coord(rng)};
    if (i % 2 == 0) {
      // From p through the lattice point c to a bit beyond it.
      const double cx = lattice(rng);
      const double cy = lattice(rng);
      const double k =
          1.0 + std::uniform_real_distribution<double>(0.01, 1.0)(rng);
      q = {p.x + k * (cx - p.x), p.y + k * (cy - p.y)};
      if (q.x < 1.0 || q.x >= 16.0 || q.y < 1.0 || q.y >= 16.0) continue;
    }
    const std::vector<Visited> walk = Walk(p, q);
    ExpectMatchesBruteForce(
        walk, static_cast<int64_t>(p.x * kScale),
        static_cast<int64_t>(p.y * kScale), static_cast<int64_t>(q.x * kScale),
        static_cast<int64_t>(q.y * kScale), static_cast<int64_t>(kScale),
        /*exact_flags=*/false, absl::StrCat("case ", i));
    if (HasFatalFailure()) return;
  }
}

// Random costs: free, weighted, inscribed, lethal and unknown cells.
Grid RandomGrid(std::mt19937& rng, int32_t w, int32_t h, double blocked) {
  Grid grid = Grid::Create(w, h).value();
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::uniform_int_distribution<int> weight(1, 252);
  const uint8_t blockers[] = {kInscribedCost, kLethalCost, kUnknownCost};
  for (int32_t y = 0; y < h; ++y) {
    for (int32_t x = 0; x < w; ++x) {
      const double r = u(rng);
      uint8_t v = kFreeCost;
      if (r < blocked) {
        v = blockers[static_cast<int>(u(rng) * 3) % 3];
      } else if (r < blocked + 0.3) {
        v = static_cast<uint8_t>(weight(rng));
      }
      grid.set_cost(x, y, v);
    }
  }
  return grid;
}

TEST(LineOfSightTest, SingleMovesAgreeWithMeasurePath) {
  std::mt19937 rng(13);
  for (int g = 0; g < 200; ++g) {
    const Grid grid = RandomGrid(rng, 6, 6, 0.3);
    for (const bool unknown_is_free : {false, true}) {
      CostParams cost;
      cost.unknown_is_free = unknown_is_free;
      cost.cost_weight = g % 2 == 0 ? 1.0 : 3.5;
      for (int32_t y = 0; y < 6; ++y) {
        for (int32_t x = 0; x < 6; ++x) {
          const Cell a{x, y};
          if (!Traversable(grid.cost(a), unknown_is_free)) continue;
          for (const Move& m : kMoves) {
            const Cell b{x + m.dx, y + m.dy};
            const PathMeasure move = MeasurePath(grid, {a, b}, cost);
            ASSERT_EQ(LineOfSight(grid, a, b, cost), move.valid)
                << CellToString(a) << " -> " << CellToString(b);
            if (!move.valid) continue;
            // Bit-identical, so any-angle and cell paths cost the same.
            EXPECT_EQ(SegmentCost(grid, a, b, cost), move.cost);
            EXPECT_EQ(MeasureAnyAnglePath(grid, {a, b}, cost).cost, move.cost);
          }
        }
      }
    }
  }
}

TEST(LineOfSightTest, OffGridAndBlockedEndpoints) {
  const Grid grid = Grid::Create(4, 3).value();
  const CostParams cost;
  EXPECT_TRUE(LineOfSight(grid, {0, 0}, {3, 2}, cost));
  EXPECT_FALSE(LineOfSight(grid, {0, 0}, {4, 2}, cost));
  EXPECT_FALSE(LineOfSight(grid, {-1, 0}, {3, 2}, cost));
  Grid blocked = grid;
  blocked.set_cost(3, 2, kLethalCost);
  EXPECT_FALSE(LineOfSight(blocked, {0, 0}, {3, 2}, cost));
  EXPECT_FALSE(LineOfSight(blocked, {3, 2}, {3, 2}, cost));
  blocked.set_cost(3, 2, kUnknownCost);
  EXPECT_FALSE(LineOfSight(blocked, {0, 0}, {3, 2}, cost));
  CostParams unknown_free;
  unknown_free.unknown_is_free = true;
  EXPECT_TRUE(LineOfSight(blocked, {0, 0}, {3, 2}, unknown_free));
}

TEST(LineOfSightTest, CornerTouchBlocksLikeTheMoveRule) {
  // (0,0) -> (2,2) passes through the corner shared by (1,0) and (0,1).
  Grid grid = Grid::Create(3, 3).value();
  const CostParams cost;
  grid.set_cost(1, 0, kLethalCost);
  EXPECT_FALSE(LineOfSight(grid, {0, 0}, {2, 2}, cost));
  EXPECT_FALSE(LineOfSight(grid, {2, 2}, {0, 0}, cost));
  grid.set_cost(1, 0, kFreeCost);
  grid.set_cost(2, 0, kLethalCost);  // not touched: the segment stays clear
  EXPECT_TRUE(LineOfSight(grid, {0, 0}, {2, 2}, cost));
}

TEST(SegmentCostTest, LargestFactorOfEnteredCellsTimesLength) {
  std::mt19937 rng(17);
  std::uniform_int_distribution<int32_t> coord(0, 11);
  int checked = 0;
  for (int g = 0; g < 300; ++g) {
    const Grid grid = RandomGrid(rng, 12, 12, 0.1);
    CostParams cost;
    cost.cost_weight = 2.0;
    for (int i = 0; i < 50; ++i) {
      const Cell a{coord(rng), coord(rng)};
      const Cell b{coord(rng), coord(rng)};
      if (!LineOfSight(grid, a, b, cost)) continue;
      // Brute force: every cell met in more than one point, except a.
      double factor = 1.0;
      for (int32_t y = 0; y < 12; ++y) {
        for (int32_t x = 0; x < 12; ++x) {
          const Touch t = BruteTouch(2 * a.x + 1, 2 * a.y + 1, 2 * b.x + 1,
                                     2 * b.y + 1, 2, x, y);
          if (!t.touched || t.single_point || Cell{x, y} == a) continue;
          factor =
              std::max(factor, CellFactor(grid.cost(x, y), cost.cost_weight));
        }
      }
      const double dx = b.x - a.x;
      const double dy = b.y - a.y;
      const double length = std::sqrt(dx * dx + dy * dy);
      EXPECT_EQ(SegmentCost(grid, a, b, cost), length * factor);
      CostParams uniform = cost;
      uniform.cost_weight = 0.0;
      EXPECT_EQ(SegmentCost(grid, a, b, uniform), length);
      ++checked;
    }
  }
  EXPECT_GT(checked, 1000);
}

}  // namespace
}  // namespace pathd
