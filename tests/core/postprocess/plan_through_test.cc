// PlanThrough (via points) against independent per-leg Dijkstra plans on
// random maps, junction handling, allow_partial, via errors and the shared
// budget; and the expansion recorder of every planner that records.
#include "core/search/registry.h"
#include "core/search/path_measure.h"
#include "core/postprocess/plan_through.h"

#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/search/planner.h"
#include "gtest/gtest.h"
#include "tests/testing/test_grids.h"

namespace pathd {
namespace {

const Planner& Get(std::string_view name) {
  const Planner* planner = PlannerRegistry::Default().Get(name);
  EXPECT_NE(planner, nullptr) << name;
  return *planner;
}

// A w x h grid with `lethal_percent` of the cells lethal (about) and a tenth
// weighted.
Grid RandomGrid(std::mt19937& rng, int32_t w, int32_t h,
                int lethal_percent = 25) {
  Grid grid = Grid::Create(w, h).value();
  std::uniform_int_distribution<int> pick(0, 99);
  for (int32_t y = 0; y < h; ++y) {
    for (int32_t x = 0; x < w; ++x) {
      const int r = pick(rng);
      grid.set_cost(x, y,
                    r < lethal_percent        ? kLethalCost
                    : r < lethal_percent + 10 ? uint8_t{120}
                                              : kFreeCost);
    }
  }
  return grid;
}

Cell RandomFreeCell(std::mt19937& rng, const Grid& grid) {
  std::uniform_int_distribution<int32_t> x(0, grid.width() - 1);
  std::uniform_int_distribution<int32_t> y(0, grid.height() - 1);
  while (true) {
    const Cell c{x(rng), y(rng)};
    if (Traversable(grid.cost(c), false)) return c;
  }
}

TEST(PlanThroughTest, CostIsTheSumOfIndependentDijkstraLegsOnRandomMaps) {
  std::mt19937 rng(20240611);
  SearchScratch scratch;
  int found = 0, failed = 0;
  for (int round = 0; round < 200; ++round) {
    // Near the percolation threshold: about half the plans fail at some leg.
    const Grid grid = RandomGrid(rng, 40, 30, 38);
    CostParams cost;
    cost.connectivity =
        round % 2 == 0 ? Connectivity::kEight : Connectivity::kFour;
    std::vector<Cell> via;
    const int count = 1 + round % 4;
    for (int i = 0; i < count; ++i) via.push_back(RandomFreeCell(rng, grid));
    const PlanRequest request = PlanRequest::Between(
        RandomFreeCell(rng, grid), RandomFreeCell(rng, grid), cost);

    // The reference: each leg alone, from the previous goal.
    std::vector<Cell> goals = via;
    goals.push_back(request.goal);
    double expected_cost = 0.0;
    int expected_reached = -1;
    Cell from = request.start;
    for (const Cell to : goals) {
      const PlanResult leg =
          Get("dijkstra")
              .Plan(grid, PlanRequest::Between(from, to, cost),
                    StopCondition::None(), scratch)
              .value();
      if (!leg.found()) break;
      expected_cost += leg.cost;
      ++expected_reached;
      from = to;
    }
    const bool all = expected_reached == static_cast<int>(via.size());

    for (const char* name : {"astar", "dijkstra"}) {
      SCOPED_TRACE(testing::Message() << name << " round " << round);
      const ThroughResult through =
          PlanThrough(Get(name), grid, request, via, StopCondition::None(),
                      scratch, ThroughOptions{.allow_partial = true})
              .value();
      EXPECT_EQ(through.plan.found(), all);
      EXPECT_EQ(through.reached_goal_index, expected_reached);
      ASSERT_EQ(through.leg_end_indices.size(),
                static_cast<size_t>(expected_reached + 1));
      if (expected_reached < 0) {
        EXPECT_TRUE(through.plan.path.empty());
        continue;
      }
      EXPECT_NEAR(through.plan.cost, expected_cost,
                  1e-9 * (1.0 + expected_cost));
      const PathMeasure measure = MeasurePath(grid, through.plan.path, cost);
      ASSERT_TRUE(measure.valid);
      EXPECT_NEAR(measure.cost, through.plan.cost,
                  1e-9 * (1.0 + expected_cost));
      EXPECT_EQ(through.plan.path.front(), request.start);
      for (size_t i = 0; i < through.leg_end_indices.size(); ++i) {
        EXPECT_EQ(through.plan.path[through.leg_end_indices[i]], goals[i]);
      }
      EXPECT_EQ(through.leg_end_indices.back() + 1,
                static_cast<int32_t>(through.plan.path.size()));
      if (all) {
        ++found;
      } else {
        ++failed;
        EXPECT_EQ(through.failed_leg, expected_reached + 1);
        EXPECT_EQ(through.plan.outcome, PlanOutcome::kNoPath);
      }
    }
  }
  // Both branches ran often enough to mean something.
  EXPECT_GT(found, 50);
  EXPECT_GT(failed, 50);
}

TEST(PlanThroughTest, JunctionCellsAppearOnce) {
  const Grid grid = MakeGrid({
      "..........",
      "..........",
      "..........",
  });
  SearchScratch scratch;
  const PlanRequest request = PlanRequest::Between({0, 0}, {9, 0});
  // A via on the start and a repeated via make one-cell legs.
  const std::vector<Cell> via = {{0, 0}, {4, 2}, {4, 2}, {7, 1}};
  const ThroughResult through = PlanThrough(Get("astar"), grid, request, via,
                                            StopCondition::None(), scratch, {})
                                    .value();
  ASSERT_TRUE(through.plan.found());
  for (size_t i = 1; i < through.plan.path.size(); ++i) {
    EXPECT_FALSE(through.plan.path[i] == through.plan.path[i - 1]) << i;
  }
  // (0,0) -> (4,2): 4 moves; -> (7,1): 3; -> (9,0): 2; plus the start.
  EXPECT_EQ(through.plan.path.size(), 10u);
  EXPECT_EQ(through.leg_end_indices, (std::vector<int32_t>{0, 4, 4, 7, 9}));
  EXPECT_EQ(through.reached_goal_index, 4);
  EXPECT_TRUE(MeasurePath(grid, through.plan.path, CostParams{}).valid);
}

// The goal sits in a walled-off pocket; both via points are reachable.
const Grid& PocketGrid() {
  static const Grid grid = MakeGrid({
      "........###",
      "........#.#",
      "........###",
  });
  return grid;
}

TEST(PlanThroughTest, WithoutAllowPartialAFailedLegFailsThePlan) {
  SearchScratch scratch;
  const PlanRequest request = PlanRequest::Between({0, 0}, {9, 1});
  const std::vector<Cell> via = {{3, 2}, {7, 0}};
  const ThroughResult through =
      PlanThrough(Get("astar"), PocketGrid(), request, via,
                  StopCondition::None(), scratch, {})
          .value();
  EXPECT_EQ(through.plan.outcome, PlanOutcome::kNoPath);
  EXPECT_TRUE(through.plan.path.empty());
  EXPECT_EQ(through.failed_leg, 2);
  EXPECT_EQ(through.reached_goal_index, -1);
  EXPECT_TRUE(through.leg_end_indices.empty());
  EXPECT_GT(through.plan.expansions, 0);
  EXPECT_EQ(LegName(through.failed_leg, 2), "leg 2 (via[1] -> goal)");
}

TEST(PlanThroughTest, AllowPartialReturnsThePathToTheLastReachedGoal) {
  SearchScratch scratch;
  const PlanRequest request = PlanRequest::Between({0, 0}, {9, 1});
  const std::vector<Cell> via = {{3, 2}, {7, 0}};
  const ThroughResult through =
      PlanThrough(Get("astar"), PocketGrid(), request, via,
                  StopCondition::None(), scratch,
                  ThroughOptions{.allow_partial = true})
          .value();
  EXPECT_EQ(through.plan.outcome, PlanOutcome::kNoPath);
  EXPECT_EQ(through.failed_leg, 2);
  EXPECT_EQ(through.reached_goal_index, 1);
  ASSERT_EQ(through.leg_end_indices.size(), 2u);
  EXPECT_EQ(through.plan.path.front(), (Cell{0, 0}));
  EXPECT_EQ(through.plan.path.back(), (Cell{7, 0}));
  EXPECT_EQ(through.plan.path[through.leg_end_indices[0]], (Cell{3, 2}));
  const PathMeasure measure =
      MeasurePath(PocketGrid(), through.plan.path, CostParams{});
  ASSERT_TRUE(measure.valid);
  EXPECT_DOUBLE_EQ(measure.cost, through.plan.cost);
}

TEST(PlanThroughTest, BadViaPointsAreNamed) {
  SearchScratch scratch;
  const PlanRequest request = PlanRequest::Between({0, 0}, {7, 2});
  const auto plan = [&](std::vector<Cell> via) {
    return PlanThrough(Get("astar"), PocketGrid(), request, via,
                       StopCondition::None(), scratch, {})
        .status();
  };
  absl::Status s = plan({{1, 1}, {20, 1}});
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("via[1] (20, 1) is outside"), std::string::npos)
      << s;
  s = plan({{8, 0}});
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("via[0] (8, 0) is on a blocked cell"),
            std::string::npos)
      << s;
}

