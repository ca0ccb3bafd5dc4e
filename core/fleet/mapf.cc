// PlanFleet: input checks, the shared instance (move graphs, distance
// tables), the dispatch to a solver, and prioritized planning (Silver,
// "Cooperative Pathfinding", 2005).
#include "core/fleet/mapf.h"

#include <algorithm>
#include <numeric>
#include <random>
#include <utility>

#include "absl/container/flat_hash_map.h"
#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "core/fleet/mapf_internal.h"

namespace pathd {

std::string_view FleetSolverName(FleetSolver solver) {
  switch (solver) {
    case FleetSolver::kPrioritized:
      return "prioritized";
    case FleetSolver::kCbs:
      return "cbs";
    case FleetSolver::kLacam:
      return "lacam";
    case FleetSolver::kPibt:
      return "pibt";
  }
  return "unknown";
}

namespace mapf_internal {

FleetPlan SolvePrioritized(const Instance& inst, const FleetOptions& options,
                           const StopCondition& stop) {
  FleetPlan plan;
  const size_t n = inst.robots();
  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::mt19937_64 rng(options.seed);
  int64_t expansions = 0;
  // One robot's search may not take the whole deadline on a goal that an
  // earlier robot walls in: past this budget the order fails and the next
  // one is tried.
  const int64_t budget =
      std::max<int64_t>(100000, 8 * static_cast<int64_t>(inst.cells));
  PlanOutcome last_failure = PlanOutcome::kExpansionLimit;
  for (int32_t attempt = 0; attempt <= std::max(0, options.restarts);
       ++attempt) {
    if (attempt > 0) std::shuffle(order.begin(), order.end(), rng);
    ++plan.iterations;
    SweepTable reserved(inst.cells);
    // Every robot is at its start at t = 0, so no earlier robot may sweep a
    // later one's start during step 0 (Silver's planner otherwise walks
    // into robots it has not planned yet).
    for (size_t i = 0; i < n; ++i) reserved.AddTimed(inst.starts[i], 0, +1);
    std::vector<IndexPath> paths(n);
    bool ok = true;
    for (const size_t i : order) {
      reserved.AddTimed(inst.starts[i], 0, -1);
      LowLevelQuery q;
      q.graph = &inst.graph(i);
      q.h = &inst.h[i];
      q.start = inst.starts[i];
      q.goal = inst.goals[i];
      q.reserved = &reserved;
      q.max_steps = inst.max_steps;
      q.max_expansions = budget;
      LowLevelResult r = SpaceTimeSearch(q, stop, &expansions);
      if (r.outcome != PlanOutcome::kFound) {
        ok = false;
        if (r.outcome == PlanOutcome::kTimeout ||
            r.outcome == PlanOutcome::kCancelled) {
          plan.outcome = r.outcome;
          plan.expansions = expansions;
          return plan;
        }
        last_failure = PlanOutcome::kExpansionLimit;
        break;
      }
      reserved.AddPath(*q.graph, r.path);  // sweeps its start at step 0 again
      paths[i] = std::move(r.path);
    }
    if (ok) {
      SetPaths(inst, std::move(paths), &plan);
      plan.outcome = PlanOutcome::kFound;
      plan.expansions = expansions;
      return plan;
    }
  }
  // Every order failed: not a proof that no plan exists.
  plan.outcome = last_failure;
  plan.expansions = expansions;
  return plan;
}

}  // namespace mapf_internal

absl::StatusOr<FleetPlan> PlanFleet(const FleetProblem& problem,
                                    const FleetOptions& options,
                                    const StopCondition& stop) {
  using namespace mapf_internal;  // NOLINT: this file's own internals
  if (problem.robots.empty()) {
    return absl::InvalidArgumentError("robots: at least one robot is needed");
  }
  if (problem.grids.empty()) {
    return absl::InvalidArgumentError("grids: at least one grid is needed");
  }
  for (size_t k = 0; k < problem.grids.size(); ++k) {
    const Grid* g = problem.grids[k];
    if (g == nullptr || g->size() == 0) {
      return absl::InvalidArgumentError(absl::StrFormat("grids[%d]: empty", k));
    }
    if (g->width() != problem.grids[0]->width() ||
        g->height() != problem.grids[0]->height()) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "grids[%d]: %dx%d, but grids[0] is %dx%d", k, g->width(), g->height(),
          problem.grids[0]->width(), problem.grids[0]->height()));
    }
  }
  if (!(options.suboptimality >= 1.0) || options.suboptimality > 1e6) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "suboptimality: %g is not in [1, 1e6]", options.suboptimality));
  }
  if (options.max_steps < 0) {
    return absl::InvalidArgumentError(
        absl::StrFormat("max_steps: %d is negative", options.max_steps));
  }
  Instance inst;
  for (const Grid* g : problem.grids) {
    inst.graphs.emplace_back(*g, problem.connectivity, problem.unknown_is_free);
  }
  inst.cells = problem.grids[0]->size();
  absl::flat_hash_map<uint32_t, size_t> start_of, goal_of;
  for (size_t i = 0; i < problem.robots.size(); ++i) {
    const FleetRobot& r = problem.robots[i];
    if (r.grid < 0 || static_cast<size_t>(r.grid) >= problem.grids.size()) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "robots[%d].grid: %d is not a grid index", i, r.grid));
    }
    const Grid& grid = *problem.grids[r.grid];
    const MoveGraph& graph = inst.graphs[r.grid];
    for (const auto& [name, c] :
         {std::pair{"start", r.start}, {"goal", r.goal}}) {
      if (!grid.InBounds(c)) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "robots[%d].%s: %s is off the grid", i, name, CellToString(c)));
      }
      if (!graph.Open(graph.Index(c))) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "robots[%d].%s: %s is not traversable", i, name, CellToString(c)));
      }
    }
    inst.graph_of.push_back(r.grid);
    inst.starts.push_back(graph.Index(r.start));
    inst.goals.push_back(graph.Index(r.goal));
    if (const auto [it, ok] = start_of.emplace(inst.starts.back(), i); !ok) {
      return absl::InvalidArgumentError(
          absl::StrFormat("robots[%d].start: %s is also robots[%d]'s start", i,
                          CellToString(r.start), it->second));
    }
    if (const auto [it, ok] = goal_of.emplace(inst.goals.back(), i); !ok) {
      return absl::InvalidArgumentError(
          absl::StrFormat("robots[%d].goal: %s is also robots[%d]'s goal", i,
                          CellToString(r.goal), it->second));
    }
  }
  FleetPlan plan;
  int32_t longest = 0;
  BfsScratch scratch;
  for (size_t i = 0; i < inst.robots(); ++i) {
    // A table is a BFS over the whole map (milliseconds on 512 x 512).
    if (const PlanOutcome o = stop.CheckNow(); o != PlanOutcome::kFound) {
      plan.outcome = o;
      return plan;
    }
    int32_t d = kUnreachable;
    inst.h.push_back(
        inst.graph(i).DistancesTo(inst.goals[i], inst.starts[i], &d, &scratch));
    if (d == kUnreachable) {
      plan.outcome = PlanOutcome::kNoPath;  // cheap proof: no plan exists
      return plan;
    }
    inst.individual_sum += d;
    longest = std::max(longest, d);
  }
  const Grid& g0 = *problem.grids[0];
  inst.max_steps_given = options.max_steps > 0;
  inst.max_steps = options.max_steps > 0
                       ? options.max_steps
                       : std::max(2 * longest, 2 * (g0.width() + g0.height())) +
                             2 * static_cast<int32_t>(inst.robots());
  if (longest > inst.max_steps) {
    plan.outcome = PlanOutcome::kExpansionLimit;  // beyond max_steps
    plan.lower_bound = inst.individual_sum;
    return plan;
  }
  switch (options.solver) {
    case FleetSolver::kPrioritized:
      plan = SolvePrioritized(inst, options, stop);
      break;
    case FleetSolver::kCbs:
      plan = SolveCbs(inst, options, stop);
      break;
    case FleetSolver::kLacam:
      plan = SolveLacam(inst, options, stop);
      break;
    case FleetSolver::kPibt:
      plan = SolvePibt(inst, options, stop);
      break;
  }
  plan.lower_bound = std::max(plan.lower_bound, inst.individual_sum);
  if (plan.complete && plan.sum_of_costs == plan.lower_bound)
    plan.optimal = true;
  return plan;
}

}  // namespace pathd
