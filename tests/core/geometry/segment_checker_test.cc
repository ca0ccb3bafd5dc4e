// The independent segment checker (tests/testing/segment_checker.h) on hand
// cases whose answers follow from the free-space rule by inspection, then
// against FreeSpace::SegmentClear on hundreds of thousands of random
// segments on random small maps (pinches, walls, unknown cells, map borders,
// endpoints outside the map), and its windowed scan against its exhaustive
// one.
#include "tests/testing/segment_checker.h"

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "absl/strings/str_format.h"
#include "core/geometry/free_space.h"
#include "core/map/cost_model.h"
#include "gtest/gtest.h"
#include "tests/testing/test_grids.h"

namespace pathd::testing {
namespace {

using Kind = SegmentDefect::Kind;

LatticePoint C(int x, int y) { return CentreOf(Cell{x, y}); }
LatticePoint K(int x, int y) { return CornerAt(x, y); }

std::string GridText(const Grid& grid) {
  std::string out;
  for (int32_t y = 0; y < grid.height(); ++y) {
    for (int32_t x = 0; x < grid.width(); ++x) {
      const uint8_t c = grid.cost(x, y);
      out += c == kLethalCost ? '#' : c == kUnknownCost ? '?' : '.';
    }
    out += '\n';
  }
  return out;
}

std::string SegmentText(LatticePoint a, LatticePoint b) {
  return absl::StrFormat("(%.1f, %.1f) -> (%.1f, %.1f)", a.x2 / 2.0, a.y2 / 2.0,
                         b.x2 / 2.0, b.y2 / 2.0);
}

TEST(SegmentCheckerTest, OpenGridBorderAndOutside) {
  const SegmentChecker check(MakeGrid({"...", "...", "..."}), false);
  EXPECT_TRUE(check.Clear(C(0, 0), C(2, 2)));
  EXPECT_TRUE(check.Clear(C(0, 0), C(2, 1)));
  // Along the map border (outside blocked, inside free) and through the map
  // corners, which have three outside cells: corners of a free square.
  EXPECT_TRUE(check.Clear(K(0, 1), K(0, 2)));
  EXPECT_TRUE(check.Clear(K(1, 3), K(2, 3)));
  EXPECT_TRUE(check.Clear(K(0, 0), K(3, 0)));
  EXPECT_TRUE(check.Clear(K(3, 3), K(3, 3)));
  // Just outside a map corner: four outside cells.
  EXPECT_EQ(check.FindDefect(K(-1, 0), K(-1, 0))->kind, Kind::kThroughClosedCorner);
  // Outside the map.
  const auto out = check.FindDefect(C(1, 1), C(-1, 1));
  ASSERT_TRUE(out.has_value());
  EXPECT_EQ(out->kind, Kind::kCrossesBlockedCell);
  // Along the outside edge between two outside cells.
  EXPECT_EQ(check.FindDefect(K(-1, 1), K(-1, 2))->kind, Kind::kAlongBlockedEdge);
}

TEST(SegmentCheckerTest, OneBlockedCellIsTouchedNotCrossed) {
  const SegmentChecker check(MakeGrid({"...", ".#.", "..."}), false);
  const auto d = check.FindDefect(C(0, 0), C(2, 2));
  ASSERT_TRUE(d.has_value());
  EXPECT_EQ(d->kind, Kind::kCrossesBlockedCell);
  EXPECT_EQ(d->cell, (Cell{1, 1}));
  EXPECT_FALSE(check.Clear(K(1, 1), K(2, 2)));
  EXPECT_FALSE(check.Clear(K(1, 2), K(2, 1)));
  // Its edges, corners and the diagonals that touch one corner.
  EXPECT_TRUE(check.Clear(K(1, 1), K(2, 1)));
  EXPECT_TRUE(check.Clear(K(1, 1), K(1, 2)));
  EXPECT_TRUE(check.Clear(C(0, 0), K(1, 1)));
  EXPECT_TRUE(check.Clear(C(0, 1), C(1, 0)));
  EXPECT_TRUE(check.Clear(C(2, 1), C(1, 2)));
  EXPECT_FALSE(check.Clear(K(0, 3), K(3, 0)));  // through (1.5, 1.5)
  EXPECT_TRUE(check.Clear(C(0, 0), C(2, 0)));
  EXPECT_FALSE(check.Clear(C(0, 0), C(2, 1)));
  // Grazing a corner at a shallow angle: (0.5, 0.5) -> (2.5, 1.0) passes
  // (1, 0.625), inside the free cell (1, 0); it reaches y = 1 only at x = 2.5.
  EXPECT_TRUE(check.Clear(C(0, 0), LatticePoint{5, 2}));
  // (0, 0.5) -> (2, 1.5) passes (1, 1) then the blocked interior.
  EXPECT_FALSE(check.Clear(LatticePoint{0, 1}, LatticePoint{4, 3}));
}

TEST(SegmentCheckerTest, PinchesAreClosed) {
  // (0, 0) and (1, 1) blocked: they touch at corner (1, 1).
  const SegmentChecker check(MakeGrid({"#..", ".#.", "..."}), false);
  EXPECT_TRUE(check.ClosedCorner(1, 1));
  const auto d = check.FindDefect(C(0, 1), C(1, 0));
  ASSERT_TRUE(d.has_value());
  EXPECT_EQ(d->kind, Kind::kThroughClosedCorner);
  EXPECT_EQ(d->corner, (Cell{1, 1}));
  // Ending at the pinch is as bad as passing it.
  EXPECT_FALSE(check.Clear(C(0, 1), K(1, 1)));
  // The other corners of the blocked cells are free.
  EXPECT_TRUE(check.Clear(C(0, 1), K(1, 2)));
  EXPECT_TRUE(check.Clear(K(2, 1), K(2, 2)));
  // Three blocked around a corner: a corner of the free square (1, 1),
  // touched from inside it, not squeezed through.
  const SegmentChecker three(MakeGrid({"##.", "#..", "..."}), false);
  EXPECT_FALSE(three.ClosedCorner(1, 1));
  EXPECT_TRUE(three.Clear(C(1, 1), K(1, 1)));
  EXPECT_TRUE(three.Clear(C(2, 0), C(0, 2)));
  // But the edges between the three blocked cells are closed.
  EXPECT_FALSE(three.Clear(K(1, 1), K(1, 0)));
  EXPECT_FALSE(three.Clear(K(1, 1), K(0, 1)));
  // Four blocked: enclosed.
  const SegmentChecker four(MakeGrid({"##.", "##.", "..."}), false);
  EXPECT_TRUE(four.ClosedCorner(1, 1));
  EXPECT_FALSE(four.ClosedCorner(2, 1));
}

TEST(SegmentCheckerTest, WallsAreNotRunAlong) {
  // A horizontal wall of two cells: its long edges are free to run along,
  // the edge between its two cells is not.
  const SegmentChecker check(MakeGrid({"....", ".##.", "...."}), false);
  EXPECT_TRUE(check.Clear(K(0, 1), K(4, 1)));
  EXPECT_TRUE(check.Clear(K(0, 2), K(4, 2)));
  const auto d = check.FindDefect(K(2, 1), K(2, 2));
  ASSERT_TRUE(d.has_value());
  EXPECT_EQ(d->kind, Kind::kAlongBlockedEdge);
  EXPECT_EQ(d->cell, (Cell{1, 1}));
  EXPECT_EQ(d->other, (Cell{2, 1}));
  // Ending at the middle of the blocked edge (a half-cell lattice point that
  // is neither centre nor corner).
  EXPECT_FALSE(check.Clear(C(2, 0), LatticePoint{4, 3}));
  EXPECT_FALSE(check.Clear(LatticePoint{4, 3}, LatticePoint{4, 3}));
  // The wall's ends are corners with two blocked cells side by side: free.
  EXPECT_TRUE(check.Clear(K(2, 1), K(2, 1)));
  EXPECT_TRUE(check.Clear(C(2, 0), K(2, 1)));
  // Along the map border: free cells beside it all the way.
  EXPECT_TRUE(check.Clear(K(0, 0), K(0, 3)));
  // A wall against the border: the border edge beside a blocked cell is the
  // edge between it and the outside.
  const SegmentChecker border(MakeGrid({"#...", "#...", "...."}), false);
  EXPECT_FALSE(border.Clear(K(0, 1), K(0, 2)));
  EXPECT_FALSE(border.Clear(K(0, 0), K(0, 3)));
  EXPECT_TRUE(border.Clear(K(1, 1), K(1, 2)));
  // Corner (0, 2): two outside cells and blocked (0, 1): three, free.
  EXPECT_TRUE(border.Clear(K(0, 2), K(0, 3)));
  EXPECT_TRUE(border.Clear(K(0, 2), C(2, 2)));
}

TEST(SegmentCheckerTest, UnknownCellsFollowTheRequest) {
  const Grid grid = MakeGrid({"...", ".?.", "..."});
  EXPECT_FALSE(SegmentChecker(grid, false).Clear(C(0, 0), C(2, 2)));
  EXPECT_TRUE(SegmentChecker(grid, true).Clear(C(0, 0), C(2, 2)));
  // Weighted cells are traversable.
  EXPECT_TRUE(SegmentChecker(MakeGrid({"...", ".9.", "..."}), false)
                  .Clear(C(0, 0), C(2, 2)));
}

TEST(SegmentCheckerTest, PolylineCheckerNamesTheFirstBadSegment) {
  const SegmentChecker check(MakeGrid({"....", ".##.", "...."}), false);
  const PolylineChecker poly(check);
  EXPECT_FALSE(poly.FirstDefect({{0.5, 0.5}, {1.0, 1.0}, {3.0, 1.0}, {3.5, 2.5}})
                   .has_value());
  const auto d = poly.FirstDefect({{0.5, 0.5}, {1.0, 1.0}, {3.5, 2.5}});
  ASSERT_TRUE(d.has_value());
  EXPECT_EQ(d->index, 1u);
  EXPECT_EQ(d->defect.kind, Kind::kCrossesBlockedCell);
  EXPECT_NE(d->ToString().find("segment 1"), std::string::npos) << d->ToString();
  const auto off = poly.FirstDefect({{0.5, 0.5}, {0.7, 0.5}});
  ASSERT_TRUE(off.has_value());
  EXPECT_EQ(off->defect.kind, Kind::kNotOnLattice);
  // One vertex: a point.
  EXPECT_TRUE(poly.FirstDefect({{1.5, 1.5}}).has_value());
  EXPECT_FALSE(poly.FirstDefect({{0.5, 0.5}}).has_value());
  EXPECT_FALSE(poly.FirstDefect({}).has_value());
}

// A random small map: random obstacles at a random density, with designed
// patterns mixed in (checkerboard patches of pinches, straight walls, unknown
// cells).
Grid RandomMap(std::mt19937_64& rng) {
  std::uniform_int_distribution<int> dim(1, 9);
  const int w = dim(rng), h = dim(rng);
  Grid grid = *Grid::Create(w, h);
  const double density = std::uniform_real_distribution<double>(0.0, 0.6)(rng);
  std::bernoulli_distribution blocked(density);
  std::bernoulli_distribution unknown(0.1);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      if (blocked(rng)) grid.set_cost(x, y, unknown(rng) ? kUnknownCost : kLethalCost);
    }
  }
  switch (rng() % 4) {
    case 0: {  // A checkerboard patch: every inner corner a pinch.
      const int x0 = static_cast<int>(rng() % w), y0 = static_cast<int>(rng() % h);
      for (int y = y0; y < std::min(h, y0 + 4); ++y) {
        for (int x = x0; x < std::min(w, x0 + 4); ++x) {
          grid.set_cost(x, y, (x + y) % 2 == 0 ? kLethalCost : kFreeCost);
        }
      }
      break;
    }
    case 1: {  // A wall, horizontal or vertical, with maybe one gap.
      const bool horizontal = rng() % 2 == 0;
      const int at = static_cast<int>(rng() % (horizontal ? h : w));
      const int len = horizontal ? w : h;
      const int gap = static_cast<int>(rng() % (len + 1));
      for (int i = 0; i < len; ++i) {
        if (i == gap) continue;
        if (horizontal) {
          grid.set_cost(i, at, kLethalCost);
        } else {
          grid.set_cost(at, i, kLethalCost);
        }
      }
      break;
    }
    default:
      break;
  }
  return grid;
}

