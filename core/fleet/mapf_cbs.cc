// Conflict-based search (Sharon, Stern, Felner & Sturtevant, "Conflict-based
// search for optimal multi-agent pathfinding", 2015) under mapf.h's conflict
// rule, with
//  - a conflict avoidance table breaking the low level's ties towards fewer
//    conflicts with the other robots' current paths;
//  - conflict prioritization (Boyarski et al., "ICBS: Improved conflict-based
//    search algorithm for multi-agent pathfinding", 2015): cardinal before
//    semi-cardinal before non-cardinal, judged on each robot's MDD;
//  - bypass (Boyarski et al., "Don't split, try to work it out: bypassing
//    conflicts in multi-agent pathfinding", 2015): a child whose cost equals
//    its parent's and has fewer conflicts gives its path to the parent
//    instead of splitting;
//  - ECBS (Barer, Sharon, Stern & Felner, "Suboptimal variants of the
//    conflict-based search algorithm for the multi-agent pathfinding
//    problem", 2014) when suboptimality w > 1: focal search at both levels,
//    the plan's sum of costs within w of the high level's lower bound.
#include <algorithm>
#include <memory>
#include <set>
#include <tuple>
#include <utility>

#include "core/fleet/mapf_internal.h"

namespace pathd::mapf_internal {
namespace {

// A CBS constraint: `robot` may not sweep `cell` during step t. Nodes share
// their ancestors' constraints through the chain.
struct ConstraintLink {
  size_t robot;
  uint32_t cell;
  int32_t t;
  std::shared_ptr<const ConstraintLink> parent;
};

// Multi-valued decision diagram of one robot: levels[t] = the cells some
// cost-optimal path (under its constraints) is at at time t, sorted.
struct Mdd {
  std::vector<std::vector<uint32_t>> levels;
};

struct Conflict {
  size_t i;
  size_t j;
  uint32_t cell;
  int32_t t;
};

struct CbsNode {
  std::vector<std::shared_ptr<const IndexPath>> paths;
  std::vector<int32_t> costs;
  std::vector<int32_t> lbs;
  std::vector<std::shared_ptr<const Mdd>> mdds;  // null until built
  std::shared_ptr<const ConstraintLink> constraints;
  int64_t cost = 0;
  int64_t lb = 0;
  int32_t conflicts = 0;
};

ConstraintSet ConstraintsOf(const CbsNode& node, size_t robot, size_t cells) {
  ConstraintSet set;
  for (const ConstraintLink* c = node.constraints.get(); c != nullptr;
       c = c->parent.get()) {
    if (c->robot == robot) set.Add(c->cell, c->t, cells);
  }
  return set;
}

// Every pair of robots whose sweeps meet, once per pair and step (the first
// shared cell), in step order.
std::vector<Conflict> FindConflicts(
    const Instance& inst,
    const std::vector<std::shared_ptr<const IndexPath>>& paths) {
  std::vector<Conflict> out;
  int32_t makespan = 0;
  for (const auto& p : paths) {
    makespan = std::max(makespan, static_cast<int32_t>(p->size()) - 1);
  }
  absl::flat_hash_map<uint32_t, size_t> owner;
  for (int32_t t = 0; t < makespan; ++t) {
    owner.clear();
    for (size_t i = 0; i < paths.size(); ++i) {
      const Sweep s = SweepAt(inst.graph(i), *paths[i], t);
      size_t reported = paths.size();
      for (int k = 0; k < s.n; ++k) {
        const auto [it, fresh] = owner.try_emplace(s.cells[k], i);
        if (!fresh && it->second != i && it->second != reported) {
          out.push_back(Conflict{it->second, i, s.cells[k], t});
          reported = it->second;
        }
      }
    }
  }
  return out;
}

Mdd BuildMdd(const Instance& inst, size_t robot, const ConstraintSet& cons,
             int32_t cost) {
  const MoveGraph& g = inst.graph(robot);
  const DistanceTable& h = inst.h[robot];
  Mdd mdd;
  mdd.levels.resize(cost + 1);
  mdd.levels[0] = {inst.starts[robot]};
  // Forward: cells reachable at t that can still reach the goal by `cost`.
  for (int32_t t = 0; t < cost; ++t) {
    absl::flat_hash_set<uint32_t> next;
    for (const uint32_t u : mdd.levels[t]) {
      auto step = [&](uint32_t v) {
        if (t + 1 + h[v] > cost) return;
        if (cons.Blocks(g.SweepOf(u, v), t, inst.cells)) return;
        next.insert(v);
      };
      step(u);
      g.ForEachMove(u, step);
    }
    mdd.levels[t + 1].assign(next.begin(), next.end());
    std::sort(mdd.levels[t + 1].begin(), mdd.levels[t + 1].end());
  }
  // Backward: keep the cells with a kept successor, ending at the goal.
  mdd.levels[cost] = {inst.goals[robot]};
  for (int32_t t = cost - 1; t >= 0; --t) {
    const std::vector<uint32_t>& later = mdd.levels[t + 1];
    std::vector<uint32_t> kept;
    for (const uint32_t u : mdd.levels[t]) {
      bool any = false;
      auto step = [&](uint32_t v) {
        if (any || !std::binary_search(later.begin(), later.end(), v)) return;
        if (!cons.Blocks(g.SweepOf(u, v), t, inst.cells)) any = true;
      };
      step(u);
      g.ForEachMove(u, step);
      if (any) kept.push_back(u);
    }
    mdd.levels[t] = std::move(kept);
  }
  return mdd;
}

// Whether every cost-optimal path of the robot sweeps `cell` during step t
// (judged on width-1 levels; parked at the goal past the MDD's end).
bool Forced(const Instance& inst, size_t robot, const Mdd& mdd, uint32_t cell,
            int32_t t) {
  const int32_t last = static_cast<int32_t>(mdd.levels.size()) - 1;
  const std::vector<uint32_t>& a = mdd.levels[std::min(t, last)];
  const std::vector<uint32_t>& b = mdd.levels[std::min(t + 1, last)];
  if (a.size() == 1 && a[0] == cell) return true;
  if (b.size() == 1 && b[0] == cell) return true;
  if (a.size() == 1 && b.size() == 1) {
    return inst.graph(robot).SweepOf(a[0], b[0]).Touches(cell);
  }
  return false;
}

class Cbs {
 public:
  Cbs(const Instance& inst, const FleetOptions& options,
      const StopCondition& stop)
      : inst_(inst), w_(options.suboptimality), stop_(stop) {}

