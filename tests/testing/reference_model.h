// The cost model of DESIGN.md written out again, apart from core's GridView
// and CostTable, with a Dijkstra of its own: the independent yardstick of
// the planner tests (hierarchical, nature).
#ifndef PATHD_TESTS_TESTING_REFERENCE_MODEL_H_
#define PATHD_TESTS_TESTING_REFERENCE_MODEL_H_

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <functional>
#include <limits>
#include <queue>
#include <tuple>
#include <vector>

#include "core/map/cost_model.h"
#include "core/map/grid.h"

namespace pathd::testing {

// Free 0..252 (unknown 255 with unknown_is_free, at factor 1); a move pays
// its length times 1 + w * c / 252 of the cell it enters; a diagonal needs
// both side cells open.
struct Model {
  const Grid& grid;
  CostParams p;
  bool Open(int x, int y) const {
    if (x < 0 || y < 0 || x >= grid.width() || y >= grid.height()) return false;
    const uint8_t c = grid.cost(x, y);
    return c <= 252 || (p.unknown_is_free && c == 255);
  }
  double Factor(int x, int y) const {
    const uint8_t c = grid.cost(x, y);
    return c == 255 ? 1.0 : 1.0 + p.cost_weight * c / 252.0;
  }
  // Cost of the move a -> b, or -1 when it is not a legal move.
  double Step(Cell a, Cell b) const {
    const int dx = b.x - a.x, dy = b.y - a.y;
    if (std::abs(dx) > 1 || std::abs(dy) > 1 || (dx == 0 && dy == 0)) return -1;
    if (!Open(a.x, a.y) || !Open(b.x, b.y)) return -1;
    if (dx != 0 && dy != 0) {
      if (p.connectivity == Connectivity::kFour) return -1;
      if (!Open(a.x + dx, a.y) || !Open(a.x, a.y + dy)) return -1;  // corner cut
      return std::sqrt(2.0) * Factor(b.x, b.y);
    }
    return Factor(b.x, b.y);
  }
  double MaxFactor() const {
    double f = 1.0;
    for (int y = 0; y < grid.height(); ++y) {
      for (int x = 0; x < grid.width(); ++x) {
        if (Open(x, y)) f = std::max(f, Factor(x, y));
      }
    }
    return f;
  }
  // The path's cost, or -1 when it is not a legal move chain from s to g.
  double PathCost(const std::vector<Cell>& path, Cell s, Cell g) const {
    if (path.empty() || !(path.front() == s) || !(path.back() == g)) return -1;
    double cost = 0;
    for (size_t i = 1; i < path.size(); ++i) {
      const double step = Step(path[i - 1], path[i]);
      if (step < 0) return -1;
      cost += step;
    }
    return cost;
  }
};

// The cost from every cell to `to` (+inf where it cannot reach it), by
// Dijkstra over reversed moves with its own queue and move loop.
inline std::vector<double> CostTo(const Model& m, Cell to) {
  const int w = m.grid.width();
  std::vector<double> dist(m.grid.size(), std::numeric_limits<double>::infinity());
  using Item = std::tuple<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> open;
  dist[to.y * w + to.x] = 0;
  open.push({0.0, to.y * w + to.x});
  while (!open.empty()) {
    const auto [d, i] = open.top();
    open.pop();
    if (d > dist[i]) continue;
    const Cell b{i % w, i / w};
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const Cell a{b.x + dx, b.y + dy};
        const double step = m.Step(a, b);
        if (step < 0) continue;
        const int j = a.y * w + a.x;
        if (d + step < dist[j]) {
          dist[j] = d + step;
          open.push({dist[j], j});
        }
      }
    }
  }
  return dist;
}

}  // namespace pathd::testing

#endif  // PATHD_TESTS_TESTING_REFERENCE_MODEL_H_
