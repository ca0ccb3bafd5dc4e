// Theta*, Lazy Theta* and path simplification: hand cases, then random grids
// checked against Dijkstra (any-angle paths are valid under
// MeasureAnyAnglePath and never costlier than the grid optimum; simplified
// paths are never longer or costlier than their input), then a sample of
// Moving AI scenarios against the stored optimal octile lengths.
#include <atomic>
#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "core/search/registry.h"
#include "core/search/path_measure.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/search/line_of_sight.h"
#include "core/map_io/map_io.h"
#include "core/postprocess/path_simplify.h"
#include "core/search/planner.h"
#include "gtest/gtest.h"
#include "tests/testing/test_grids.h"

namespace pathd {
namespace {

constexpr double kTolerance = 1e-9;

const Planner& Get(std::string_view name) {
  const Planner* planner = PlannerRegistry::Default().Get(name);
  EXPECT_NE(planner, nullptr) << name;
  return *planner;
}

PlanResult PlanOrDie(std::string_view planner, const Grid& grid,
                     const PlanRequest& request,
                     const StopCondition& stop = StopCondition::None()) {
  SearchScratch scratch;
  absl::StatusOr<PlanResult> result =
      Get(planner).Plan(grid, request, stop, scratch);
  EXPECT_TRUE(result.ok()) << result.status();
  return result.ok() ? *std::move(result) : PlanResult{};
}

// The reported figures match an independent measurement of the path.
void ExpectConsistentAnyAngle(const Grid& grid, const PlanRequest& request,
                              const PlanResult& result) {
  ASSERT_TRUE(result.found());
  EXPECT_TRUE(result.any_angle);
  ASSERT_FALSE(result.path.empty());
  EXPECT_EQ(result.path.front(), request.start);
  EXPECT_EQ(result.path.back(), request.goal);
  const PathMeasure m = MeasureAnyAnglePath(grid, result.path, request.cost);
  ASSERT_TRUE(m.valid) << "segment " << m.first_invalid << " blocked";
  EXPECT_NEAR(m.cost, result.cost, kTolerance);
  EXPECT_NEAR(m.length, result.length, kTolerance);
}

class ThetaTest : public testing::TestWithParam<std::string> {};

INSTANTIATE_TEST_SUITE_P(Variants, ThetaTest,
                         testing::Values("theta_star", "lazy_theta_star"));

TEST_P(ThetaTest, TraitsAreAnyAngle) {
  const PlannerTraits& traits = Get(GetParam()).traits();
  EXPECT_TRUE(traits.any_angle);
  EXPECT_FALSE(traits.optimal);
  EXPECT_TRUE(traits.complete);
  EXPECT_EQ(GuaranteeName(traits), "any-angle");
}

TEST_P(ThetaTest, OpenFieldIsOneSegment) {
  const Grid grid = Grid::Create(30, 20).value();
  const PlanRequest request = PlanRequest::Between({1, 2}, {27, 13});
  const PlanResult result = PlanOrDie(GetParam(), grid, request);
  ExpectConsistentAnyAngle(grid, request, result);
  EXPECT_EQ(result.path, (std::vector<Cell>{{1, 2}, {27, 13}}));
  EXPECT_DOUBLE_EQ(result.length, std::sqrt(26.0 * 26.0 + 11.0 * 11.0));
}

TEST_P(ThetaTest, StartEqualsGoal) {
  const Grid grid = Grid::Create(5, 5).value();
  const PlanRequest request = PlanRequest::Between({2, 3}, {2, 3});
  const PlanResult result = PlanOrDie(GetParam(), grid, request);
  ASSERT_TRUE(result.found());
  EXPECT_EQ(result.path, (std::vector<Cell>{{2, 3}}));
  EXPECT_EQ(result.cost, 0.0);
  EXPECT_EQ(result.length, 0.0);
}

TEST_P(ThetaTest, AroundACornerTurnsAtTheWallEnd) {
  const Grid grid = MakeGrid({
      "..........",
      "..........",
      "....#.....",
      "....#.....",
      "....#.....",
      "....#.....",
  });
  const PlanRequest request = PlanRequest::Between({1, 5}, {8, 5});
  const PlanResult result = PlanOrDie(GetParam(), grid, request);
  ExpectConsistentAnyAngle(grid, request, result);
  // Taut over the wall's top: no segment through cell centres can touch
  // (4,1) alone without also touching the wall cell (4,2).
  EXPECT_EQ(result.path, (std::vector<Cell>{{1, 5}, {3, 1}, {5, 1}, {8, 5}}));
  EXPECT_DOUBLE_EQ(result.length, std::sqrt(20.0) + 2.0 + 5.0);
  EXPECT_LT(result.length, PlanOrDie("dijkstra", grid, request).length);
}

TEST_P(ThetaTest, NoCornerCuttingThroughDiagonalGaps) {
  // The obstacles meet only at corners: every way across cuts a corner.
  const Grid grid = MakeGrid({
      "....#",
      "...#.",
      "..#..",
      ".#...",
      "#....",
  });
  const PlanResult result =
      PlanOrDie(GetParam(), grid, PlanRequest::Between({0, 0}, {4, 4}));
  EXPECT_EQ(result.outcome, PlanOutcome::kNoPath);
  EXPECT_TRUE(result.path.empty());
}

TEST_P(ThetaTest, SegmentsNeverClipAnObstacleCorner) {
  // (0,0) -> (4,2) passes (1,0), (1,1) ... with slope 1/2; the lone obstacle
  // (2,1) is on it, and (0,0) -> (3,1) would touch the corner of (2,1) too.
  const Grid grid = MakeGrid({
      ".....",
      "..#..",
      ".....",
  });
  const PlanRequest request = PlanRequest::Between({0, 0}, {4, 2});
  const PlanResult result = PlanOrDie(GetParam(), grid, request);
  ExpectConsistentAnyAngle(grid, request, result);
  EXPECT_GT(result.path.size(), 2u);
}

TEST_P(ThetaTest, UnreachableGoalAndBlockedEndpoints) {
  const Grid grid = MakeGrid({
      "..#..",
      "..#..",
      "..#..",
  });
  EXPECT_EQ(
      PlanOrDie(GetParam(), grid, PlanRequest::Between({0, 0}, {4, 2})).outcome,
      PlanOutcome::kNoPath);
  SearchScratch scratch;
  const auto blocked = Get(GetParam())
                           .Plan(grid, PlanRequest::Between({2, 0}, {4, 2}),
                                 StopCondition::None(), scratch);
  EXPECT_EQ(blocked.status().code(), absl::StatusCode::kInvalidArgument);
  const auto off_map = Get(GetParam())
                           .Plan(grid, PlanRequest::Between({0, 0}, {5, 2}),
                                 StopCondition::None(), scratch);
  EXPECT_EQ(off_map.status().code(), absl::StatusCode::kInvalidArgument);
}

TEST_P(ThetaTest, HonoursTheStopCondition) {
  const Grid grid = MakeGrid({
      "..............#.......",
      "..............#.......",
      "..............#.......",
      "..............#.......",
      "......................",
  });
  const PlanRequest request = PlanRequest::Between({0, 0}, {21, 0});
  const PlanResult budget =
      PlanOrDie(GetParam(), grid, request,
                StopCondition(absl::InfiniteFuture(), nullptr, 5));
  EXPECT_EQ(budget.outcome, PlanOutcome::kExpansionLimit);
  EXPECT_LE(budget.expansions, 5);
  EXPECT_TRUE(budget.path.empty());
  const std::atomic<bool> cancelled{true};
  EXPECT_EQ(PlanOrDie(GetParam(), grid, request,
                      StopCondition(absl::InfiniteFuture(), &cancelled, 0))
                .outcome,
            PlanOutcome::kCancelled);
  EXPECT_EQ(PlanOrDie(GetParam(), grid, request,
                      StopCondition(absl::Now() - absl::Seconds(1), nullptr, 0))
                .outcome,
            PlanOutcome::kTimeout);
}

TEST_P(ThetaTest, WeightedCellsAreAvoidedWhenCheaper) {
  // A band of cost 9 * 28 across the direct line; going round is cheaper.
  const Grid grid = MakeGrid({
      "..........",
      "....99....",
      "....99....",
      "....99....",
      "..........",
  });
  const PlanRequest request = PlanRequest::Between({0, 2}, {9, 2});
  const PlanResult result = PlanOrDie(GetParam(), grid, request);
  ExpectConsistentAnyAngle(grid, request, result);
  EXPECT_LE(result.cost,
            PlanOrDie("dijkstra", grid, request).cost + kTolerance);
  for (const Cell& c : result.path) EXPECT_EQ(grid.cost(c), kFreeCost);
}

TEST_P(ThetaTest, FourConnectedIsNoLongerThanManhattan) {
  const Grid grid = MakeGrid({
      "........",
      "..###...",
      "....#...",
      "........",
  });
  PlanRequest request = PlanRequest::Between({0, 3}, {7, 0});
  request.cost.connectivity = Connectivity::kFour;
  const PlanResult result = PlanOrDie(GetParam(), grid, request);
  ExpectConsistentAnyAngle(grid, request, result);
  EXPECT_LE(result.length, 10.0 + kTolerance);  // Manhattan optimum
  EXPECT_LT(result.length, 10.0);               // shortcuts run diagonally
}

// Lazy Theta* as published expands (7,0)'s neighbourhood with g values that
// assumed a blocked segment, and closes cells at the corrected, larger g
// before their better grid predecessor is expanded: 5 instead of 3 + sqrt(2).
// Re-queueing a cell whose g went up keeps the expansion order by true f.
TEST_P(ThetaTest, NoLongerThanOctileWhenAnAssumedSegmentIsBlocked) {
  const Grid grid = MakeGrid({
      ".......",
      "...#...",
      "......#",
      "....#..",
  });
  CostParams cost;
  cost.cost_weight = 0.0;
  const PlanRequest request = PlanRequest::Between({3, 0}, {3, 3}, cost);
  const PlanResult result = PlanOrDie(GetParam(), grid, request);
  ExpectConsistentAnyAngle(grid, request, result);
  EXPECT_LE(result.length, 3.0 + kSqrt2 + kTolerance);
}

// Random grids of 2..14 cells a side, obstacle density up to 45%, random
// weights on a third of the grids, both connectivities; Dijkstra is the
// reference. Seeds are fixed.
struct RandomCase {
  Grid grid;
  PlanRequest request;
};

bool MakeRandomCase(std::mt19937& rng, int index, RandomCase* out) {
  std::uniform_int_distribution<int32_t> side(2, 14);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int32_t w = side(rng);
  const int32_t h = side(rng);
  const double density = 0.45 * u(rng);
  const bool weighted = index % 3 == 0;
  Grid grid = Grid::Create(w, h).value();
  for (int32_t y = 0; y < h; ++y) {
    for (int32_t x = 0; x < w; ++x) {
      uint8_t v = kFreeCost;
      const double r = u(rng);
      if (r < density) {
        v = r < density / 4 ? kUnknownCost : kLethalCost;
      } else if (weighted && u(rng) < 0.5) {
        v = static_cast<uint8_t>(1 + u(rng) * 251);
      }
      grid.set_cost(x, y, v);
    }
  }
  CostParams cost;
  cost.connectivity =
      index % 4 == 1 ? Connectivity::kFour : Connectivity::kEight;
  cost.cost_weight =
      weighted ? 0.5 + 4.0 * u(rng) : (index % 2 == 0 ? 0.0 : 1.0);
  cost.unknown_is_free = index % 5 == 0;
  std::vector<Cell> open;
  for (int32_t y = 0; y < h; ++y) {
    for (int32_t x = 0; x < w; ++x) {
      if (Traversable(grid.cost(x, y), cost.unknown_is_free))
        open.push_back({x, y});
    }
  }
  if (open.empty()) return false;
  std::uniform_int_distribution<size_t> pick(0, open.size() - 1);
  out->request = PlanRequest::Between(open[pick(rng)], open[pick(rng)], cost);
  out->grid = std::move(grid);
  return true;
}

TEST(AnyAngleProperty, RandomGridsAgainstDijkstra) {
  std::mt19937 rng(20240611);
  SearchScratch scratch;
  int found = 0;
  int shorter = 0;
  for (int i = 0; i < 20000; ++i) {
    RandomCase c;
    if (!MakeRandomCase(rng, i, &c)) continue;
    SCOPED_TRACE(absl::StrCat("case ", i, " from ",
                              CellToString(c.request.start), " to ",
                              CellToString(c.request.goal)));
    const PlanResult optimum =
        *Get("dijkstra")
             .Plan(c.grid, c.request, StopCondition::None(), scratch);
    for (const char* name : {"theta_star", "lazy_theta_star"}) {
      SCOPED_TRACE(name);
      const PlanResult result =
          *Get(name).Plan(c.grid, c.request, StopCondition::None(), scratch);
      ASSERT_EQ(result.found(), optimum.found());
      if (!result.found()) continue;
      ExpectConsistentAnyAngle(c.grid, c.request, result);
      // The guarantee: never costlier than the grid optimum, so on uniform
      // maps never longer than the octile (Manhattan) optimum.
      ASSERT_LE(result.cost, optimum.cost + kTolerance);
      if (c.request.cost.cost_weight == 0.0) {
        ASSERT_LE(result.length, optimum.cost + kTolerance);
      }
      if (result.length < optimum.length - kTolerance) ++shorter;
      ++found;
    }
  }
  EXPECT_GT(found, 20000);
  EXPECT_GT(shorter, found / 4);  // any-angle paths usually are shorter
}

TEST(AnyAngleProperty, SimplifiedPathsAreValidAndNeverWorse) {
  std::mt19937 rng(77);
  SearchScratch scratch;
  int simplified = 0;
  for (int i = 0; i < 6000; ++i) {
    RandomCase c;
    if (!MakeRandomCase(rng, i, &c)) continue;
    SCOPED_TRACE(absl::StrCat("case ", i));
    for (const char* name :
         {"astar", "dijkstra", "bfs", "theta_star", "lazy_theta_star"}) {
      SCOPED_TRACE(name);
      PlanResult result =
          *Get(name).Plan(c.grid, c.request, StopCondition::None(), scratch);
      if (!result.found()) continue;
      const PlanResult input = result;
      SimplifyPath(c.grid, c.request.cost, &result);
      ExpectConsistentAnyAngle(c.grid, c.request, result);
      ASSERT_LE(result.cost, input.cost + kTolerance);
      ASSERT_LE(result.length, input.length + kTolerance);
      ASSERT_LE(result.path.size(), input.path.size());
      if (result.path.size() < input.path.size()) ++simplified;
      // Already simplified: a second pass changes nothing.
      PlanResult again = result;
      SimplifyPath(c.grid, c.request.cost, &again);
      EXPECT_EQ(again.path, result.path);
    }
  }
  EXPECT_GT(simplified, 3000);
}

TEST(SimplifyPathTest, OpenFieldBecomesOneSegment) {
  const Grid grid = Grid::Create(12, 7).value();
  const PlanRequest request = PlanRequest::Between({0, 0}, {11, 6});
  PlanResult result = PlanOrDie("astar", grid, request);
  SimplifyPath(grid, request.cost, &result);
  EXPECT_TRUE(result.any_angle);
  EXPECT_EQ(result.path, (std::vector<Cell>{{0, 0}, {11, 6}}));
  EXPECT_DOUBLE_EQ(result.length, std::sqrt(11.0 * 11.0 + 6.0 * 6.0));
  EXPECT_DOUBLE_EQ(result.cost, result.length);
}

TEST(SimplifyPathTest, DoesNotClipCornersBresenhamWouldMiss) {
  // (0,0) -> (2,1) passes through (1,0) and (1,1); Bresenham draws only one
  // of them, so with (1,1) blocked it would accept the shortcut.
  const Grid grid = MakeGrid({
      "...",
      ".#.",
  });
  const CostParams cost;
  PlanResult result;
  result.outcome = PlanOutcome::kFound;
  result.path = {{0, 0}, {1, 0}, {2, 0}, {2, 1}};
  SimplifyPath(grid, cost, &result);
  EXPECT_EQ(result.path, (std::vector<Cell>{{0, 0}, {2, 0}, {2, 1}}));
  EXPECT_TRUE(MeasureAnyAnglePath(grid, result.path, cost).valid);
}

TEST(SimplifyPathTest, DoesNotCutThroughACornerPoint) {
  // (0,0) -> (2,2) passes exactly through the corner of the blocked (1,0).
  const Grid grid = MakeGrid({
      ".#.",
      "...",
      "...",
  });
  const CostParams cost;
  PlanResult result;
  result.outcome = PlanOutcome::kFound;
  result.path = {{0, 0}, {0, 1}, {1, 2}, {2, 2}};
  SimplifyPath(grid, cost, &result);
  EXPECT_EQ(result.path, (std::vector<Cell>{{0, 0}, {1, 2}, {2, 2}}));
}

TEST(SimplifyPathTest, KeepsDetoursAroundExpensiveCells) {
  // The straight line crosses cost-9 cells; the path around them is cheaper,
  // so the shortcut is refused even though it is clear and shorter.
  const Grid grid = MakeGrid({
      ".....",
      ".999.",
      ".....",
  });
  const CostParams cost;  // cost_weight 1
  const PlanRequest request = PlanRequest::Between({0, 1}, {4, 1}, cost);
  PlanResult result = PlanOrDie("dijkstra", grid, request);
  const double before = result.cost;
  SimplifyPath(grid, cost, &result);
  EXPECT_LE(result.cost, before + kTolerance);
  for (size_t i = 1; i < result.path.size(); ++i) {
    EXPECT_FALSE(result.path[i - 1].y == 1 && result.path[i].y == 1)
        << "segment through the expensive row";
  }
}

TEST(SimplifyPathTest, LeavesMissingAndTrivialPathsAlone) {
  const Grid grid = Grid::Create(3, 3).value();
  PlanResult none;
  none.outcome = PlanOutcome::kNoPath;
  SimplifyPath(grid, CostParams{}, &none);
  EXPECT_TRUE(none.path.empty());
  EXPECT_FALSE(none.any_angle);
  PlanResult one;
  one.outcome = PlanOutcome::kFound;
  one.path = {{1, 1}};
  SimplifyPath(grid, CostParams{}, &one);
  EXPECT_EQ(one.path, (std::vector<Cell>{{1, 1}}));
  EXPECT_EQ(one.cost, 0.0);
}

TEST(SimplifyPathTest, CutsLoopsOfRevisitingPaths) {
  // A real-time planner's trajectory may go back and forth.
  const Grid grid = Grid::Create(4, 1).value();
  PlanResult result;
  result.outcome = PlanOutcome::kFound;
  result.path = {{0, 0}, {1, 0}, {2, 0}, {1, 0}, {2, 0}, {3, 0}};
  SimplifyPath(grid, CostParams{}, &result);
  EXPECT_EQ(result.path, (std::vector<Cell>{{0, 0}, {3, 0}}));
  EXPECT_DOUBLE_EQ(result.cost, 3.0);
}

// A sample of Moving AI scenarios (the bench and the report cover more):
// valid, and no longer than the stored optimal octile length.
TEST(AnyAngleMovingAi, NoLongerThanTheOptimalOctileLength) {
  const std::filesystem::path root = "../shared/benchmarks/movingai";
  int checked = 0;
  for (const char* map :
       {"dao/arena2", "room/8room_000", "random/random512-10-0"}) {
    const std::string map_path = (root / (std::string(map) + ".map")).string();
    if (!std::filesystem::exists(map_path)) continue;
    const Grid grid = ReadMovingAiMapFile(map_path).value();
    const ScenarioFile file =
        ReadMovingAiScenarioFileWithVersion(map_path + ".scen").value();
    SearchScratch scratch;
    for (size_t i = 0; i < file.scenarios.size() && i < 40; ++i) {
      const Scenario& s = file.scenarios[i];
      CostParams cost;
      cost.cost_weight = 0.0;
      const PlanRequest request = PlanRequest::Between(s.start, s.goal, cost);
      for (const char* name : {"theta_star", "lazy_theta_star"}) {
        SCOPED_TRACE(absl::StrCat(map, " line ", s.line, " ", name));
        const PlanResult result =
            *Get(name).Plan(grid, request, StopCondition::None(), scratch);
        ExpectConsistentAnyAngle(grid, request, result);
        EXPECT_LE(result.length,
                  s.optimal_length + ScenarioTolerance(s, file.version));
        ++checked;
      }
    }
  }
  if (checked == 0)
    GTEST_SKIP() << "Moving AI benchmarks not found at " << root;
}

}  // namespace
}  // namespace pathd
