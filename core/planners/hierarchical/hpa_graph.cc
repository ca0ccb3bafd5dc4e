// HPA*'s abstract graph: clusters, entrances, transitions and intra-cluster
// costs (Botea, Müller & Schaeffer 2004), built per map version and advanced
// cluster by cluster.
#include "core/planners/hierarchical/hpa_graph.h"

#include <algorithm>
#include <cstdlib>
#include <limits>
#include <utility>

#include "absl/strings/str_format.h"

namespace pathd {
namespace {

using internal::GridView;
using internal::LocalSearch;

// A transition: a cell of this cluster and its straight neighbour across a
// border, both traversable.
struct Transition {
  uint32_t inside;
  uint32_t outside;
};

// Appends the transitions of one border: positions 0..length-1 along it,
// cell(p) the cell inside the cluster, across(p) its neighbour outside.
// An entrance is a maximal run of positions where both are traversable;
// one shorter than kHpaLongEntrance gets a transition in its middle, a
// longer one one at each end (Botea et al., section 3.1). The two clusters
// of a border walk it in the same order, so they place the same ones.
template <typename CellAt, typename Across>
void BorderTransitions(const GridView& view, int32_t length, CellAt cell, Across across,
                       std::vector<Transition>& out) {
  auto open = [&](int32_t p) {
    const Cell a = cell(p);
    const Cell b = across(p);
    return view.Passable(a.x, a.y) && view.Passable(b.x, b.y);
  };
  auto add = [&](int32_t p) {
    const Cell a = cell(p);
    const Cell b = across(p);
    out.push_back({view.Index(a.x, a.y), view.Index(b.x, b.y)});
  };
  int32_t p = 0;
  while (p < length) {
    if (!open(p)) {
      ++p;
      continue;
    }
    const int32_t begin = p;
    while (p < length && open(p)) ++p;
    const int32_t run = p - begin;
    if (run >= kHpaLongEntrance) {
      add(begin);
      add(p - 1);
    } else {
      add(begin + (run - 1) / 2);
    }
  }
}

}  // namespace

std::string HpaKey(const HpaParams& params) {
  return absl::StrFormat("hpa_star cluster=%d connectivity=%d cost_weight=%.17g "
                         "unknown_is_free=%d",
                         params.cluster_size, static_cast<int>(params.cost.connectivity),
                         params.cost.cost_weight, params.cost.unknown_is_free ? 1 : 0);
}

int32_t HpaCluster::LocalIndex(uint32_t cell) const {
  const auto it = std::lower_bound(nodes.begin(), nodes.end(), cell);
  if (it == nodes.end() || *it != cell) return -1;
  return static_cast<int32_t>(it - nodes.begin());
}

size_t HpaCluster::MemoryBytes() const {
  return sizeof(HpaCluster) + nodes.capacity() * sizeof(uint32_t) +
         intra.capacity() * sizeof(float) + inter_begin.capacity() * sizeof(uint32_t) +
         inter.capacity() * sizeof(HpaEdge);
}

void HpaGraph::Bounds(int32_t id, int32_t& x0, int32_t& y0, int32_t& x1,
                      int32_t& y1) const {
  const int32_t c = params_.cluster_size;
  x0 = (id % clusters_x_) * c;
  y0 = (id / clusters_x_) * c;
  x1 = std::min(x0 + c, width_);
  y1 = std::min(y0 + c, height_);
}

// The intra-cluster costs of BuildCluster: nodes.size()^2 costs between the
// nodes (cells of the rectangle [x0, x1) x [y0, y1)), row = from, column =
// to, under the moves MoveRule allows inside the rectangle. One Dijkstra per
// node, all over one move graph of the rectangle built once (GridView's
// neighbour rule run once per cell, not once per cell and node), each
// stopped once every node it still has to price is settled. When every
// traversable cell of the rectangle pays the same factor the costs are
// symmetric (a diagonal's side cells are the same both ways), so node i
// prices only the nodes after it and the mirror half is copied. Settled
// Dijkstra costs are the minimum over relaxations from cells settled
// before, so stopping early changes no cost: a repaired cluster equals a
// rebuilt one bit for bit.
class HpaGraph::IntraSearch {
 public:
  std::vector<float> Costs(const GridView& view, int32_t x0, int32_t y0, int32_t x1,
                           int32_t y1, const std::vector<uint32_t>& nodes);

