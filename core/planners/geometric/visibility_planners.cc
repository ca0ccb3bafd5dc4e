// Exact Euclidean shortest paths in the free space of core/geometry/free_space.h
// by two searches over the tangent visibility graph of its bend corners
// (core/geometry/visibility_graph.h):
//  - visibility_graph: A* with the Euclidean heuristic over the graph built
//    once per map version (all O(V^2) pairs tested), with the start and the
//    goal linked to the vertices they see.
//  - minimal_construct: Missura, Lee & Bennewitz, "Minimal Construct:
//    Efficient Shortest Path Finding for Mobile Robots in Polygonal Maps",
//    IROS 2018. No edge is tested in advance: A* starts on the straight line
//    from start to goal, tests a segment only when it pops the node at its
//    end, and when the segment is blocked it removes the edge, gives the node
//    the best expanded neighbour as parent, and adds the corners of the
//    blocking obstacle (once per obstacle), linked to every node so far.
//    Obstacles here are the connected groups of blocked cells
//    (ObstacleCorners); a map whose walls touch its border is one obstacle.
//
// Both searches relax only taut continuations: a node reached through its
// parent is extended only to nodes such that the path wraps the node's
// blocked cell (TautAt); any other bend could be cut, so no shortest path
// makes it. For Minimal Construct this halves the segment tests.
//
// Minimal Construct differs from the paper in one way, for exactness: a
// node discovered late can make an expanded node cheaper, so f is not
// monotone and the paper's closed list could keep a detour. Expanded nodes
// are reopened when offered a smaller g (as in A* with an inconsistent
// graph), and a node whose unverified edge fails falls back to the verified
// parent it was expanded with. With that, the first unexpanded node of the
// shortest path among the obstacles discovered so far always waits in the
// open list with f <= that path's length, so the goal is popped, through a
// clear segment, at the optimum.
#include <algorithm>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <queue>
#include <string_view>
#include <utility>
#include <vector>

#include "absl/container/flat_hash_map.h"
#include "core/geometry/free_space.h"
#include "core/geometry/visibility_graph.h"
#include "core/map/cost_model.h"
#include "core/planners/planners.h"
#include "core/search/derived.h"
#include "core/search/grid_planner.h"

namespace pathd {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();

// An open-list entry; stale entries (g no longer the node's) are skipped.
struct OpenEntry {
  double f;
  double g;
  uint32_t node;
  bool operator>(const OpenEntry& o) const {
    return f > o.f || (f == o.f && g < o.g);
  }
};
using OpenQueue =
    std::priority_queue<OpenEntry, std::vector<OpenEntry>, std::greater<>>;

// The one cell factor of the geometric planners' uniform-cost maps.
double UniformFactor(const Grid& grid, const PlanRequest& request) {
  return CellFactor(grid.cost(request.start), request.cost.cost_weight);
}

PlannerTraits GeometricTraits(std::string_view description) {
  PlannerTraits t;
  t.optimal = true;
  t.geometric = true;
  t.needs_uniform_cost = true;
  t.needs_eight_connected = true;
  t.description = description;
  return t;
}

// The start == goal answer: one point, one cell.
PlanResult SinglePoint(const FreeSpace& space, LatticePoint p) {
  PlanResult result;
  const LatticePoint only[] = {p};
  FillPolylineResult(space, only, 1.0, result);
  return result;
}

// One A* query over a visibility graph, the start and the goal linked to the
// vertices they see. Nodes are the graph's vertices, then the start, then
// the goal. Single use.
class GraphSearch {
 public:
  GraphSearch(const VisibilityGraph& graph, LatticePoint start, LatticePoint goal)
      : graph_(graph),
        start_(start),
        goal_(goal),
        start_id_(static_cast<uint32_t>(graph.vertex_count())),
        goal_id_(start_id_ + 1),
        to_goal_(graph.vertex_count(), kInfinity),
        g_(graph.vertex_count() + 2, kInfinity),
        parent_(graph.vertex_count() + 2, kNone),
        closed_(graph.vertex_count() + 2, 0) {
    graph_.ForEachTangentVisible(goal, [&](uint32_t v, double d) { to_goal_[v] = d; });
    g_[start_id_] = 0.0;
    open_.push({Distance(start, goal), 0.0, start_id_});
  }