TEST(PlanThroughTest, ViaCountIsCapped) {
  SearchScratch scratch;
  const PlanRequest request = PlanRequest::Between({0, 0}, {1, 0});
  std::vector<Cell> via(kMaxViaPoints, Cell{0, 1});
  absl::StatusOr<ThroughResult> at_cap =
      PlanThrough(Get("astar"), PocketGrid(), request, via,
                  StopCondition::None(), scratch, {});
  ASSERT_TRUE(at_cap.ok()) << at_cap.status();
  EXPECT_TRUE(at_cap->plan.found());
  EXPECT_EQ(at_cap->reached_goal_index, kMaxViaPoints);
  EXPECT_EQ(at_cap->plan.path.size(), 3u);
  via.push_back(Cell{0, 1});
  const absl::Status over = PlanThrough(Get("astar"), PocketGrid(), request,
                                        via, StopCondition::None(), scratch, {})
                                .status();
  EXPECT_EQ(over.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(over.message().find(
                "via has 257 points; a plan may pass through at most 256"),
            std::string::npos)
      << over;
}

TEST(PlanThroughTest, CostToGoWithViaIsRefused) {
  SearchScratch scratch;
  PlanRequest request = PlanRequest::Between({0, 0}, {7, 2});
  request.want_cost_to_go = true;
  const absl::Status s =
      PlanThrough(Get("distance_transform_exact"), PocketGrid(), request,
                  {{3, 1}}, StopCondition::None(), scratch, {})
          .status();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("want_cost_to_go"), std::string::npos) << s;
}