 private:
  // The move graph: moves out of local cell l are moves_[begin_[l] ..
  // begin_[l + 1]), each with its cost (length times the entered cell's
  // factor, as LocalSearch's forward run prices it).
  struct Move {
    int32_t to;
    bool diagonal;
    double cost;
  };
  std::vector<int32_t> begin_;
  std::vector<Move> moves_;
  // node_of_[l]: the position in `nodes` of local cell l, or -1.
  std::vector<int32_t> node_of_;
  std::vector<int32_t> local_;
  std::vector<double> cost_;
  std::vector<uint8_t> closed_;
  // The open lists, reused: (cost, local cell) entries.
  using Entry = std::pair<double, int32_t>;
  std::vector<Entry> open_[2];

  // A binary heap in open_[0].
  struct Heap {};
  // Two FIFO queues open_[0] (straight moves) and open_[1] (diagonal).
  struct FifoPair {
    size_t head[2] = {0, 0};
  };
  void Clear(Heap&) { open_[0].clear(); }
  void Clear(FifoPair& q) {
    open_[0].clear();
    open_[1].clear();
    q = FifoPair{};
  }
  void Push(Heap&, Entry e, bool /*diagonal*/) {
    open_[0].push_back(e);
    std::push_heap(open_[0].begin(), open_[0].end(), After);
  }
  void Push(FifoPair&, Entry e, bool diagonal) { open_[diagonal ? 1 : 0].push_back(e); }
  bool Pop(Heap&, Entry& e) {
    if (open_[0].empty()) return false;
    std::pop_heap(open_[0].begin(), open_[0].end(), After);
    e = open_[0].back();
    open_[0].pop_back();
    return true;
  }
  bool Pop(FifoPair& q, Entry& e) {
    const bool has0 = q.head[0] < open_[0].size();
    const bool has1 = q.head[1] < open_[1].size();
    if (!has0 && !has1) return false;
    const int from =
        !has0 || (has1 && open_[1][q.head[1]].first < open_[0][q.head[0]].first) ? 1 : 0;
    e = open_[from][q.head[from]++];
    return true;
  }
  static bool After(const Entry& a, const Entry& b) { return a.first > b.first; }

