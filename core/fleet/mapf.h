// Conflict-free timed paths for many robots on one grid (multi-agent path
// finding): prioritized planning with a reservation table (Silver,
// "Cooperative Pathfinding", 2005), conflict-based search (Sharon, Stern,
// Felner & Sturtevant, "Conflict-based search for optimal multi-agent
// pathfinding", 2015) and PIBT / LaCAM (Okumura et al., "Priority inheritance
// with backtracking for iterative multi-agent path finding", 2022; Okumura,
// "LaCAM: Search-based algorithm for quick multi-agent pathfinding", 2023).
// Pure functions of the grids; thread-compatible.
//
// The model. Time is discrete; at each step every robot stays or makes one
// legal move of the grid's cost model (4- or 8-connected, no corner cutting
// past blocked cells), one step per move, diagonal or straight. A robot's
// timed path lists its cell at t = 0, 1, ...; after its last entry it stays
// at its goal forever. During the step t -> t+1 a robot sweeps its cell at t,
// its cell at t+1 and, for a diagonal move, the two cells beside the move
// (a robot one cell wide passes within 0.71 cells of their centres). Two
// robots conflict when their swept cells of one step share a cell. That one
// rule forbids vertex conflicts (one cell at one time), edge conflicts
// (swaps), following conflicts (entering a cell another robot leaves in the
// same step) and diagonal moves crossing or grazing another robot.
//
// Costs are in steps: a robot's cost is the time it reaches its goal for the
// last time (trailing waits at the goal are free); the sum of costs adds
// them; the makespan is the largest.
#ifndef PATHD_CORE_FLEET_MAPF_H_
#define PATHD_CORE_FLEET_MAPF_H_

#include <cstdint>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/types/span.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/search/plan_types.h"
#include "core/search/stop_condition.h"

namespace pathd {

enum class FleetSolver {
  // Space-time A* per robot in priority order against a reservation table;
  // on failure the order is shuffled and tried again (restarts). Incomplete.
  kPrioritized,
  // Conflict-based search: optimal sum of costs; with suboptimality > 1,
  // ECBS (focal search) bounded by that factor.
  kCbs,
  // LaCAM over configurations with PIBT as the successor generator:
  // complete. Returns its first plan, or with FleetOptions::refine goes on
  // as LaCAM*, refining towards optimal until the stop condition fires.
  kLacam,
  // PIBT alone, one configuration per step up to max_steps: fastest,
  // incomplete.
  kPibt,
};

std::string_view FleetSolverName(FleetSolver solver);

struct FleetRobot {
  Cell start;
  Cell goal;
  // Index into FleetProblem::grids: the grid this robot's centre may use
  // (the server passes one grid per distinct radius, inflated for it).
  int32_t grid = 0;
};

struct FleetOptions {
  FleetSolver solver = FleetSolver::kLacam;
  // kPrioritized: orders tried after the first (given) one.
  int32_t restarts = 10;
  // kCbs: 1 = optimal; w > 1 = ECBS, sum of costs within w of optimal.
  double suboptimality = 1.0;
  // kLacam: after the first plan, keep improving it (LaCAM*) until the stop
  // condition fires (outcome kTimeout etc. with the best plan, complete) or
  // the search is exhausted (kFound; least sum of loss, the cost that
  // counts waits at the goal as free even before a robot leaves again).
  // Without a deadline or budget a refining call can run very long.
  bool refine = false;
  // Seed of every random choice (priority orders, tie breaks): equal inputs
  // give equal plans.
  uint64_t seed = 1;
  // Longest timed path a solver may return (kPibt runs at most this many
  // steps; space-time searches do not look beyond it). 0 = the solver's
  // default, a bound derived from the map size and the robot count.
  int32_t max_steps = 0;
};

// All robots share one time line; grids must all have the same size.
struct FleetProblem {
  std::vector<const Grid*> grids;
  Connectivity connectivity = Connectivity::kEight;
  bool unknown_is_free = false;
  std::vector<FleetRobot> robots;
};

struct FleetPlan {
  // kFound: `paths` is a conflict-free plan for every robot (`complete`).
  // kNoPath: proved unsolvable (a robot's goal unreachable on its grid, or a
  // solver that exhausted its space). kExpansionLimit also when an
  // incomplete solver gave up: kPrioritized after every order, kPibt at
  // max_steps. kTimeout / kCancelled /
  // kExpansionLimit: the stop condition fired; `paths` then holds the best
  // plan found so far when one was (complete = true; not proved optimal), or
  // is empty.
  PlanOutcome outcome = PlanOutcome::kNoPath;
  bool complete = false;
  // True when the sum of costs is proved optimal (kCbs with suboptimality 1
  // that finished, or any plan whose cost equals the lower bound).
  bool optimal = false;
  // paths[i][t] is robot i's cell at time t; paths[i].front() == its start,
  // paths[i].back() == its goal.
  std::vector<std::vector<Cell>> paths;
  int64_t makespan = 0;
  int64_t sum_of_costs = 0;
  // A proved lower bound on the optimal sum of costs: at least the sum of
  // the robots' individual shortest paths in steps; kCbs raises it to its
  // best open node's cost. 0 when the stop condition fired while the
  // per-robot distance tables were being built (the first step of every
  // solver).
  int64_t lower_bound = 0;
  // Low-level search expansions (space-time A*, PIBT calls, LaCAM nodes).
  int64_t expansions = 0;
  // kPrioritized: priority orders tried; kCbs: constraint tree nodes
  // expanded; kLacam: configurations generated.
  int64_t iterations = 0;
};

// Preconditions (the caller validates and names them): at least one robot;
// every grid index valid; every start and goal on the grid and traversable
// on the robot's grid; starts pairwise distinct, goals pairwise distinct.
// Errors: InvalidArgument when two starts or two goals coincide, or when
// start sets violate the conflict rule at t = 0 (the same cell).
absl::StatusOr<FleetPlan> PlanFleet(const FleetProblem& problem,
                                    const FleetOptions& options,
                                    const StopCondition& stop);

}  // namespace pathd

#endif  // PATHD_CORE_FLEET_MAPF_H_
