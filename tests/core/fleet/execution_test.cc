// core/fleet/execution.h: robots executing PlanFleet's plans at random
// speeds, one event at a time (a robot starts a move it is released for, or
// finishes one and reports its cell), checked after every event by this
// file's own occupancy rule: a standing robot holds its cell, a moving one
// the cells of its move (both ends and, diagonally, the two side cells); no
// cell is ever held twice. Every robot must reach its goal (the schedule
// never deadlocks), also when robots leave half way. Random instances:
// PATHD_EXECUTION_CASES (default 300; the ASan run takes fewer).
#include "core/fleet/execution.h"

#include <algorithm>
#include <cstdlib>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "absl/time/time.h"
#include "core/fleet/mapf.h"
#include "core/map/grid.h"
#include "gtest/gtest.h"

namespace pathd {
namespace {

int EnvInt(const char* name, int fallback) {
  const char* v = std::getenv(name);
  return v != nullptr ? std::atoi(v) : fallback;
}

// The cells a robot holds: standing at `from` (to == from) or moving.
std::vector<std::pair<int, int>> Held(Cell from, Cell to) {
  std::vector<std::pair<int, int>> held = {{from.x, from.y}};
  if (to.x == from.x && to.y == from.y) return held;
  held.push_back({to.x, to.y});
  if (to.x != from.x && to.y != from.y) {
    held.push_back({from.x, to.y});
    held.push_back({to.x, from.y});
  }
  return held;
}

struct Robot {
  int64_t at = 0;       // index it stands at (or leaves)
  bool moving = false;  // on its way to at + 1
  bool gone = false;
};

// Runs the plan event by event; returns "" or what went wrong.
std::string Execute(const std::vector<std::vector<Cell>>& paths, int width,
                    std::mt19937& rng, double leave_chance) {
  FleetSchedule schedule(paths, width);
  std::vector<Robot> robots(paths.size());
  const int n = static_cast<int>(paths.size());
  int64_t events = 0;
  int64_t total_steps = 0;
  for (const auto& p : paths) total_steps += static_cast<int64_t>(p.size());
  std::uniform_int_distribution<int> pick(0, n - 1);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (;;) {
    // Which robots can do something: finish a move, or start a released one.
    std::vector<int> able;
    bool all_done = true;
    for (int r = 0; r < n; ++r) {
      if (robots[r].gone) continue;
      const bool at_goal =
          robots[r].at + 1 == static_cast<int64_t>(paths[r].size());
      if (!at_goal || robots[r].moving) all_done = false;
      if (robots[r].moving || schedule.Release(r) > robots[r].at)
        able.push_back(r);
    }
    if (all_done) return "";
    if (able.empty())
      return absl::StrFormat("deadlock after %d events", events);
    if (++events > 20 * total_steps + 100) return "no end in sight";
    const int r =
        able[std::uniform_int_distribution<size_t>(0, able.size() - 1)(rng)];
    Robot& robot = robots[r];
    if (robot.moving) {
      robot.moving = false;
      ++robot.at;
      if (!schedule.Report(r, paths[r][robot.at])) {
        return absl::StrFormat("robot %d's report of index %d was refused", r,
                               robot.at);
      }
      if (schedule.progress(r) < robot.at) {
        return absl::StrFormat("robot %d at index %d has progress %d", r,
                               robot.at, schedule.progress(r));
      }
      // Waits it was released through count as done.
      robot.at = schedule.progress(r);
      if (leave_chance > 0 && unit(rng) < leave_chance) {
        robot.gone = true;
        schedule.Remove(r);
      }
    } else {
      robot.moving = true;
    }
    // The independent occupancy rule.
    std::set<std::pair<int, int>> held;
    for (int q = 0; q < n; ++q) {
      if (robots[q].gone) continue;
      const Cell from = paths[q][robots[q].at];
      const Cell to = robots[q].moving ? paths[q][robots[q].at + 1] : from;
      for (const auto& c : Held(from, to)) {
        if (!held.insert(c).second) {
          return absl::StrFormat(
              "after %d events cell (%d, %d) is held twice (robot %d)", events,
              c.first, c.second, q);
        }
      }
    }
  }
}

Grid RandomGrid(std::mt19937& rng, int w, int h, double obstacles) {
  Grid g = Grid::Create(w, h).value();
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      if (unit(rng) < obstacles) g.set_cost(x, y, kLethalCost);
    }
  }
  return g;
}

