// A region quadtree of a grid (lecture "Spatial Decomposition"; Samet, "The
// Quadtree and Related Hierarchical Data Structures", 1984): the grid,
// padded to a power-of-two square with blocked cells, split into aligned
// squares until each holds cells of one kind (one traversable cost byte, or
// blocked). The canonical tree (every square that can be a leaf is one) is
// unique, so a tree advanced around changed cells can be compared with a
// rebuilt one leaf for leaf. A derived value per map version
// (core/search/derived.h); the `quadtree` planner (quadtree_planner.cc)
// searches its leaf adjacency.
#ifndef PATHD_CORE_PLANNERS_HIERARCHICAL_QUADTREE_H_
#define PATHD_CORE_PLANNERS_HIERARCHICAL_QUADTREE_H_

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "absl/types/span.h"
#include "core/map/grid.h"
#include "core/search/derived.h"

namespace pathd {

// The map is cut into tiles of kTileSide² cells (one tile, the padded
// map, when it is smaller), each its own canonical quadtree held behind a
// shared pointer, so a new version copies one pointer per tile and only the
// tiles a change touches (leaves never span tiles, which costs little: a
// 64-cell square is already a long step for the search; 64 rather than
// 256 made a repair of 100 scattered cells 3-7x cheaper, as each copies
// 16x less, measured in docs/performance.md). Nodes are numbered densely
// across tiles (a tile's first id is the sum of the node slots before it;
// Advance shifts the ids of the tiles after a changed one instead of
// reading every tile). Immutable once built; thread-safe to share.
class Quadtree {
 public:
  // A leaf's value for blocked cells (and the padding outside the grid).
  static constexpr uint16_t kBlocked = 256;
  static constexpr int32_t kTileSide = 64;
  // Squares Advance rebuilds from the grid around a changed cell.
  static constexpr int32_t kBlock = 16;

  struct Node {
    // Index in its tile of the first of four children (x then y), or -1
    // for a leaf.
    int32_t first_child;
    int32_t x0;
    int32_t y0;
    int32_t size;
    // Leaves: the cost byte of every cell, or kBlocked.
    uint16_t value;
    bool leaf() const { return first_child < 0; }
    bool open() const { return value != kBlocked; }
  };

  // The tree of `grid` (unknown cells traversable when unknown_is_free);
  // null when `stop` fired first (asked between tiles).
  static std::shared_ptr<const Quadtree> Build(const Grid& grid, bool unknown_is_free,
                                               DerivedStop& stop);
  // The tree of `grid` from this one of an older version whose cells differ
  // from `grid` only in `changed`: in each tile holding a changed cell, the
  // leaves holding one are split down to the kBlock-sized squares around
  // it, those squares are rebuilt from the grid, and squares whose four
  // children became equal leaves merge again; other tiles are shared. Null
  // when the sizes differ.
  std::shared_ptr<const Quadtree> Advance(const Grid& grid,
                                          absl::Span<const Cell> changed) const;

  // The id of the leaf holding cell (x, y), which must be on the grid.
  int32_t Locate(int32_t x, int32_t y) const;
  const Node& node(int32_t id) const;
  // One more than the largest node id.
  size_t node_slots() const { return base_.back(); }
  size_t leaf_count() const { return leaves_; }
  int32_t width() const { return width_; }
  int32_t height() const { return height_; }
  // Memory this version holds, counting shared tiles in full.
  size_t MemoryBytes() const { return bytes_; }

  // Empty when both trees have the same leaves; else the first difference.
  static std::string FirstDifference(const Quadtree& a, const Quadtree& b);

 private:
  struct Tile {
    // nodes[0] is the tile's root; abandoned subtrees stay until they are
    // half the array.
    std::vector<Node> nodes;
    size_t leaves = 0;
    // Nodes reachable from the root.
    size_t live = 1;
  };

  Quadtree() = default;
  uint16_t Value(const Grid& grid, int32_t x, int32_t y) const;
  // Fills node `id` of `tile` (already allocated) for the square at (x0, y0).
  void Fill(const Grid& grid, Tile& tile, int32_t id, int32_t x0, int32_t y0,
            int32_t size) const;
  // Applies the changed cells of one tile to its copy.
  void AdvanceTile(const Grid& grid, Tile& tile, absl::Span<const Cell> changed) const;
  // base_, leaves_ and bytes_ from the tiles.
  void Summarise();

  int32_t width_ = 0;
  int32_t height_ = 0;
  int32_t tile_side_ = 1;
  int32_t tiles_x_ = 0;
  int32_t tiles_y_ = 0;
  bool unknown_is_free_ = false;
  std::vector<std::shared_ptr<const Tile>> tiles_;
  std::vector<uint32_t> base_{0};
  size_t leaves_ = 0;
  size_t bytes_ = 0;
};

}  // namespace pathd

#endif  // PATHD_CORE_PLANNERS_HIERARCHICAL_QUADTREE_H_
