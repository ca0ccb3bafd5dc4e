// HPA* (Botea, Müller & Schaeffer 2004, "Near Optimal Hierarchical
// Path-Finding"), the "hierarchical planning with coarse resolution and
// re-planning on finer resolution" of the lecture notes: one query
//  1. takes the map version's abstract graph (hpa_graph.h) from the derived
//     store, or from its scratch when there is none, advanced from the last
//     grid it saw;
//  2. inserts start and goal for this query only: a Dijkstra inside the
//     start's cluster gives its edges to that cluster's transitions (and to
//     the goal when it lies in the same cluster), a reversed one inside the
//     goal's cluster the costs from that cluster's transitions to the goal;
//     the shared graph is never written;
//  3. runs A* (the one best-first loop, octile or Manhattan heuristic) over
//     the abstract nodes, numbered per query;
//  4. refines the abstract path by one A* over the cells of the clusters it
//     passes through (its corridor), so the answer is the best path in the
//     corridor and costs at most what the abstract path did; or, as the
//     paper does (HpaRefinement::kPerEdge), every intra-cluster edge by A*
//     inside its cluster (the edge's cost was that search's optimum) and
//     every inter-cluster edge by its single move.
// Complete: every grid path crosses cluster borders through entrances, and
// each entrance's cells on either side form a straight run of traversable
// cells inside their cluster that reaches the entrance's transition, so the
// abstract graph connects whatever the grid does (docs/decisions.md, "HPA*").
// Not optimal: the abstract path picks the corridor, and the best path may
// leave it; docs/performance.md gives the measured excess.
//
// Expansions count abstract nodes taken off the open list plus the cells the
// insertion and refinement searches expand; the expansion recorder gets the
// abstract nodes.
#include "core/planners/hierarchical/hpa_star.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "absl/container/flat_hash_map.h"
#include "absl/status/status.h"
#include "core/planners/hierarchical/hpa_graph.h"
#include "core/planners/planners.h"
#include "core/search/best_first.h"
#include "core/search/derived.h"
#include "core/search/grid_planner.h"
#include "core/search/heuristics.h"

namespace pathd {
namespace {

using internal::GridView;
using internal::LocalSearch;

// What hpa_star keeps in a SearchScratch between queries: search buffers,
// and, for callers without a derived store (a robot linking core, tests),
// the last graph with a copy of the cells it was made for, so a query on an
// unchanged grid reuses it and one on an edited grid advances it.
struct HpaScratch final : public SearchScratch::Extension {
  LocalSearch local;
  // Per-query numbering of the abstract nodes a search touches.
  absl::flat_hash_map<uint32_t, uint32_t> ids;
  std::vector<uint32_t> cells;
  std::vector<HpaEdge> start_edges;
  std::vector<double> goal_costs;
  // The corridor: per cluster its slot in this query's corridor, valid
  // where corridor_stamp equals the query's stamp, and per slot its
  // cluster.
  std::vector<uint32_t> corridor_stamp;
  std::vector<uint32_t> corridor_slot;
  std::vector<int32_t> corridor_clusters;
  // Per slot, its cluster's first cell.
  std::vector<Cell> corridor_origin;
  uint32_t stamp = 0;

  std::string key;
  int32_t width = 0;
  int32_t height = 0;
  std::vector<uint8_t> grid_cells;
  std::shared_ptr<const HpaGraph> graph;