TEST(PlanThroughTest, TheExpansionBudgetIsSharedByTheLegs) {
  const Grid grid = MakeGrid({std::string(60, '.'), std::string(60, '.')});
  SearchScratch scratch;
  const PlanRequest request = PlanRequest::Between({0, 0}, {0, 1});
  const std::vector<Cell> via = {{59, 0}};
  // Dijkstra's first leg alone takes more than 100 expansions (the row is 60
  // long and two rows deep), so the 150 left for the second leg cannot
  // bring it back.
  const ThroughResult unlimited =
      PlanThrough(Get("dijkstra"), grid, request, via, StopCondition::None(),
                  scratch, {})
          .value();
  ASSERT_TRUE(unlimited.plan.found());
  const int64_t budget = unlimited.plan.expansions - 1;
  const ThroughResult limited =
      PlanThrough(Get("dijkstra"), grid, request, via,
                  StopCondition(absl::InfiniteFuture(), nullptr, budget),
                  scratch, ThroughOptions{.allow_partial = true})
          .value();
  EXPECT_EQ(limited.plan.outcome, PlanOutcome::kExpansionLimit);
  EXPECT_LE(limited.plan.expansions, budget);
  EXPECT_EQ(limited.failed_leg, 1);
  EXPECT_EQ(limited.reached_goal_index, 0);
}

TEST(PlanThroughTest, AnyAngleAndSimplifiedLegsKeepTheViaPoints) {
  std::mt19937 rng(7);
  SearchScratch scratch;
  const Grid grid = RandomGrid(rng, 40, 30);
  for (int round = 0; round < 20; ++round) {
    const std::vector<Cell> via = {RandomFreeCell(rng, grid),
                                   RandomFreeCell(rng, grid)};
    const PlanRequest request = PlanRequest::Between(RandomFreeCell(rng, grid),
                                                     RandomFreeCell(rng, grid));
    const ThroughResult grid_plan =
        PlanThrough(Get("dijkstra"), grid, request, via, StopCondition::None(),
                    scratch, {})
            .value();
    for (const auto& [name, simplify] :
         {std::pair{"theta_star", false}, std::pair{"astar", true}}) {
      SCOPED_TRACE(testing::Message() << name << " round " << round);
      const ThroughResult through =
          PlanThrough(Get(name), grid, request, via, StopCondition::None(),
                      scratch, ThroughOptions{.simplify = simplify})
              .value();
      ASSERT_EQ(through.plan.found(), grid_plan.plan.found());
      if (!through.plan.found()) continue;
      EXPECT_TRUE(through.plan.any_angle);
      const PathMeasure measure =
          MeasureAnyAnglePath(grid, through.plan.path, CostParams{});
      ASSERT_TRUE(measure.valid);
      EXPECT_NEAR(measure.cost, through.plan.cost, 1e-6);
      EXPECT_LE(through.plan.cost, grid_plan.plan.cost + 1e-6);
      for (size_t i = 0; i < via.size(); ++i) {
        EXPECT_EQ(through.plan.path[through.leg_end_indices[i]], via[i]);
      }
    }
  }
}

// --- expansion recorder ------------------------------------------------------

