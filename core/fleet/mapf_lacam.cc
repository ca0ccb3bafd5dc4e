// PIBT (Okumura, Machida, Défago & Tamura, "Priority inheritance with
// backtracking for iterative multi-agent path finding", 2022) adapted to
// mapf.h's conflict rule, alone (kPibt) and as the configuration generator
// of LaCAM (Okumura, "LaCAM: Search-based algorithm for quick multi-agent
// pathfinding", 2023; kLacam).
//
// The adaptation. PIBT lets a robot enter a cell its occupant leaves in the
// same step (following) and pushes lower-priority robots out of its way by
// priority inheritance. mapf.h forbids following: every robot sweeps its own
// cell during the step, so a robot may only move into (and, diagonally,
// past) cells no robot is on at time t, and the sweeps of one step are
// pairwise disjoint. Inheritance therefore works across one step: a robot
// whose best cell holds an undecided robot asks that robot to move away
// (inheriting its priority, preferring any move to staying) and, when it
// did, waits one step for the cell; when it could not, the robot tries its
// next candidate. Staying is always legal (no other robot may sweep an
// occupied cell), so every robot always gets a move: PIBT never fails here,
// it only waits. LaCAM's constraints fix some robots' next cells first; a
// fixed move that breaks the rule makes that successor invalid.
//
// LaCAM is complete (it returns a plan or proves none exists). With
// FleetOptions::refine it goes on as LaCAM* (Okumura, "Improving LaCAM for
// scalable eventually optimal multi-agent pathfinding", 2023): every node
// keeps its cost from the start (sum of loss: robots not resting at their
// goals), a configuration reached again by a cheaper way rewires its
// descendants, nodes that cannot beat the plan in hand are dropped, and the
// best plan is returned when the stop condition fires or the search is
// exhausted (then it has the least sum of loss).
#include <algorithm>
#include <deque>
#include <queue>
#include <random>
#include <tuple>
#include <utility>

#include "core/fleet/mapf_internal.h"

namespace pathd::mapf_internal {
namespace {

constexpr int32_t kNobody = -1;

// One PIBT step; reusable across steps (its per-cell arrays are reset by
// the cells they touched).
class PibtStep {
 public:
  PibtStep(const Instance& inst, uint64_t seed)
      : inst_(inst),
        occ_(inst.cells, kNobody),
        claim_(inst.cells, kNobody),
        rng_(seed) {}

  // The next configuration from `from`: robots in `fixed` (robot, cell) get
  // their cell when legal (else false), then every other robot in `order`
  // (highest priority first).
  bool Run(const std::vector<uint32_t>& from,
           const std::vector<std::pair<size_t, uint32_t>>& fixed,
           const std::vector<size_t>& order, std::vector<uint32_t>* to) {
    const size_t n = from.size();
    from_ = &from;
    to_ = to;
    to->assign(n, kNoCell);
    decided_.assign(n, 0);
    for (const uint32_t c : touched_) {
      occ_[c] = kNobody;
      claim_[c] = kNobody;
    }
    touched_.clear();
    for (size_t i = 0; i < n; ++i) Occupy(from[i], static_cast<int32_t>(i));
    bool ok = true;
    for (const auto& [i, v] : fixed) {
      decided_[i] = 1;
      if (!Take(i, v)) ok = false;
    }
    if (!ok) return false;
    for (const size_t i : order) {
      if (decided_[i] == 0) Pibt(i, nullptr);
    }
    return true;
  }

  int64_t calls() const { return calls_; }

 private:
  void Occupy(uint32_t c, int32_t i) {
    occ_[c] = i;
    touched_.push_back(c);
  }
  // Whether robot i may take v (its cell or one legal move) now; claims its
  // sweep when so.
  bool Take(size_t i, uint32_t v) {
    const uint32_t u = (*from_)[i];
    const MoveGraph& g = inst_.graph(i);
    if (v != u) {
      bool legal = false;
      g.ForEachMove(u, [&](uint32_t w) { legal = legal || w == v; });
      if (!legal) return false;
    }
    const Sweep s = g.SweepOf(u, v);
    for (int k = 0; k < s.n; ++k) {
      const uint32_t c = s.cells[k];
      if (claim_[c] != kNobody) return false;
      if (c != u && occ_[c] != kNobody) return false;
    }
    for (int k = 0; k < s.n; ++k) {
      claim_[s.cells[k]] = static_cast<int32_t>(i);
      touched_.push_back(s.cells[k]);
    }
    (*to_)[i] = v;
    return true;
  }

