// The region quadtree of a grid, tile by tile, built per map version and
// advanced around changed cells.
#include "core/planners/hierarchical/quadtree.h"

#include <algorithm>
#include <utility>

#include "absl/container/flat_hash_set.h"
#include "absl/strings/str_format.h"
#include "core/map/cost_model.h"

namespace pathd {
namespace {

// Leaves of the subtree at `id`, and its nodes.
void CountSubtree(const std::vector<Quadtree::Node>& nodes, int32_t id, size_t& leaves,
                  size_t& count) {
  ++count;
  const Quadtree::Node& n = nodes[id];
  if (n.leaf()) {
    ++leaves;
    return;
  }
  for (int32_t q = 0; q < 4; ++q) CountSubtree(nodes, n.first_child + q, leaves, count);
}

void Leaves(const std::vector<Quadtree::Node>& nodes, int32_t id,
            std::vector<Quadtree::Node>& out) {
  const Quadtree::Node& n = nodes[id];
  if (n.leaf()) {
    out.push_back(n);
    return;
  }
  for (int32_t q = 0; q < 4; ++q) Leaves(nodes, n.first_child + q, out);
}

}  // namespace

uint16_t Quadtree::Value(const Grid& grid, int32_t x, int32_t y) const {
  if (x >= width_ || y >= height_) return kBlocked;
  const uint8_t c = grid.cost(x, y);
  return Traversable(c, unknown_is_free_) ? c : kBlocked;
}

void Quadtree::Fill(const Grid& grid, Tile& tile, int32_t id, int32_t x0, int32_t y0,
                    int32_t size) const {
  std::vector<Node>& nodes = tile.nodes;
  if (size == 1 || x0 >= width_ || y0 >= height_) {
    // One cell, or a square wholly in the padding.
    nodes[id] = Node{-1, x0, y0, size, Value(grid, x0, y0)};
    return;
  }
  const auto first = static_cast<int32_t>(nodes.size());
  nodes.resize(nodes.size() + 4);
  const int32_t h = size / 2;
  for (int32_t q = 0; q < 4; ++q) {
    Fill(grid, tile, first + q, x0 + (q & 1) * h, y0 + (q >> 1) * h, h);
  }
  // Four leaf children append nothing after their slots, so equal ones
  // fold back into this node and give their slots back.
  bool same = nodes.size() == static_cast<size_t>(first) + 4;
  for (int32_t q = 0; same && q < 4; ++q) {
    same = nodes[first + q].leaf() && nodes[first + q].value == nodes[first].value;
  }
  if (same) {
    const uint16_t value = nodes[first].value;
    nodes.resize(first);
    nodes[id] = Node{-1, x0, y0, size, value};
  } else {
    nodes[id] = Node{first, x0, y0, size, 0};
  }
}

void Quadtree::Summarise() {
  base_.assign(1, 0);
  leaves_ = 0;
  bytes_ = sizeof(Quadtree) + tiles_.capacity() * sizeof(std::shared_ptr<const Tile>) +
           base_.capacity() * sizeof(uint32_t);
  for (const auto& tile : tiles_) {
    base_.push_back(base_.back() + static_cast<uint32_t>(tile->nodes.size()));
    leaves_ += tile->leaves;
    bytes_ += sizeof(Tile) + 16 + tile->nodes.capacity() * sizeof(Node);
  }
}

std::shared_ptr<const Quadtree> Quadtree::Build(const Grid& grid, bool unknown_is_free,
                                                DerivedStop& stop) {
  std::shared_ptr<Quadtree> tree(new Quadtree());
  tree->width_ = grid.width();
  tree->height_ = grid.height();
  tree->unknown_is_free_ = unknown_is_free;
  while (tree->tile_side_ < std::max(grid.width(), grid.height()) &&
         tree->tile_side_ < kTileSide) {
    tree->tile_side_ *= 2;
  }
  const int32_t t = tree->tile_side_;
  tree->tiles_x_ = (grid.width() + t - 1) / t;
  tree->tiles_y_ = (grid.height() + t - 1) / t;
  for (int32_t ty = 0; ty < tree->tiles_y_; ++ty) {
    for (int32_t tx = 0; tx < tree->tiles_x_; ++tx) {
      if (stop.Stopped()) {
        stop.Note(absl::StrFormat("building the quadtree of this map version (%d of %d tiles)",
                                  tree->tiles_.size(), tree->tiles_x_ * tree->tiles_y_));
        return nullptr;
      }
      auto tile = std::make_shared<Tile>();
      tile->nodes.resize(1);
      tree->Fill(grid, *tile, 0, tx * t, ty * t, t);
      tile->leaves = 0;
      tile->live = 0;
      CountSubtree(tile->nodes, 0, tile->leaves, tile->live);
      tree->tiles_.push_back(std::move(tile));
    }
  }
  tree->Summarise();
  return tree;
}

void Quadtree::AdvanceTile(const Grid& grid, Tile& tile,
                           absl::Span<const Cell> changed) const {
  std::vector<Node>& nodes = tile.nodes;
  const int32_t block = std::min(kBlock, tile_side_);
  absl::flat_hash_set<int32_t> rebuilt;
  // Internal nodes above a rebuilt square: they may merge afterwards.
  std::vector<std::pair<int32_t, int32_t>> above;  // (size, id)
  for (const Cell& cell : changed) {
    int32_t id = 0;
    while (nodes[id].size > block) {
      if (nodes[id].leaf()) {
        // Split a uniform leaf: four leaves of its value.
        const auto first = static_cast<int32_t>(nodes.size());
        const Node n = nodes[id];
        const int32_t h = n.size / 2;
        for (int32_t q = 0; q < 4; ++q) {
          nodes.push_back(Node{-1, n.x0 + (q & 1) * h, n.y0 + (q >> 1) * h, h, n.value});
        }
        nodes[id].first_child = first;
        nodes[id].value = 0;
        tile.leaves += 3;
        tile.live += 4;
      }
      above.emplace_back(nodes[id].size, id);
      const Node& n = nodes[id];
      const int32_t h = n.size / 2;
      id = n.first_child + (cell.x >= n.x0 + h ? 1 : 0) + (cell.y >= n.y0 + h ? 2 : 0);
    }
    if (!rebuilt.insert(id).second) continue;
    size_t old_leaves = 0, old_count = 0;
    CountSubtree(nodes, id, old_leaves, old_count);
    const Node square = nodes[id];
    Fill(grid, tile, id, square.x0, square.y0, square.size);
    size_t new_leaves = 0, new_count = 0;
    CountSubtree(nodes, id, new_leaves, new_count);
    tile.leaves = tile.leaves + new_leaves - old_leaves;
    tile.live = tile.live + new_count - old_count;
  }
  // Deepest first, so a merge below is seen by the check above it.
  std::sort(above.begin(), above.end());
  above.erase(std::unique(above.begin(), above.end()), above.end());
  for (const auto& [size, id] : above) {
    const Node n = nodes[id];
    if (n.leaf()) continue;
    bool same = true;
    for (int32_t q = 0; same && q < 4; ++q) {
      same = nodes[n.first_child + q].leaf() &&
             nodes[n.first_child + q].value == nodes[n.first_child].value;
    }
    if (!same) continue;
    nodes[id].value = nodes[n.first_child].value;
    nodes[id].first_child = -1;
    tile.leaves -= 3;
    tile.live -= 4;
  }
  // Abandoned subtrees stay until they are half the array; then the live
  // nodes are copied out breadth-first.
  if (2 * tile.live < nodes.size()) {
    std::vector<Node> compact;
    compact.reserve(tile.live);
    compact.push_back(nodes[0]);
    for (size_t i = 0; i < compact.size(); ++i) {
      if (compact[i].leaf()) continue;
      const int32_t from = compact[i].first_child;
      compact[i].first_child = static_cast<int32_t>(compact.size());
      for (int32_t q = 0; q < 4; ++q) compact.push_back(nodes[from + q]);
    }
    nodes = std::move(compact);
  }
}

std::shared_ptr<const Quadtree> Quadtree::Advance(const Grid& grid,
                                                  absl::Span<const Cell> changed) const {
  if (grid.width() != width_ || grid.height() != height_) return nullptr;
  // Changed cells by tile.
  std::vector<std::pair<int32_t, Cell>> by_tile;
  by_tile.reserve(changed.size());
  for (const Cell& cell : changed) {
    if (!grid.InBounds(cell)) continue;
    by_tile.emplace_back((cell.y / tile_side_) * tiles_x_ + cell.x / tile_side_, cell);
  }
  std::sort(by_tile.begin(), by_tile.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first < b.first
                              : std::pair(a.second.y, a.second.x) < std::pair(b.second.y, b.second.x);
  });
  std::shared_ptr<Quadtree> next(new Quadtree(*this));
  std::vector<Cell> cells;
  // Summarise() without reading every tile: the node count of tile t moves
  // base_[t + 1 ..] by its change, accumulated over the changed tiles in
  // order; leaves_ and bytes_ move by each tile's change.
  int64_t shift = 0;
  size_t shifted = 0;  // base_[0 .. shifted] are final
  for (size_t i = 0; i < by_tile.size();) {
    const int32_t t = by_tile[i].first;
    cells.clear();
    for (; i < by_tile.size() && by_tile[i].first == t; ++i) cells.push_back(by_tile[i].second);
    const Tile& old_tile = *tiles_[t];
    auto tile = std::make_shared<Tile>(old_tile);
    AdvanceTile(grid, *tile, cells);
    for (; shifted < static_cast<size_t>(t); ++shifted) {
      next->base_[shifted + 1] = static_cast<uint32_t>(next->base_[shifted + 1] + shift);
    }
    shift += static_cast<int64_t>(tile->nodes.size()) - static_cast<int64_t>(old_tile.nodes.size());
    next->leaves_ = next->leaves_ + tile->leaves - old_tile.leaves;
    next->bytes_ = next->bytes_ + tile->nodes.capacity() * sizeof(Node) -
                   old_tile.nodes.capacity() * sizeof(Node);
    next->tiles_[t] = std::move(tile);
  }
  for (; shifted + 1 < next->base_.size(); ++shifted) {
    next->base_[shifted + 1] = static_cast<uint32_t>(next->base_[shifted + 1] + shift);
  }
  return next;
}