  size_t MemoryBytes() const override {
    return ids.capacity() * (sizeof(uint32_t) * 2 + 1) + cells.capacity() * 4 +
           start_edges.capacity() * sizeof(HpaEdge) + goal_costs.capacity() * 8 +
           (corridor_stamp.capacity() + corridor_slot.capacity() +
            corridor_clusters.capacity()) * 4 + corridor_origin.capacity() * sizeof(Cell) +
           grid_cells.capacity() + (graph != nullptr ? graph->MemoryBytes() : 0);
  }
};

// The graph for this query's grid and cost model; null when `stop` fired.
std::shared_ptr<const HpaGraph> GraphFor(const Grid& grid, const PlanRequest& request,
                                         const HpaParams& params, DerivedStop& stop,
                                         HpaScratch& state) {
  const std::string key = HpaKey(params);
  if (request.derived != nullptr) {
    return GetDerived<HpaGraph>(
        request.derived, grid, key, "the HPA* abstract graph of this map version", stop,
        [params](const Grid& g, DerivedStop& s) { return HpaGraph::Build(g, params, s); },
        [](const HpaGraph& previous, const Grid& g, absl::Span<const Cell> changed,
           DerivedStop& s) { return previous.Advance(g, changed, s); },
        [](const HpaGraph& graph) { return graph.MemoryBytes(); });
  }
  const bool same_shape = state.graph != nullptr && state.key == key &&
                          state.width == grid.width() && state.height == grid.height();
  if (same_shape && state.grid_cells == grid.cells()) return state.graph;
  std::shared_ptr<const HpaGraph> graph;
  if (same_shape) {
    std::vector<Cell> changed;
    for (size_t i = 0; i < grid.size(); ++i) {
      if (state.grid_cells[i] != grid.cells()[i]) changed.push_back(grid.CellAt(i));
    }
    graph = state.graph->Advance(grid, changed, stop);
  } else {
    graph = HpaGraph::Build(grid, params, stop);
  }
  if (graph == nullptr) return nullptr;
  state.key = key;
  state.width = grid.width();
  state.height = grid.height();
  state.grid_cells = grid.cells();
  state.graph = graph;
  return graph;
}

// The expansion policy of the abstract search: node ids are numbered per
// query (so the SearchScratch records of the few hundred nodes a query
// touches sit together, not spread over a map-sized array), successors are
// a node's intra- and inter-cluster edges plus the query's start and goal
// edges. Single use; not thread-safe.
class HpaExpansion {
 public:
  HpaExpansion(const HpaGraph& graph, const GridView& view, HpaScratch& state, Cell start,
               Cell goal)
      : graph_(graph),
        view_(view),
        state_(state),
        start_(view.Index(start.x, start.y)),
        goal_(view.Index(goal.x, goal.y)),
        goal_cluster_(graph.ClusterOf(goal.x, goal.y)) {}

  uint32_t Id(Cell c) const { return IdOf(view_.Index(c.x, c.y)); }
  Cell CellOf(uint32_t id) const { return view_.CellOf(state_.cells[id]); }

  template <typename Visit>
  void ForEachSuccessor(uint32_t id, double g, Visit&& visit) const {
    const uint32_t cell = state_.cells[id];
    auto offer = [&](uint32_t to, double cost) {
      const uint32_t next = IdOf(to);
      const Cell c = view_.CellOf(to);
      visit(next, c.x, c.y, g + cost);
    };
    const Cell at = view_.CellOf(cell);
    const int32_t cluster_id = graph_.ClusterOf(at.x, at.y);
    const HpaCluster& cluster = graph_.cluster(cluster_id);
    const int32_t local = cluster.LocalIndex(cell);
    if (cell == start_) {
      // The insertion search's costs replace the start's intra-cluster row.
      for (const HpaEdge& e : state_.start_edges) offer(e.to, e.cost);
    } else if (local >= 0) {
      const size_t k = cluster.nodes.size();
      const float* row = cluster.intra.data() + static_cast<size_t>(local) * k;
      for (size_t j = 0; j < k; ++j) {
        if (j != static_cast<size_t>(local) && std::isfinite(row[j])) {
          offer(cluster.nodes[j], row[j]);
        }
      }
    }
    if (local < 0) return;
    for (uint32_t e = cluster.inter_begin[local]; e < cluster.inter_begin[local + 1]; ++e) {
      offer(cluster.inter[e].to, cluster.inter[e].cost);
    }
    if (cluster_id == goal_cluster_ && std::isfinite(state_.goal_costs[local])) {
      offer(goal_, state_.goal_costs[local]);
    }
  }

 private:
  uint32_t IdOf(uint32_t cell) const {
    const auto [it, inserted] =
        state_.ids.try_emplace(cell, static_cast<uint32_t>(state_.cells.size()));
    if (inserted) state_.cells.push_back(cell);
    return it->second;
  }

  const HpaGraph& graph_;
  const GridView& view_;
  HpaScratch& state_;
  const uint32_t start_;
  const uint32_t goal_;
  const int32_t goal_cluster_;
};

// The expansion policy of the corridor search: cells of the corridor's
// clusters, numbered slot * C^2 + the cell's place in its cluster, with the
// grid's moves that stay in the corridor. Shifts and masks replace the
// divisions when C is a power of two (the registered 16): they ran in
// every neighbour test. Single use; not thread-safe.
class CorridorExpansion {
 public:
  CorridorExpansion(const HpaGraph& graph, const GridView& view, const HpaScratch& state)
      : graph_(graph), view_(view), state_(state), c_(graph.params().cluster_size) {
    if ((c_ & (c_ - 1)) == 0) {
      while ((1 << shift_) < c_) ++shift_;
    } else {
      shift_ = -1;
    }
  }