  // Returns whether robot i moved. `vacate`: a higher-priority robot wants
  // to sweep i's cell next step, so any move beats staying, and i may not
  // move onto another cell of that sweep (it would be in the way again).
  bool Pibt(size_t i, const Sweep* vacate) {
    ++calls_;
    decided_[i] = 1;
    const uint32_t u = (*from_)[i];
    const MoveGraph& g = inst_.graph(i);
    const DistanceTable& h = inst_.h[i];
    // Candidates by distance to the goal, then free before occupied (a
    // free cell as near as an occupied one is taken without waiting), then
    // by straight-line distance to the goal, then at random. With unit-time
    // moves many neighbours are equally many steps away; picking among them
    // at random made robots zig-zag across open floor; with this key, 30
    // robots on arena2 (examples/fleet) drive 3915 m instead of 4306 m and
    // change direction 512 times instead of 1725, for a sum of costs of
    // 3326 instead of 3317 steps (lacam; pibt 3339 instead of 3442).
    const Cell goal = g.CellOf(inst_.goals[i]);
    const auto line = [&](uint32_t v) {
      const Cell c = g.CellOf(v);
      const int64_t dx = c.x - goal.x;
      const int64_t dy = c.y - goal.y;
      return dx * dx + dy * dy;
    };
    struct Candidate {
      uint32_t v;
      int32_t h;
      int occupied;
      int64_t line;
    };
    std::vector<Candidate> cands;
    g.ForEachMove(u, [&](uint32_t v) {
      if (vacate != nullptr && vacate->Touches(v)) return;
      const Sweep s = g.SweepOf(u, v);
      int occupied = 0;
      for (int k = 0; k < s.n; ++k) {
        if (s.cells[k] != u && occ_[s.cells[k]] != kNobody) occupied = 1;
      }
      cands.push_back(Candidate{v, h[v], occupied, line(v)});
    });
    if (vacate == nullptr) cands.push_back(Candidate{u, h[u], 0, line(u)});
    std::shuffle(cands.begin(), cands.end(), rng_);
    std::stable_sort(
        cands.begin(), cands.end(), [](const Candidate& a, const Candidate& b) {
          return std::tie(a.h, a.occupied, a.line) < std::tie(b.h, b.occupied, b.line);
        });
    for (const Candidate& cand : cands) {
      const uint32_t v = cand.v;
      if (v == u) break;
      const Sweep s = g.SweepOf(u, v);
      bool claimed = false;
      bool held = false;  // by a robot already decided
      int32_t blockers[4];
      int nb = 0;
      for (int k = 0; k < s.n; ++k) {
        const uint32_t c = s.cells[k];
        if (c == u) continue;
        if (claim_[c] != kNobody) claimed = true;
        const int32_t o = occ_[c];
        if (o == kNobody) continue;
        if (decided_[o] != 0) held = true;
        blockers[nb++] = o;
      }
      if (claimed || held) continue;
      if (nb == 0) {
        Take(i, v);
        return true;
      }
      // Undecided robots on the cells this move sweeps: ask them to move
      // away (priority inheritance) and, when all did, wait a step.
      bool all_moved = true;
      for (int k = 0; k < nb; ++k) {
        if (decided_[blockers[k]] != 0 || !Pibt(blockers[k], &s)) {
          all_moved = false;
        }
      }
      if (all_moved) {
        Take(i, u);
        return false;
      }
    }
    Take(i, u);
    return false;
  }