  // Runs until the goal is popped, the open list empties, or `stop` fires;
  // counts pops in `expansions`.
  PlanOutcome Run(const StopCondition& stop, int64_t& expansions) {
    while (true) {
      const double best_f = open_.empty() ? StopCondition::kNoKey : open_.top().f;
      const PlanOutcome outcome = stop.Check(expansions, best_f);
      if (outcome != PlanOutcome::kFound) return outcome;
      if (open_.empty()) return PlanOutcome::kNoPath;
      const OpenEntry top = open_.top();
      open_.pop();
      if (closed_[top.node] || top.g != g_[top.node]) continue;
      ++expansions;
      if (top.node == goal_id_) return PlanOutcome::kFound;
      closed_[top.node] = 1;
      Expand(top.node);
    }
  }

  // Start to goal, after Run() found it.
  std::vector<LatticePoint> Polyline() const {
    std::vector<LatticePoint> polyline;
    for (uint32_t at = goal_id_; at != kNone; at = parent_[at]) {
      polyline.push_back(Point(at));
    }
    std::reverse(polyline.begin(), polyline.end());
    return polyline;
  }

 private:
  LatticePoint Point(uint32_t id) const {
    return id == start_id_ ? start_ : id == goal_id_ ? goal_ : graph_.vertex(id);
  }

  void Relax(uint32_t from, uint32_t to, double length) {
    const double g = g_[from] + length;
    if (closed_[to] || g >= g_[to]) return;
    g_[to] = g;
    parent_[to] = from;
    open_.push({g + Distance(Point(to), goal_), g, to});
  }

  void Expand(uint32_t id) {
    if (id == start_id_) {
      graph_.ForEachTangentVisible(
          start_, [&](uint32_t v, double d) { Relax(start_id_, v, d); });
      if (graph_.space().SegmentClear(start_, goal_)) {
        Relax(start_id_, goal_id_, Distance(start_, goal_));
      }
      return;
    }
    // Only taut continuations: a shortest path wraps each corner it bends at.
    const LatticePoint at = graph_.vertex(id);
    const LatticePoint from = Point(parent_[id]);
    const CornerQuadrant q = graph_.quadrant(id);
    for (const VisibilityGraph::Edge& e : graph_.EdgesOf(id)) {
      if (TautAt(from, at, q, graph_.vertex(e.to))) Relax(id, e.to, e.length);
    }
    if (to_goal_[id] < kInfinity && TautAt(from, at, q, goal_)) {
      Relax(id, goal_id_, to_goal_[id]);
    }
  }

  const VisibilityGraph& graph_;
  const LatticePoint start_;
  const LatticePoint goal_;
  const uint32_t start_id_;
  const uint32_t goal_id_;
  // Per vertex: the length of its clear, tangent segment to the goal.
  std::vector<double> to_goal_;
  std::vector<double> g_;
  std::vector<uint32_t> parent_;
  std::vector<uint8_t> closed_;
  OpenQueue open_;
};

class VisibilityGraphPlanner final : public GridPlanner {
 public:
  VisibilityGraphPlanner()
      : GridPlanner("visibility_graph",
                    GeometricTraits(
                        "A* over the tangent visibility graph of the obstacle "
                        "corners, built once per map version: exact Euclidean "
                        "shortest paths")) {}

 protected:
  // result.expansions counts nodes taken from the open list (start and goal
  // included).
  absl::StatusOr<PlanResult> Search(const GridQuery& q) const override {
    const PlanRequest& request = q.request;
    DerivedStop stop(q.stop);
    const std::shared_ptr<const VisibilityGraph> graph = GetVisibilityGraph(
        request.derived, q.grid, request.cost.unknown_is_free, stop);
    if (graph == nullptr) return StoppedWhileDeriving(stop);
    const LatticePoint start = CentreOf(request.start);
    const LatticePoint goal = CentreOf(request.goal);
    if (start == goal) return SinglePoint(graph->space(), start);
    GraphSearch search(*graph, start, goal);
    PlanResult result;
    result.outcome = search.Run(q.stop, result.expansions);
    if (result.found()) {
      FillPolylineResult(graph->space(), search.Polyline(),
                         UniformFactor(q.grid, request), result);
    }
    return result;
  }
};

// One query of Minimal Construct. Nodes 0 and 1 are the start and the goal,
// the rest obstacle corners in the order they were discovered. Single use.
class MinimalConstruct {
 public:
  MinimalConstruct(const ObstacleCorners& obstacles, LatticePoint start,
                   LatticePoint goal)
      : obstacles_(obstacles),
        space_(obstacles.space()),
        goal_(goal),
        added_(static_cast<size_t>(obstacles.obstacle_count()), 0) {
    AddNode(start);
    AddNode(goal);
    Node& s = nodes_[kStart];
    s.g = s.settled_g = 0.0;
    s.closed = true;
    closed_list_.push_back(kStart);
    Offer(kGoal, kStart, Distance(start, goal));
  }

