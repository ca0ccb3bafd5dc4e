// The potential field planner: reaches goals on open maps, reports a local
// minimum (not a loop) in front of a concave obstacle, keeps its trajectory and
// path collision-free, honours its parameters and every stop condition.
#include <atomic>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "absl/time/clock.h"
#include "core/search/registry.h"
#include "core/search/path_measure.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/search/line_of_sight.h"
#include "core/search/planner.h"
#include "gtest/gtest.h"
#include "tests/testing/test_grids.h"

namespace pathd {
namespace {

// The U opens towards the start (west); the goal is behind its closed side.
const std::vector<std::string> kUMap = {
    "........................................",
    "........................................",
    "........................................",
    "........................................",
    "....................#######.............",
    "..........................#.............",
    "..........................#.............",
    "..........................#.............",
    "..........................#.............",
    "..........................#.............",
    "..........................#.............",
    "..........................#.............",
    "..........................#.............",
    "....................#######.............",
    "........................................",
    "........................................",
    "........................................",
};

const Planner& PotentialField() {
  const Planner* planner = PlannerRegistry::Default().Get("potential_field");
  EXPECT_NE(planner, nullptr);
  return *planner;
}

absl::StatusOr<PlanResult> Plan(
    const Grid& grid, const PlanRequest& request,
    const StopCondition& stop = StopCondition::None()) {
  static SearchScratch* scratch = new SearchScratch();
  return PotentialField().Plan(grid, request, stop, *scratch);
}

// Everything a result must satisfy whatever its outcome: the trajectory starts
// at the start cell's centre and every segment of it stays on traversable
// cells (corner touches included); a found path runs start to goal by legal
// moves, through cells the trajectory passes, with cost and length measured.
void ExpectConsistent(const Grid& grid, const PlanRequest& request,
                      const PlanResult& r) {
  ASSERT_FALSE(r.trajectory.empty());
  EXPECT_EQ(r.trajectory.front().x, request.start.x + 0.5);
  EXPECT_EQ(r.trajectory.front().y, request.start.y + 0.5);
  std::vector<bool> touched(grid.size(), false);
  touched[grid.Index(request.start)] = true;
  for (size_t i = 1; i < r.trajectory.size(); ++i) {
    ForEachCellOnSegment(
        r.trajectory[i - 1], r.trajectory[i], [&](int32_t x, int32_t y, bool) {
          EXPECT_TRUE(
              grid.InBounds(x, y) &&
              Traversable(grid.cost(x, y), request.cost.unknown_is_free))
              << "segment " << i << " meets " << x << "," << y;
          if (grid.InBounds(x, y)) touched[grid.Index(x, y)] = true;
          return true;
        });
  }
  if (!r.found()) {
    EXPECT_TRUE(r.path.empty());
    return;
  }
  ASSERT_FALSE(r.path.empty());
  EXPECT_EQ(r.path.front(), request.start);
  EXPECT_EQ(r.path.back(), request.goal);
  const CellPoint end = r.trajectory.back();
  EXPECT_EQ(static_cast<int32_t>(std::floor(end.x)), request.goal.x);
  EXPECT_EQ(static_cast<int32_t>(std::floor(end.y)), request.goal.y);
  const PathMeasure m = MeasurePath(grid, r.path, request.cost);
  ASSERT_TRUE(m.valid) << "illegal move to path cell " << m.first_invalid;
  EXPECT_NEAR(r.cost, m.cost, 1e-9 * (1 + m.cost));
  EXPECT_NEAR(r.length, m.length, 1e-9 * (1 + m.length));
  for (const Cell& c : r.path) {
    EXPECT_TRUE(touched[grid.Index(c)])
        << CellToString(c) << " is off the trajectory";
  }
}

// Smallest distance from any trajectory point to the square of a blocked cell.
double Clearance(const Grid& grid, const std::vector<CellPoint>& trajectory) {
  double best = std::numeric_limits<double>::infinity();
  for (const CellPoint& p : trajectory) {
    for (int32_t y = 0; y < grid.height(); ++y) {
      for (int32_t x = 0; x < grid.width(); ++x) {
        if (grid.cost(x, y) < kInscribedCost) continue;
        const double dx = std::max({x - p.x, 0.0, p.x - (x + 1)});
        const double dy = std::max({y - p.y, 0.0, p.y - (y + 1)});
        best = std::min(best, std::hypot(dx, dy));
      }
    }
  }
  return best;
}

TEST(PotentialFieldTest, RegisteredAsHeuristicAndIncomplete) {
  const PlannerTraits& traits = PotentialField().traits();
  EXPECT_EQ(PotentialField().name(), "potential_field");
  EXPECT_FALSE(traits.complete);
  EXPECT_FALSE(traits.optimal);
  EXPECT_FALSE(traits.any_angle);
  EXPECT_EQ(GuaranteeName(traits), "heuristic");
}

TEST(PotentialFieldTest, OpenMapReachesTheGoal) {
  const Grid grid = Grid::Create(40, 30).value();
  const Cell pairs[][2] = {{{2, 3}, {35, 26}},   {{20, 15}, {3, 4}},
                           {{0, 0}, {39, 29}},   {{5, 29}, {38, 0}},
                           {{10, 10}, {11, 10}}, {{0, 15}, {39, 15}}};
  for (const auto& pair : pairs) {
    for (Connectivity c : {Connectivity::kEight, Connectivity::kFour}) {
      for (AttractiveShape shape :
           {AttractiveShape::kQuadratic, AttractiveShape::kConic}) {
        PlanRequest request = PlanRequest::Between(pair[0], pair[1]);
        request.cost.connectivity = c;
        request.potential.attractive = shape;
        const absl::StatusOr<PlanResult> r = Plan(grid, request);
        ASSERT_TRUE(r.ok()) << r.status();
        EXPECT_EQ(r->outcome, PlanOutcome::kFound)
            << CellToString(pair[0]) << " -> " << CellToString(pair[1]);
        ExpectConsistent(grid, request, *r);
        EXPECT_GT(r->expansions, 0);
      }
    }
  }
}

TEST(PotentialFieldTest, EightConnectedPathFollowsTheStraightLine) {
  // On an open map the descent runs straight at the goal; the path takes the
  // diagonals instead of a staircase, so it costs what A* finds.
  const Grid grid = Grid::Create(40, 20).value();
  const PlanRequest request = PlanRequest::Between({2, 3}, {35, 16});
  const absl::StatusOr<PlanResult> r = Plan(grid, request);
  ASSERT_TRUE(r.ok() && r->found());
  ExpectConsistent(grid, request, *r);
  EXPECT_NEAR(r->cost, 33 + 13 * (kSqrt2 - 1), 1e-9);
}

TEST(PotentialFieldTest, StartEqualsGoalIsOneCellPath) {
  const Grid grid = MakeGrid({"...", ".#.", "..."});
  const PlanRequest request = PlanRequest::Between({2, 1}, {2, 1});
  const absl::StatusOr<PlanResult> r = Plan(grid, request);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->outcome, PlanOutcome::kFound);
  EXPECT_EQ(r->path, (std::vector<Cell>{{2, 1}}));
  EXPECT_EQ(r->cost, 0.0);
  EXPECT_EQ(r->length, 0.0);
  EXPECT_EQ(r->expansions, 0);
  EXPECT_EQ(r->trajectory.size(), 1u);
}

TEST(PotentialFieldTest, ConcaveObstacleIsALocalMinimumInsideIt) {
  const Grid grid = MakeGrid(kUMap);
  for (AttractiveShape shape :
       {AttractiveShape::kQuadratic, AttractiveShape::kConic}) {
    PlanRequest request = PlanRequest::Between({5, 8}, {35, 8});
    request.potential.attractive = shape;
    // A budget far beyond what the descent needs: it must stop by itself.
    request.potential.max_steps = 1'000'000;
    const absl::StatusOr<PlanResult> r = Plan(grid, request);
    ASSERT_TRUE(r.ok()) << r.status();
    EXPECT_EQ(r->outcome, PlanOutcome::kLocalMinimum);
    EXPECT_FALSE(r->found());
    EXPECT_TRUE(r->path.empty());
    EXPECT_LT(r->expansions, 200);
    // Inside the U: between its arms, west of its closed side.
    EXPECT_GT(r->stall_point.x, 20.0);
    EXPECT_LT(r->stall_point.x, 26.0);
    EXPECT_GT(r->stall_point.y, 5.0);
    EXPECT_LT(r->stall_point.y, 13.0);
    ExpectConsistent(grid, request, *r);
  }
}

TEST(PotentialFieldTest, BlockedDescentIsALocalMinimum) {
  // With almost no repulsion the pull drives the robot straight into the
  // wall; once no shortened step is free, it reports where it got stuck.
  const Grid grid = MakeGrid({
      "...........#.......",
      "...........#.......",
      "...........#.......",
      "...........#.......",
      "...........#.......",
  });
  PlanRequest request = PlanRequest::Between({1, 2}, {17, 2});
  request.potential.repulsive_gain = 1e-9;
  const absl::StatusOr<PlanResult> r = Plan(grid, request);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->outcome, PlanOutcome::kLocalMinimum);
  EXPECT_GT(r->stall_point.x, 10.5);
  EXPECT_LT(r->stall_point.x, 11.0);
  ExpectConsistent(grid, request, *r);
}