TEST(FleetScheduleTest, TheRobotPlannedSecondThroughACellWaitsForTheFirst) {
  // Robot 0 crosses (2, 1) at step 2; robot 1 waits, then goes through it.
  const std::vector<std::vector<Cell>> paths = {
      {{0, 1}, {1, 1}, {2, 1}, {3, 1}, {4, 1}},
      {{2, 3}, {2, 3}, {2, 3}, {2, 2}, {2, 1}, {2, 0}},
  };
  FleetSchedule schedule(paths, 5);
  EXPECT_EQ(schedule.Release(0), 4);
  // Robot 1 may go up to (2, 2) but not into (2, 1) before robot 0 is past.
  EXPECT_EQ(schedule.Release(1), 3);
  ASSERT_TRUE(schedule.Report(1, {2, 2}));
  EXPECT_EQ(schedule.progress(1), 3);
  EXPECT_EQ(schedule.Release(1), 3);
  ASSERT_TRUE(schedule.Report(0, {2, 1}));
  EXPECT_EQ(schedule.Release(1), 3);  // robot 0 still stands in it
  ASSERT_TRUE(schedule.Report(0, {3, 1}));
  EXPECT_EQ(schedule.Release(1), 5);
  // A cell off the released stretch is a robot off its plan.
  EXPECT_FALSE(schedule.Report(0, {0, 0}));
  EXPECT_EQ(schedule.progress(0), 3);
}

TEST(FleetScheduleTest, AGoalHoldsEveryoneLaterForEver) {
  // Robot 0 parks at (1, 0); robot 1's plan never goes there, robot 2's
  // plan passes it before robot 0 arrives, so robot 0 waits for robot 2.
  const std::vector<std::vector<Cell>> paths = {
      {{0, 0}, {0, 0}, {0, 0}, {1, 0}},
      {{2, 2}},
      {{1, 1}, {1, 0}, {2, 0}},
  };
  FleetSchedule schedule(paths, 3);
  EXPECT_EQ(schedule.Release(0), 2);
  EXPECT_EQ(schedule.Release(2), 2);
  ASSERT_TRUE(schedule.Report(2, {1, 0}));
  EXPECT_EQ(schedule.Release(0), 2);
  ASSERT_TRUE(schedule.Report(2, {2, 0}));
  EXPECT_EQ(schedule.Release(0), 3);
  EXPECT_TRUE(schedule.arrived(2));
}

TEST(FleetScheduleTest, ALeavingRobotHoldsNobodyBack) {
  const std::vector<std::vector<Cell>> paths = {
      {{0, 1}, {1, 1}, {2, 1}, {3, 1}},
      {{1, 0}, {1, 0}, {1, 0}, {1, 1}, {1, 2}},
  };
  FleetSchedule schedule(paths, 4);
  EXPECT_EQ(schedule.Release(1), 2);
  schedule.Remove(0);
  EXPECT_EQ(schedule.Release(1), 4);
}

TEST(FleetScheduleTest, RandomPlansExecuteAtRandomSpeedsWithoutSharingACell) {
  const int cases = EnvInt("PATHD_EXECUTION_CASES", 300);
  std::mt19937 rng(20261203);
  int executed = 0;
  for (int c = 0; c < cases; ++c) {
    const int w = std::uniform_int_distribution<int>(6, 20)(rng);
    const int h = std::uniform_int_distribution<int>(6, 20)(rng);
    Grid grid = RandomGrid(rng, w, h, 0.2);
    std::vector<Cell> free;
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        if (Traversable(grid.cost(x, y), false)) free.push_back({x, y});
      }
    }
    const int n = std::min<int>(std::uniform_int_distribution<int>(2, 16)(rng),
                                static_cast<int>(free.size()) / 2);
    if (n < 2) continue;
    std::shuffle(free.begin(), free.end(), rng);
    FleetProblem problem;
    problem.grids = {&grid};
    problem.connectivity =
        c % 2 == 0 ? Connectivity::kEight : Connectivity::kFour;
    for (int r = 0; r < n; ++r)
      problem.robots.push_back({free[r], free[n + r], 0});
    FleetOptions options;
    options.solver =
        c % 3 == 0 ? FleetSolver::kPrioritized : FleetSolver::kLacam;
    options.seed = static_cast<uint64_t>(c);
    const StopCondition stop(absl::Now() + absl::Seconds(5), nullptr,
                             2'000'000);
    absl::StatusOr<FleetPlan> plan = PlanFleet(problem, options, stop);
    ASSERT_TRUE(plan.ok()) << plan.status();
    if (!plan->complete) continue;
    const double leave = c % 4 == 3 ? 0.05 : 0.0;
    for (int run = 0; run < 3; ++run) {
      const std::string error = Execute(plan->paths, w, rng, leave);
      ASSERT_EQ(error, "") << "case " << c << " run " << run << ": " << n
                           << " robots on " << w << " x " << h;
    }
    ++executed;
  }
  EXPECT_GT(executed, cases / 2);
}

}  // namespace
}  // namespace pathd