int32_t Quadtree::Locate(int32_t x, int32_t y) const {
  const int32_t t = (y / tile_side_) * tiles_x_ + x / tile_side_;
  const std::vector<Node>& nodes = tiles_[t]->nodes;
  int32_t id = 0;
  while (!nodes[id].leaf()) {
    const Node& n = nodes[id];
    const int32_t h = n.size / 2;
    id = n.first_child + (x >= n.x0 + h ? 1 : 0) + (y >= n.y0 + h ? 2 : 0);
  }
  return static_cast<int32_t>(base_[t]) + id;
}

const Quadtree::Node& Quadtree::node(int32_t id) const {
  const auto t = static_cast<size_t>(
      std::upper_bound(base_.begin(), base_.end(), static_cast<uint32_t>(id)) - base_.begin() -
      1);
  return tiles_[t]->nodes[static_cast<size_t>(id) - base_[t]];
}

std::string Quadtree::FirstDifference(const Quadtree& a, const Quadtree& b) {
  if (a.width_ != b.width_ || a.height_ != b.height_) return "different grid sizes";
  // Each tree's node numbering (kept incrementally by Advance) must be the
  // prefix sums of its tiles' node counts.
  for (const Quadtree* tree : {&a, &b}) {
    if (tree->base_.size() != tree->tiles_.size() + 1) return "node bases of another tile count";
    for (size_t t = 0; t < tree->tiles_.size(); ++t) {
      if (tree->base_[t + 1] != tree->base_[t] + tree->tiles_[t]->nodes.size()) {
        return absl::StrFormat("%s tree: node base of tile %d is %d, its tiles sum to %d",
                               tree == &a ? "first" : "second", t + 1, tree->base_[t + 1],
                               tree->base_[t] + tree->tiles_[t]->nodes.size());
      }
    }
  }
  std::vector<Node> la, lb;
  for (const auto& tile : a.tiles_) Leaves(tile->nodes, 0, la);
  for (const auto& tile : b.tiles_) Leaves(tile->nodes, 0, lb);
  if (a.leaves_ != la.size() || b.leaves_ != lb.size()) {
    return absl::StrFormat("leaf counts %d / %d, counted %d / %d", a.leaves_, b.leaves_,
                           la.size(), lb.size());
  }
  for (size_t i = 0; i < std::min(la.size(), lb.size()); ++i) {
    const Node& x = la[i];
    const Node& y = lb[i];
    if (x.x0 != y.x0 || x.y0 != y.y0 || x.size != y.size || x.value != y.value) {
      return absl::StrFormat("leaf %d: (%d, %d) size %d value %d vs (%d, %d) size %d value %d",
                             i, x.x0, x.y0, x.size, x.value, y.x0, y.y0, y.size, y.value);
    }
  }
  if (la.size() != lb.size()) return absl::StrFormat("%d vs %d leaves", la.size(), lb.size());
  return "";
}

}  // namespace pathd
