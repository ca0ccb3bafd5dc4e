// Pieces every grid search shares: the cost model's per-query lookup table,
// the one move rule (no corner cutting), neighbour generation with it, the
// expansion listeners, and path reconstruction from SearchScratch's parent
// links.
#ifndef PATHD_CORE_SEARCH_GRID_VIEW_H_
#define PATHD_CORE_SEARCH_GRID_VIEW_H_

#include <algorithm>
#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "absl/base/attributes.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/search/path_measure.h"
#include "core/search/planner.h"
#include "core/search/search_scratch.h"

namespace pathd::internal {

// The cost model of one query flattened into two 256-entry tables indexed by
// a cell's cost byte: traversable or not, and the factor a move into it pays.
// Every grid search (GridView, the raster distance transform, the incremental
// engine's MoveModel) reads the cost model through one of these.
class CostTable {
 public:
  explicit CostTable(const CostParams& params) {
    for (int c = 0; c < 256; ++c) {
      const auto v = static_cast<uint8_t>(c);
      passable_[c] = Traversable(v, params.unknown_is_free);
      factor_[c] = CellFactor(v, params.cost_weight);
    }
  }
  bool Passable(uint8_t cost) const { return passable_[cost]; }
  double Factor(uint8_t cost) const { return factor_[cost]; }

 private:
  std::array<bool, 256> passable_{};
  std::array<double, 256> factor_{};
};

// The move rule of DESIGN.md's cost model, stated once: a straight move
// needs its target open, a diagonal one (8-connected only) its target and
// both side cells open, so no move cuts an obstacle's corner (the Moving AI
// benchmark rule). GridView generates moves with it; CheckMove
// (path_measure.h) judges given moves with it.
struct MoveRule {
  // Whether a diagonal move whose side cells (the straight neighbours along
  // its x and its y) are open as given may be taken.
  static bool DiagonalAllowed(bool side_x_open, bool side_y_open) {
    return side_x_open && side_y_open;
  }
  // Judges the step a -> b, both cells already known to be traversable;
  // `open(x, y)` says whether a cell is on the grid and traversable.
  template <typename Open>
  static MoveFault Check(Cell a, Cell b, Connectivity connectivity,
                         Open&& open) {
    // int64: cells given by clients may be anywhere in int32.
    const int64_t dx = int64_t{b.x} - a.x;
    const int64_t dy = int64_t{b.y} - a.y;
    if (dx < -1 || dx > 1 || dy < -1 || dy > 1 || (dx == 0 && dy == 0)) {
      return MoveFault::kNotAdjacent;
    }
    if (dx == 0 || dy == 0) return MoveFault::kNone;
    if (connectivity != Connectivity::kEight) {
      return MoveFault::kDiagonalOnFourConnected;
    }
    return DiagonalAllowed(open(b.x, a.y), open(a.x, b.y))
               ? MoveFault::kNone
               : MoveFault::kCornerCut;
  }
};

// One query's view of a grid: the cost table and the moves MoveRule allows.
// Holds a pointer into the grid, which must outlive it.
class GridView {
 public:
  GridView(const Grid& grid, const CostParams& params)
      : cells_(grid.cells().data()),
        width_(grid.width()),
        height_(grid.height()),
        moves_(MoveCount(params.connectivity)),
        table_(params) {}

  int32_t width() const { return width_; }
  int32_t height() const { return height_; }
  bool Passable(int32_t x, int32_t y) const {
    return x >= 0 && y >= 0 && x < width_ && y < height_ &&
           table_.Passable(cells_[Index(x, y)]);
  }
  // Passable(x, y) for the cell at an index known to be on the grid.
  bool PassableAt(uint32_t index) const {
    return table_.Passable(cells_[index]);
  }
  uint32_t Index(int32_t x, int32_t y) const {
    return static_cast<uint32_t>(y) * static_cast<uint32_t>(width_) +
           static_cast<uint32_t>(x);
  }
  Cell CellOf(uint32_t index) const {
    return Cell{static_cast<int32_t>(index % static_cast<uint32_t>(width_)),
                static_cast<int32_t>(index / static_cast<uint32_t>(width_))};
  }
  double Factor(uint32_t index) const { return table_.Factor(cells_[index]); }
  const CostTable& table() const { return table_; }