TEST(PotentialFieldTest, LargerInfluenceDistanceKeepsFurtherFromObstacles) {
  // A block just south of the straight line from start to goal.
  std::vector<std::string> rows(21, std::string(60, '.'));
  for (int y = 12; y <= 15; ++y) {
    for (int x = 27; x <= 32; ++x) rows[y][x] = '#';
  }
  const Grid grid = MakeGrid(rows);
  double previous = 0.0;
  for (double influence : {1.5, 3.0, 6.0}) {
    PlanRequest request = PlanRequest::Between({3, 10}, {56, 10});
    request.potential.influence_distance = influence;
    const absl::StatusOr<PlanResult> r = Plan(grid, request);
    ASSERT_TRUE(r.ok());
    ASSERT_TRUE(r->found()) << "influence " << influence;
    ExpectConsistent(grid, request, *r);
    const double clearance = Clearance(grid, r->trajectory);
    EXPECT_GT(clearance, previous) << "influence " << influence;
    previous = clearance;
  }
}

TEST(PotentialFieldTest, MapEdgeRepelsLikeAnObstacle) {
  // Start and goal on the top row: the descent is pushed off the edge row
  // on the way and only returns to it for the final approach.
  const Grid grid = Grid::Create(40, 12).value();
  const PlanRequest request = PlanRequest::Between({2, 0}, {37, 0});
  const absl::StatusOr<PlanResult> r = Plan(grid, request);
  ASSERT_TRUE(r.ok());
  ASSERT_TRUE(r->found());
  ExpectConsistent(grid, request, *r);
  double furthest = 0.0;
  for (const CellPoint& p : r->trajectory) furthest = std::max(furthest, p.y);
  EXPECT_GT(furthest, 1.0);
}

