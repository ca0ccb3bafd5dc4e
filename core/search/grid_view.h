// Pieces every grid search loop shares: per-query lookup tables for the cost
// model, neighbour generation with the no-corner-cutting rule, and path
// reconstruction from the parent links in SearchScratch.
#ifndef PATHD_CORE_SEARCH_GRID_VIEW_H_
#define PATHD_CORE_SEARCH_GRID_VIEW_H_

#include <algorithm>
#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "core/search/path_measure.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/search/planner.h"
#include "core/search/search_scratch.h"

namespace pathd::internal {

// The cost model for one query, flattened into tables so the inner loop does
// two array reads per neighbour.
class GridView {
 public:
  GridView(const Grid& grid, const CostParams& params)
      : cells_(grid.cells().data()),
        width_(grid.width()),
        height_(grid.height()),
        moves_(MoveCount(params.connectivity)) {
    for (int c = 0; c < 256; ++c) {
      const auto v = static_cast<uint8_t>(c);
      passable_[c] = Traversable(v, params.unknown_is_free);
      factor_[c] = CellFactor(v, params.cost_weight);
    }
  }

  int32_t width() const { return width_; }
  int32_t height() const { return height_; }
  bool Passable(int32_t x, int32_t y) const {
    return x >= 0 && y >= 0 && x < width_ && y < height_ &&
           passable_[cells_[Index(x, y)]];
  }
  // Passable(x, y) for the cell at an index known to be on the grid.
  bool PassableAt(uint32_t index) const { return passable_[cells_[index]]; }
  uint32_t Index(int32_t x, int32_t y) const {
    return static_cast<uint32_t>(y) * static_cast<uint32_t>(width_) +
           static_cast<uint32_t>(x);
  }
  Cell CellOf(uint32_t index) const {
    return Cell{static_cast<int32_t>(index % static_cast<uint32_t>(width_)),
                static_cast<int32_t>(index / static_cast<uint32_t>(width_))};
  }
  double Factor(uint32_t index) const { return factor_[cells_[index]]; }

  // Calls visit(neighbour_index, nx, ny, move_length) for every legal move out of
  // (x, y): in bounds, passable, and for diagonals both side cells passable.
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
      if (!open[kSideX[d]] || !open[kSideY[d]]) continue;
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
  std::array<bool, 256> passable_{};
  std::array<double, 256> factor_{};
};

// Follows parent links from `goal` back to the root and returns root..goal.
// The walk is bounded by the number of cells, so corrupt links cannot hang it.
inline std::vector<Cell> TracePath(const GridView& view, const SearchScratch& scratch,
                                   uint32_t goal, size_t cells) {
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
    const bool diagonal = path[i].x != path[i - 1].x && path[i].y != path[i - 1].y;
    length += diagonal ? kSqrt2 : 1.0;
  }
  return length;
}

// Records the expansion of cell `index` when the request asks for expansions;
// a pointer test otherwise.
inline void RecordExpansion(const PlanRequest& request, const GridView& view,
                            uint32_t index) {
  if (request.expansion_recorder != nullptr) {
    request.expansion_recorder->Record(view.CellOf(index));
  }
}

// A listener that records nothing; search loops call it on every expansion and
// the calls compile away.
struct NullListener {
  void OnExpand(uint32_t /*index*/) {}
};

// A listener that records each expanded cell of a grid `width` cells wide.
struct RecordingListener {
  ExpansionRecorder& recorder;
  int32_t width;
  void OnExpand(uint32_t index) {
    const auto w = static_cast<uint32_t>(width);
    recorder.Record(
        Cell{static_cast<int32_t>(index % w), static_cast<int32_t>(index / w)});
  }
};

}  // namespace pathd::internal

#endif  // PATHD_CORE_SEARCH_GRID_VIEW_H_
