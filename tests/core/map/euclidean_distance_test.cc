// The exact distance transform and obstacle inflation against brute force on
// random grids (fixed seeds) and on the bundled arena2 map.
#include "core/map/euclidean_distance.h"

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "absl/status/status.h"
#include "core/map/grid.h"
#include "core/map/inflation.h"
#include "core/map_io/map_io.h"
#include "gtest/gtest.h"

namespace pathd {
namespace {

Grid RandomGrid(int32_t w, int32_t h, double lethal_density,
                std::mt19937& rng) {
  Grid grid = Grid::Create(w, h).value();
  std::uniform_real_distribution<double> coin(0.0, 1.0);
  std::uniform_int_distribution<int> other(0, 255);
  for (int32_t y = 0; y < h; ++y) {
    for (int32_t x = 0; x < w; ++x) {
      uint8_t v = static_cast<uint8_t>(other(rng));
      if (v == kLethalCost) v = kFreeCost;
      if (coin(rng) < lethal_density) v = kLethalCost;
      grid.set_cost(x, y, v);
    }
  }
  return grid;
}

// Minimum over every source (and the border ring when asked) of the squared
// centre distance; +infinity without sources.
std::vector<double> BruteForce(const Grid& grid,
                               const DistanceSources& sources) {
  const int32_t w = grid.width(), h = grid.height();
  std::vector<Cell> points;
  for (int32_t y = 0; y < h; ++y) {
    for (int32_t x = 0; x < w; ++x) {
      if (sources.by_cost[grid.cost(x, y)]) points.push_back({x, y});
    }
  }
  if (sources.border) {
    for (int32_t x = -1; x <= w; ++x) {
      points.push_back({x, -1});
      points.push_back({x, h});
    }
    for (int32_t y = 0; y < h; ++y) {
      points.push_back({-1, y});
      points.push_back({w, y});
    }
  }
  std::vector<double> out(grid.size(), std::numeric_limits<double>::infinity());
  for (int32_t y = 0; y < h; ++y) {
    for (int32_t x = 0; x < w; ++x) {
      for (const Cell& p : points) {
        const double dx = x - p.x, dy = y - p.y;
        out[grid.Index(x, y)] =
            std::min(out[grid.Index(x, y)], dx * dx + dy * dy);
      }
    }
  }
  return out;
}

TEST(DistanceFieldTest, MatchesBruteForceOnRandomGrids) {
  std::mt19937 rng(20240611);
  const int32_t sizes[][2] = {{1, 1},   {1, 17}, {23, 1}, {2, 2},   {7, 5},
                              {16, 16}, {40, 3}, {3, 40}, {37, 29}, {64, 48}};
  const double densities[] = {0.0, 0.005, 0.05, 0.3, 0.9, 1.0};
  int compared = 0;
  for (const auto& size : sizes) {
    for (double density : densities) {
      for (bool border : {false, true}) {
        const Grid grid = RandomGrid(size[0], size[1], density, rng);
        DistanceSources sources = SourcesOfCost(kLethalCost);
        sources.border = border;
        const std::vector<double> expected = BruteForce(grid, sources);
        const std::vector<double> got = SquaredDistanceToNearest(grid, sources);
        ASSERT_EQ(got.size(), expected.size());
        for (size_t i = 0; i < got.size(); ++i) {
          ASSERT_EQ(got[i], expected[i])
              << size[0] << "x" << size[1] << " density " << density
              << " border " << border << " cell "
              << CellToString(grid.CellAt(i));
          ++compared;
        }
      }
    }
  }
  EXPECT_GT(compared, 50000);
}

TEST(DistanceFieldTest, SourcesBySeveralCosts) {
  std::mt19937 rng(7);
  const Grid grid = RandomGrid(31, 27, 0.0, rng);
  DistanceSources sources;
  for (int c = 200; c < 256; ++c) sources.by_cost[c] = true;
  EXPECT_EQ(SquaredDistanceToNearest(grid, sources), BruteForce(grid, sources));
}

TEST(DistanceFieldTest, BoundReportsFarBeyondItAndExactWithin) {
  std::mt19937 rng(99);
  EuclideanDistanceField transform;
  for (int trial = 0; trial < 20; ++trial) {
    const Grid grid = RandomGrid(45, 38, trial % 2 ? 0.01 : 0.1, rng);
    DistanceSources sources = SourcesOfCost(kLethalCost);
    sources.border = trial % 3 == 0;
    const std::vector<double> expected = BruteForce(grid, sources);
    // Small bounds take the windowed row pass, large ones the envelope; the
    // switch is at a radius of 16 or so.
    for (int64_t bound :
         {int64_t{-1}, int64_t{0}, int64_t{1}, int64_t{2}, int64_t{9},
          int64_t{50}, int64_t{255}, int64_t{256}, int64_t{288}, int64_t{289},
          int64_t{290}, int64_t{624}, int64_t{625}, int64_t{5000}}) {
      // Reused across calls and grids: results must not depend on history.
      const std::vector<int64_t>& got = transform.Compute(grid, sources, bound);
      for (size_t i = 0; i < got.size(); ++i) {
        if (expected[i] <= static_cast<double>(bound)) {
          ASSERT_EQ(static_cast<double>(got[i]), expected[i])
              << "bound " << bound;
        } else {
          ASSERT_EQ(got[i], EuclideanDistanceField::kFar) << "bound " << bound;
        }
      }
    }
  }
}

TEST(DistanceFieldTest, WithinMatchesBruteForce) {
  std::mt19937 rng(31337);
  EuclideanDistanceField transform;
  for (int trial = 0; trial < 24; ++trial) {
    const Grid grid = RandomGrid(1 + trial * 3, 40 - trial,
                                 trial % 4 == 0 ? 0.002 : 0.06, rng);
    DistanceSources sources = SourcesOfCost(kLethalCost);
    sources.border = trial % 2 == 1;
    const std::vector<double> expected = BruteForce(grid, sources);
    for (int64_t bound : {int64_t{-1}, int64_t{0}, int64_t{1}, int64_t{2},
                          int64_t{5}, int64_t{24}, int64_t{25}, int64_t{26},
                          int64_t{1000}, EuclideanDistanceField::kFar}) {
      int32_t rows = 0;
      transform.ForEachRowWithin(
          grid, sources, bound, [&](int32_t y, const uint8_t* within) {
            ASSERT_EQ(y, rows++);
            for (int32_t x = 0; x < grid.width(); ++x) {
              ASSERT_EQ(within[x] != 0, expected[grid.Index(x, y)] <=
                                            static_cast<double>(bound))
                  << "bound " << bound << " cell " << x << "," << y
                  << " border " << sources.border;
            }
          });
      EXPECT_EQ(rows, grid.height());
    }
  }
}

TEST(DistanceFieldTest, ExactAtTheLargestDistances) {
  // One source in a corner of a long strip: squared distances up to ~4e8
  // must come out exact (a float field would round them).
  Grid grid = Grid::Create(20000, 2).value();
  grid.set_cost(0, 0, kLethalCost);
  const std::vector<double> got =
      SquaredDistanceToNearest(grid, SourcesOfCost(kLethalCost));
  for (int32_t x = 0; x < grid.width(); x += 997) {
    EXPECT_EQ(got[grid.Index(x, 1)], static_cast<double>(x) * x + 1.0);
  }
  EXPECT_EQ(got[grid.Index(19999, 1)], 19999.0 * 19999.0 + 1.0);
}

// --- Inflation -----------------------------------------------------------

// r^2 >= n in exact arithmetic: r = m * 2^e with a 53-bit m, so r^2 = m^2 *
// 2^(2e) fits in 128 bits for the radii used here.
bool SquareAtLeast(double r, int64_t n) {
  int exp = 0;
  const double frac =
      std::frexp(r, &exp);  // r = frac * 2^exp, frac in [0.5, 1)
  const auto m = static_cast<unsigned __int128>(std::ldexp(frac, 53));
  const int shift = 2 * (exp - 53);  // r^2 = m^2 * 2^shift
  // Both sides scaled to integers; n < 2^20 and shift > -110 for the radii
  // used here, so nothing overflows.
  const unsigned __int128 m2 = m * m;
  const auto wide_n = static_cast<unsigned __int128>(n);
  return shift >= 0 ? (m2 << shift) >= wide_n : m2 >= wide_n << -shift;
}

Grid BruteInflate(const Grid& grid, double r) {
  Grid out = grid;
  const int32_t reach = static_cast<int32_t>(std::ceil(r));
  for (int32_t y = 0; y < grid.height(); ++y) {
    for (int32_t x = 0; x < grid.width(); ++x) {
      if (grid.cost(x, y) != kLethalCost) continue;
      for (int32_t dy = -reach; dy <= reach; ++dy) {
        for (int32_t dx = -reach; dx <= reach; ++dx) {
          const int32_t nx = x + dx, ny = y + dy;
          if (!grid.InBounds(nx, ny) || !SquareAtLeast(r, dx * dx + dy * dy))
            continue;
          if (grid.cost(nx, ny) < kLethalCost)
            out.set_cost(nx, ny, kInscribedCost);
        }
      }
    }
  }
  return out;
}

TEST(InflationTest, MatchesBruteForceOnRandomGrids) {
  std::mt19937 rng(424242);
  const double radii[] = {0.0, 0.4, 1.0, std::sqrt(2.0),
                          1.5, 2.0, 2.5, std::sqrt(5.0),
                          3.0, 4.7, 9.0};
  for (int trial = 0; trial < 12; ++trial) {
    const Grid grid = RandomGrid(20 + trial * 3, 15 + trial * 2,
                                 trial % 3 == 0 ? 0.01 : 0.08, rng);
    for (double r : radii) {
      const absl::StatusOr<Grid> got = InflateObstacles(grid, r);
      ASSERT_TRUE(got.ok()) << got.status();
      EXPECT_EQ(got->cells(), BruteInflate(grid, r).cells())
          << "trial " << trial << " radius " << r;
    }
  }
}

TEST(InflationTest, RadiiJustBelowAndAboveAnIntegerSquare) {
  // Cell (11, 10) is sqrt(41) from the lethal cell. The double nearest
  // sqrt(41) squares to just below 41 exactly, yet r * r rounds to 41.0: the
  // cell must stay free for it and its lower neighbour, and be inflated for
  // the next double up.
  Grid grid = Grid::Create(13, 13).value();
  grid.set_cost(6, 6, kLethalCost);
  const double root41 = std::sqrt(41.0);
  ASSERT_FALSE(SquareAtLeast(root41, 41));
  ASSERT_EQ(root41 * root41, 41.0);
  for (double r :
       {std::nextafter(root41, 0.0), root41, std::nextafter(root41, 10.0)}) {
    const Grid got = InflateObstacles(grid, r).value();
    EXPECT_EQ(got.cost(11, 10) == kInscribedCost, r > root41) << r;
    EXPECT_EQ(got.cells(), BruteInflate(grid, r).cells()) << r;
  }
}

TEST(InflationTest, KeepsOtherCostsUnknownAndGeometry) {
  Grid grid = Grid::Create(7, 3).value();
  grid.set_resolution(0.05);
  grid.set_origin(GridOrigin{1.5, -2.0, 0.3});
  grid.set_cost(0, 1, kLethalCost);
  grid.set_cost(1, 1, kUnknownCost);
  grid.set_cost(2, 1, 100);
  grid.set_cost(3, 1, 100);
  grid.set_cost(4, 1, kInscribedCost);
  const Grid got = InflateObstacles(grid, 2.0).value();
  EXPECT_EQ(got.cost(0, 1), kLethalCost);
  EXPECT_EQ(got.cost(1, 1), kUnknownCost);
  EXPECT_EQ(got.cost(2, 1), kInscribedCost);
  EXPECT_EQ(got.cost(3, 1), 100);
  EXPECT_EQ(got.cost(4, 1), kInscribedCost);
  EXPECT_EQ(got.cost(1, 0), kInscribedCost);
  EXPECT_EQ(got.cost(2, 0), kFreeCost);  // sqrt(5) > 2
  EXPECT_EQ(got.resolution(), 0.05);
  EXPECT_EQ(got.origin().x, 1.5);
  EXPECT_EQ(got.origin().y, -2.0);
  EXPECT_EQ(got.origin().yaw, 0.3);
}

TEST(InflationTest, RadiusZeroIsAnIdenticalCopy) {
  std::mt19937 rng(5);
  const Grid grid = RandomGrid(30, 20, 0.1, rng);
  const Grid got = InflateObstacles(grid, 0.0).value();
  EXPECT_EQ(got.cells(), grid.cells());
  EXPECT_EQ(got.width(), grid.width());
  EXPECT_EQ(got.height(), grid.height());
}

TEST(InflationTest, HugeRadiusBlocksEverythingReachable) {
  std::mt19937 rng(6);
  const Grid grid = RandomGrid(30, 20, 0.002, rng);
  const Grid got = InflateObstacles(grid, 1e12).value();
  for (size_t i = 0; i < grid.size(); ++i) {
    EXPECT_EQ(got.cells()[i], grid.cells()[i] >= kLethalCost ? grid.cells()[i]
                                                             : kInscribedCost);
  }
}

TEST(InflationTest, RejectsBadRadiusNamingIt) {
  const Grid grid = Grid::Create(4, 4).value();
  for (double r : {-1.0, -1e-300, std::numeric_limits<double>::infinity(),
                   std::numeric_limits<double>::quiet_NaN()}) {
    const absl::StatusOr<Grid> got = InflateObstacles(grid, r);
    ASSERT_FALSE(got.ok()) << r;
    EXPECT_EQ(got.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(got.status().message().find("robot radius"), std::string::npos)
        << got.status();
  }
}

TEST(InflationTest, MatchesBruteForceOnBundledMap) {
  const absl::StatusOr<Grid> grid = ReadMovingAiMapFile("maps/arena2.map");
  ASSERT_TRUE(grid.ok()) << grid.status();
  for (double r : {1.5, 5.0, 20.0}) {
    EXPECT_EQ(InflateObstacles(*grid, r)->cells(),
              BruteInflate(*grid, r).cells())
        << "radius " << r;
  }
}

}  // namespace
}  // namespace pathd
