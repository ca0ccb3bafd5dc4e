// LPA*, D* Lite and the shortest path map (core/incremental/incremental_search.h):
// the edge cases (blocked ends, bad updates, stops, memory, the
// repair-or-rebuild rule, the extraction guard).
#include "core/search/path_measure.h"
#include "core/incremental/incremental_search.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <memory>
#include <queue>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "absl/strings/str_format.h"
#include "absl/strings/str_split.h"
#include "absl/time/clock.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/incremental/engine.h"
#include "core/map_io/map_io.h"
#include "core/search/planner.h"
#include "gtest/gtest.h"
#include "tests/testing/test_grids.h"
#include "tests/core/incremental/incremental_test_util.h"

namespace pathd {
namespace {

using internal::IncrementalAccess;
using internal::MoveRules;
using namespace testing_incremental;  // NOLINT: test helpers

// ---------------------------------------------------------------------------
// Edge cases.

TEST(Incremental, StartEqualsGoal) {
  auto grid = Share(MakeGrid({"...", "...", "..."}));
  auto lpa = LpaStar::Create(grid, {1, 1}, {1, 1}, {});
  ASSERT_TRUE(lpa.ok());
  auto l = (*lpa)->Plan(StopCondition::None());
  ASSERT_TRUE(l.ok() && l->found());
  EXPECT_EQ(l->path, (std::vector<Cell>{Cell{1, 1}}));
  EXPECT_EQ(l->cost, 0.0);

  auto dstar = DStarLite::Create(grid, {1, 1}, {});
  ASSERT_TRUE(dstar.ok() && (*dstar)->SetStart({1, 1}).ok());
  auto d = (*dstar)->Plan(StopCondition::None());
  ASSERT_TRUE(d.ok() && d->found());
  EXPECT_EQ(d->path, (std::vector<Cell>{Cell{1, 1}}));
  EXPECT_EQ(d->cost, 0.0);

  auto spm = ShortestPathMap::Build(grid, {1, 1}, {}, StopCondition::None());
  ASSERT_TRUE(spm.ok());
  auto s = (*spm)->PathFrom({1, 1});
  ASSERT_TRUE(s.ok() && s->found());
  EXPECT_EQ(s->path, (std::vector<Cell>{Cell{1, 1}}));
  EXPECT_EQ((*spm)->CostToGo({1, 1}), 0.0f);
}

TEST(Incremental, GoalBlockedThenFreedAgain) {
  Grid grid = MakeGrid({".....", ".#...", "....."});
  const Cell start{0, 0}, goal{4, 2};
  auto dstar = DStarLite::Create(Share(grid), goal, {});
  auto lpa = LpaStar::Create(Share(grid), start, goal, {});
  auto spm = ShortestPathMap::Build(Share(grid), goal, {}, StopCondition::None());
  ASSERT_TRUE(dstar.ok() && lpa.ok() && spm.ok());
  ASSERT_TRUE((*dstar)->SetStart(start).ok());
  const double optimum = ReferenceCostToGo(grid, goal, {})[grid.Index(start)];
  ASSERT_TRUE((*dstar)->Plan(StopCondition::None())->found());
  ASSERT_TRUE((*lpa)->Plan(StopCondition::None())->found());

  const std::vector<Cell> changed{goal};
  grid.set_cost(goal, kLethalCost);
  auto blocked = Share(grid);
  ASSERT_TRUE((*dstar)->UpdateMap(blocked, changed).ok());
  ASSERT_TRUE((*lpa)->UpdateMap(blocked, changed).ok());
  ASSERT_TRUE((*spm)->UpdateMap(blocked, changed).ok());
  auto d = (*dstar)->Plan(StopCondition::None());
  ASSERT_TRUE(d.ok());
  EXPECT_EQ(d->outcome, PlanOutcome::kNoPath);
  auto l = (*lpa)->Plan(StopCondition::None());
  ASSERT_TRUE(l.ok());
  EXPECT_EQ(l->outcome, PlanOutcome::kNoPath);
  auto s = (*spm)->PathFrom(start);
  ASSERT_TRUE(s.ok());
  EXPECT_EQ(s->outcome, PlanOutcome::kNoPath);
  EXPECT_TRUE(std::isinf((*spm)->CostToGo(start)));

  grid.set_cost(goal, kFreeCost);
  auto freed = Share(grid);
  ASSERT_TRUE((*dstar)->UpdateMap(freed, changed).ok());
  ASSERT_TRUE((*lpa)->UpdateMap(freed, changed).ok());
  ASSERT_TRUE((*spm)->UpdateMap(freed, changed).ok());
  d = (*dstar)->Plan(StopCondition::None());
  ASSERT_TRUE(d.ok() && d->found());
  EXPECT_NEAR(d->cost, optimum, 1e-9);
  l = (*lpa)->Plan(StopCondition::None());
  ASSERT_TRUE(l.ok() && l->found());
  EXPECT_NEAR(l->cost, optimum, 1e-9);
  s = (*spm)->PathFrom(start);
  ASSERT_TRUE(s.ok() && s->found());
  EXPECT_NEAR(s->cost, optimum, 1e-9);
}

TEST(Incremental, BlockedStart) {
  Grid grid = MakeGrid({"....", ".#..", "...."});
  auto shared = Share(grid);
  EXPECT_EQ(LpaStar::Create(shared, {1, 1}, {3, 2}, {}).status().code(),
            absl::StatusCode::kInvalidArgument);
  auto dstar = DStarLite::Create(shared, {3, 2}, {});
  ASSERT_TRUE(dstar.ok());
  EXPECT_EQ((*dstar)->Plan(StopCondition::None()).status().code(),
            absl::StatusCode::kFailedPrecondition);
  ASSERT_TRUE((*dstar)->SetStart({1, 1}).ok());
  auto d = (*dstar)->Plan(StopCondition::None());
  EXPECT_EQ(d.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(d.status().message().find("start (1, 1)"), std::string::npos) << d.status();
  EXPECT_EQ((*dstar)->SetStart({4, 0}).code(), absl::StatusCode::kInvalidArgument);
  // Moving off the blocked cell recovers.
  ASSERT_TRUE((*dstar)->SetStart({0, 0}).ok());
  d = (*dstar)->Plan(StopCondition::None());
  ASSERT_TRUE(d.ok() && d->found());

  auto spm = ShortestPathMap::Build(shared, {3, 2}, {}, StopCondition::None());
  ASSERT_TRUE(spm.ok());
  EXPECT_EQ((*spm)->PathFrom({1, 1}).status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ((*spm)->PathFrom({-1, 1}).status().code(),
            absl::StatusCode::kInvalidArgument);

  // Blocked goals are refused up front, naming the goal.
  auto bad = DStarLite::Create(shared, {1, 1}, {});
  EXPECT_EQ(bad.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(bad.status().message().find("goal"), std::string::npos) << bad.status();
  EXPECT_EQ(ShortestPathMap::Build(shared, {9, 9}, {}, StopCondition::None())
                .status()
                .code(),
            absl::StatusCode::kInvalidArgument);
}

TEST(Incremental, BadUpdatesAreInvalidArgument) {
  auto grid = Share(MakeGrid({"....", "....", "...."}));
  auto other = Share(MakeGrid({"...", "...", "..."}));
  auto dstar = DStarLite::Create(grid, {0, 0}, {});
  auto lpa = LpaStar::Create(grid, {3, 2}, {0, 0}, {});
  auto spm = ShortestPathMap::Build(grid, {0, 0}, {}, StopCondition::None());
  ASSERT_TRUE(dstar.ok() && lpa.ok() && spm.ok());
  const std::vector<Cell> off_map{{1, 1}, {4, 0}};
  for (const absl::Status& s :
       {(*dstar)->UpdateMap(grid, off_map), (*lpa)->UpdateMap(grid, off_map),
        (*spm)->UpdateMap(grid, off_map)}) {
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(s.message().find("(4, 0)"), std::string::npos) << s;
  }
  const std::vector<Cell> none;
  EXPECT_EQ((*dstar)->UpdateMap(other, none).code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ((*lpa)->UpdateMap(other, none).code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ((*spm)->UpdateMap(other, none).code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ((*spm)->UpdateMap(nullptr, none).code(), absl::StatusCode::kInvalidArgument);
}

TEST(Incremental, ChangedCellsListsDifferencesInRowMajorOrder) {
  Grid a = MakeGrid({"...", "...", "..."});
  Grid b = MakeGrid({"..#", "...", "#.5"});
  auto changed = ChangedCells(a, b);
  ASSERT_TRUE(changed.ok());
  EXPECT_EQ(*changed, (std::vector<Cell>{{2, 0}, {0, 2}, {2, 2}}));
  EXPECT_EQ(ChangedCells(a, MakeGrid({"..", ".."})).status().code(),
            absl::StatusCode::kInvalidArgument);
}

// A budget of one expansion stops every Plan() after one expansion; calling
// again continues where the last one stopped, and the result is the optimum.
TEST(Incremental, StopAndResume) {
  Grid grid = Grid::Create(40, 30).value();
  for (int y = 0; y < 25; ++y) grid.set_cost(20, y, kLethalCost);
  auto shared = Share(grid);
  const Cell start{2, 3}, goal{37, 4};
  const double optimum = ReferenceCostToGo(grid, goal, {})[grid.Index(start)];
  const StopCondition one(absl::InfiniteFuture(), nullptr, 1);

  auto dstar = DStarLite::Create(shared, goal, {});
  ASSERT_TRUE(dstar.ok() && (*dstar)->SetStart(start).ok());
  int stops = 0;
  absl::StatusOr<PlanResult> d;
  while (true) {
    d = (*dstar)->Plan(one);
    ASSERT_TRUE(d.ok()) << d.status();
    if (d->outcome != PlanOutcome::kExpansionLimit) break;
    EXPECT_EQ(d->expansions, 1);
    EXPECT_TRUE(d->path.empty());
    ++stops;
  }
  ASSERT_TRUE(d->found());
  EXPECT_GT(stops, 50);
  EXPECT_NEAR(d->cost, optimum, 1e-9);

  auto lpa = LpaStar::Create(shared, start, goal, {});
  ASSERT_TRUE(lpa.ok());
  absl::StatusOr<PlanResult> l = (*lpa)->Plan(one);
  ASSERT_TRUE(l.ok());
  EXPECT_EQ(l->outcome, PlanOutcome::kExpansionLimit);
  std::atomic<bool> cancelled{true};
  l = (*lpa)->Plan(StopCondition(absl::InfiniteFuture(), &cancelled, 0));
  ASSERT_TRUE(l.ok());
  EXPECT_EQ(l->outcome, PlanOutcome::kCancelled);
  l = (*lpa)->Plan(StopCondition(absl::Now() - absl::Seconds(1), nullptr, 0));
  ASSERT_TRUE(l.ok());
  EXPECT_EQ(l->outcome, PlanOutcome::kTimeout);
  l = (*lpa)->Plan(StopCondition::None());
  ASSERT_TRUE(l.ok() && l->found());
  EXPECT_NEAR(l->cost, optimum, 1e-9);

  EXPECT_EQ(ShortestPathMap::Build(shared, goal, {}, one).status().code(),
            absl::StatusCode::kResourceExhausted);
  EXPECT_EQ(ShortestPathMap::Build(shared, goal, {},
                                   StopCondition(absl::Now() - absl::Seconds(1),
                                                 nullptr, 0))
                .status()
                .code(),
            absl::StatusCode::kDeadlineExceeded);
}

// The memory targets on a 512 x 512 map: D* Lite keeps 16 bytes per cell
// (g and rhs as doubles) plus its open list, the shortest path map 4 bytes per
// cell (the float field) and nothing else once built or repaired.
TEST(Incremental, MemoryPerCellOn512By512) {
  std::mt19937 rng(7);
  Grid grid = Grid::Create(512, 512).value();
  for (uint8_t& v : grid.mutable_cells()) v = rng() % 5 == 0 ? kLethalCost : kFreeCost;
  const Cell start{3, 5}, goal{500, 490};
  grid.set_cost(start, kFreeCost);
  grid.set_cost(goal, kFreeCost);
  auto shared = Share(grid);
  const double cells = static_cast<double>(grid.size());

  auto dstar = DStarLite::Create(shared, goal, {});
  ASSERT_TRUE(dstar.ok() && (*dstar)->SetStart(start).ok());
  ASSERT_TRUE((*dstar)->Plan(StopCondition::None())->found());
  const double dstar_per_cell = static_cast<double>((*dstar)->MemoryBytes()) / cells;
  EXPECT_GE(dstar_per_cell, 16.0);
  EXPECT_LE(dstar_per_cell, 17.0) << "the open list should be a small fraction";

  auto spm = ShortestPathMap::Build(shared, goal, {}, StopCondition::None());
  ASSERT_TRUE(spm.ok());
  EXPECT_GE((*spm)->MemoryBytes(), 4 * grid.size());
  EXPECT_LE((*spm)->MemoryBytes(), 4 * grid.size() + 8192);
  Grid next = grid;
  std::vector<Cell> changed;
  for (int i = 0; i < 20; ++i) {
    const Cell c{static_cast<int32_t>(200 + i), 250};
    next.set_cost(c, kLethalCost);
    changed.push_back(c);
  }
  ASSERT_TRUE((*spm)->UpdateMap(Share(next), changed).ok());
  EXPECT_FALSE((*spm)->last_stats().rebuilt);
  EXPECT_LE((*spm)->MemoryBytes(), 4 * grid.size() + 8192);
}

// A few changed cells are repaired, touching a fraction of the map; a change
// of a large part of the map is rebuilt. Either way the field equals a fresh
// build.
TEST(Incremental, ShortestPathMapRepairsSmallChangesAndRebuildsLargeOnes) {
  std::mt19937 rng(11);
  Grid grid = Grid::Create(200, 200).value();
  for (uint8_t& v : grid.mutable_cells()) v = rng() % 5 == 0 ? kLethalCost : kFreeCost;
  const Cell goal{100, 100};
  grid.set_cost(goal, kFreeCost);
  auto spm = ShortestPathMap::Build(Share(grid), goal, {}, StopCondition::None());
  ASSERT_TRUE(spm.ok());
  const int64_t build_expansions = (*spm)->last_stats().expansions;
  EXPECT_TRUE((*spm)->last_stats().rebuilt);

  std::vector<Cell> changed{{150, 150}, {151, 150}};
  for (const Cell c : changed) grid.set_cost(c, kLethalCost);
  ASSERT_TRUE((*spm)->UpdateMap(Share(grid), changed).ok());
  EXPECT_FALSE((*spm)->last_stats().rebuilt);
  EXPECT_EQ((*spm)->last_stats().changed_cells, 2);
  EXPECT_LT((*spm)->last_stats().expansions, build_expansions / 10);
  auto fresh = ShortestPathMap::Build(Share(grid), goal, {}, StopCondition::None());
  ASSERT_TRUE(fresh.ok());
  EXPECT_TRUE(std::equal((*spm)->field().begin(), (*spm)->field().end(),
                         (*fresh)->field().begin()));

  // 2.5% of the cells, scattered: below the size rule, but the repair runs
  // over its budget and turns into a rebuild.
  changed.clear();
  for (int i = 0; i < 1000; ++i) {
    const Cell c{static_cast<int32_t>(rng() % 200), static_cast<int32_t>(rng() % 200)};
    if (c == goal) continue;
    grid.set_cost(c, grid.cost(c) == kFreeCost ? kLethalCost : kFreeCost);
    changed.push_back(c);
  }
  ASSERT_TRUE((*spm)->UpdateMap(Share(grid), changed).ok());
  EXPECT_TRUE((*spm)->last_stats().rebuilt);
  EXPECT_GT((*spm)->last_stats().expansions, build_expansions / 5);
  fresh = ShortestPathMap::Build(Share(grid), goal, {}, StopCondition::None());
  ASSERT_TRUE(fresh.ok());
  EXPECT_TRUE(std::equal((*spm)->field().begin(), (*spm)->field().end(),
                         (*fresh)->field().begin()));

  // 10% of the cells: rebuilt at once.
  changed.clear();
  for (int i = 0; i < 4000; ++i) {
    const Cell c{static_cast<int32_t>(rng() % 200), static_cast<int32_t>(rng() % 200)};
    if (c == goal) continue;
    grid.set_cost(c, grid.cost(c) == kFreeCost ? kLethalCost : kFreeCost);
    changed.push_back(c);
  }
  ASSERT_TRUE((*spm)->UpdateMap(Share(grid), changed).ok());
  EXPECT_TRUE((*spm)->last_stats().rebuilt);
  // No repair was tried: the expansions are the build's alone.
  fresh = ShortestPathMap::Build(Share(grid), goal, {}, StopCondition::None());
  ASSERT_TRUE(fresh.ok());
  EXPECT_EQ((*spm)->last_stats().expansions, (*fresh)->last_stats().expansions);
  EXPECT_TRUE(std::equal((*spm)->field().begin(), (*spm)->field().end(),
                         (*fresh)->field().begin()));
}

TEST(Incremental, CloneIsIndependent) {
  Grid grid = MakeGrid({".....", ".....", "....."});
  auto spm = ShortestPathMap::Build(Share(grid), {4, 2}, {}, StopCondition::None());
  ASSERT_TRUE(spm.ok());
  std::unique_ptr<ShortestPathMap> copy = (*spm)->Clone();
  grid.set_cost(3, 2, kLethalCost);
  grid.set_cost(3, 1, kLethalCost);
  const std::vector<Cell> changed{{3, 2}, {3, 1}};
  ASSERT_TRUE(copy->UpdateMap(Share(grid), changed).ok());
  EXPECT_NE(copy->CostToGo({0, 2}), (*spm)->CostToGo({0, 2}));
  EXPECT_EQ((*spm)->grid().cost(3, 2), kFreeCost);
  EXPECT_NEAR((*spm)->CostToGo({0, 2}), 4.0, 1e-6);
}

TEST(Incremental, KmGrowsByTheHeuristicDistanceOfEachMove) {
  auto grid = Share(Grid::Create(10, 10).value());
  auto dstar = DStarLite::Create(grid, {9, 9}, {});
  ASSERT_TRUE(dstar.ok());
  ASSERT_TRUE((*dstar)->SetStart({0, 0}).ok());
  EXPECT_EQ((*dstar)->km(), 0.0);
  ASSERT_TRUE((*dstar)->Plan(StopCondition::None())->found());
  ASSERT_TRUE((*dstar)->SetStart({1, 1}).ok());
  EXPECT_NEAR((*dstar)->km(), kSqrt2, 1e-12);
  ASSERT_TRUE((*dstar)->SetStart({3, 1}).ok());
  EXPECT_NEAR((*dstar)->km(), kSqrt2 + 2.0, 1e-12);
  auto d = (*dstar)->Plan(StopCondition::None());
  ASSERT_TRUE(d.ok() && d->found());
  EXPECT_NEAR(d->cost, 6 * kSqrt2 + 2.0, 1e-9);
}

// A broken state is reported, naming the cell, instead of looping.
TEST(Incremental, ExtractionGuardReportsBrokenState) {
  auto grid = Share(Grid::Create(12, 12).value());
  auto spm = ShortestPathMap::Build(grid, {11, 11}, {}, StopCondition::None());
  ASSERT_TRUE(spm.ok());
  // A false sink: the descent runs into (5, 5) and finds nothing lower.
  IncrementalAccess::CorruptField(**spm, {5, 5}, 0.5f);
  auto s = (*spm)->PathFrom({0, 0});
  EXPECT_EQ(s.status().code(), absl::StatusCode::kInternal);
  EXPECT_NE(s.status().message().find("(5, 5)"), std::string::npos) << s.status();
  EXPECT_EQ(IncrementalAccess::PathCosts(**spm).status().code(),
            absl::StatusCode::kInternal);

  auto dstar = DStarLite::Create(grid, {11, 11}, {});
  ASSERT_TRUE(dstar.ok() && (*dstar)->SetStart({0, 0}).ok());
  ASSERT_TRUE((*dstar)->Plan(StopCondition::None())->found());
  IncrementalAccess::CorruptG(**dstar, {1, 1}, 0.25);
  auto d = (*dstar)->Plan(StopCondition::None());
  EXPECT_EQ(d.status().code(), absl::StatusCode::kInternal);
  EXPECT_NE(d.status().message().find("(1, 1)"), std::string::npos) << d.status();
}

}  // namespace
}  // namespace pathd