TEST(PotentialFieldTest, StepSizeSetsTheTrajectorySpacing) {
  const Grid grid = Grid::Create(50, 50).value();
  for (double step : {0.25, 0.5, 1.0}) {
    PlanRequest request = PlanRequest::Between({25, 25}, {25, 45});
    request.potential.step_size = step;
    const absl::StatusOr<PlanResult> r = Plan(grid, request);
    ASSERT_TRUE(r.ok() && r->found());
    // Free descent steps are exactly step_size long; the last one is the
    // straight final approach from within the influence distance.
    for (size_t i = 1; i + 1 < r->trajectory.size(); ++i) {
      const CellPoint a = r->trajectory[i - 1], b = r->trajectory[i];
      EXPECT_NEAR(std::hypot(b.x - a.x, b.y - a.y), step, 1e-9);
    }
    EXPECT_NEAR(static_cast<double>(r->expansions),
                (20.0 - request.potential.influence_distance) / step + 1, 1.0);
  }
}

// Found by request_fuzz: with no final approach (a tiny influence distance)
// half-cell steps from a cell centre land exactly on the goal cell's left
// edge, which counts as inside the goal but which the last step only
// touched, so the path ended one cell short of the goal.
TEST(PotentialFieldTest, DescentStoppingOnTheGoalCellsEdgeEndsThePathInIt) {
  const Grid grid = Grid::Create(8, 8).value();
  for (const Cell goal : {Cell{7, 0}, Cell{0, 7}, Cell{7, 7}}) {
    PlanRequest request = PlanRequest::Between({0, 0}, goal);
    request.potential.attractive = AttractiveShape::kConic;
    request.potential.influence_distance = 1e-3;
    request.potential.step_size = 0.5;
    const absl::StatusOr<PlanResult> r = Plan(grid, request);
    ASSERT_TRUE(r.ok()) << r.status();
    ASSERT_TRUE(r->found()) << CellToString(goal);
    ExpectConsistent(grid, request, *r);
  }
}

TEST(PotentialFieldTest, UnknownCellsFollowTheOption) {
  std::vector<std::string> rows(15, std::string(30, '.'));
  for (auto& row : rows) row[15] = '?';
  const Grid grid = MakeGrid(rows);
  PlanRequest request = PlanRequest::Between({3, 7}, {26, 7});
  absl::StatusOr<PlanResult> r = Plan(grid, request);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->outcome, PlanOutcome::kLocalMinimum);
  ExpectConsistent(grid, request, *r);
  request.cost.unknown_is_free = true;
  r = Plan(grid, request);
  ASSERT_TRUE(r.ok());
  EXPECT_TRUE(r->found());
  ExpectConsistent(grid, request, *r);
}