  // Precondition: c lies in the corridor.
  uint32_t Id(Cell c) const {
    if (shift_ >= 0) {
      const int32_t mask = c_ - 1;
      const int32_t cluster = (c.y >> shift_) * graph_.clusters_x() + (c.x >> shift_);
      return (state_.corridor_slot[cluster] << (2 * shift_)) |
             static_cast<uint32_t>(((c.y & mask) << shift_) | (c.x & mask));
    }
    const int32_t cluster = graph_.ClusterOf(c.x, c.y);
    return state_.corridor_slot[cluster] * static_cast<uint32_t>(c_ * c_) +
           static_cast<uint32_t>((c.y % c_) * c_ + c.x % c_);
  }
  Cell CellOf(uint32_t id) const {
    if (shift_ >= 0) {
      const Cell origin = state_.corridor_origin[id >> (2 * shift_)];
      const auto local = static_cast<int32_t>(id & ((1u << (2 * shift_)) - 1));
      return Cell{origin.x + (local & (c_ - 1)), origin.y + (local >> shift_)};
    }
    const uint32_t per = static_cast<uint32_t>(c_ * c_);
    const Cell origin = state_.corridor_origin[id / per];
    const auto local = static_cast<int32_t>(id % per);
    return Cell{origin.x + local % c_, origin.y + local / c_};
  }
  template <typename Visit>
  void ForEachSuccessor(uint32_t id, double g, Visit&& visit) const {
    const Cell at = CellOf(id);
    view_.ForEachNeighbor(at.x, at.y,
                          [&](uint32_t index, int32_t nx, int32_t ny, double length) {
                            if (!InCorridor(nx, ny)) return;
                            visit(Id(Cell{nx, ny}), nx, ny, g + length * view_.Factor(index));
                          });
  }

 private:
  bool InCorridor(int32_t x, int32_t y) const {
    const int32_t cluster = shift_ >= 0
                                ? (y >> shift_) * graph_.clusters_x() + (x >> shift_)
                                : graph_.ClusterOf(x, y);
    return state_.corridor_stamp[cluster] == state_.stamp;
  }

  const HpaGraph& graph_;
  const GridView& view_;
  const HpaScratch& state_;
  const int32_t c_;
  int32_t shift_ = 0;
};

class HpaStarPlanner final : public GridPlanner {
 public:
  HpaStarPlanner(int32_t cluster_size, HpaRefinement refinement)
      : GridPlanner("hpa_star",
                    PlannerTraits{
                        .description =
                            "HPA*: A* over cluster entrances (abstract graph kept per "
                            "map version, repaired per changed cluster), refined by A* "
                            "in the clusters it passes; complete, not optimal (0.02-0.5% "
                            "longer on the Moving AI maps)"}),
        cluster_size_(cluster_size),
        refinement_(refinement) {}

 protected:
  absl::StatusOr<PlanResult> Search(const GridQuery& q) const override {
    const Grid& grid = q.grid;
    const PlanRequest& request = q.request;
    const StopCondition& stop = q.stop;
    PlanResult result;
    // Polled before the graph is fetched, so an expired request costs no
    // build.
    result.outcome = stop.Check(0);
    if (result.outcome != PlanOutcome::kFound) return result;
    if (request.start == request.goal) {
      result.path = {request.start};
      return result;
    }
    HpaScratch& state = q.scratch.extension<HpaScratch>();
    const HpaParams params{cluster_size_, request.cost};
    DerivedStop derived_stop(stop);
    const std::shared_ptr<const HpaGraph> graph =
        GraphFor(grid, request, params, derived_stop, state);
    if (graph == nullptr) return StoppedWhileDeriving(derived_stop);

    const GridView view(grid, request.cost);
    int64_t expansions = 0;
    result.outcome = Insert(*graph, view, request.start, request.goal, stop, expansions, state);
    std::vector<Cell> nodes;
    if (result.found()) {
      result.outcome =
          AbstractSearch(*graph, view, request, stop, expansions, q.scratch, state, nodes);
    }
    if (result.found()) {
      std::vector<Cell> path;
      result.outcome =
          refinement_ == HpaRefinement::kCorridor
              ? RefineInCorridor(*graph, view, request, nodes, stop, expansions, q.scratch,
                                 state, path)
              : Refine(*graph, view, nodes, stop, expansions, state, path);
      if (result.found()) internal::SetMeasuredPath(grid, request.cost, std::move(path), &result);
    }
    result.expansions = expansions;
    return result;
  }

