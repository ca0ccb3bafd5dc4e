// Small grids written as text, and a reference search, for the core tests.
#ifndef PATHD_TESTS_CORE_TEST_GRIDS_H_
#define PATHD_TESTS_CORE_TEST_GRIDS_H_

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "core/map/cost_model.h"
#include "core/map/grid.h"

namespace pathd {

// One string per row, row 0 first: '.' free, '#' lethal, '?' unknown, digit
// d (1-9) cost 28 * d (weighted); anything else is free.
inline Grid MakeGrid(const std::vector<std::string>& rows) {
  const auto h = static_cast<int32_t>(rows.size());
  const auto w = static_cast<int32_t>(rows[0].size());
  Grid grid = Grid::Create(w, h).value();
  for (int32_t y = 0; y < h; ++y) {
    for (int32_t x = 0; x < w; ++x) {
      const char c = rows[y][x];
      uint8_t v = kFreeCost;
      if (c == '#') v = kLethalCost;
      if (c == '?') v = kUnknownCost;
      if (c >= '1' && c <= '9') v = static_cast<uint8_t>((c - '0') * 28);
      grid.set_cost(x, y, v);
    }
  }
  return grid;
}

// Fewest legal moves from `start` to every cell (-1 where unreachable), by a
// plain breadth-first search over the cost model's move table that shares no
// code with the planners.
inline std::vector<int> MoveCounts(const Grid& grid, Cell start, const CostParams& p) {
  std::vector<int> moves(grid.size(), -1);
  std::vector<Cell> frontier{start};
  moves[grid.Index(start)] = 0;
  auto ok = [&](int x, int y) {
    return grid.InBounds(x, y) && Traversable(grid.cost(x, y), p.unknown_is_free);
  };
  for (int depth = 1; !frontier.empty(); ++depth) {
    std::vector<Cell> next;
    for (Cell c : frontier) {
      for (int m = 0; m < MoveCount(p.connectivity); ++m) {
        const int nx = c.x + kMoves[m].dx, ny = c.y + kMoves[m].dy;
        if (!ok(nx, ny) || moves[grid.Index(nx, ny)] >= 0) continue;
        if (kMoves[m].dx != 0 && kMoves[m].dy != 0 &&
            (!ok(c.x + kMoves[m].dx, c.y) || !ok(c.x, c.y + kMoves[m].dy))) {
          continue;
        }
        moves[grid.Index(nx, ny)] = depth;
        next.push_back({nx, ny});
      }
    }
    frontier = std::move(next);
  }
  return moves;
}

}  // namespace pathd

#endif  // PATHD_TESTS_CORE_TEST_GRIDS_H_
