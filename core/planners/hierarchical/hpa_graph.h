// The abstract graph of HPA* (Botea, Müller & Schaeffer 2004, "Near Optimal
// Hierarchical Path-Finding", JOGD 1(1)): the grid cut into square clusters,
// transitions placed on the entrances along every cluster border, and the
// exact within-cluster costs between the transitions of each cluster. It is
// a derived value of one map version (core/search/derived.h): built once,
// then advanced to the next version by rebuilding only the clusters a change
// touches, sharing every other cluster with the previous version. The search
// on it, the insertion of start and goal and the refinement to grid cells
// are in hpa_star.cc; LocalSearch, the bounded search inside one cluster
// that the build and the planner share, is here.
#ifndef PATHD_CORE_PLANNERS_HIERARCHICAL_HPA_GRAPH_H_
#define PATHD_CORE_PLANNERS_HIERARCHICAL_HPA_GRAPH_H_

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "absl/types/span.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/search/derived.h"
#include "core/search/grid_view.h"
#include "core/search/plan_types.h"
#include "core/search/stop_condition.h"

namespace pathd {

// What an abstract graph depends on besides the grid: the cluster side and
// the cost model (the costs are exact under it, so a graph serves only
// requests with the same connectivity, cost weight and unknown rule).
struct HpaParams {
  int32_t cluster_size = 16;
  CostParams cost;
};

// The key of a graph in a DerivedStore: every parameter it depends on.
std::string HpaKey(const HpaParams& params);

// An entrance of at least this many cells gets a transition at each end,
// a shorter one a single transition in its middle (Botea et al. use 6).
inline constexpr int32_t kHpaLongEntrance = 6;

// A directed edge of the abstract graph to the node at cell index `to`.
struct HpaEdge {
  uint32_t to;
  float cost;
};

// One cluster's part of the graph. Immutable once built; shared between map
// versions whose cells in and around it are the same.
struct HpaCluster {
  // The cluster's nodes: row-major cell indices of its transition cells,
  // sorted, each once (a cell at a corner may serve two borders).
  std::vector<uint32_t> nodes;
  // nodes.size()^2 costs, row = from, column = to: the cheapest move chain
  // between the two nodes that stays inside the cluster, under the cost
  // model; +infinity when there is none. Directed: a move pays the factor of
  // the cell it enters, so the two directions may differ.
  std::vector<float> intra;
  // Edges to the neighbouring clusters' transition cells: those of node i
  // are inter[inter_begin[i] .. inter_begin[i + 1]).
  std::vector<uint32_t> inter_begin;
  std::vector<HpaEdge> inter;

  // The position of `cell` in `nodes`, or -1.
  int32_t LocalIndex(uint32_t cell) const;
  size_t MemoryBytes() const;
};

// The abstract graph of one grid. Immutable; thread-safe to share.
class HpaGraph {
 public:
  // The graph of `grid`, or null when `stop` fired first (polled between
  // clusters). Precondition: params.cluster_size >= 2.
  static std::shared_ptr<const HpaGraph> Build(const Grid& grid, const HpaParams& params,
                                               DerivedStop& stop);
  // The graph of `grid` from this graph of an older version whose cells
  // differ from `grid` only in `changed` (cells listed that did not change
  // are harmless): the clusters containing a changed cell, and the
  // neighbours across a border a changed cell lies on, are rebuilt; every
  // other cluster is shared. Null when the sizes differ or `stop` fired.
  std::shared_ptr<const HpaGraph> Advance(const Grid& grid, absl::Span<const Cell> changed,
                                          DerivedStop& stop) const;

  const HpaParams& params() const { return params_; }
  int32_t width() const { return width_; }
  int32_t height() const { return height_; }
  int32_t clusters_x() const { return clusters_x_; }
  int32_t clusters_y() const { return clusters_y_; }
  // The cluster holding cell (x, y) (on the grid).
  int32_t ClusterOf(int32_t x, int32_t y) const {
    return (y / params_.cluster_size) * clusters_x_ + x / params_.cluster_size;
  }
  const HpaCluster& cluster(int32_t id) const {
    const int32_t cx = id % clusters_x_;
    return *(*(*rows_[id / clusters_x_])[cx / kBlock])[cx % kBlock];
  }
  // Cells [x0, x1) x [y0, y1) of cluster `id`.
  void Bounds(int32_t id, int32_t& x0, int32_t& y0, int32_t& x1, int32_t& y1) const;
  // Whether two versions share cluster `id` (the same object).
  bool SharesCluster(const HpaGraph& other, int32_t id) const {
    return &cluster(id) == &other.cluster(id);
  }