 private:
  // Step 2: the start's edges into state.start_edges, the costs from the
  // goal cluster's nodes to the goal into state.goal_costs.
  static PlanOutcome Insert(const HpaGraph& graph, const GridView& view, Cell start,
                            Cell goal, const StopCondition& stop, int64_t& expansions,
                            HpaScratch& state) {
    int32_t x0, y0, x1, y1;
    const int32_t start_cluster = graph.ClusterOf(start.x, start.y);
    graph.Bounds(start_cluster, x0, y0, x1, y1);
    PlanOutcome outcome = state.local.Run(view, x0, y0, x1, y1, start, /*forward=*/true,
                                          nullptr, &stop, &expansions);
    if (outcome != PlanOutcome::kFound) return outcome;
    state.start_edges.clear();
    for (const uint32_t node : graph.cluster(start_cluster).nodes) {
      const double cost = state.local.Cost(view.CellOf(node));
      if (std::isfinite(cost)) state.start_edges.push_back({node, static_cast<float>(cost)});
    }
    const int32_t goal_cluster = graph.ClusterOf(goal.x, goal.y);
    if (goal_cluster == start_cluster) {
      const double cost = state.local.Cost(goal);
      if (std::isfinite(cost)) {
        state.start_edges.push_back({view.Index(goal.x, goal.y), static_cast<float>(cost)});
      }
    }
    graph.Bounds(goal_cluster, x0, y0, x1, y1);
    outcome = state.local.Run(view, x0, y0, x1, y1, goal, /*forward=*/false, nullptr, &stop,
                              &expansions);
    if (outcome != PlanOutcome::kFound) return outcome;
    state.goal_costs.clear();
    for (const uint32_t node : graph.cluster(goal_cluster).nodes) {
      state.goal_costs.push_back(state.local.Cost(view.CellOf(node)));
    }
    return PlanOutcome::kFound;
  }

  // Step 3: the abstract path's node cells, start to goal, into `nodes`.
  static PlanOutcome AbstractSearch(const HpaGraph& graph, const GridView& view,
                                    const PlanRequest& request, const StopCondition& stop,
                                    int64_t& expansions, SearchScratch& scratch,
                                    HpaScratch& state, std::vector<Cell>& nodes) {
    state.ids.clear();
    state.cells.clear();
    // Ids go to nodes, the start and the goal only.
    scratch.BeginSearch(graph.node_count() + 2);
    const HpaExpansion expansion(graph, view, state, request.start, request.goal);
    const internal::AStarPriority<internal::GridDistanceHeuristic> priority{
        {request.goal, request.cost.connectivity}};
    internal::OpenList open(scratch);
    const uint32_t start = expansion.Id(request.start);
    const uint32_t goal = expansion.Id(request.goal);
    internal::PushRoot(scratch, open, start, request.start, priority);
    const PlanOutcome outcome = internal::WithExpansionListener(
        request.expansion_recorder, expansion, [&](auto listener) {
          return internal::BestFirstSearch(scratch, open, goal, stop, expansions, priority,
                                           expansion, internal::PlainParentUpdate(),
                                           listener);
        });
    if (outcome != PlanOutcome::kFound) return outcome;
    nodes.clear();
    for (uint32_t at = goal; at != SearchScratch::kNoParent; at = scratch.Raw(at).parent) {
      nodes.push_back(expansion.CellOf(at));
      if (nodes.size() > state.cells.size()) {
        return PlanOutcome::kNoPath;  // corrupt links; cannot happen
      }
    }
    std::reverse(nodes.begin(), nodes.end());
    return PlanOutcome::kFound;
  }