  const Instance& inst_;
  std::vector<int32_t> occ_;    // robot on the cell at t
  std::vector<int32_t> claim_;  // robot sweeping the cell this step
  std::vector<uint32_t> touched_;
  std::vector<uint8_t> decided_;
  const std::vector<uint32_t>* from_ = nullptr;
  std::vector<uint32_t>* to_ = nullptr;
  std::mt19937_64 rng_;
  int64_t calls_ = 0;
};

// PIBT's priorities: a robot's grows by one each step it is not at its goal
// and drops to its tie-breaking fraction when it is.
void UpdatePriorities(const Instance& inst, const std::vector<uint32_t>& config,
                      const std::vector<double>& tie,
                      std::vector<double>* prio) {
  for (size_t i = 0; i < config.size(); ++i) {
    (*prio)[i] = config[i] == inst.goals[i] ? tie[i] : (*prio)[i] + 1.0;
  }
}

std::vector<size_t> OrderOf(const std::vector<double>& prio) {
  std::vector<size_t> order(prio.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return prio[a] > prio[b]; });
  return order;
}

std::vector<double> TieBreaks(const Instance& inst, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<double> tie(inst.robots());
  for (double& t : tie) t = unit(rng);
  return tie;
}

// Paths from a sequence of configurations.
std::vector<IndexPath> PathsOf(
    const std::vector<std::vector<uint32_t>>& configs) {
  std::vector<IndexPath> paths(configs.front().size());
  for (const auto& q : configs) {
    for (size_t i = 0; i < q.size(); ++i) paths[i].push_back(q[i]);
  }
  return paths;
}

// Past about this many bytes of search state LaCAM gives up
// (kExpansionLimit) rather than grow without bound. A node holds its
// configuration twice (node and explored set, 4 + 4 bytes a robot), its
// priorities and order (8 + 8), and a constraint deque and the rest
// (about 700 bytes); a constraint is 16.
constexpr int64_t kMaxSearchBytes = int64_t{1} << 29;  // 512 MiB
int64_t SearchBytes(size_t nodes, size_t robots, size_t constraints) {
  return static_cast<int64_t>(nodes) *
             (24 * static_cast<int64_t>(robots) + 700) +
         16 * static_cast<int64_t>(constraints);
}

}  // namespace

FleetPlan SolvePibt(const Instance& inst, const FleetOptions& options,
                    const StopCondition& stop) {
  FleetPlan plan;
  std::mt19937_64 rng(options.seed);
  const std::vector<double> tie = TieBreaks(inst, rng);
  std::vector<double> prio = tie;
  PibtStep step(inst, rng());
  std::vector<std::vector<uint32_t>> configs{inst.starts};
  std::vector<uint32_t> next;
  while (configs.back() != inst.goals) {
    if (static_cast<int32_t>(configs.size()) > inst.max_steps) {
      plan.outcome = PlanOutcome::kExpansionLimit;  // not solved in max_steps
      plan.expansions = step.calls();
      plan.iterations = static_cast<int64_t>(configs.size()) - 1;
      return plan;
    }
    // PIBT calls grow by the robot count a step, so Check's every-1024th
    // clock poll could be skipped: poll each step, the budget by hand.
    const PlanOutcome o =
        stop.max_expansions() > 0 && step.calls() >= stop.max_expansions()
            ? PlanOutcome::kExpansionLimit
            : stop.Poll(step.calls());
    if (o != PlanOutcome::kFound) {
      plan.outcome = o;
      plan.expansions = step.calls();
      return plan;
    }
    UpdatePriorities(inst, configs.back(), tie, &prio);
    step.Run(configs.back(), {}, OrderOf(prio), &next);
    configs.push_back(next);
  }
  plan.iterations = static_cast<int64_t>(configs.size()) - 1;
  plan.expansions = step.calls();
  SetPaths(inst, PathsOf(configs), &plan);
  plan.outcome = PlanOutcome::kFound;
  return plan;
}

