// An independent checker of multi-robot timed plans, written apart from
// core/fleet from the rule as mapf.h states it: every path starts at its
// robot's start and ends at its goal; each step stays or makes one move of
// the grid (4- or 8-connected, a diagonal only with both side cells
// traversable); during a step a robot sweeps its cell before and after and,
// diagonally, the two side cells; the sweeps of one step are pairwise
// disjoint over all robots, including those parked at their goals. It
// recomputes each robot's cost (its last arrival at its goal), the makespan
// and the sum of costs.
#ifndef PATHD_TESTS_TESTING_FLEET_CHECKER_H_
#define PATHD_TESTS_TESTING_FLEET_CHECKER_H_

#include <cstdint>
#include <string>
#include <vector>

#include "core/map/grid.h"

namespace pathd::testing {

struct FleetCheckRobot {
  Cell start;
  Cell goal;
  const Grid* grid = nullptr;  // the cells this robot may use
};

struct FleetCheckResult {
  bool ok = false;
  // The first problem found, naming the robot, the time and the cell.
  std::string error;
  std::vector<int64_t> costs;
  int64_t makespan = 0;
  int64_t sum_of_costs = 0;
};

FleetCheckResult CheckFleetPlan(const std::vector<FleetCheckRobot>& robots,
                                bool eight_connected, bool unknown_is_free,
                                const std::vector<std::vector<Cell>>& paths);

}  // namespace pathd::testing

#endif  // PATHD_TESTS_TESTING_FLEET_CHECKER_H_