  size_t node_count() const { return node_count_; }
  size_t edge_count() const { return edge_count_; }
  // Memory this graph holds, counting shared clusters in full.
  size_t MemoryBytes() const { return bytes_; }

  // Empty when the two graphs have the same nodes and edges with bit-equal
  // costs; else the first difference, in words (for tests comparing an
  // advanced graph with a rebuilt one).
  static std::string FirstDifference(const HpaGraph& a, const HpaGraph& b);

 private:
  HpaGraph() = default;
  // Builds cluster `id` from the grid. `same_inside`, when given, is the
  // cluster of an older version with the same cells inside (only cells
  // across its borders changed): its costs between nodes are kept when the
  // nodes are the same, as they depend on nothing else.
  // `search` holds the buffers the costs are computed in, reused from
  // cluster to cluster.
  class IntraSearch;
  std::shared_ptr<const HpaCluster> BuildCluster(const internal::GridView& view, int32_t id,
                                                 const HpaCluster* same_inside,
                                                 IntraSearch& search) const;

  HpaParams params_;
  int32_t width_ = 0;
  int32_t height_ = 0;
  int32_t clusters_x_ = 0;
  int32_t clusters_y_ = 0;
  // Clusters row by row, each row in blocks of kBlock clusters; rows and
  // blocks are shared between versions until a cluster in them is rebuilt,
  // so an advance copies one pointer per row, one per block of the rows it
  // touches and one per cluster of the blocks it touches (not one per
  // cluster: 262,144 of them on a 8192 x 8192 map, each a reference count
  // on its own cache line; copying whole rows of 512 cost 9 us a row).
  static constexpr int32_t kBlock = 16;
  using Block = std::array<std::shared_ptr<const HpaCluster>, kBlock>;
  using Row = std::vector<std::shared_ptr<const Block>>;
  std::vector<std::shared_ptr<const Row>> rows_;
  size_t node_count_ = 0;
  size_t edge_count_ = 0;
  size_t bytes_ = 0;
};

namespace internal {

// Best-first search over the cells of one rectangle of a grid, with moves
// that stay inside it (MoveRule, the query's costs). Dense per-rectangle
// buffers reused between runs; not thread-safe.
class LocalSearch {
 public:
  static constexpr double kInfinity = std::numeric_limits<double>::infinity();

  // Searches [x0, x1) x [y0, y1) from `source`. forward: costs of reaching
  // each cell from the source; otherwise costs of reaching the source from
  // each cell (moves reversed, each paying the factor of the cell it
  // enters). With `target` set (inside the rectangle) it is A* towards it
  // with the grid-distance heuristic and stops there; otherwise Dijkstra
  // over the whole rectangle. Each expansion adds one to *expansions and
  // is checked against `stop` (null: never stops). Returns kFound when
  // the search ran out or reached the target, kNoPath when the target was
  // not reached, else the stop condition's outcome.
  PlanOutcome Run(const GridView& view, int32_t x0, int32_t y0, int32_t x1, int32_t y1,
                  Cell source, bool forward, const Cell* target,
                  const StopCondition* stop, int64_t* expansions);
  // The cost found for an in-rectangle cell; +infinity when not reached.
  double Cost(Cell c) const;
  // A forward run's move chain from the source to `c` (reached).
  std::vector<Cell> PathTo(Cell c) const;

 private:
  int32_t Local(Cell c) const { return (c.y - y0_) * w_ + (c.x - x0_); }
  int32_t x0_ = 0, y0_ = 0, w_ = 0, h_ = 0;
  std::vector<double> cost_;
  std::vector<int32_t> parent_;
  std::vector<uint8_t> closed_;
  struct Entry {
    double f;
    double g;
    int32_t local;
  };
  std::vector<Entry> heap_;
};

}  // namespace internal
}  // namespace pathd

#endif  // PATHD_CORE_PLANNERS_HIERARCHICAL_HPA_GRAPH_H_