namespace {

// A LaCAM low-level node: robot `who` goes to `where`, with its ancestors'
// constraints (the chain up to the root, depth 0).
struct Constraint {
  int32_t parent;
  int32_t depth;
  uint32_t who;
  uint32_t where;
};

struct HighNode {
  std::vector<uint32_t> config;
  std::vector<double> prio;
  std::vector<size_t> order;
  std::deque<int32_t> tree;  // constraint nodes still to try
  int32_t parent;
  int32_t depth;
  // LaCAM*: cost from the start along parent links (sum of loss), the
  // admissible estimate to the goal configuration, the configurations
  // reached from this one.
  int64_t g = 0;
  int64_t h = 0;
  std::vector<int32_t> neighbors;
};

// LaCAM*'s transition cost: the robots not resting at their goals (sum of
// loss: a robot waiting at its goal costs nothing, as after its last
// arrival).
int64_t Loss(const Instance& inst, const std::vector<uint32_t>& from,
             const std::vector<uint32_t>& to) {
  int64_t loss = 0;
  for (size_t i = 0; i < from.size(); ++i) {
    if (from[i] != inst.goals[i] || to[i] != inst.goals[i]) ++loss;
  }
  return loss;
}

int64_t Estimate(const Instance& inst, const std::vector<uint32_t>& config) {
  int64_t h = 0;
  for (size_t i = 0; i < config.size(); ++i) h += inst.h[i][config[i]];
  return h;
}

}  // namespace