  // Step 4: the abstract path refined to legal moves, into `path`.
  static PlanOutcome Refine(const HpaGraph& graph, const GridView& view,
                            const std::vector<Cell>& nodes, const StopCondition& stop,
                            int64_t& expansions, HpaScratch& state, std::vector<Cell>& path) {
    path.assign(1, nodes.front());
    for (size_t i = 1; i < nodes.size(); ++i) {
      const Cell from = nodes[i - 1];
      const Cell to = nodes[i];
      const int32_t cluster = graph.ClusterOf(from.x, from.y);
      if (cluster != graph.ClusterOf(to.x, to.y)) {
        // An inter-cluster edge: one straight move across the border.
        path.push_back(to);
        continue;
      }
      int32_t x0, y0, x1, y1;
      graph.Bounds(cluster, x0, y0, x1, y1);
      const PlanOutcome outcome = state.local.Run(view, x0, y0, x1, y1, from,
                                                  /*forward=*/true, &to, &stop, &expansions);
      // kNoPath cannot happen: the edge's cost came from the same search.
      if (outcome != PlanOutcome::kFound) return outcome;
      const std::vector<Cell> piece = state.local.PathTo(to);
      path.insert(path.end(), piece.begin() + 1, piece.end());
    }
    return PlanOutcome::kFound;
  }

  // Step 4 by one A* over the corridor's cells, into `path`.
  static PlanOutcome RefineInCorridor(const HpaGraph& graph, const GridView& view,
                                      const PlanRequest& request,
                                      const std::vector<Cell>& nodes,
                                      const StopCondition& stop, int64_t& expansions,
                                      SearchScratch& scratch, HpaScratch& state,
                                      std::vector<Cell>& path) {
    const size_t clusters = static_cast<size_t>(graph.clusters_x()) * graph.clusters_y();
    if (state.corridor_stamp.size() != clusters) {
      state.corridor_stamp.assign(clusters, 0);
      state.corridor_slot.assign(clusters, 0);
      state.stamp = 0;
    }
    if (++state.stamp == 0) {
      std::fill(state.corridor_stamp.begin(), state.corridor_stamp.end(), 0);
      state.stamp = 1;
    }
    state.corridor_clusters.clear();
    state.corridor_origin.clear();
    // Every abstract edge runs inside one cluster or crosses into the next,
    // so the clusters of the nodes hold the whole abstract path.
    for (const Cell& node : nodes) {
      const int32_t cluster = graph.ClusterOf(node.x, node.y);
      if (state.corridor_stamp[cluster] == state.stamp) continue;
      state.corridor_stamp[cluster] = state.stamp;
      state.corridor_slot[cluster] = static_cast<uint32_t>(state.corridor_clusters.size());
      state.corridor_clusters.push_back(cluster);
      int32_t x0, y0, x1, y1;
      graph.Bounds(cluster, x0, y0, x1, y1);
      state.corridor_origin.push_back(Cell{x0, y0});
    }
    const int32_t c = graph.params().cluster_size;
    scratch.BeginSearch(state.corridor_clusters.size() * static_cast<size_t>(c * c));
    const CorridorExpansion expansion(graph, view, state);
    const internal::AStarPriority<internal::GridDistanceHeuristic> priority{
        {request.goal, request.cost.connectivity}};
    internal::OpenList open(scratch);
    const uint32_t goal = expansion.Id(request.goal);
    internal::PushRoot(scratch, open, expansion.Id(request.start), request.start, priority);
    const PlanOutcome outcome = internal::BestFirstSearch(scratch, open, goal, stop,
                                                          expansions, priority, expansion);
    // kNoPath cannot happen: the abstract path's refinement lies in the
    // corridor.
    if (outcome != PlanOutcome::kFound) return outcome;
    path.clear();
    for (uint32_t at = goal; at != SearchScratch::kNoParent; at = scratch.Raw(at).parent) {
      path.push_back(expansion.CellOf(at));
    }
    std::reverse(path.begin(), path.end());
    return PlanOutcome::kFound;
  }

  int32_t cluster_size_;
  HpaRefinement refinement_;
};

}  // namespace

std::unique_ptr<Planner> MakeHpaStarPlanner(int32_t cluster_size, HpaRefinement refinement) {
  return std::make_unique<HpaStarPlanner>(cluster_size, refinement);
}

std::unique_ptr<Planner> MakeHpaStarPlanner() {
  return MakeHpaStarPlanner(kHpaDefaultClusterSize);
}

}  // namespace pathd