  // Calls visit(neighbour_index, nx, ny, move_length) for every move out of
  // (x, y) that MoveRule allows, straight moves first (kMoves order).
  template <typename Visit>
  void ForEachNeighbor(int32_t x, int32_t y, Visit&& visit) const {
    // Straight moves first; remember which were open for the diagonal rule.
    bool open[4];
    for (int m = 0; m < 4; ++m) {
      const int32_t nx = x + kMoves[m].dx;
      const int32_t ny = y + kMoves[m].dy;
      open[m] = Passable(nx, ny);
      if (open[m]) visit(Index(nx, ny), nx, ny, 1.0);
    }
    if (moves_ == 4) return;
    // kMoves[4..7] = (+1,+1) (+1,-1) (-1,+1) (-1,-1); side cells are the
    // straight moves with the same dx (index 0 or 1) and dy (2 or 3).
    static constexpr int kSideX[4] = {0, 0, 1, 1};
    static constexpr int kSideY[4] = {2, 3, 2, 3};
    for (int d = 0; d < 4; ++d) {
      if (!MoveRule::DiagonalAllowed(open[kSideX[d]], open[kSideY[d]]))
        continue;
      const int32_t nx = x + kMoves[4 + d].dx;
      const int32_t ny = y + kMoves[4 + d].dy;
      if (Passable(nx, ny)) visit(Index(nx, ny), nx, ny, kSqrt2);
    }
  }

 private:
  const uint8_t* cells_;
  int32_t width_;
  int32_t height_;
  int moves_;
  CostTable table_;
};

// Follows parent links from `goal` back to the root and returns root..goal.
// The walk is bounded by the number of cells, so corrupt links cannot hang it.
inline std::vector<Cell> TracePath(const GridView& view,
                                   const SearchScratch& scratch, uint32_t goal,
                                   size_t cells) {
  std::vector<Cell> path;
  uint32_t at = goal;
  while (at != SearchScratch::kNoParent && path.size() <= cells) {
    path.push_back(view.CellOf(at));
    at = scratch.Raw(at).parent;
  }
  std::reverse(path.begin(), path.end());
  return path;
}

// Sets result->path and its cost and length measured under the cost model, for
// planners whose search does not track cost (BFS, wave-front, descents of a
// cost-to-go field). Precondition: `path` is a legal move chain.
inline void SetMeasuredPath(const Grid& grid, const CostParams& cost,
                            std::vector<Cell> path, PlanResult* result) {
  const PathMeasure measure = MeasurePath(grid, path, cost);
  result->path = std::move(path);
  result->cost = measure.cost;
  result->length = measure.length;
}

// Geometric length of a path of adjacent cells.
inline double PathLength(const std::vector<Cell>& path) {
  double length = 0.0;
  for (size_t i = 1; i < path.size(); ++i) {
    const bool diagonal =
        path[i].x != path[i - 1].x && path[i].y != path[i - 1].y;
    length += diagonal ? kSqrt2 : 1.0;
  }
  return length;
}

// Expansion listeners: every search calls listener.OnExpand(id) once per
// node it expands (takes off its open list or queue to close), with the id
// its expansion policy numbers nodes by. The listener is a template
// parameter, so NullListener's calls compile away; WithExpansionListener
// picks one per query.

// Records nothing.
struct NullListener {
  void OnExpand(uint32_t /*id*/) {}
};

// Records each expanded node's cell; `cell_of` maps a node id to its cell
// (GridView::CellOf, or a jump-point table's).
template <typename CellOf>
struct RecordingListener {
  ExpansionRecorder& recorder;
  const CellOf& cell_of;
  void OnExpand(uint32_t id) { recorder.Record(cell_of.CellOf(id)); }
};

// Calls body(listener) with a RecordingListener over `cell_of` when the
// query has a recorder, else with a NullListener: the pointer is tested once
// per query, and the search body is compiled once for each case. Always
// inlined, so the search loop stays in the caller's frame with the caller's
// GridView: the compiler then keeps the view's fields in registers across the
// loop's calls, as it cannot for an object whose address left the function.
template <typename CellOf, typename Body>
ABSL_ATTRIBUTE_ALWAYS_INLINE inline decltype(auto) WithExpansionListener(
    ExpansionRecorder* recorder, const CellOf& cell_of, Body&& body) {
  if (recorder == nullptr) return body(NullListener{});
  return body(RecordingListener<CellOf>{*recorder, cell_of});
}

}  // namespace pathd::internal

#endif  // PATHD_CORE_SEARCH_GRID_VIEW_H_