FleetPlan SolveLacam(const Instance& inst, const FleetOptions& options,
                     const StopCondition& stop) {
  FleetPlan plan;
  const size_t n = inst.robots();
  std::mt19937_64 rng(options.seed);
  const std::vector<double> tie = TieBreaks(inst, rng);
  PibtStep step(inst, rng());
  std::vector<Constraint> constraints{{-1, 0, 0, 0}};  // the shared root
  // A deque: growing never moves (or, std::deque having no noexcept move,
  // copies) the nodes already stored.
  std::deque<HighNode> nodes;
  absl::flat_hash_map<std::vector<uint32_t>, int32_t> explored;
  std::vector<int32_t> open;

  auto add = [&](std::vector<uint32_t> config, int32_t parent,
                 const std::vector<double>& parent_prio) {
    HighNode node;
    if (parent >= 0) {
      node.g = nodes[parent].g + Loss(inst, nodes[parent].config, config);
    }
    node.h = Estimate(inst, config);
    node.prio = parent_prio;
    UpdatePriorities(inst, config, tie, &node.prio);
    node.order = OrderOf(node.prio);
    node.config = std::move(config);
    node.tree.push_back(0);
    node.parent = parent;
    node.depth = parent < 0 ? 0 : nodes[parent].depth + 1;
    const auto id = static_cast<int32_t>(nodes.size());
    explored.emplace(node.config, id);
    nodes.push_back(std::move(node));
    if (parent >= 0) nodes[parent].neighbors.push_back(id);
    open.push_back(id);
  };
  // LaCAM*: the goal configuration's node once reached (its g only falls).
  int32_t goal_node = -1;
  auto finish = [&](PlanOutcome outcome) {
    plan.outcome = outcome;
    plan.expansions = step.calls();
    if (goal_node < 0) return plan;
    std::vector<std::vector<uint32_t>> configs;
    for (int32_t at = goal_node; at >= 0; at = nodes[at].parent) {
      configs.push_back(nodes[at].config);
    }
    std::reverse(configs.begin(), configs.end());
    SetPaths(inst, PathsOf(configs), &plan);
    return plan;
  };
  // LaCAM*: a shorter way into `from` was found; carry it on to every node
  // reached from there (Dijkstra over the explored graph). Every edge but a
  // configuration's loop to itself costs at least one, so parents stay
  // acyclic.
  auto rewire = [&](int32_t from) {
    using Entry = std::pair<int64_t, int32_t>;
    std::priority_queue<Entry, std::vector<Entry>, std::greater<>> queue;
    queue.push({nodes[from].g, from});
    while (!queue.empty()) {
      const auto [g, u] = queue.top();
      queue.pop();
      if (g != nodes[u].g) continue;
      for (const int32_t v : nodes[u].neighbors) {
        const int64_t ng = g + Loss(inst, nodes[u].config, nodes[v].config);
        if (ng >= nodes[v].g) continue;
        nodes[v].g = ng;
        nodes[v].parent = u;
        queue.push({ng, v});
        if (goal_node >= 0 && ng + nodes[v].h < nodes[goal_node].g) {
          open.push_back(v);
        }
      }
    }
  };
  {
    // Initial priorities: farther robots first.
    std::vector<double> prio(n);
    for (size_t i = 0; i < n; ++i) {
      prio[i] = static_cast<double>(inst.h[i][inst.starts[i]]) /
                    static_cast<double>(inst.cells) +
                tie[i] * 1e-9 - 1.0;
    }
    add(inst.starts, -1, prio);
  }
  bool horizon_hit = false;
  std::vector<uint32_t> next;
  std::vector<std::pair<size_t, uint32_t>> fixed;
  while (!open.empty()) {
    // An iteration runs PIBT over every robot (and, refining, may rewire
    // much of the explored graph): read the clock every 64 iterations, not
    // every 1024 as Check would.
    const PlanOutcome o =
        stop.max_expansions() > 0 && plan.iterations >= stop.max_expansions()
            ? PlanOutcome::kExpansionLimit
        : (plan.iterations & 63) == 0 ? stop.Poll(plan.iterations)
                                      : PlanOutcome::kFound;
    if (o != PlanOutcome::kFound) {
      return finish(o);  // with the best plan so far when refining
    }
    const int32_t id = open.back();
    if (goal_node < 0 && nodes[id].config == inst.goals) {
      goal_node = id;
      if (!options.refine) return finish(PlanOutcome::kFound);
    }
    // LaCAM*: nothing through this node can beat the plan in hand.
    if (goal_node >= 0 && nodes[goal_node].g <= nodes[id].g + nodes[id].h) {
      open.pop_back();
      continue;
    }
    if (nodes[id].tree.empty()) {
      open.pop_back();
      continue;
    }
    const int32_t c = nodes[id].tree.front();
    nodes[id].tree.pop_front();
    const Constraint con = constraints[c];
    if (con.depth < static_cast<int32_t>(n)) {
      const size_t i = nodes[id].order[con.depth];
      const uint32_t u = nodes[id].config[i];
      std::vector<uint32_t> cands{u};
      inst.graph(i).ForEachMove(u, [&](uint32_t v) { cands.push_back(v); });
      std::shuffle(cands.begin(), cands.end(), rng);
      for (const uint32_t v : cands) {
        constraints.push_back(
            Constraint{c, con.depth + 1, static_cast<uint32_t>(i), v});
        nodes[id].tree.push_back(static_cast<int32_t>(constraints.size()) - 1);
      }
    }
    fixed.clear();
    for (int32_t at = c; constraints[at].depth > 0;
         at = constraints[at].parent) {
      fixed.emplace_back(constraints[at].who, constraints[at].where);
    }
    ++plan.iterations;
    if (!step.Run(nodes[id].config, fixed, nodes[id].order, &next)) continue;
    if (const auto it = explored.find(next); it != explored.end()) {
      // Back to a known configuration: search on from it (LaCAM*'s
      // reinsertion; each push follows a consumed constraint, so the search
      // still ends).
      nodes[id].neighbors.push_back(it->second);
      open.push_back(it->second);
      if (options.refine) {
        const int64_t ng = nodes[id].g + Loss(inst, nodes[id].config, next);
        if (ng < nodes[it->second].g) {
          nodes[it->second].g = ng;
          nodes[it->second].parent = id;
          rewire(it->second);
        }
      }
      continue;
    }
    if (inst.max_steps_given && nodes[id].depth + 1 > inst.max_steps) {
      horizon_hit = true;
      continue;
    }
    if (SearchBytes(nodes.size() + 1, n, constraints.size()) >
        kMaxSearchBytes) {
      return finish(PlanOutcome::kExpansionLimit);
    }
    const std::vector<double> prio = nodes[id].prio;
    add(next, id, prio);
  }
  // Every configuration reachable within max_steps was explored: the plan
  // in hand (refining) has the least sum of loss, or there is none.
  if (goal_node >= 0) return finish(PlanOutcome::kFound);
  return finish(horizon_hit ? PlanOutcome::kExpansionLimit
                            : PlanOutcome::kNoPath);
}

}  // namespace pathd::mapf_internal
