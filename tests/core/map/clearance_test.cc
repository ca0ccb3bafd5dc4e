// Clearance costs and path clearance (core/map/clearance.h) against brute
// force: every obstacle centre and the map's outside ring measured one by
// one, nothing shared with the distance transform or the ring search.
#include "core/map/clearance.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/map/inflation.h"
#include "gtest/gtest.h"

namespace pathd {
namespace {

// Euclidean distance from `c`'s centre to the nearest centre of a cell the
// robot centre may not occupy, the ring of cells just outside the map
// included.
double BruteClearance(const Grid& grid, Cell c, bool unknown_is_free) {
  double best = std::numeric_limits<double>::infinity();
  for (int32_t y = -1; y <= grid.height(); ++y) {
    for (int32_t x = -1; x <= grid.width(); ++x) {
      const bool outside = x < 0 || y < 0 || x >= grid.width() || y >= grid.height();
      if (!outside && Traversable(grid.cost(Cell{x, y}), unknown_is_free)) continue;
      best = std::min(best, std::hypot(x - c.x, y - c.y));
    }
  }
  return best;
}

Grid RandomGrid(std::mt19937& rng, int32_t w, int32_t h, double blocked) {
  Grid grid = Grid::Create(w, h).value();
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::uniform_int_distribution<int> cost(0, 255);
  for (int32_t y = 0; y < h; ++y) {
    for (int32_t x = 0; x < w; ++x) {
      const double r = u(rng);
      // Mostly free or lethal, some of every other cost (inscribed and
      // unknown included).
      uint8_t c = r < blocked ? kLethalCost : 0;
      if (u(rng) < 0.15) c = static_cast<uint8_t>(cost(rng));
      grid.set_cost(x, y, c);
    }
  }
  return grid;
}

TEST(ClearanceCost, LinearRampRoundedUp) {
  EXPECT_EQ(ClearanceCost(0.0, 10.0), kMaxTraversableCost);
  EXPECT_EQ(ClearanceCost(1.0, 10.0), 227);  // ceil(252 * 0.9) = ceil(226.8)
  EXPECT_EQ(ClearanceCost(5.0, 10.0), 126);
  EXPECT_EQ(ClearanceCost(9.99, 10.0), 1);
  EXPECT_EQ(ClearanceCost(10.0, 10.0), 0);
  EXPECT_EQ(ClearanceCost(50.0, 10.0), 0);
}

TEST(ApplyClearanceCost, RefusesABadClearance) {
  Grid grid = Grid::Create(4, 4).value();
  EXPECT_EQ(ApplyClearanceCost(0.0, false, &grid).code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(ApplyClearanceCost(-1.0, false, &grid).code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(ApplyClearanceCost(std::nan(""), false, &grid).code(),
            absl::StatusCode::kInvalidArgument);
}

// Every cell of 300 random maps: blocked and unknown-as-blocked cells keep
// their cost, traversable ones get max(own, ramp(brute-force distance)).
TEST(ApplyClearanceCost, MatchesBruteForceOnRandomMaps) {
  std::mt19937 rng(17);
  std::uniform_int_distribution<int> size(1, 24);
  std::uniform_real_distribution<double> clearance(0.3, 9.0);
  for (int trial = 0; trial < 300; ++trial) {
    const Grid grid = RandomGrid(rng, size(rng), size(rng), trial % 3 == 0 ? 0.02 : 0.2);
    const double m = clearance(rng);
    const bool unknown_is_free = trial % 2 == 1;
    Grid shaped = grid;
    ASSERT_TRUE(ApplyClearanceCost(m, unknown_is_free, &shaped).ok());
    for (int32_t y = 0; y < grid.height(); ++y) {
      for (int32_t x = 0; x < grid.width(); ++x) {
        const Cell c{x, y};
        const uint8_t own = grid.cost(c);
        if (!Traversable(own, unknown_is_free)) {
          ASSERT_EQ(shaped.cost(c), own) << "trial " << trial;
          continue;
        }
        const double d = BruteClearance(grid, c, unknown_is_free);
        const uint8_t base = own == kUnknownCost ? 0 : own;
        const uint8_t ramp = d < m ? static_cast<uint8_t>(std::clamp(
                                         std::ceil(252.0 * (m - d) / m), 1.0, 252.0))
                                   : 0;
        const uint8_t want = ramp > base ? ramp : own;
        ASSERT_EQ(shaped.cost(c), want)
            << "trial " << trial << " cell (" << x << "," << y << ") d " << d
            << " m " << m;
      }
    }
  }
}

// Grid paths (single moves) and paths with long segments: the smallest
// clearance of the cells passed, by brute force on every cell the quarter
// cell samples land in.
TEST(PathClearance, MatchesBruteForceOnRandomPaths) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 400; ++trial) {
    const Grid grid = RandomGrid(rng, 30, 20, 0.08);
    std::uniform_int_distribution<int> px(0, 29), py(0, 19), step(-1, 1);
    std::vector<Cell> path{{px(rng), py(rng)}};
    const bool long_segments = trial % 2 == 1;
    for (int i = 0; i < 40; ++i) {
      Cell next = long_segments ? Cell{px(rng), py(rng)}
                                : Cell{std::clamp(path.back().x + step(rng), 0, 29),
                                       std::clamp(path.back().y + step(rng), 0, 19)};
      path.push_back(next);
    }
    double want = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < path.size(); ++i) {
      want = std::min(want, BruteClearance(grid, path[i], false));
      if (i == 0) continue;
      const double dx = path[i].x - path[i - 1].x;
      const double dy = path[i].y - path[i - 1].y;
      const int n = static_cast<int>(std::ceil(4 * std::max(std::abs(dx), std::abs(dy))));
      for (int k = 1; k < n; ++k) {
        const double t = static_cast<double>(k) / n;
        const Cell at{static_cast<int32_t>(std::lround(path[i - 1].x + t * dx)),
                      static_cast<int32_t>(std::lround(path[i - 1].y + t * dy))};
        want = std::min(want, BruteClearance(grid, at, false));
      }
    }
    EXPECT_DOUBLE_EQ(PathClearance(grid, path, false), want) << "trial " << trial;
  }
  EXPECT_EQ(PathClearance(Grid::Create(3, 3).value(), {}, false),
            std::numeric_limits<double>::infinity());
}

// The shape: inflation first, clearance measured from the inscribed cells.
TEST(ShapeGrid, MeasuresClearanceFromTheInflatedObstacles) {
  Grid grid = Grid::Create(21, 21).value();
  grid.set_cost(10, 10, kLethalCost);
  const Grid shaped = ShapeGrid(grid, GridShape::Of(2.0, 0.0, 0.0, 3.0, false)).value();
  EXPECT_EQ(shaped.cost(12, 10), kInscribedCost);
  // (13, 10) is 1 from the inscribed (12, 10): ramp ceil(252 * 2 / 3) = 168.
  EXPECT_EQ(shaped.cost(13, 10), 168);
  EXPECT_EQ(shaped.cost(15, 10), 0);
  EXPECT_FALSE(GridShape::Of(0.0, 0.0, 0.0, 0.0, true).shaped());
  EXPECT_EQ(GridShape::Of(1.0, 0.0, 0.0, 0.0, true), GridShape::Of(1.0, 0.0, 0.0, 0.0, false));
}

}  // namespace
}  // namespace pathd
