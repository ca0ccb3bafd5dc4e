// Small grids written as text for the core tests.
#ifndef PATHD_TESTS_CORE_TEST_GRIDS_H_
#define PATHD_TESTS_CORE_TEST_GRIDS_H_

#include <cstdint>
#include <string>
#include <vector>

#include "core/grid.h"

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

}  // namespace pathd

#endif  // PATHD_TESTS_CORE_TEST_GRIDS_H_
