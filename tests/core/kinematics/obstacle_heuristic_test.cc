// The obstacle heuristic (core/kinematics/obstacle_heuristic.h) against a
// Bellman-Ford relaxation written here, on random weighted maps.
#include "core/kinematics/obstacle_heuristic.h"

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "core/kinematics/footprint.h"
#include "core/map/cost_model.h"
#include "gtest/gtest.h"

namespace pathd {
namespace {

// Every cell's cost to the goal by relaxing every move until nothing
// changes: a move into cell u costs its length x (1 + penalty c(u) / 252); a
// diagonal needs one of its side cells open.
std::vector<double> Relaxed(const Grid& grid, const ObstacleHeuristicParams& p,
                            const std::vector<float>& distance) {
  const double inf = std::numeric_limits<double>::infinity();
  const auto open = [&](int x, int y) {
    return grid.InBounds(x, y) && Traversable(grid.cost(x, y), p.unknown_is_free) &&
           distance[grid.Index(x, y)] >= p.blocked_within;
  };
  std::vector<double> d(grid.size(), inf);
  d[grid.Index(p.goal)] = 0.0;
  for (bool changed = true; changed;) {
    changed = false;
    for (int y = 0; y < grid.height(); ++y) {
      for (int x = 0; x < grid.width(); ++x) {
        if (!open(x, y) && !(Cell{x, y} == p.goal)) continue;
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            if ((dx == 0 && dy == 0) || !grid.InBounds(x + dx, y + dy)) continue;
            // From (x, y) into u = (x + dx, y + dy), whose cost is known.
            const double du = d[grid.Index(x + dx, y + dy)];
            if (du == inf) continue;
            if (dx != 0 && dy != 0 && !open(x + dx, y) && !open(x, y + dy)) continue;
            const double step = (dx != 0 && dy != 0 ? std::sqrt(2.0) : 1.0) *
                                CellFactor(grid.cost(x + dx, y + dy), p.cost_penalty);
            if (du + step < d[grid.Index(x, y)] - 1e-9) {
              d[grid.Index(x, y)] = du + step;
              changed = true;
            }
          }
        }
      }
    }
  }
  return d;
}

TEST(ObstacleHeuristic, MatchesABellmanFordRelaxation) {
  std::mt19937 rng(4);
  for (int trial = 0; trial < 60; ++trial) {
    const int w = 5 + static_cast<int>(rng() % 20), h = 5 + static_cast<int>(rng() % 20);
    Grid grid = Grid::Create(w, h).value();
    for (size_t i = 0; i < grid.size(); ++i) {
      const int roll = static_cast<int>(rng() % 10);
      grid.mutable_cells()[i] = roll < 2   ? kLethalCost
                                : roll < 3 ? kUnknownCost
                                : roll < 6 ? static_cast<uint8_t>(rng() % 253)
                                           : kFreeCost;
    }
    ObstacleHeuristicParams p;
    p.goal = Cell{static_cast<int32_t>(rng() % w), static_cast<int32_t>(rng() % h)};
    p.unknown_is_free = trial % 2 == 0;
    p.cost_penalty = (rng() % 5) * 1.5;
    p.blocked_within = trial % 3 == 0 ? 1.2 : 0.0;
    const std::vector<float> distance = ObstacleDistanceField(grid, p.unknown_is_free);
    DerivedStop never;
    const auto field = BuildObstacleHeuristic(grid, p, distance.data(), never);
    ASSERT_NE(field, nullptr);
    const std::vector<double> expected = Relaxed(grid, p, distance);
    for (size_t i = 0; i < grid.size(); ++i) {
      if (std::isinf(expected[i])) {
        EXPECT_TRUE(std::isinf(field->cost[i])) << "trial " << trial << " cell " << i;
      } else {
        EXPECT_NEAR(field->cost[i], expected[i], 1e-4 * (1 + expected[i]))
            << "trial " << trial << " cell " << i;
      }
    }
  }
}

}  // namespace
}  // namespace pathd