  // Runs until the goal is popped through a clear segment, the open list
  // empties, or `stop` fires; counts pops in `expansions`.
  PlanOutcome Run(const StopCondition& stop, int64_t& expansions) {
    while (true) {
      const double best_f = open_.empty() ? StopCondition::kNoKey : open_.top().f;
      const PlanOutcome outcome = stop.Check(expansions, best_f);
      if (outcome != PlanOutcome::kFound) return outcome;
      if (open_.empty()) return PlanOutcome::kNoPath;
      const OpenEntry top = open_.top();
      open_.pop();
      Node& node = nodes_[top.node];
      if (node.closed || top.g != node.g) continue;
      ++expansions;
      if (!Verify(top.node)) continue;
      if (top.node == kGoal) return PlanOutcome::kFound;
      Expand(top.node);
    }
  }

  // Start to goal, after Run() found it.
  std::vector<LatticePoint> Polyline() const {
    std::vector<LatticePoint> polyline;
    for (uint32_t at = kGoal; at != kNone; at = nodes_[at].parent) {
      polyline.push_back(nodes_[at].p);
    }
    std::reverse(polyline.begin(), polyline.end());
    return polyline;
  }

 private:
  static constexpr uint32_t kStart = 0;
  static constexpr uint32_t kGoal = 1;

  struct Node {
    LatticePoint p;
    CornerQuadrant q;
    double h = 0.0;
    double g = kInfinity;
    uint32_t parent = kNone;
    // g and parent when last expanded, through a tested segment: what a
    // failed cheaper offer falls back to.
    double settled_g = kInfinity;
    uint32_t settled_parent = kNone;
    bool closed = false;
    bool in_closed_list = false;
  };

  uint32_t AddNode(LatticePoint p) {
    Node node;
    node.p = p;
    node.q = QuadrantAt(space_, p);
    node.h = Distance(p, goal_);
    nodes_.push_back(node);
    return static_cast<uint32_t>(nodes_.size() - 1);
  }

  static uint64_t Key(uint32_t a, uint32_t b) {
    if (a > b) std::swap(a, b);
    return (static_cast<uint64_t>(a) << 32) | b;
  }

  // a-b may continue a shortest path that reached expanded node a through
  // its parent: taut at a, tangent at b, and not known to be blocked.
  bool MayLink(uint32_t a, uint32_t b) const {
    const Node& na = nodes_[a];
    const Node& nb = nodes_[b];
    if (!Tangent(nb.p, nb.q, na.p)) return false;
    if (na.parent == kNone ? !Tangent(na.p, na.q, nb.p)
                           : !TautAt(nodes_[na.parent].p, na.p, na.q, nb.p)) {
      return false;
    }
    const auto it = tested_.find(Key(a, b));
    return it == tested_.end() || it->second;
  }

  void Offer(uint32_t to, uint32_t from, double g) {
    Node& node = nodes_[to];
    node.g = g;
    node.parent = from;
    node.closed = false;
    open_.push({g + node.h, g, to});
  }