  FleetPlan Run();

 private:
  // Replans `robot` in `node` under its constraints, avoiding the others'
  // paths; false when it has no path (or the stop condition fired).
  bool Replan(CbsNode* node, size_t robot);
  void Push(std::unique_ptr<CbsNode> node);
  const Mdd& MddOf(CbsNode* node, size_t robot);

  const Instance& inst_;
  const double w_;
  const StopCondition& stop_;
  int64_t expansions_ = 0;
  PlanOutcome stopped_ = PlanOutcome::kFound;
  std::vector<std::unique_ptr<CbsNode>> nodes_;
  std::set<std::pair<int64_t, size_t>> open_;  // (lb, id)
  std::set<std::pair<int64_t, size_t>>
      pending_;  // open, not in focal: (cost, id)
  std::set<std::tuple<int32_t, int64_t, size_t>>
      focal_;  // (conflicts, cost, id)
  double bound_ = -1.0;
};

bool Cbs::Replan(CbsNode* node, size_t robot) {
  SweepTable avoid(inst_.cells);
  for (size_t k = 0; k < node->paths.size(); ++k) {
    if (k != robot && node->paths[k] != nullptr) {
      avoid.AddPath(inst_.graph(k), *node->paths[k]);
    }
  }
  const ConstraintSet cons = ConstraintsOf(*node, robot, inst_.cells);
  LowLevelQuery q;
  q.graph = &inst_.graph(robot);
  q.h = &inst_.h[robot];
  q.start = inst_.starts[robot];
  q.goal = inst_.goals[robot];
  q.constraints = &cons;
  q.avoid = &avoid;
  q.max_steps = inst_.max_steps;
  q.w = w_;
  LowLevelResult r = SpaceTimeSearch(q, stop_, &expansions_);
  if (r.outcome != PlanOutcome::kFound) {
    if (r.outcome != PlanOutcome::kNoPath) stopped_ = r.outcome;
    return false;
  }
  TrimPath(&r.path);
  node->paths[robot] = std::make_shared<const IndexPath>(std::move(r.path));
  node->costs[robot] = static_cast<int32_t>(node->paths[robot]->size()) - 1;
  node->lbs[robot] = std::min(r.lower_bound, node->costs[robot]);
  node->mdds[robot] = nullptr;
  return true;
}

const Mdd& Cbs::MddOf(CbsNode* node, size_t robot) {
  if (node->mdds[robot] == nullptr) {
    node->mdds[robot] = std::make_shared<const Mdd>(
        BuildMdd(inst_, robot, ConstraintsOf(*node, robot, inst_.cells),
                 node->costs[robot]));
  }
  return *node->mdds[robot];
}

void Cbs::Push(std::unique_ptr<CbsNode> node) {
  node->cost = 0;
  int64_t lb = 0;
  for (size_t i = 0; i < node->costs.size(); ++i) {
    node->cost += node->costs[i];
    lb += node->lbs[i];
  }
  // A parent's bound holds for its whole subtree.
  node->lb = std::max(node->lb, lb);
  node->conflicts =
      static_cast<int32_t>(FindConflicts(inst_, node->paths).size());
  const size_t id = nodes_.size();
  open_.emplace(node->lb, id);
  if (static_cast<double>(node->cost) <= bound_) {
    focal_.emplace(node->conflicts, node->cost, id);
  } else {
    pending_.emplace(node->cost, id);
  }
  nodes_.push_back(std::move(node));
}

FleetPlan Cbs::Run() {
  FleetPlan plan;
  const size_t n = inst_.robots();
  auto root = std::make_unique<CbsNode>();
  root->paths.resize(n);
  root->costs.assign(n, 0);
  root->lbs.assign(n, 0);
  root->mdds.resize(n);
  for (size_t i = 0; i < n; ++i) {
    if (!Replan(root.get(), i)) {
      plan.outcome =
          stopped_ != PlanOutcome::kFound ? stopped_ : PlanOutcome::kNoPath;
      plan.expansions = expansions_;
      return plan;
    }
  }
  Push(std::move(root));
  while (!open_.empty()) {
    const int64_t lb_min = open_.begin()->first;
    plan.lower_bound = lb_min;
    if (const PlanOutcome o = stop_.CheckNow(); o != PlanOutcome::kFound) {
      stopped_ = o;
      break;
    }
    const double new_bound = w_ * static_cast<double>(lb_min) + 1e-9;
    if (new_bound > bound_) {
      bound_ = new_bound;
      while (!pending_.empty() &&
             static_cast<double>(pending_.begin()->first) <= bound_) {
        const size_t id = pending_.begin()->second;
        pending_.erase(pending_.begin());
        focal_.emplace(nodes_[id]->conflicts, nodes_[id]->cost, id);
      }
    }
    // Open nodes hold a path and an MDD pointer, a cost and a bound per
    // robot (about 40 bytes; the paths mostly shared): past 2^23 such
    // entries (about 0.3 GiB plus the paths) give up rather than grow
    // without bound.
    if (static_cast<int64_t>(open_.size()) *
            static_cast<int64_t>(inst_.robots()) >
        (int64_t{1} << 23)) {
      stopped_ = PlanOutcome::kExpansionLimit;
      break;
    }
    const size_t id = std::get<2>(*focal_.begin());
    focal_.erase(focal_.begin());
    std::unique_ptr<CbsNode> node = std::move(nodes_[id]);
    open_.erase({node->lb, id});
    ++plan.iterations;
    const std::vector<Conflict> conflicts = FindConflicts(inst_, node->paths);
    if (conflicts.empty()) {
      std::vector<IndexPath> paths;
      for (const auto& p : node->paths) paths.push_back(*p);
      SetPaths(inst_, std::move(paths), &plan);
      plan.outcome = PlanOutcome::kFound;
      plan.optimal = w_ == 1.0;
      plan.lower_bound = w_ == 1.0 ? node->cost : std::min(lb_min, node->cost);
      plan.expansions = expansions_;
      return plan;
    }
    // Conflict prioritization on the MDDs (optimal CBS only: under focal
    // search the paths are not cost-optimal, so MDDs say nothing of them).
    Conflict chosen = conflicts.front();
    if (w_ == 1.0) {
      int best = -1;
      for (const Conflict& c : conflicts) {
        const int rank =
            (Forced(inst_, c.i, MddOf(node.get(), c.i), c.cell, c.t) ? 1 : 0) +
            (Forced(inst_, c.j, MddOf(node.get(), c.j), c.cell, c.t) ? 1 : 0);
        if (rank > best) {
          best = rank;
          chosen = c;
          if (rank == 2) break;
        }
      }
    }
    std::vector<std::unique_ptr<CbsNode>> children;
    bool bypassed = false;
    for (const size_t robot : {chosen.i, chosen.j}) {
      auto child = std::make_unique<CbsNode>(*node);
      child->constraints = std::make_shared<const ConstraintLink>(
          ConstraintLink{robot, chosen.cell, chosen.t, node->constraints});
      if (!Replan(child.get(), robot)) {
        if (stopped_ != PlanOutcome::kFound) break;
        continue;  // this branch has no plan
      }
      if (w_ == 1.0 && child->costs[robot] == node->costs[robot]) {
        // Bypass: the same cost with fewer conflicts replaces the parent's
        // path (the child's path also meets the parent's constraints).
        const auto fewer =
            static_cast<int32_t>(FindConflicts(inst_, child->paths).size());
        if (fewer < node->conflicts) {
          node->paths[robot] = child->paths[robot];
          node->mdds[robot] = nullptr;
          bypassed = true;
          break;
        }
      }
      children.push_back(std::move(child));
    }
    if (stopped_ != PlanOutcome::kFound) break;
    if (bypassed) {
      Push(std::move(node));
      continue;
    }
    for (auto& child : children) Push(std::move(child));
  }
  plan.outcome =
      stopped_ != PlanOutcome::kFound ? stopped_ : PlanOutcome::kNoPath;
  if (!open_.empty()) plan.lower_bound = open_.begin()->first;
  plan.expansions = expansions_;
  return plan;
}

}  // namespace

FleetPlan SolveCbs(const Instance& inst, const FleetOptions& options,
                   const StopCondition& stop) {
  return Cbs(inst, options, stop).Run();
}

}  // namespace pathd::mapf_internal