// Planners that record one cell per expansion, and those that record none.
constexpr const char* kRecording[] = {"astar",
                                      "dijkstra",
                                      "weighted_astar",
                                      "greedy",
                                      "bfs",
                                      "dfs",
                                      "jps",
                                      "theta_star",
                                      "lazy_theta_star",
                                      "rtaa_star",
                                      "lrta_star",
                                      "wavefront",
                                      "distance_transform_exact"};
constexpr const char* kNotRecording[] = {
    "potential_field", "distance_transform", "lpa_star", "dstar_lite", "spm"};

TEST(ExpansionRecorderTest, RecordingPlannersRecordOneCellPerExpansion) {
  const Grid grid = MakeGrid({
      "..........#.........",
      "..####....#...###...",
      ".....#....#.....#...",
      ".....#..........#...",
      "..........#.........",
  });
  SearchScratch scratch;
  for (const char* name : kRecording) {
    SCOPED_TRACE(name);
    ExpansionRecorder recorder(1'000'000);
    PlanRequest request = PlanRequest::Between({0, 0}, {19, 4});
    request.expansion_recorder = &recorder;
    const PlanResult result =
        Get(name).Plan(grid, request, StopCondition::None(), scratch).value();
    ASSERT_TRUE(result.found());
    EXPECT_FALSE(recorder.truncated());
    EXPECT_EQ(static_cast<int64_t>(recorder.cells().size()), result.expansions);
    for (const Cell c : recorder.cells()) {
      ASSERT_TRUE(grid.InBounds(c));
      EXPECT_TRUE(Traversable(grid.cost(c), false)) << CellToString(c);
    }
  }
}

TEST(ExpansionRecorderTest, AStarClosesEachCellOnceStartFirstGoalLast) {
  std::mt19937 rng(99);
  const Grid grid = RandomGrid(rng, 60, 60);
  SearchScratch scratch;
  ExpansionRecorder recorder(1'000'000);
  PlanRequest request = PlanRequest::Between(RandomFreeCell(rng, grid), {0, 0});
  request.goal = RandomFreeCell(rng, grid);
  request.expansion_recorder = &recorder;
  const PlanResult result =
      Get("astar").Plan(grid, request, StopCondition::None(), scratch).value();
  ASSERT_EQ(static_cast<int64_t>(recorder.cells().size()), result.expansions);
  std::set<std::pair<int32_t, int32_t>> distinct;
  for (const Cell c : recorder.cells()) distinct.insert({c.x, c.y});
  EXPECT_EQ(distinct.size(), recorder.cells().size());
  EXPECT_EQ(recorder.cells().front(), request.start);
  if (result.found()) {
    EXPECT_EQ(recorder.cells().back(), request.goal);
  }
}

TEST(ExpansionRecorderTest, OtherPlannersRecordNothing) {
  const Grid grid = MakeGrid({"..........", "..........", ".........."});
  SearchScratch scratch;
  for (const char* name : kNotRecording) {
    SCOPED_TRACE(name);
    ExpansionRecorder recorder(100);
    PlanRequest request = PlanRequest::Between({0, 0}, {9, 2});
    request.expansion_recorder = &recorder;
    const PlanResult result =
        Get(name).Plan(grid, request, StopCondition::None(), scratch).value();
    EXPECT_TRUE(result.found());
    EXPECT_TRUE(recorder.cells().empty());
  }
}

TEST(ExpansionRecorderTest, TheCapTruncatesAndSaysSo) {
  const Grid grid = MakeGrid({std::string(30, '.'), std::string(30, '.')});
  SearchScratch scratch;
  ExpansionRecorder recorder(10);
  PlanRequest request = PlanRequest::Between({0, 0}, {29, 1});
  request.expansion_recorder = &recorder;
  const PlanResult result =
      Get("dijkstra")
          .Plan(grid, request, StopCondition::None(), scratch)
          .value();
  ASSERT_GT(result.expansions, 10);
  EXPECT_EQ(recorder.cells().size(), 10u);
  EXPECT_TRUE(recorder.truncated());
}

TEST(ExpansionRecorderTest, ViaPlansRecordEveryLeg) {
  SearchScratch scratch;
  ExpansionRecorder recorder(1'000'000);
  PlanRequest request = PlanRequest::Between({0, 0}, {7, 2});
  request.expansion_recorder = &recorder;
  const ThroughResult through =
      PlanThrough(Get("astar"), PocketGrid(), request, {{3, 2}, {7, 0}},
                  StopCondition::None(), scratch, {})
          .value();
  ASSERT_TRUE(through.plan.found());
  EXPECT_EQ(static_cast<int64_t>(recorder.cells().size()),
            through.plan.expansions);
}

}  // namespace
}  // namespace pathd