  // Tests the popped node's segment to its parent (once per pair). When it
  // is blocked: drops the edge, re-parents the node, and adds the blocking
  // obstacle's corners the first time it blocks. Returns whether it is clear.
  bool Verify(uint32_t id) {
    Node& node = nodes_[id];
    const uint64_t key = Key(id, node.parent);
    if (tested_.contains(key)) return true;  // only clear pairs are offered
    const std::optional<int32_t> blocker =
        obstacles_.Blocker(nodes_[node.parent].p, node.p);
    tested_[key] = !blocker.has_value();
    if (!blocker.has_value()) return true;
    if (node.settled_parent != kNone) {
      // Back to what it was expanded with; its children already count on it.
      node.g = node.settled_g;
      node.parent = node.settled_parent;
      node.closed = true;
    } else {
      node.g = kInfinity;
      node.parent = kNone;
    }
    FindParent(id);
    if (!added_[*blocker]) {
      added_[*blocker] = 1;
      const auto first = static_cast<uint32_t>(nodes_.size());
      for (LatticePoint c : obstacles_.CornersOf(*blocker)) AddNode(c);
      for (auto v = first; v < nodes_.size(); ++v) FindParent(v);
    }
    return false;
  }

  // Offers `id` the expanded neighbour that reaches it most cheaply, if that
  // beats its g.
  void FindParent(uint32_t id) {
    uint32_t best = kNone;
    double best_g = nodes_[id].g;
    for (uint32_t m : closed_list_) {
      const Node& cand = nodes_[m];
      if (m == id || !cand.closed) continue;
      const double g = cand.g + Distance(cand.p, nodes_[id].p);
      if (g < best_g && MayLink(m, id)) {
        best_g = g;
        best = m;
      }
    }
    if (best != kNone) Offer(id, best, best_g);
  }

  void Expand(uint32_t id) {
    Node& node = nodes_[id];
    node.closed = true;
    node.settled_g = node.g;
    node.settled_parent = node.parent;
    if (!node.in_closed_list) {
      node.in_closed_list = true;
      closed_list_.push_back(id);
    }
    for (uint32_t c = 1; c < nodes_.size(); ++c) {
      if (c == id) continue;
      const double g = nodes_[id].g + Distance(nodes_[id].p, nodes_[c].p);
      if (g >= nodes_[c].g || !MayLink(id, c)) continue;
      Offer(c, id, g);
    }
  }

  const ObstacleCorners& obstacles_;
  const FreeSpace& space_;
  const LatticePoint goal_;
  std::vector<Node> nodes_;
  // Per obstacle: its corners are nodes.
  std::vector<uint8_t> added_;
  // Tested pairs: clear or not.
  absl::flat_hash_map<uint64_t, bool> tested_;
  // Nodes ever expanded (check `closed`: they may have been reopened).
  std::vector<uint32_t> closed_list_;
  OpenQueue open_;
};

class MinimalConstructPlanner final : public GridPlanner {
 public:
  MinimalConstructPlanner()
      : GridPlanner("minimal_construct",
                    GeometricTraits(
                        "Minimal Construct (Missura, Lee & Bennewitz 2018): "
                        "A* that builds only the part of the visibility graph "
                        "it needs, testing segments when it reaches them: "
                        "exact Euclidean shortest paths")) {}

 protected:
  // result.expansions counts nodes taken from the open list, including those
  // whose segment turned out blocked.
  absl::StatusOr<PlanResult> Search(const GridQuery& q) const override {
    const PlanRequest& request = q.request;
    DerivedStop stop(q.stop);
    const std::shared_ptr<const ObstacleCorners> obstacles = GetObstacleCorners(
        request.derived, q.grid, request.cost.unknown_is_free, stop);
    if (obstacles == nullptr) return StoppedWhileDeriving(stop);
    const LatticePoint start = CentreOf(request.start);
    const LatticePoint goal = CentreOf(request.goal);
    if (start == goal) return SinglePoint(obstacles->space(), start);
    MinimalConstruct search(*obstacles, start, goal);
    PlanResult result;
    result.outcome = search.Run(q.stop, result.expansions);
    if (result.found()) {
      FillPolylineResult(obstacles->space(), search.Polyline(),
                         UniformFactor(q.grid, request), result);
    }
    return result;
  }
};

}  // namespace

std::unique_ptr<Planner> MakeVisibilityGraphPlanner() {
  return std::make_unique<VisibilityGraphPlanner>();
}

std::unique_ptr<Planner> MakeMinimalConstructPlanner() {
  return std::make_unique<MinimalConstructPlanner>();
}

}  // namespace pathd
