// The incremental engine's view of a grid (core/incremental/engine.h): the
// move rules it may be configured with and MoveModel, the cost table and move
// generator it searches over, built on the grid view's CostTable and MoveRule.
// Internal to core.
#ifndef PATHD_CORE_INCREMENTAL_MOVE_MODEL_H_
#define PATHD_CORE_INCREMENTAL_MOVE_MODEL_H_

#include <array>
#include <cstddef>
#include <cstdint>

#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/search/grid_view.h"

namespace pathd::internal {

// Move rules beyond CostParams. The defaults are DESIGN.md's cost model; only
// the test that replays the "D* Lite – Example" of Faigl's lecture "Path
// Planning" (B4M36UIR Lecture 03: diagonal 1.4, diagonals past obstacle
// corners allowed, h = 0) changes them.
struct MoveRules {
  double diagonal_length = kSqrt2;
  // Diagonal moves need only their two end cells traversable.
  bool corner_cutting = false;
  // Octile/Manhattan focusing heuristic; false means h = 0.
  bool heuristic = true;
};

// The cost model of one grid flattened into tables (from the grid view's
// CostTable): whether a cost value is traversable and what a straight or
// diagonal move into a cell of that value costs, with GridView's MoveRule
// unless corner cutting is configured. Move costs are looked up, never
// recomputed, so the same edge always yields bit-identical sums, which the
// exact rhs comparisons rely on.
class MoveModel {
 public:
  MoveModel(const Grid& grid, const CostParams& cost, const MoveRules& rules)
      : cells_(grid.cells().data()),
        width_(grid.width()),
        height_(grid.height()),
        eight_(cost.connectivity == Connectivity::kEight),
        corner_cutting_(rules.corner_cutting) {
    const CostTable table(cost);
    for (int c = 0; c < 256; ++c) {
      const auto v = static_cast<uint8_t>(c);
      passable_[c] = table.Passable(v);
      const double factor = table.Factor(v);
      step_[0][c] = factor;
      step_[1][c] = rules.diagonal_length * factor;
    }
  }

  int32_t width() const { return width_; }
  int32_t height() const { return height_; }
  bool eight() const { return eight_; }
  bool Passable(uint32_t i) const { return passable_[cells_[i]]; }
  // Cost of a straight (diagonal = false) or diagonal move into cell `into`.
  double MoveCost(uint32_t into, bool diagonal) const {
    return step_[diagonal][cells_[into]];
  }
  uint32_t Index(Cell c) const {
    return static_cast<uint32_t>(c.y) * static_cast<uint32_t>(width_) +
           static_cast<uint32_t>(c.x);
  }
  Cell CellOf(uint32_t i) const {
    return Cell{static_cast<int32_t>(i % static_cast<uint32_t>(width_)),
                static_cast<int32_t>(i / static_cast<uint32_t>(width_))};
  }

  // Calls visit(j, diagonal) for every legal move between cell i and a
  // neighbour j (legal moves are symmetric). None when i is not traversable.
  template <typename Visit>
  void ForEachMove(uint32_t i, Visit&& visit) const {
    if (!Passable(i)) return;
    const Cell c = CellOf(i);
    const auto w = static_cast<uint32_t>(width_);
    const bool right = c.x + 1 < width_, left = c.x > 0;
    const bool down = c.y + 1 < height_, up = c.y > 0;
    const bool open_r = right && Passable(i + 1);
    const bool open_l = left && Passable(i - 1);
    const bool open_d = down && Passable(i + w);
    const bool open_u = up && Passable(i - w);
    if (open_r) visit(i + 1, false);
    if (open_l) visit(i - 1, false);
    if (open_d) visit(i + w, false);
    if (open_u) visit(i - w, false);
    if (!eight_) return;
    const bool cut = corner_cutting_;
    if (right && down && (cut || MoveRule::DiagonalAllowed(open_r, open_d)) && Passable(i + w + 1)) {
      visit(i + w + 1, true);
    }
    if (right && up && (cut || MoveRule::DiagonalAllowed(open_r, open_u)) && Passable(i - w + 1)) {
      visit(i - w + 1, true);
    }
    if (left && down && (cut || MoveRule::DiagonalAllowed(open_l, open_d)) && Passable(i + w - 1)) {
      visit(i + w - 1, true);
    }
    if (left && up && (cut || MoveRule::DiagonalAllowed(open_l, open_u)) && Passable(i - w - 1)) {
      visit(i - w - 1, true);
    }
  }

  // Whether the move from cell (x, y) by (dx, dy) (one of kMoves) is legal.
  bool Legal(int32_t x, int32_t y, int32_t dx, int32_t dy) const {
    const int32_t nx = x + dx, ny = y + dy;
    if (nx < 0 || ny < 0 || nx >= width_ || ny >= height_) return false;
    if (!PassableXY(x, y) || !PassableXY(nx, ny)) return false;
    if (dx == 0 || dy == 0 || corner_cutting_) return true;
    return MoveRule::DiagonalAllowed(PassableXY(nx, y), PassableXY(x, ny));
  }

 private:
  bool PassableXY(int32_t x, int32_t y) const {
    return passable_[cells_[static_cast<size_t>(y) * static_cast<size_t>(width_) +
                            static_cast<size_t>(x)]];
  }

  const uint8_t* cells_;
  int32_t width_;
  int32_t height_;
  bool eight_;
  bool corner_cutting_;
  std::array<bool, 256> passable_{};
  std::array<std::array<double, 256>, 2> step_{};
};

}  // namespace pathd::internal

#endif  // PATHD_CORE_INCREMENTAL_MOVE_MODEL_H_