// A random endpoint: mostly cell centres and grid corners, some edge
// midpoints, some up to a cell outside the map.
LatticePoint RandomPoint(std::mt19937_64& rng, const Grid& grid) {
  std::uniform_int_distribution<int> xs(-1, grid.width());
  std::uniform_int_distribution<int> ys(-1, grid.height());
  const int kind = static_cast<int>(rng() % 10);
  int x = xs(rng), y = ys(rng);
  if (kind < 8) {
    // Inside or on the map, most of the time.
    x = std::clamp(x, 0, grid.width());
    y = std::clamp(y, 0, grid.height());
  }
  if (kind < 4) {
    return CentreOf(Cell{std::min(x, grid.width() - 1), std::min(y, grid.height() - 1)});
  }
  if (kind < 7) return CornerAt(x, y);
  // Edge midpoints and the rest of the lattice.
  return LatticePoint{2 * x + static_cast<int64_t>(rng() % 2),
                      2 * y + static_cast<int64_t>(rng() % 2)};
}

TEST(SegmentCheckerTest, AgreesWithFreeSpaceOnRandomSegments) {
  std::mt19937_64 rng(20261201);
  int64_t segments = 0, clear = 0;
  for (int map = 0; map < 3000; ++map) {
    const Grid grid = RandomMap(rng);
    for (bool unknown_is_free : {false, true}) {
      const SegmentChecker check(grid, unknown_is_free);
      const FreeSpace space(grid, unknown_is_free);
      for (int i = 0; i < 60; ++i) {
        const LatticePoint a = RandomPoint(rng, grid);
        const LatticePoint b = i % 10 == 0 ? a : RandomPoint(rng, grid);
        const auto mine = check.FindDefect(a, b);
        const bool exhaustive = !check.FindDefect(a, b, true).has_value();
        const bool theirs = space.SegmentClear(a, b);
        ++segments;
        clear += theirs ? 1 : 0;
        ASSERT_EQ(!mine.has_value(), exhaustive)
            << "windowed vs exhaustive scan, map " << map << " segment "
            << SegmentText(a, b) << " unknown_is_free " << unknown_is_free
            << "\n" << GridText(grid);
        ASSERT_EQ(!mine.has_value(), theirs)
            << "map " << map << " segment " << SegmentText(a, b)
            << " unknown_is_free " << unknown_is_free << ": checker says "
            << (mine ? mine->ToString() : "clear") << ", FreeSpace says "
            << (theirs ? "clear" : "blocked") << "\n" << GridText(grid);
        if (a == b) {
          ASSERT_EQ(!mine.has_value(), space.PointFree(a))
              << "point " << SegmentText(a, b) << "\n" << GridText(grid);
        }
      }
    }
  }
  std::printf("%lld segments, %lld clear\n", static_cast<long long>(segments),
              static_cast<long long>(clear));
  // Both answers are common, so agreement means something.
  EXPECT_GT(clear, segments / 5);
  EXPECT_LT(clear, segments * 4 / 5);
}

