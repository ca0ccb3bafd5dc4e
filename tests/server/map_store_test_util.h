// Grid helpers shared by map_store_test's files (map_store_test.cc and
// map_store_concurrency_test.cc).
#ifndef PATHD_TESTS_SERVER_MAP_STORE_TEST_UTIL_H_
#define PATHD_TESTS_SERVER_MAP_STORE_TEST_UTIL_H_

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/map/grid.h"

namespace pathd::server::map_store_test {

inline Grid FreeGrid(int32_t w, int32_t h) { return *Grid::Create(w, h, kFreeCost); }

// The cells whose cost differs between two grids of one size, row-major.
inline std::vector<Cell> Differences(const Grid& a, const Grid& b) {
  std::vector<Cell> out;
  for (size_t i = 0; i < a.size(); ++i) {
    if (a.cells()[i] != b.cells()[i]) out.push_back(a.CellAt(i));
  }
  return out;
}

}  // namespace pathd::server::map_store_test

#endif  // PATHD_TESTS_SERVER_MAP_STORE_TEST_UTIL_H_
