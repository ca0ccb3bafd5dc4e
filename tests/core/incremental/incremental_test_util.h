// Helpers shared by the incremental search tests: a grid as shared_ptr, an
// independent reference Dijkstra for cost-to-go, a relative comparison, and
// random map cells.
#ifndef PATHD_TESTS_CORE_INCREMENTAL_INCREMENTAL_TEST_UTIL_H_
#define PATHD_TESTS_CORE_INCREMENTAL_INCREMENTAL_TEST_UTIL_H_

#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <queue>
#include <random>
#include <utility>
#include <vector>

#include "core/map/cost_model.h"
#include "core/map/grid.h"

namespace pathd::testing_incremental {

inline constexpr double kInf = std::numeric_limits<double>::infinity();

inline std::shared_ptr<const Grid> Share(Grid grid) {
  return std::make_shared<const Grid>(std::move(grid));
}

// Cost-to-go of every cell to `goal` (+infinity where unreachable) by a plain
// Dijkstra over the move table, backwards: a move v -> u costs its length
// times the factor of the entered cell u. Shares no code with the engine.
inline std::vector<double> ReferenceCostToGo(const Grid& grid, Cell goal, const CostParams& p) {
  std::vector<double> dist(grid.size(), kInf);
  auto ok = [&](int x, int y) {
    return grid.InBounds(x, y) && Traversable(grid.cost(x, y), p.unknown_is_free);
  };
  if (!ok(goal.x, goal.y)) return dist;
  using Item = std::pair<double, size_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> open;
  dist[grid.Index(goal)] = 0.0;
  open.push({0.0, grid.Index(goal)});
  while (!open.empty()) {
    const auto [d, i] = open.top();
    open.pop();
    if (d > dist[i]) continue;
    const Cell u = grid.CellAt(i);
    const double into_u_factor = CellFactor(grid.cost(u), p.cost_weight);
    for (int m = 0; m < MoveCount(p.connectivity); ++m) {
      const int vx = u.x + kMoves[m].dx, vy = u.y + kMoves[m].dy;
      if (!ok(vx, vy)) continue;
      if (kMoves[m].dx != 0 && kMoves[m].dy != 0 &&
          (!ok(u.x + kMoves[m].dx, u.y) || !ok(u.x, u.y + kMoves[m].dy))) {
        continue;
      }
      const double nd = d + kMoves[m].length * into_u_factor;
      const size_t j = grid.Index(vx, vy);
      if (nd < dist[j]) {
        dist[j] = nd;
        open.push({nd, j});
      }
    }
  }
  return dist;
}

inline bool Near(double a, double b, double rel) {
  if (std::isinf(a) || std::isinf(b)) return a == b;
  return std::abs(a - b) <= rel * (1.0 + std::abs(b));
}

struct World {
  Grid grid;
  CostParams cost;
};

inline uint8_t RandomCellValue(std::mt19937& rng, bool weighted) {
  const int roll = static_cast<int>(rng() % 100);
  if (roll < 22) return rng() % 4 == 0 ? kUnknownCost : kLethalCost;
  if (weighted && roll < 55) return static_cast<uint8_t>(rng() % 253);
  return kFreeCost;
}

inline Cell RandomCell(std::mt19937& rng, const Grid& grid) {
  return Cell{static_cast<int32_t>(rng() % grid.width()),
              static_cast<int32_t>(rng() % grid.height())};
}

}  // namespace pathd::testing_incremental

#endif  // PATHD_TESTS_CORE_INCREMENTAL_INCREMENTAL_TEST_UTIL_H_
