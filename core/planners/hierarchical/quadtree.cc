// The region quadtree of a grid, built per map version and advanced around
// changed cells.
#include "core/planners/hierarchical/quadtree.h"

#include <algorithm>
#include <utility>

#include "absl/container/flat_hash_set.h"
#include "absl/strings/str_format.h"
#include "core/map/cost_model.h"

namespace pathd {
namespace {

// Leaves of the subtree at `id`, and its node count (children included).
void CountSubtree(const std::vector<Quadtree::Node>& nodes, int32_t id, size_t& leaves,
                  size_t& slots) {
  const Quadtree::Node& n = nodes[id];
  if (n.leaf()) {
    ++leaves;
    return;
  }
  slots += 4;
  for (int32_t q = 0; q < 4; ++q) CountSubtree(nodes, n.first_child + q, leaves, slots);
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

void Quadtree::Fill(const Grid& grid, int32_t id, int32_t x0, int32_t y0, int32_t size) {
  if (size == 1 || x0 >= width_ || y0 >= height_) {
    // One cell, or a square wholly in the padding.
    nodes_[id] = Node{-1, x0, y0, size, Value(grid, x0, y0)};
    return;
  }
  const auto first = static_cast<int32_t>(nodes_.size());
  nodes_.resize(nodes_.size() + 4);
  const int32_t h = size / 2;
  for (int32_t q = 0; q < 4; ++q) {
    Fill(grid, first + q, x0 + (q & 1) * h, y0 + (q >> 1) * h, h);
  }
  // Four leaf children append nothing after their slots, so equal ones
  // fold back into this node and give their slots back.
  bool same = nodes_.size() == static_cast<size_t>(first) + 4;
  for (int32_t q = 0; same && q < 4; ++q) {
    same = nodes_[first + q].leaf() && nodes_[first + q].value == nodes_[first].value;
  }
  if (same) {
    const uint16_t value = nodes_[first].value;
    nodes_.resize(first);
    nodes_[id] = Node{-1, x0, y0, size, value};
  } else {
    nodes_[id] = Node{first, x0, y0, size, 0};
  }
}

void Quadtree::CountLeaves() {
  size_t slots = 1;
  leaves_ = 0;
  CountSubtree(nodes_, 0, leaves_, slots);
}

std::shared_ptr<const Quadtree> Quadtree::Build(const Grid& grid, bool unknown_is_free,
                                                DerivedStop& stop) {
  std::shared_ptr<Quadtree> tree(new Quadtree());
  tree->width_ = grid.width();
  tree->height_ = grid.height();
  tree->unknown_is_free_ = unknown_is_free;
  while (tree->side_ < std::max(grid.width(), grid.height())) tree->side_ *= 2;
  tree->nodes_.resize(1);
  // Built a band of kBlock rows' squares at a time would need another
  // order; a whole-map build reads every cell once (about 15 ns a cell),
  // so the stop condition is asked before it, and a 16384² map's build
  // (4 s) is the longest it goes unasked.
  if (stop.Stopped()) {
    stop.Note("building the quadtree of this map version");
    return nullptr;
  }
  tree->Fill(grid, 0, 0, 0, tree->side_);
  tree->CountLeaves();
  return tree;
}

std::shared_ptr<const Quadtree> Quadtree::Advance(const Grid& grid,
                                                  absl::Span<const Cell> changed) const {
  if (grid.width() != width_ || grid.height() != height_) return nullptr;
  std::shared_ptr<Quadtree> next(new Quadtree(*this));
  std::vector<Node>& nodes = next->nodes_;
  const int32_t block = std::min(kBlock, side_);
  absl::flat_hash_set<int32_t> rebuilt;
  // Internal nodes above a rebuilt square: they may merge afterwards.
  std::vector<std::pair<int32_t, int32_t>> above;  // (size, id)
  for (const Cell& cell : changed) {
    if (!grid.InBounds(cell)) continue;
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
        next->leaves_ += 3;
      }
      above.emplace_back(nodes[id].size, id);
      const Node& n = nodes[id];
      const int32_t h = n.size / 2;
      id = n.first_child + (cell.x >= n.x0 + h ? 1 : 0) + (cell.y >= n.y0 + h ? 2 : 0);
    }
    if (!rebuilt.insert(id).second) continue;
    size_t old_leaves = 0, old_slots = 0;
    CountSubtree(nodes, id, old_leaves, old_slots);
    const Node square = nodes[id];
    next->Fill(grid, id, square.x0, square.y0, square.size);
    size_t new_leaves = 0, new_slots = 0;
    CountSubtree(nodes, id, new_leaves, new_slots);
    next->leaves_ += new_leaves;
    next->leaves_ -= old_leaves;
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
    next->leaves_ -= 3;
  }
  // Abandoned subtrees stay in the array until they are half of it; then
  // the live nodes are copied out in depth-first order.
  size_t live_leaves = 0, live_slots = 1;
  CountSubtree(nodes, 0, live_leaves, live_slots);
  if (2 * live_slots < nodes.size()) {
    std::vector<Node> compact;
    compact.reserve(live_slots);
    compact.push_back(nodes[0]);
    // Breadth-first: each internal node's children get four fresh slots.
    for (size_t i = 0; i < compact.size(); ++i) {
      if (compact[i].leaf()) continue;
      const int32_t from = compact[i].first_child;
      compact[i].first_child = static_cast<int32_t>(compact.size());
      for (int32_t q = 0; q < 4; ++q) compact.push_back(nodes[from + q]);
    }
    nodes = std::move(compact);
  }
  return next;
}

int32_t Quadtree::Locate(int32_t x, int32_t y) const {
  int32_t id = 0;
  while (!nodes_[id].leaf()) {
    const Node& n = nodes_[id];
    const int32_t h = n.size / 2;
    id = n.first_child + (x >= n.x0 + h ? 1 : 0) + (y >= n.y0 + h ? 2 : 0);
  }
  return id;
}

std::string Quadtree::FirstDifference(const Quadtree& a, const Quadtree& b) {
  if (a.width_ != b.width_ || a.height_ != b.height_) return "different grid sizes";
  std::vector<Node> la, lb;
  Leaves(a.nodes_, 0, la);
  Leaves(b.nodes_, 0, lb);
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