// Long segments on a larger map, where the windowed scan matters: the same
// answers as FreeSpace and as the exhaustive scan.
TEST(SegmentCheckerTest, LongSegmentsOnALargerMap) {
  std::mt19937_64 rng(7);
  for (int map = 0; map < 20; ++map) {
    Grid grid = *Grid::Create(64, 48);
    std::bernoulli_distribution blocked(0.01 * (map % 8));
    for (int y = 0; y < grid.height(); ++y) {
      for (int x = 0; x < grid.width(); ++x) {
        if (blocked(rng)) grid.set_cost(x, y, kLethalCost);
      }
    }
    const SegmentChecker check(grid, false);
    const FreeSpace space(grid, false);
    for (int i = 0; i < 500; ++i) {
      const LatticePoint a = RandomPoint(rng, grid);
      const LatticePoint b = RandomPoint(rng, grid);
      const bool mine = check.Clear(a, b);
      ASSERT_EQ(mine, !check.FindDefect(a, b, true).has_value())
          << "windowed vs exhaustive, map " << map << " " << SegmentText(a, b);
      ASSERT_EQ(mine, space.SegmentClear(a, b))
          << "map " << map << " " << SegmentText(a, b) << "\n" << GridText(grid);
    }
  }
}

// FreeSpace advanced cell by cell (FreeSpace::Update, what the planners'
// structures advance) agrees with a checker made for the new grid.
TEST(SegmentCheckerTest, UpdatedFreeSpaceAgreesWithAFreshChecker) {
  std::mt19937_64 rng(11);
  for (int map = 0; map < 300; ++map) {
    Grid grid = RandomMap(rng);
    FreeSpace space(grid, false);
    for (int step = 0; step < 5; ++step) {
      std::vector<Cell> changed;
      for (int k = static_cast<int>(rng() % 4); k >= 0; --k) {
        const Cell c{static_cast<int32_t>(rng() % grid.width()),
                     static_cast<int32_t>(rng() % grid.height())};
        grid.set_cost(c, grid.cost(c) == kFreeCost ? kLethalCost : kFreeCost);
        changed.push_back(c);
      }
      space.Update(grid, changed);
      const SegmentChecker check(grid, false);
      for (int i = 0; i < 40; ++i) {
        const LatticePoint a = RandomPoint(rng, grid);
        const LatticePoint b = RandomPoint(rng, grid);
        ASSERT_EQ(check.Clear(a, b), space.SegmentClear(a, b))
            << "map " << map << " step " << step << " " << SegmentText(a, b)
            << "\n" << GridText(grid);
      }
    }
  }
}

}  // namespace
}  // namespace pathd::testing