  // Dijkstra from node i until `left` nodes it prices are settled, writing
  // their costs into intra (and the mirror entries when symmetric).
  template <typename Queue>
  void Dijkstra(size_t i, size_t k, size_t left, bool symmetric, Queue& queue,
                std::vector<float>& intra) {
    std::fill(cost_.begin(), cost_.end(), LocalSearch::kInfinity);
    std::fill(closed_.begin(), closed_.end(), uint8_t{0});
    Clear(queue);
    cost_[local_[i]] = 0.0;
    Push(queue, {0.0, local_[i]}, false);
    Entry e;
    while (left > 0 && Pop(queue, e)) {
      const auto [g, l] = e;
      if (closed_[l]) continue;
      closed_[l] = 1;
      const int32_t j = node_of_[l];
      if (j >= 0 && static_cast<size_t>(j) != i && (!symmetric || static_cast<size_t>(j) > i)) {
        intra[i * k + j] = static_cast<float>(g);
        if (symmetric) intra[j * k + i] = static_cast<float>(g);
        --left;
      }
      for (int32_t m = begin_[l]; m < begin_[l + 1]; ++m) {
        const Move& move = moves_[m];
        if (closed_[move.to]) continue;
        const double next = g + move.cost;
        if (next < cost_[move.to]) {
          cost_[move.to] = next;
          Push(queue, {next, move.to}, move.diagonal);
        }
      }
    }
  }
};

std::vector<float> HpaGraph::IntraSearch::Costs(const GridView& view, int32_t x0, int32_t y0,
                                                int32_t x1, int32_t y1,
                                                const std::vector<uint32_t>& nodes) {
  const int32_t w = x1 - x0;
  const int32_t n = w * (y1 - y0);
  begin_.assign(static_cast<size_t>(n) + 1, 0);
  moves_.clear();
  bool uniform = true;
  double factor = -1.0;
  for (int32_t l = 0; l < n; ++l) {
    begin_[l] = static_cast<int32_t>(moves_.size());
    const int32_t x = x0 + l % w;
    const int32_t y = y0 + l / w;
    if (!view.Passable(x, y)) continue;
    const double f = view.Factor(view.Index(x, y));
    if (factor < 0.0) factor = f;
    uniform = uniform && f == factor;
    view.ForEachNeighbor(x, y, [&](uint32_t index, int32_t nx, int32_t ny, double length) {
      if (nx < x0 || ny < y0 || nx >= x1 || ny >= y1) return;
      moves_.push_back({(ny - y0) * w + (nx - x0), length != 1.0, length * view.Factor(index)});
    });
  }
  begin_[n] = static_cast<int32_t>(moves_.size());
  const size_t k = nodes.size();
  node_of_.assign(static_cast<size_t>(n), -1);
  local_.resize(k);
  for (size_t i = 0; i < k; ++i) {
    const Cell c = view.CellOf(nodes[i]);
    local_[i] = (c.y - y0) * w + (c.x - x0);
    node_of_[local_[i]] = static_cast<int32_t>(i);
  }
  std::vector<float> intra(k * k, std::numeric_limits<float>::infinity());
  cost_.resize(static_cast<size_t>(n));
  closed_.resize(static_cast<size_t>(n));
  for (size_t i = 0; i < k; ++i) {
    // Node i prices nodes j > i when symmetric, every other node else; the
    // last node of a symmetric cluster has nothing left to price.
    const size_t left = uniform ? k - 1 - i : k - 1;
    intra[i * k + i] = 0.0f;
    if (left == 0) continue;
    // A uniform cluster's moves cost f or f * sqrt(2), so two FIFO queues,
    // one per move length, are each in key order (keys pushed are the
    // nondecreasing settled costs plus one constant) and their fronts'
    // minimum is the open list's: Dijkstra without a heap.
    if (uniform) {
      FifoPair queue;
      Dijkstra(i, k, left, true, queue, intra);
    } else {
      Heap queue;
      Dijkstra(i, k, left, false, queue, intra);
    }
  }
  return intra;
}

std::shared_ptr<const HpaCluster> HpaGraph::BuildCluster(const GridView& view, int32_t id,
                                                         const HpaCluster* same_inside,
                                                         IntraSearch& search) const {
  int32_t x0, y0, x1, y1;
  Bounds(id, x0, y0, x1, y1);
  const int32_t cx = id % clusters_x_;
  const int32_t cy = id / clusters_x_;
  std::vector<Transition> transitions;
  if (cy > 0) {  // top border
    BorderTransitions(
        view, x1 - x0, [&](int32_t p) { return Cell{x0 + p, y0}; },
        [&](int32_t p) { return Cell{x0 + p, y0 - 1}; }, transitions);
  }
  if (cy + 1 < clusters_y_) {  // bottom
    BorderTransitions(
        view, x1 - x0, [&](int32_t p) { return Cell{x0 + p, y1 - 1}; },
        [&](int32_t p) { return Cell{x0 + p, y1}; }, transitions);
  }
  if (cx > 0) {  // left
    BorderTransitions(
        view, y1 - y0, [&](int32_t p) { return Cell{x0, y0 + p}; },
        [&](int32_t p) { return Cell{x0 - 1, y0 + p}; }, transitions);
  }
  if (cx + 1 < clusters_x_) {  // right
    BorderTransitions(
        view, y1 - y0, [&](int32_t p) { return Cell{x1 - 1, y0 + p}; },
        [&](int32_t p) { return Cell{x1, y0 + p}; }, transitions);
  }
  auto cluster = std::make_shared<HpaCluster>();
  if (transitions.empty()) return cluster;
  std::sort(transitions.begin(), transitions.end(),
            [](const Transition& a, const Transition& b) {
              return a.inside != b.inside ? a.inside < b.inside : a.outside < b.outside;
            });
  for (const Transition& t : transitions) {
    if (cluster->nodes.empty() || cluster->nodes.back() != t.inside) {
      cluster->nodes.push_back(t.inside);
      cluster->inter_begin.push_back(static_cast<uint32_t>(cluster->inter.size()));
    }
    // A straight move into the neighbour's cell.
    cluster->inter.push_back({t.outside, static_cast<float>(view.Factor(t.outside))});
  }
  cluster->inter_begin.push_back(static_cast<uint32_t>(cluster->inter.size()));
  cluster->intra = same_inside != nullptr && same_inside->nodes == cluster->nodes
                       ? same_inside->intra
                       : search.Costs(view, x0, y0, x1, y1, cluster->nodes);
  return cluster;
}

namespace {
// A shared_ptr's control block with make_shared's inline object, and the
// block's pointer to it.
constexpr size_t kClusterOverhead = 16 + sizeof(std::shared_ptr<const HpaCluster>);
}  // namespace

std::shared_ptr<const HpaGraph> HpaGraph::Build(const Grid& grid, const HpaParams& params,
                                                DerivedStop& stop) {
  std::shared_ptr<HpaGraph> graph(new HpaGraph());
  graph->params_ = params;
  graph->width_ = grid.width();
  graph->height_ = grid.height();
  const int32_t c = params.cluster_size;
  graph->clusters_x_ = (grid.width() + c - 1) / c;
  graph->clusters_y_ = (grid.height() + c - 1) / c;
  const int32_t count = graph->clusters_x_ * graph->clusters_y_;
  const int32_t blocks = (graph->clusters_x_ + kBlock - 1) / kBlock;
  graph->bytes_ = sizeof(HpaGraph) +
                  graph->clusters_y_ * (sizeof(std::shared_ptr<const Row>) + sizeof(Row) + 16 +
                                        blocks * (sizeof(std::shared_ptr<const Block>) +
                                                  sizeof(Block) + 16));
  const GridView view(grid, params.cost);
  IntraSearch search;
  for (int32_t cy = 0; cy < graph->clusters_y_; ++cy) {
    auto row = std::make_shared<Row>(static_cast<size_t>(blocks));
    std::shared_ptr<Block> block;
    for (int32_t cx = 0; cx < graph->clusters_x_; ++cx) {
      const int32_t id = cy * graph->clusters_x_ + cx;
      if (id % 16 == 0 && stop.Stopped()) {
        stop.Note(absl::StrFormat("building the HPA* abstract graph of this map version "
                                  "(%d of %d clusters)",
                                  id, count));
        return nullptr;
      }
      std::shared_ptr<const HpaCluster> cluster = graph->BuildCluster(view, id, nullptr, search);
      graph->node_count_ += cluster->nodes.size();
      graph->edge_count_ += cluster->intra.size() + cluster->inter.size();
      graph->bytes_ += cluster->MemoryBytes() + kClusterOverhead;
      if (cx % kBlock == 0) {
        block = std::make_shared<Block>();
        (*row)[cx / kBlock] = block;
      }
      (*block)[cx % kBlock] = std::move(cluster);
    }
    graph->rows_.push_back(std::move(row));
  }
  return graph;
}

std::shared_ptr<const HpaGraph> HpaGraph::Advance(const Grid& grid,
                                                  absl::Span<const Cell> changed,
                                                  DerivedStop& stop) const {
  if (grid.width() != width_ || grid.height() != height_) return nullptr;
  const int32_t c = params_.cluster_size;
  // A cluster depends on its own cells and, through its transitions and the
  // costs of its moves out, on the cells just across its borders. Marked
  // clusters in id order; `inside` says a changed cell lies in the cluster
  // itself (else only across its border, and its costs between unchanged
  // nodes are kept).
  struct Marked {
    int32_t id;
    bool inside;
  };
  std::vector<Marked> order;
  auto mark = [&](int32_t cx, int32_t cy, bool inside) {
    if (cx < 0 || cy < 0 || cx >= clusters_x_ || cy >= clusters_y_) return;
    order.push_back({cy * clusters_x_ + cx, inside});
  };
  for (const Cell& cell : changed) {
    if (!grid.InBounds(cell)) continue;
    const int32_t cx = cell.x / c;
    const int32_t cy = cell.y / c;
    mark(cx, cy, true);
    if (cell.x % c == 0) mark(cx - 1, cy, false);
    if (cell.x % c == c - 1 || cell.x == width_ - 1) mark(cx + 1, cy, false);
    if (cell.y % c == 0) mark(cx, cy - 1, false);
    if (cell.y % c == c - 1 || cell.y == height_ - 1) mark(cx, cy + 1, false);
  }
  // By id, those with a changed cell inside first; then one entry per id.
  std::sort(order.begin(), order.end(), [](const Marked& a, const Marked& b) {
    return a.id != b.id ? a.id < b.id : a.inside > b.inside;
  });
  order.erase(std::unique(order.begin(), order.end(),
                          [](const Marked& a, const Marked& b) { return a.id == b.id; }),
              order.end());
  std::shared_ptr<HpaGraph> next(new HpaGraph(*this));
  const GridView view(grid, params_.cost);
  IntraSearch search;
  // The row and the block being rebuilt, copied from this version's on
  // first write.
  std::shared_ptr<Row> row;
  std::shared_ptr<Block> block;
  int32_t row_y = -1;
  int32_t block_x = -1;
  for (size_t i = 0; i < order.size(); ++i) {
    if (i % 16 == 15 && stop.Stopped()) {
      stop.Note(absl::StrFormat("repairing the HPA* abstract graph (%d of %d clusters)",
                                i, order.size()));
      return nullptr;
    }
    const int32_t id = order[i].id;
    const int32_t cy = id / clusters_x_;
    const int32_t cx = id % clusters_x_;
    if (cy != row_y) {
      row = std::make_shared<Row>(*rows_[cy]);
      next->rows_[cy] = row;
      row_y = cy;
      block_x = -1;
    }
    if (cx / kBlock != block_x) {
      block_x = cx / kBlock;
      block = std::make_shared<Block>(*(*row)[block_x]);
      (*row)[block_x] = block;
    }
    std::shared_ptr<const HpaCluster>& slot = (*block)[cx % kBlock];
    next->node_count_ -= slot->nodes.size();
    next->edge_count_ -= slot->intra.size() + slot->inter.size();
    next->bytes_ -= slot->MemoryBytes();
    slot = next->BuildCluster(view, id, order[i].inside ? nullptr : slot.get(), search);
    next->node_count_ += slot->nodes.size();
    next->edge_count_ += slot->intra.size() + slot->inter.size();
    next->bytes_ += slot->MemoryBytes();
  }
  return next;
}

std::string HpaGraph::FirstDifference(const HpaGraph& a, const HpaGraph& b) {
  if (a.width_ != b.width_ || a.height_ != b.height_ ||
      a.params_.cluster_size != b.params_.cluster_size) {
    return "different grid or cluster sizes";
  }
  if (a.node_count_ != b.node_count_ || a.edge_count_ != b.edge_count_) {
    return absl::StrFormat("%d nodes / %d edges vs %d / %d", a.node_count_, a.edge_count_,
                           b.node_count_, b.edge_count_);
  }
  for (int32_t id = 0; id < a.clusters_x_ * a.clusters_y_; ++id) {
    const HpaCluster& x = a.cluster(id);
    const HpaCluster& y = b.cluster(id);
    const std::string where = absl::StrFormat("cluster %d (%d, %d)", id,
                                              id % a.clusters_x_, id / a.clusters_x_);
    if (x.nodes != y.nodes) {
      return absl::StrFormat("%s: %d vs %d nodes or different cells", where,
                             x.nodes.size(), y.nodes.size());
    }
    // Costs are never NaN, so == on the floats is equality of the bits
    // (but for 0 and -0, which no search produces).
    if (x.intra != y.intra) {
      return where + ": intra-cluster costs differ";
    }
    if (x.inter_begin != y.inter_begin || x.inter.size() != y.inter.size()) {
      return where + ": inter-cluster edges differ";
    }
    for (size_t i = 0; i < x.inter.size(); ++i) {
      if (x.inter[i].to != y.inter[i].to || x.inter[i].cost != y.inter[i].cost) {
        return where + ": inter-cluster edges differ";
      }
    }
  }
  return "";
}

namespace internal {

PlanOutcome LocalSearch::Run(const GridView& view, int32_t x0, int32_t y0, int32_t x1,
                             int32_t y1, Cell source, bool forward, const Cell* target,
                             const StopCondition* stop, int64_t* expansions) {
  x0_ = x0;
  y0_ = y0;
  w_ = x1 - x0;
  h_ = y1 - y0;
  const size_t n = static_cast<size_t>(w_) * static_cast<size_t>(h_);
  cost_.assign(n, kInfinity);
  parent_.assign(n, -1);
  closed_.assign(n, 0);
  heap_.clear();
  // Ties on f go to the larger g, as in the grid planners' open list.
  auto after = [](const Entry& a, const Entry& b) {
    return a.f > b.f || (a.f == b.f && a.g < b.g);
  };
  // The octile distance is a lower bound on every cost (each factor is
  // >= 1) in either direction, and under 4-connectivity too.
  auto h = [&](int32_t x, int32_t y) {
    if (target == nullptr) return 0.0;
    const double dx = std::abs(x - target->x);
    const double dy = std::abs(y - target->y);
    return dx > dy ? dx + (kSqrt2 - 1.0) * dy : dy + (kSqrt2 - 1.0) * dx;
  };
  const int32_t root = Local(source);
  cost_[root] = 0.0;
  heap_.push_back({h(source.x, source.y), 0.0, root});
  int64_t expanded = *expansions;
  PlanOutcome outcome = target == nullptr ? PlanOutcome::kFound : PlanOutcome::kNoPath;
  while (!heap_.empty()) {
    std::pop_heap(heap_.begin(), heap_.end(), after);
    const Entry e = heap_.back();
    heap_.pop_back();
    if (closed_[e.local] || e.g > cost_[e.local]) continue;
    if (stop != nullptr) {
      const PlanOutcome why = stop->Check(expanded);
      if (why != PlanOutcome::kFound) {
        outcome = why;
        break;
      }
    }
    ++expanded;
    closed_[e.local] = 1;
    const Cell at{x0_ + e.local % w_, y0_ + e.local / w_};
    if (target != nullptr && at == *target) {
      outcome = PlanOutcome::kFound;
      break;
    }
    const double reverse_factor = view.Factor(view.Index(at.x, at.y));
    view.ForEachNeighbor(at.x, at.y,
                         [&](uint32_t index, int32_t nx, int32_t ny, double length) {
                           if (nx < x0_ || ny < y0_ || nx >= x0_ + w_ || ny >= y0_ + h_) {
                             return;
                           }
                           const int32_t l = (ny - y0_) * w_ + (nx - x0_);
                           if (closed_[l]) return;
                           const double g =
                               e.g + length * (forward ? view.Factor(index) : reverse_factor);
                           if (g < cost_[l]) {
                             cost_[l] = g;
                             parent_[l] = e.local;
                             heap_.push_back({g + h(nx, ny), g, l});
                             std::push_heap(heap_.begin(), heap_.end(), after);
                           }
                         });
  }
  *expansions = expanded;
  return outcome;
}

double LocalSearch::Cost(Cell c) const { return cost_[Local(c)]; }

std::vector<Cell> LocalSearch::PathTo(Cell c) const {
  std::vector<Cell> path;
  for (int32_t l = Local(c); l >= 0 && path.size() <= cost_.size(); l = parent_[l]) {
    path.push_back(Cell{x0_ + l % w_, y0_ + l / w_});
  }
  std::reverse(path.begin(), path.end());
  return path;
}

}  // namespace internal
}  // namespace pathd