TEST(PotentialFieldTest, StopConditionsAreHonoured) {
  const Grid grid = Grid::Create(100, 100).value();
  PlanRequest request = PlanRequest::Between({0, 0}, {99, 99});

  absl::StatusOr<PlanResult> r =
      Plan(grid, request, StopCondition(absl::InfiniteFuture(), nullptr, 10));
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->outcome, PlanOutcome::kExpansionLimit);
  EXPECT_EQ(r->expansions, 10);
  EXPECT_TRUE(r->path.empty());
  EXPECT_EQ(r->trajectory.size(), 11u);

  request.potential.max_steps = 7;
  r = Plan(grid, request);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->outcome, PlanOutcome::kExpansionLimit);
  EXPECT_EQ(r->expansions, 7);
  request.potential.max_steps = 0;

  r = Plan(grid, request,
           StopCondition(absl::Now() - absl::Seconds(1), nullptr, 0));
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->outcome, PlanOutcome::kTimeout);
  EXPECT_TRUE(r->path.empty());

  std::atomic<bool> cancelled{true};
  r = Plan(grid, request, StopCondition(absl::InfiniteFuture(), &cancelled, 0));
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->outcome, PlanOutcome::kCancelled);
}

TEST(PotentialFieldTest, DefaultStepBudgetCoversAStraightCrossing) {
  // A wide open map whose straight descent needs more than the default
  // 4 * (width + height) / step_size steps only with a tiny step.
  const Grid grid = Grid::Create(400, 3).value();
  PlanRequest request = PlanRequest::Between({0, 1}, {399, 1});
  request.potential.step_size = 0.1;
  absl::StatusOr<PlanResult> r = Plan(grid, request);
  ASSERT_TRUE(r.ok());
  EXPECT_TRUE(r->found());
  EXPECT_LE(r->expansions, 4 * (400 + 3) / 0.1);
}

TEST(PotentialFieldTest, RandomMapsGiveValidPathsWhenFound) {
  std::mt19937 rng(8675309);
  int found = 0, stalled = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const int w = 3 + static_cast<int>(rng() % 40);
    const int h = 3 + static_cast<int>(rng() % 40);
    Grid grid = Grid::Create(w, h).value();
    const int obstacle_pct = static_cast<int>(rng() % 30);
    for (size_t i = 0; i < grid.size(); ++i) {
      const int roll = static_cast<int>(rng() % 100);
      uint8_t v = kFreeCost;
      if (roll < obstacle_pct) {
        v = (rng() % 5 == 0) ? kUnknownCost
                             : (rng() % 4 == 0 ? kInscribedCost : kLethalCost);
      } else if (rng() % 3 == 0) {
        v = static_cast<uint8_t>(rng() % 253);
      }
      grid.mutable_cells()[i] = v;
    }
    PlanRequest request;
    request.cost.connectivity =
        trial % 2 ? Connectivity::kFour : Connectivity::kEight;
    request.cost.unknown_is_free = trial % 7 == 0;
    request.potential.attractive =
        trial % 3 == 0 ? AttractiveShape::kConic : AttractiveShape::kQuadratic;
    request.potential.step_size = trial % 5 == 0 ? 1.0 : 0.5;
    request.start = {static_cast<int32_t>(rng() % w),
                     static_cast<int32_t>(rng() % h)};
    request.goal = {static_cast<int32_t>(rng() % w),
                    static_cast<int32_t>(rng() % h)};
    if (!Traversable(grid.cost(request.start), request.cost.unknown_is_free) ||
        !Traversable(grid.cost(request.goal), request.cost.unknown_is_free)) {
      continue;
    }
    const absl::StatusOr<PlanResult> r = Plan(grid, request);
    ASSERT_TRUE(r.ok()) << r.status();
    ASSERT_TRUE(r->outcome == PlanOutcome::kFound ||
                r->outcome == PlanOutcome::kLocalMinimum ||
                r->outcome == PlanOutcome::kExpansionLimit)
        << PlanOutcomeName(r->outcome);
    SCOPED_TRACE("trial " + std::to_string(trial));
    ExpectConsistent(grid, request, *r);
    if (r->found()) ++found;
    if (r->outcome == PlanOutcome::kLocalMinimum) ++stalled;
  }
  // Both outcomes occur, so the checks above exercised each.
  EXPECT_GT(found, 150) << found;
  EXPECT_GT(stalled, 60) << stalled;
}

}  // namespace
}  // namespace pathd
