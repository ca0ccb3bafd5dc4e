// The shared pieces of the multi-agent solvers (mapf_internal.h): move
// graphs, distance tables, the sweep table and the space-time search.
#include <algorithm>
#include <deque>
#include <queue>
#include <set>
#include <tuple>
#include <utility>

#include "core/fleet/mapf_internal.h"

namespace pathd::mapf_internal {

MoveGraph::MoveGraph(const Grid& grid, Connectivity connectivity,
                     bool unknown_is_free)
    : width_(grid.width()),
      height_(grid.height()),
      moves_(MoveCount(connectivity)),
      open_(grid.size()),
      padded_open_(static_cast<size_t>(width_ + 2) * (height_ + 2), 0) {
  for (size_t i = 0; i < grid.size(); ++i) {
    open_[i] = Traversable(grid.cells()[i], unknown_is_free) ? 1 : 0;
  }
  for (int32_t y = 0; y < height_; ++y) {
    for (int32_t x = 0; x < width_; ++x) {
      padded_open_[static_cast<size_t>(y + 1) * (width_ + 2) + x + 1] =
          open_[static_cast<size_t>(y) * width_ + x];
    }
  }
}

DistanceTable MoveGraph::DistancesTo(uint32_t goal, uint32_t from,
                                     int32_t* from_distance,
                                     BfsScratch* scratch) const {
  // On the copy padded with one blocked cell all round, so the moves need
  // no bounds tests: one robot's table is a BFS over the whole map.
  const int64_t stride = width_ + 2;
  const size_t padded = padded_open_.size();
  const std::vector<uint8_t>& open = padded_open_;
  int64_t offset[8];
  int64_t side_a[8];
  int64_t side_b[8];
  for (int k = 0; k < moves_; ++k) {
    offset[k] = kMoves[k].dx + kMoves[k].dy * stride;
    const bool diagonal = kMoves[k].dx != 0 && kMoves[k].dy != 0;
    side_a[k] = diagonal ? kMoves[k].dx : offset[k];
    side_b[k] = diagonal ? kMoves[k].dy * stride : offset[k];
  }
  std::vector<int32_t>& dist_padded = scratch->dist;
  dist_padded.assign(padded, kUnreachable);
  std::vector<uint32_t>& queue = scratch->queue;
  queue.clear();
  const Cell g = CellOf(goal);
  const int64_t start = (g.y + 1) * stride + g.x + 1;
  dist_padded[start] = 0;
  queue.push_back(static_cast<uint32_t>(start));
  for (size_t head = 0; head < queue.size(); ++head) {
    const int64_t u = queue[head];
    const int32_t du = dist_padded[u] + 1;
    for (int k = 0; k < moves_; ++k) {
      const int64_t v = u + offset[k];
      if (open[v] == 0 || dist_padded[v] != kUnreachable) continue;
      if (open[u + side_a[k]] == 0 || open[u + side_b[k]] == 0) continue;
      dist_padded[v] = du;
      queue.push_back(static_cast<uint32_t>(v));
    }
  }
  DistanceTable dist(cells(), kFar);
  for (int32_t y = 0; y < height_; ++y) {
    for (int32_t x = 0; x < width_; ++x) {
      const int32_t d = dist_padded[(y + 1) * stride + x + 1];
      if (d != kUnreachable) {
        dist[static_cast<size_t>(y) * width_ + x] =
            static_cast<uint16_t>(std::min<int32_t>(d, kFar - 1));
      }
    }
  }
  const Cell f = CellOf(from);
  *from_distance = dist_padded[(f.y + 1) * stride + f.x + 1];
  return dist;
}

int32_t PathCost(const IndexPath& path) {
  int32_t cost = static_cast<int32_t>(path.size()) - 1;
  while (cost > 0 && path[cost - 1] == path.back()) --cost;
  return cost;
}

void TrimPath(IndexPath* path) { path->resize(PathCost(*path) + 1); }

void SweepTable::AddTimed(uint32_t cell, int32_t t, int32_t delta) {
  auto [it, inserted] = timed_.try_emplace(Key(cell, t), 0);
  it->second += delta;
  if (it->second == 0) {
    timed_.erase(it);
    // A cell's only sweeps were at step 0 (prioritized planning's start
    // reservations): none is left.
    if (t == 0 && last_step_[cell] == 0) last_step_[cell] = -1;
  }
  if (delta > 0) {
    last_step_[cell] = std::max(last_step_[cell], t);
    horizon_ = std::max(horizon_, t + 1);
  }
}

void SweepTable::Update(const MoveGraph& graph, const IndexPath& path,
                        int32_t delta) {
  const auto last = static_cast<int32_t>(path.size()) - 1;
  for (int32_t t = 0; t < last; ++t) {
    const Sweep s = SweepAt(graph, path, t);
    for (int k = 0; k < s.n; ++k) AddTimed(s.cells[k], t, delta);
  }
  parked_since_[path.back()] = delta > 0 ? last : kNever;
  if (delta > 0) horizon_ = std::max(horizon_, last);
}

namespace {

struct Node {
  uint32_t cell;
  int32_t t;
  int32_t conflicts;
  int32_t parent;
  bool open;
};

// The earliest time a robot may stop at its goal when another sweeps the goal
// during step `last` (-1: never): it may not be there at time last (it
// would sweep the goal during that step by staying) nor at last + 1 (by
// entering), so from last + 2 on.
int32_t StopAfter(int32_t last) { return last < 0 ? 0 : last + 2; }

}  // namespace

LowLevelResult SpaceTimeSearch(const LowLevelQuery& q,
                               const StopCondition& stop, int64_t* expansions) {
  LowLevelResult result;
  const MoveGraph& graph = *q.graph;
  const DistanceTable& h = *q.h;
  const size_t cells = graph.cells();
  if (h[q.start] == kFar) return result;
  // Past `still` nothing in the constraints or tables changes with time, so
  // a state is its cell alone and an earlier arrival dominates a later one.
  int32_t still = 0;
  int32_t earliest_stop = 0;
  if (q.constraints != nullptr) {
    still = std::max(still, q.constraints->Horizon());
    earliest_stop =
        std::max(earliest_stop, StopAfter(q.constraints->LastStep(q.goal)));
  }
  if (q.reserved != nullptr) {
    still = std::max(still, q.reserved->Horizon());
    earliest_stop =
        std::max(earliest_stop, StopAfter(q.reserved->LastStep(q.goal)));
  }
  if (q.avoid != nullptr) still = std::max(still, q.avoid->Horizon());
  // Keyed by the cell alone only once the robot may stop at its goal (else
  // waiting there from `still` would look like a revisit and be dropped; the
  // sweep of the goal at step earliest_stop - 2 already keeps the robot off
  // it at still = earliest_stop - 1, so this is a guard, not a fix).
  still = std::max(still, earliest_stop);
  auto key_of = [&](uint32_t cell, int32_t t) {
    return static_cast<uint64_t>(std::min(t, still)) * cells + cell;
  };

  std::vector<Node> nodes;
  absl::flat_hash_map<uint64_t, int32_t> index;
  // open: (f, id); focal: the open nodes with f <= bound by (conflicts, f,
  // later time first, id). bound = w * f_min only grows (h is consistent, so
  // no node enters below f_min).
  std::set<std::pair<int32_t, int32_t>> open;
  std::set<std::tuple<int32_t, int32_t, int32_t, int32_t, int32_t>> focal;
  int32_t bound = -1;
  // The robot cannot finish before earliest_stop, so max(h, earliest_stop -
  // t) is also admissible (and consistent): without it a robot whose goal a
  // reservation crosses late would search every state that could reach the
  // goal sooner.
  auto f_of = [&](const Node& n) {
    return std::max(n.t + h[n.cell], earliest_stop);
  };
  auto focal_key = [&](int32_t id) {
    const Node& n = nodes[id];
    return std::make_tuple(n.conflicts, f_of(n), h[n.cell], -n.t, id);
  };
  // w = 1 (A*): one binary heap with lazy deletion, ordered as focal is.
  const bool focal_search = q.w > 1.0;
  // (f, conflicts, h, -t, id): among equal f, nearer the goal and then
  // later first (with the earliest_stop term, equal f no longer means
  // nearer).
  using HeapKey = std::tuple<int32_t, int32_t, int32_t, int32_t, int32_t>;
  std::priority_queue<HeapKey, std::vector<HeapKey>, std::greater<>> heap;
  auto push = [&](int32_t id) {
    Node& n = nodes[id];
    n.open = true;
    if (!focal_search) {
      heap.emplace(f_of(n), n.conflicts, h[n.cell], -n.t, id);
      return;
    }
    open.emplace(f_of(n), id);
    if (f_of(n) <= bound) focal.insert(focal_key(id));
  };
  auto erase = [&](int32_t id) {
    nodes[id].open = false;
    if (!focal_search) return;  // its heap entries go stale
    open.erase({f_of(nodes[id]), id});
    focal.erase(focal_key(id));
  };
  auto reach = [&](uint32_t cell, int32_t t, int32_t conflicts,
                   int32_t parent) {
    const auto [it, inserted] =
        index.try_emplace(key_of(cell, t), static_cast<int32_t>(nodes.size()));
    if (inserted) {
      nodes.push_back(Node{cell, t, conflicts, parent, false});
      push(it->second);
      return;
    }
    Node& n = nodes[it->second];
    if (t > n.t || (t == n.t && conflicts >= n.conflicts)) return;
    if (n.open) erase(it->second);
    n.t = t;
    n.conflicts = conflicts;
    n.parent = parent;
    push(it->second);  // reopened when it was closed
  };
  // The next node to expand and f_min, or -1 when none is open.
  auto next = [&](int32_t* f_min) -> int32_t {
    if (!focal_search) {
      while (!heap.empty()) {
        const auto [f, c, hv, neg_t, id] = heap.top();
        heap.pop();
        const Node& n = nodes[id];
        if (!n.open || n.t != -neg_t || n.conflicts != c) continue;  // stale
        *f_min = f;
        erase(id);
        return id;
      }
      return -1;
    }
    if (open.empty()) return -1;
    *f_min = open.begin()->first;
    const auto new_bound = static_cast<int32_t>(q.w * *f_min + 1e-9);
    if (new_bound > bound) {
      for (auto it = open.lower_bound({bound + 1, -1});
           it != open.end() && it->first <= new_bound; ++it) {
        focal.insert(focal_key(it->second));
      }
      bound = new_bound;
    }
    const int32_t id = std::get<4>(*focal.begin());
    erase(id);
    return id;
  };

  reach(q.start, 0, 0, -1);
  int64_t local = 0;
  int32_t f_min = 0;
  for (int32_t id = next(&f_min); id >= 0; id = next(&f_min)) {
    const Node n = nodes[id];
    ++*expansions;
    ++local;
    if (const PlanOutcome o = stop.Check(*expansions, f_min);
        o != PlanOutcome::kFound) {
      result.outcome = o;
      result.lower_bound = f_min;
      return result;
    }
    if (q.max_expansions > 0 && local >= q.max_expansions) {
      result.outcome = PlanOutcome::kExpansionLimit;
      result.lower_bound = f_min;
      return result;
    }
    if (n.cell == q.goal && n.t >= earliest_stop) {
      for (int32_t at = id; at >= 0; at = nodes[at].parent) {
        result.path.push_back(nodes[at].cell);
      }
      std::reverse(result.path.begin(), result.path.end());
      result.outcome = PlanOutcome::kFound;
      result.cost = static_cast<int32_t>(result.path.size()) - 1;
      result.lower_bound = std::min(f_min, result.cost);
      result.conflicts = n.conflicts;
      return result;
    }
    if (n.t >= q.max_steps) continue;
    auto step = [&](uint32_t to) {
      const Sweep s = graph.SweepOf(n.cell, to);
      if (q.constraints != nullptr && q.constraints->Blocks(s, n.t, cells))
        return;
      if (q.reserved != nullptr && q.reserved->Count(s, n.t) > 0) return;
      const int32_t c = q.avoid != nullptr ? q.avoid->Count(s, n.t) : 0;
      reach(to, n.t + 1, n.conflicts + c, id);
    };
    step(n.cell);
    graph.ForEachMove(n.cell, step);
  }
  return result;  // kNoPath within max_steps
}

void SetPaths(const Instance& inst, std::vector<IndexPath> paths,
              FleetPlan* plan) {
  plan->paths.assign(paths.size(), {});
  plan->makespan = 0;
  plan->sum_of_costs = 0;
  for (size_t i = 0; i < paths.size(); ++i) {
    TrimPath(&paths[i]);
    const MoveGraph& g = inst.graph(i);
    for (const uint32_t c : paths[i]) plan->paths[i].push_back(g.CellOf(c));
    const auto cost = static_cast<int64_t>(paths[i].size()) - 1;
    plan->makespan = std::max(plan->makespan, cost);
    plan->sum_of_costs += cost;
  }
  plan->complete = true;
}

}  // namespace pathd::mapf_internal
