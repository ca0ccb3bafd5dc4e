// The DESIGN.md cost model: which cells a robot centre may occupy, which moves
// are legal (no corner cutting) and what each move costs.
#ifndef PATHD_CORE_MAP_COST_MODEL_H_
#define PATHD_CORE_MAP_COST_MODEL_H_

#include <cmath>
#include <cstdint>

#include "core/map/grid.h"

namespace pathd {

inline constexpr double kSqrt2 = 1.4142135623730951;

enum class Connectivity : int { kFour = 4, kEight = 8 };

// Parameters of the cost model shared by every planner.
struct CostParams {
  Connectivity connectivity = Connectivity::kEight;
  // w in step = length * (1 + w * c / 252). 0 makes every traversable cell cost
  // the same.
  double cost_weight = 1.0;
  // Unknown cells (255) are traversable (as free) instead of blocked.
  bool unknown_is_free = false;
};

// True when the robot centre may be on a cell of this cost.
inline bool Traversable(uint8_t cost, bool unknown_is_free) {
  return cost <= kMaxTraversableCost || (unknown_is_free && cost == kUnknownCost);
}

// Multiplier (1 + w * c / 252) for entering a cell of cost c; unknown cells
// treated as free cost like free cells.
inline double CellFactor(uint8_t cost, double cost_weight) {
  if (cost > kMaxTraversableCost) return 1.0;
  return 1.0 + cost_weight * static_cast<double>(cost) /
                   static_cast<double>(kMaxTraversableCost);
}

// The eight moves, straight ones first. For 4-connectivity use the first four.
struct Move {
  int dx;
  int dy;
  double length;
};
inline constexpr Move kMoves[8] = {
    {1, 0, 1.0},     {-1, 0, 1.0},     {0, 1, 1.0},     {0, -1, 1.0},
    {1, 1, kSqrt2},  {1, -1, kSqrt2},  {-1, 1, kSqrt2}, {-1, -1, kSqrt2},
};
inline int MoveCount(Connectivity c) { return c == Connectivity::kFour ? 4 : 8; }

// Admissible, consistent heuristic for the given connectivity with unit cell
// factor: octile for 8, Manhattan for 4 (every cell factor is >= 1).
inline double OctileDistance(Cell a, Cell b) {
  const double dx = std::abs(a.x - b.x);
  const double dy = std::abs(a.y - b.y);
  return dx > dy ? dx + (kSqrt2 - 1.0) * dy : dy + (kSqrt2 - 1.0) * dx;
}
inline double ManhattanDistance(Cell a, Cell b) {
  return std::abs(a.x - b.x) + std::abs(a.y - b.y);
}
inline double GridDistance(Cell a, Cell b, Connectivity c) {
  return c == Connectivity::kFour ? ManhattanDistance(a, b) : OctileDistance(a, b);
}

// Cost and geometric length of a cell path under the cost model, and whether
// every step is a legal move. Used by tests and by the server to check paths.
struct PathMeasure {
  bool valid = false;
  double cost = 0.0;
  double length = 0.0;
  // Index of the first illegal cell when !valid.
  size_t first_invalid = 0;
};

}  // namespace pathd

#endif  // PATHD_CORE_MAP_COST_MODEL_H_
