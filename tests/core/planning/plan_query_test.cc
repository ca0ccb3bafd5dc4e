// The planning façade (core/planning/plan_query.h): goal tolerance, robot
// radius, via points and simplification against Dijkstra's costs and a
// brute-force nearest cell; the order of its checks; and a stateful engine.
#include "core/planning/plan_query.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <optional>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "core/kinematics/footprint.h"
#include "core/kinematics/vehicle.h"
#include "core/map/clearance.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/map/inflation.h"
#include "core/search/endpoints.h"
#include "core/search/path_measure.h"
#include "core/search/registry.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "tests/testing/kinematic_checker.h"
#include "tests/testing/test_grids.h"

namespace pathd {
namespace {

using ::testing::HasSubstr;

const Planner& Get(std::string_view name) {
  const Planner* planner = PlannerRegistry::Default().Get(name);
  EXPECT_NE(planner, nullptr) << name;
  return *planner;
}

PlanSnapshot Snapshot(Grid grid, uint64_t version = 7) {
  return PlanSnapshot{std::make_shared<const Grid>(std::move(grid)), version};
}

PlanQuery Query(Cell start, Cell goal) {
  PlanQuery query;
  query.planner = "astar";
  query.request = PlanRequest::Between(start, goal);
  query.requested_goal = goal;
  return query;
}

PlanEngine Engine(std::string_view planner = "astar") {
  PlanEngine engine;
  engine.planner = &Get(planner);
  return engine;
}

// Dijkstra's cost from start to goal on `grid`, nullopt when unreachable.
std::optional<double> DijkstraCost(const Grid& grid, Cell start, Cell goal) {
  SearchScratch scratch;
  absl::StatusOr<PlanResult> result = Get("dijkstra").Plan(
      grid, PlanRequest::Between(start, goal), StopCondition::None(), scratch);
  if (!result.ok() || !result->found()) return std::nullopt;
  return result->cost;
}

// Three corridors joined at alternate ends: plans through via points on it
// turn back on themselves.
Grid ViaMaze() {
  return MakeGrid({
      ".......",
      ".#####.",
      ".......",
      "##.####",
      ".......",
  });
}

absl::StatusOr<PlanAnswer> Plan(const PlanQuery& query, const PlanSnapshot& snapshot,
                                const PlanEngine& engine) {
  SearchScratch scratch;
  return PlanOnce(query, snapshot, engine, StopCondition::None(), scratch);
}

// The nearest traversable cell to `target` within `tolerance` by (squared
// distance, y, x), by brute force over the whole grid.
std::optional<Cell> BruteNearest(const Grid& grid, Cell target, double tolerance) {
  std::optional<Cell> best;
  int64_t best_d2 = 0;
  for (int32_t y = 0; y < grid.height(); ++y) {
    for (int32_t x = 0; x < grid.width(); ++x) {
      if (!Traversable(grid.cost(x, y), false)) continue;
      const int64_t dx = x - target.x;
      const int64_t dy = y - target.y;
      const int64_t d2 = dx * dx + dy * dy;
      if (static_cast<double>(d2) > tolerance * tolerance) continue;
      if (!best.has_value() || d2 < best_d2) {
        best = Cell{x, y};
        best_d2 = d2;
      }
    }
  }
  return best;
}

TEST(PlanQueryTest, PlainPlanCostsWhatDijkstraSaysAndIsOneLeg) {
  const PlanSnapshot snapshot = Snapshot(MakeGrid({
      "......",
      ".####.",
      ".#..#.",
      ".####.",
      "......",
  }));
  absl::StatusOr<PlanAnswer> answer = Plan(Query({0, 0}, {3, 2}), snapshot, Engine());
  ASSERT_TRUE(answer.ok()) << answer.status();
  // (3,2) is enclosed: no path is an answer, not an error.
  EXPECT_FALSE(answer->result.found());
  EXPECT_EQ(answer->reached_goal_index, -1);
  EXPECT_TRUE(answer->leg_end_indices.empty());

  answer = Plan(Query({0, 0}, {5, 4}), snapshot, Engine());
  ASSERT_TRUE(answer.ok()) << answer.status();
  ASSERT_TRUE(answer->result.found());
  EXPECT_DOUBLE_EQ(answer->result.cost, *DijkstraCost(*snapshot.grid, {0, 0}, {5, 4}));
  EXPECT_EQ(answer->reached_goal_index, 0);
  EXPECT_EQ(answer->leg_end_indices,
            std::vector<int32_t>{static_cast<int32_t>(answer->result.path.size()) - 1});
  EXPECT_EQ(answer->source.grid, snapshot.grid);
  EXPECT_EQ(answer->source.map_version, 7u);
}

// A minimum clearance: the plan is optimal on the shaped grid (Dijkstra's
// cost there), keeps further from the pillar than the plain plan, reports
// its clearance, and the stored grid is untouched.
TEST(PlanQueryTest, MinimumClearanceKeepsAwayFromObstaclesAtTheShapedCost) {
  std::vector<std::string> rows(21, std::string(41, '.'));
  for (int y = 8; y <= 12; ++y) rows[y].replace(18, 5, "#####");
  const PlanSnapshot snapshot = Snapshot(MakeGrid(rows));
  PlanQuery plain = Query({2, 9}, {38, 11});
  absl::StatusOr<PlanAnswer> hugging = Plan(plain, snapshot, Engine());
  ASSERT_TRUE(hugging.ok()) << hugging.status();
  EXPECT_LT(hugging->result.min_clearance, 0.0);  // not asked for
  const double plain_clearance =
      PathClearance(*snapshot.grid, hugging->result.path, false);

  PlanQuery query = plain;
  query.min_clearance_cells = 5.0;
  absl::StatusOr<PlanAnswer> wide = Plan(query, snapshot, Engine());
  ASSERT_TRUE(wide.ok()) << wide.status();
  ASSERT_TRUE(wide->result.found());
  EXPECT_NE(wide->source.grid, snapshot.grid);
  const Grid shaped = ShapeGrid(*snapshot.grid, GridShape::Of(0.0, 0.0, 0.0, 5.0, false)).value();
  EXPECT_EQ(wide->source.grid->cells(), shaped.cells());
  EXPECT_NEAR(wide->result.cost, *DijkstraCost(shaped, {2, 9}, {38, 11}), 1e-9);
  EXPECT_DOUBLE_EQ(wide->result.min_clearance,
                   PathClearance(shaped, wide->result.path, false));
  EXPECT_GT(wide->result.min_clearance, plain_clearance);
  EXPECT_GT(wide->result.length, hugging->result.length);
  EXPECT_EQ(snapshot.grid->cost(17, 9), 0);

  // The same through a via point: every leg on the shaped grid.
  query.via = {{20, 3}};
  ASSERT_TRUE(CheckPlanQuery(*snapshot.grid, false, &query).ok());
  SearchScratch scratch;
  absl::StatusOr<PlanAnswer> through =
      RunPlanQuery(query, snapshot, Engine(), StopCondition::None(), scratch);
  ASSERT_TRUE(through.ok()) << through.status();
  EXPECT_NEAR(through->result.cost,
              *DijkstraCost(shaped, {2, 9}, {20, 3}) + *DijkstraCost(shaped, {20, 3}, {38, 11}),
              1e-9);
  EXPECT_GE(through->result.min_clearance, 0.0);
}

// A clearance that cannot act is refused, naming the option.
TEST(PlanQueryTest, MinimumClearanceIsRefusedWhereCostsDoNotCount) {
  const Grid grid = MakeGrid({"....", "....", "...."});
  PlanQuery query = Query({0, 0}, {3, 2});
  query.min_clearance_cells = 2.0;
  query.planner = "navmesh";
  absl::Status s = CheckPlanQuery(grid, false, &query);
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(s.message(), HasSubstr("min_clearance"));
  EXPECT_THAT(s.message(), HasSubstr("navmesh"));
  query.planner = "astar";
  query.request.cost.cost_weight = 0.0;
  s = CheckPlanQuery(grid, false, &query);
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(s.message(), HasSubstr("cost_weight 0"));
  query.request.cost.cost_weight = 1.0;
  EXPECT_TRUE(CheckPlanQuery(grid, false, &query).ok());
}

TEST(PlanQueryTest, GoalToleranceSubstitutesTheNearestFreeCell) {
  const PlanSnapshot snapshot = Snapshot(MakeGrid({
      "........",
      "...###..",
      "...###..",
      "...###..",
      "........",
  }));
  PlanQuery query = Query({0, 4}, {4, 2});
  query.goal_tolerance_cells = 2.0;
  absl::StatusOr<PlanAnswer> answer = Plan(query, snapshot, Engine());
  ASSERT_TRUE(answer.ok()) << answer.status();
  // (4,0), (2,2), (6,2) and (4,4) are all 2 away; (4,0) wins on y.
  EXPECT_EQ(answer->goal, (Cell{4, 0}));
  EXPECT_EQ(answer->result.path.back(), (Cell{4, 0}));
  EXPECT_DOUBLE_EQ(answer->result.cost, *DijkstraCost(*snapshot.grid, {0, 4}, {4, 0}));

  query.goal_tolerance_cells = 0.5;
  answer = Plan(query, snapshot, Engine());
  ASSERT_FALSE(answer.ok());
  EXPECT_EQ(answer.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(answer.status().message(), HasSubstr("goal tolerance of 0.5 cells"));
  EXPECT_EQ(EndpointFaultOf(answer.status()), EndpointFault::kGoalBlocked);
}

TEST(PlanQueryTest, ChecksRunInTheDocumentedOrder) {
  const Grid grid = MakeGrid({
      "#...",
      "...#",
  });
  // Tolerance first: the goal's error wins over the blocked start.
  PlanQuery query = Query({0, 0}, {3, 1});
  query.goal_tolerance_cells = 0.5;
  absl::Status s = CheckPlanQuery(grid, /*stateful=*/false, &query);
  EXPECT_EQ(EndpointFaultOf(s), EndpointFault::kGoalBlocked) << s;
  // Then ValidateEndpoints: the start before the goal.
  query = Query({0, 0}, {3, 1});
  s = CheckPlanQuery(grid, false, &query);
  EXPECT_EQ(EndpointFaultOf(s), EndpointFault::kStartBlocked) << s;
  // Then via points: a stateful engine refuses them before they are checked.
  query = Query({1, 0}, {2, 1});
  query.planner = "spm";
  query.via = {Cell{9, 9}};
  s = CheckPlanQuery(grid, /*stateful=*/true, &query);
  EXPECT_THAT(s.message(), HasSubstr("via: planner spm keeps cached state"));
  query.request.want_cost_to_go = true;
  s = CheckPlanQuery(grid, false, &query);
  EXPECT_THAT(s.message(), HasSubstr("options.return_cost_to_go"));
  query.request.want_cost_to_go = false;
  s = CheckPlanQuery(grid, false, &query);
  EXPECT_THAT(s.message(), HasSubstr("via[0] (9, 9) is outside the 4 x 2 map"));
}

TEST(PlanQueryTest, RobotRadiusRejectsAnInscribedGoalOrMovesItWithATolerance) {
  const PlanSnapshot snapshot = Snapshot(MakeGrid({
      "........",
      "........",
      "....#...",
      "........",
      "........",
  }));
  // (4,1) is free but within radius 1.5 of (4,2); the nearest clear cell is
  // (4,0) at distance 1.
  PlanQuery query = Query({0, 4}, {4, 1});
  query.robot_radius_cells = 1.5;
  absl::StatusOr<PlanAnswer> answer = Plan(query, snapshot, Engine());
  ASSERT_FALSE(answer.ok());
  EXPECT_THAT(answer.status().message(),
              HasSubstr("goal (4, 1) is within the robot radius (1.5 cells)"));
  EXPECT_EQ(EndpointFaultOf(answer.status()), EndpointFault::kGoalBlocked);

  query.goal_tolerance_cells = 1.0;
  answer = Plan(query, snapshot, Engine());
  ASSERT_TRUE(answer.ok()) << answer.status();
  EXPECT_EQ(answer->goal, (Cell{4, 0}));
  const Grid inflated = InflateObstacles(*snapshot.grid, 1.5).value();
  EXPECT_DOUBLE_EQ(answer->result.cost, *DijkstraCost(inflated, {0, 4}, {4, 0}));
  EXPECT_NE(answer->source.grid, snapshot.grid);  // planned on the inflation

  // A start the radius made inscribed.
  query = Query({3, 2}, {0, 0});
  query.robot_radius_cells = 1.5;
  answer = Plan(query, snapshot, Engine());
  ASSERT_FALSE(answer.ok());
  EXPECT_EQ(EndpointFaultOf(answer.status()), EndpointFault::kStartBlocked);
}

// The façade searches the inflated map again only when the radius made the
// stored map's choice inscribed; the answer must equal choosing afresh on
// the inflated map from the requested goal (the rule it replaces).
TEST(PlanQueryTest, ToleranceOnceUnderARadiusMatchesChoosingAfreshOnRandomMaps) {
  std::mt19937 rng(20261201);
  int substituted = 0, moved_by_radius = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const int32_t w = 6 + static_cast<int32_t>(rng() % 10);
    const int32_t h = 6 + static_cast<int32_t>(rng() % 10);
    Grid grid = Grid::Create(w, h).value();
    for (int32_t y = 0; y < h; ++y) {
      for (int32_t x = 0; x < w; ++x) {
        if (rng() % 100 < 15) grid.set_cost(x, y, kLethalCost);
      }
    }
    const Cell start{0, 0};
    grid.set_cost(start, kFreeCost);
    const Cell goal{static_cast<int32_t>(rng() % w), static_cast<int32_t>(rng() % h)};
    const double tolerance = 0.5 + (rng() % 40) / 10.0;
    const double radius = 0.5 + (rng() % 15) / 10.0;
    const Grid inflated = InflateObstacles(grid, radius).value();
    const std::optional<Cell> want = BruteNearest(inflated, goal, tolerance);

    PlanQuery query = Query(start, goal);
    query.goal_tolerance_cells = tolerance;
    query.robot_radius_cells = radius;
    const PlanSnapshot snapshot = Snapshot(grid);
    absl::StatusOr<PlanAnswer> answer = Plan(query, snapshot, Engine("dijkstra"));
    if (!answer.ok()) {
      // Either no cell near the goal is clear, or the start is inscribed.
      const bool start_inscribed = inflated.cost(start) == kInscribedCost;
      EXPECT_TRUE(!want.has_value() || start_inscribed)
          << trial << ": " << answer.status();
      continue;
    }
    ASSERT_TRUE(want.has_value()) << trial;
    EXPECT_EQ(answer->goal, *want) << trial;
    substituted += !(answer->goal == goal);
    const std::optional<Cell> on_stored = BruteNearest(grid, goal, tolerance);
    moved_by_radius += on_stored.has_value() && !(*on_stored == *want);
    const std::optional<double> cost = DijkstraCost(inflated, start, *want);
    ASSERT_EQ(answer->result.found(), cost.has_value()) << trial;
    if (cost.has_value()) {
      EXPECT_DOUBLE_EQ(answer->result.cost, *cost) << trial;
    }
  }
  // The cases the rule is about were met.
  EXPECT_GT(substituted, 20);
  EXPECT_GT(moved_by_radius, 5);
}

TEST(PlanQueryTest, ViaPointsPlanLegByLegAtDijkstrasCost) {
  const PlanSnapshot snapshot = Snapshot(ViaMaze());
  PlanQuery query = Query({0, 0}, {6, 4});
  query.via = {Cell{6, 0}, Cell{0, 2}};
  absl::StatusOr<PlanAnswer> answer = Plan(query, snapshot, Engine("dijkstra"));
  ASSERT_TRUE(answer.ok()) << answer.status();
  ASSERT_TRUE(answer->result.found());
  const Grid& grid = *snapshot.grid;
  const double legs = *DijkstraCost(grid, {0, 0}, {6, 0}) +
                      *DijkstraCost(grid, {6, 0}, {0, 2}) +
                      *DijkstraCost(grid, {0, 2}, {6, 4});
  EXPECT_NEAR(answer->result.cost, legs, 1e-9);
  EXPECT_EQ(answer->reached_goal_index, 2);
  ASSERT_EQ(answer->leg_end_indices.size(), 3u);
  EXPECT_EQ(answer->result.path[answer->leg_end_indices[0]], (Cell{6, 0}));
  EXPECT_EQ(answer->result.path[answer->leg_end_indices[1]], (Cell{0, 2}));
  EXPECT_EQ(answer->result.path.back(), (Cell{6, 4}));

  // A via point the radius made inscribed is named.
  const PlanSnapshot post = Snapshot(MakeGrid({
      "........",
      "........",
      "....#...",
      "........",
      "........",
  }));
  query = Query({0, 0}, {7, 4});
  query.via = {Cell{7, 0}, Cell{4, 3}};
  query.robot_radius_cells = 1.0;
  answer = Plan(query, post, Engine());
  ASSERT_FALSE(answer.ok());
  EXPECT_THAT(answer.status().message(),
              HasSubstr("via[1] (4, 3) is within the robot radius (1 cells)"));
}

TEST(PlanQueryTest, SimplifyNeverCostsMoreThanThePlan) {
  const PlanSnapshot snapshot = Snapshot(MakeGrid({
      "..........",
      "..........",
      "....##....",
      "..........",
      "..........",
  }));
  PlanQuery query = Query({0, 0}, {9, 4});
  absl::StatusOr<PlanAnswer> plain = Plan(query, snapshot, Engine());
  query.simplify = true;
  absl::StatusOr<PlanAnswer> simple = Plan(query, snapshot, Engine());
  ASSERT_TRUE(plain.ok() && simple.ok());
  EXPECT_TRUE(simple->result.any_angle);
  EXPECT_LE(simple->result.cost, plain->result.cost + 1e-9);
  EXPECT_LT(simple->result.path.size(), plain->result.path.size());
}

// Answers with the settled query and says what it saw.
class RecordingSearch final : public StatefulSearch {
 public:
  absl::Status Plan(const PlanQuery& query, const StopCondition&,
                    PlanAnswer* answer) override {
    seen_goal = query.request.goal;
    seen_radius = query.robot_radius_cells;
    answer->result.outcome = PlanOutcome::kFound;
    answer->result.path = {query.request.start, query.request.goal};
    answer->source.map_version = 9;  // a newer version than the query's
    answer->source.cache_hit = true;
    return absl::OkStatus();
  }
  Cell seen_goal;
  double seen_radius = 0.0;
};

TEST(PlanQueryTest, StatefulEngineGetsTheSettledGoalAndReportsItsSource) {
  const PlanSnapshot snapshot = Snapshot(MakeGrid({
      "....",
      "...#",
  }));
  RecordingSearch search;
  PlanQuery query = Query({0, 0}, {3, 1});
  query.goal_tolerance_cells = 1.0;
  PlanEngine engine;
  engine.stateful = &search;
  absl::StatusOr<PlanAnswer> answer = Plan(query, snapshot, engine);
  ASSERT_TRUE(answer.ok()) << answer.status();
  EXPECT_EQ(search.seen_goal, (Cell{3, 0}));
  EXPECT_EQ(answer->goal, (Cell{3, 0}));
  EXPECT_EQ(answer->source.map_version, 9u);
  EXPECT_TRUE(answer->source.cache_hit);
  EXPECT_EQ(answer->reached_goal_index, 0);

  // Exactly one engine.
  EXPECT_EQ(Plan(Query({0, 0}, {1, 0}), snapshot, PlanEngine{}).status().code(),
            absl::StatusCode::kInternal);
}

TEST(PlanQueryTest, GeometricViaPlansJoinTheirPolylinesAtTheViaCentres) {
  const PlanSnapshot snapshot = Snapshot(ViaMaze());
  for (const char* planner : {"navmesh", "visibility_graph", "trapezoidal"}) {
    SCOPED_TRACE(planner);
    PlanQuery query = Query({0, 0}, {6, 4});
    query.planner = planner;
    query.via = {Cell{6, 0}, Cell{0, 2}};
    absl::StatusOr<PlanAnswer> answer = Plan(query, snapshot, Engine(planner));
    ASSERT_TRUE(answer.ok()) << answer.status();
    ASSERT_TRUE(answer->result.found());
    const PlanResult& r = answer->result;
    ASSERT_GE(r.polyline.size(), 4u);
    EXPECT_DOUBLE_EQ(r.polyline.front().x, 0.5);
    EXPECT_DOUBLE_EQ(r.polyline.back().x, 6.5);
    EXPECT_DOUBLE_EQ(r.polyline.back().y, 4.5);
    // Each via centre appears once, in order.
    size_t at = 0;
    for (const CellPoint via : {CellPoint{6.5, 0.5}, CellPoint{0.5, 2.5}}) {
      size_t seen = 0;
      for (size_t i = 0; i < r.polyline.size(); ++i) {
        if (r.polyline[i].x == via.x && r.polyline[i].y == via.y) {
          ++seen;
          EXPECT_GT(i, at);
          at = i;
        }
      }
      EXPECT_EQ(seen, 1u);
    }
    const PathMeasure m = MeasurePolyline(*snapshot.grid, r.polyline, {});
    ASSERT_TRUE(m.valid) << m.first_invalid;
    EXPECT_NEAR(r.length, m.length, 1e-9);
    double legs = 0.0;
    const Cell stops[] = {{0, 0}, {6, 0}, {0, 2}, {6, 4}};
    for (int leg = 0; leg < 3; ++leg) {
      absl::StatusOr<PlanAnswer> one =
          Plan(Query(stops[leg], stops[leg + 1]), snapshot, Engine(planner));
      ASSERT_TRUE(one.ok() && one->result.found());
      legs += one->result.length;
    }
    EXPECT_NEAR(r.length, legs, 1e-9);
    ASSERT_EQ(answer->leg_end_indices.size(), 3u);
    EXPECT_EQ(r.path[answer->leg_end_indices[0]], (Cell{6, 0}));
    EXPECT_EQ(r.path[answer->leg_end_indices[1]], (Cell{0, 2}));
    EXPECT_EQ(r.path.back(), (Cell{6, 4}));
  }
}

// Kinematic planners through via points: each leg starts at the pose where
// the previous one ended (so the robot never turns on the spot between
// legs), a via leg ends at the via cell's centre with any heading, and the
// whole path passes the independent checker for the footprint and the
// turning radius; a colliding via point is named with its leg.
TEST(PlanQueryTest, KinematicViaLegsJoinWherePreviousLegsEnded) {
  // A hall 40 x 24 cells with a wall down the middle, open at both ends.
  std::vector<std::string> rows(24, std::string(40, '.'));
  for (int y = 6; y < 18; ++y) rows[y][20] = '#';
  const PlanSnapshot snapshot = Snapshot(MakeGrid(rows));
  const Footprint rect = Footprint::Polygon({{-0.6, -0.4}, {0.9, -0.4}, {0.9, 0.4}, {-0.6, 0.4}})
                             .value();
  for (const char* planner : {"hybrid_astar", "state_lattice"}) {
    SCOPED_TRACE(planner);
    KinematicQuery k;
    k.start = Pose{4.5, 12.5, 0.0};
    k.goal = Pose{4.5, 4.5, std::numbers::pi};
    k.footprint = SharedFootprintChecker(rect).value();
    k.min_turning_radius_cells = 2.0;
    k.motion = MotionModel::kReedsShepp;
    k.goal_tolerance_cells = 0.5;
    k.goal_tolerance_yaw = 0.1;
    PlanQuery query = Query(k.start.cell(), k.goal.cell());
    query.planner = planner;
    query.simplify = false;
    query.request.kinematic = std::make_shared<KinematicQuery>(k);
    query.via = {Cell{34, 12}, Cell{28, 20}};
    absl::StatusOr<PlanAnswer> answer = Plan(query, snapshot, Engine(planner));
    ASSERT_TRUE(answer.ok()) << answer.status();
    ASSERT_TRUE(answer->result.found()) << PlanOutcomeName(answer->result.outcome);
    const PlanResult& r = answer->result;
    ASSERT_EQ(answer->leg_end_indices.size(), 3u);
    EXPECT_EQ(r.path[answer->leg_end_indices[0]], (Cell{34, 12}));
    EXPECT_EQ(r.path[answer->leg_end_indices[1]], (Cell{28, 20}));
    std::vector<Pose> poses;
    std::vector<bool> reverse;
    for (const PathPose& p : r.poses) {
      poses.push_back(p.pose);
      reverse.push_back(p.reverse);
    }
    testing::KinematicCheck check;
    check.footprint = rect.vertices();
    check.min_turning_radius = k.min_turning_radius_cells;
    check.start = k.start;
    check.goal = k.goal;
    check.goal_tolerance = k.goal_tolerance_cells;
    check.goal_yaw_tolerance = k.goal_tolerance_yaw;
    // The state lattice's control set (cells of the map, not the lattice's
    // 5 cm) turns on its own radii, at least the query's.
    EXPECT_EQ(testing::CheckKinematicPath(*snapshot.grid, poses, reverse, check), "");
    // Each via point is passed within the tolerance.
    for (const Cell via : {Cell{34, 12}, Cell{28, 20}}) {
      double nearest = 1e9;
      for (const Pose& p : poses) {
        nearest = std::min(nearest, std::hypot(p.x - (via.x + 0.5), p.y - (via.y + 0.5)));
      }
      EXPECT_LE(nearest, k.goal_tolerance_cells + 1e-9) << CellToString(via);
    }
  }
  // A via point where the footprint fits at no heading: named with its leg.
  std::vector<std::string> rows2(24, std::string(40, '.'));
  for (int x = 0; x < 40; ++x) rows2[11][x] = '#';
  rows2[11][30] = '.';
  KinematicQuery k;
  k.start = Pose{4.5, 4.5, 0.0};
  k.goal = Pose{8.5, 4.5, 0.0};
  k.footprint = SharedFootprintChecker(rect).value();
  k.min_turning_radius_cells = 2.0;
  PlanQuery query = Query(k.start.cell(), k.goal.cell());
  query.planner = "hybrid_astar";
  query.simplify = false;
  query.request.kinematic = std::make_shared<KinematicQuery>(k);
  query.via = {Cell{30, 11}};
  absl::StatusOr<PlanAnswer> answer =
      Plan(query, Snapshot(MakeGrid(rows2)), Engine("hybrid_astar"));
  ASSERT_FALSE(answer.ok());
  EXPECT_EQ(answer.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(answer.status().message(), HasSubstr("leg 0 (start -> via[0])"));
  EXPECT_THAT(answer.status().message(), HasSubstr("collides"));
}

// Grid planners with smooth_for: the path also as poses smoothed for the
// robot on the map as stored, which the independent checker finds free for
// a disc the planner kept well clear of (the radius's inflation measures
// between cell centres, as Nav2's does, so a disc of the robot radius itself
// may touch a wall's corner: that is what footprint_collision reports); for
// a robot longer than its inscribed disc, footprint_collision names the
// first pose the checker finds colliding, and every pose before it is free.
TEST(PlanQueryTest, SmoothForRobotAnswersPosesAndNamesTheFirstCollision) {
  // A corridor 5 cells wide that turns a right angle.
  std::vector<std::string> rows(24, std::string(24, '#'));
  for (int y = 2; y <= 6; ++y) {
    for (int x = 2; x <= 18; ++x) rows[y][x] = '.';
  }
  for (int y = 2; y <= 21; ++y) {
    for (int x = 14; x <= 18; ++x) rows[y][x] = '.';
  }
  const PlanSnapshot snapshot = Snapshot(MakeGrid(rows));
  const auto poses_of = [](const PlanResult& r) {
    std::vector<Pose> poses;
    for (const PathPose& p : r.poses) poses.push_back(p.pose);
    return poses;
  };
  {
    // Inflated by 2 cells: every path cell's centre is at least 1.58 cells
    // from any wall, so the polyline itself (diagonal steps pass 0.71
    // closer) is free for a 0.7 disc.
    PlanQuery query = Query({4, 4}, {16, 19});
    query.robot_radius_cells = 2.0;
    query.smooth_for = SharedFootprintChecker(Footprint::Circle(0.7).value()).value();
    absl::StatusOr<PlanAnswer> answer = Plan(query, snapshot, Engine("astar"));
    ASSERT_TRUE(answer.ok()) << answer.status();
    ASSERT_TRUE(answer->result.found());
    const std::vector<Pose> poses = poses_of(answer->result);
    ASSERT_GT(poses.size(), answer->result.path.size());
    EXPECT_EQ(answer->footprint_collision, -1);
    testing::KinematicCheck check;
    check.circle_radius = 0.7;
    // A grid path is not a car's: where smoothing cannot round a bend the
    // heading turns over the piece after it.
    check.allow_sideways = true;
    check.allow_reverse = false;
    check.start = poses.front();
    check.goal = Pose{16.5, 19.5, 0.0};
    check.goal_yaw_tolerance = 4.0;
    EXPECT_EQ(testing::CheckKinematicPath(*snapshot.grid, poses,
                                          std::vector<bool>(poses.size(), false), check),
              "");
    EXPECT_DOUBLE_EQ(poses.front().x, 4.5);
    EXPECT_DOUBLE_EQ(poses.front().y, 4.5);
    // Smoothing shortened the path: it left the cell centres' polyline.
    double polyline = 0.0;
    for (size_t i = 1; i < answer->result.path.size(); ++i) {
      const Cell a = answer->result.path[i - 1], b = answer->result.path[i];
      polyline += std::hypot(b.x - a.x, b.y - a.y);
    }
    double smoothed = 0.0;
    double sharpest = 0.0;
    for (size_t i = 1; i < poses.size(); ++i) {
      smoothed += std::hypot(poses[i].x - poses[i - 1].x, poses[i].y - poses[i - 1].y);
      sharpest = std::max(sharpest, std::fabs(NormalizeAngle(poses[i].yaw - poses[i - 1].yaw)));
    }
    EXPECT_LT(smoothed, polyline - 0.1);
    // The 45-degree bends of the cell path are rounded (0.23 rad measured).
    EXPECT_LT(sharpest, 0.5);
  }
  {
    // A robot 4 cells long and 1 wide plans for its inscribed 0.5 and
    // cannot turn the corner.
    const Footprint long_robot =
        Footprint::Polygon({{-2.0, -0.5}, {2.0, -0.5}, {2.0, 0.5}, {-2.0, 0.5}}).value();
    PlanQuery query = Query({4, 4}, {16, 19});
    query.robot_radius_cells = long_robot.inscribed_radius();
    query.smooth_for = SharedFootprintChecker(long_robot).value();
    absl::StatusOr<PlanAnswer> answer = Plan(query, snapshot, Engine("astar"));
    ASSERT_TRUE(answer.ok()) << answer.status();
    ASSERT_TRUE(answer->result.found());
    const std::vector<Pose> poses = poses_of(answer->result);
    ASSERT_GE(answer->footprint_collision, 0);
    ASSERT_LT(answer->footprint_collision, static_cast<int64_t>(poses.size()));
    const auto pose_free = [&](const Pose& p) {
      testing::KinematicCheck check;
      check.footprint = long_robot.vertices();
      check.start = p;
      check.goal = p;
      return testing::CheckKinematicPath(*snapshot.grid, {p}, {false}, check).empty();
    };
    for (int64_t i = 0; i < answer->footprint_collision; ++i) {
      EXPECT_TRUE(pose_free(poses[static_cast<size_t>(i)])) << i;
    }
    EXPECT_FALSE(pose_free(poses[static_cast<size_t>(answer->footprint_collision)]));
  }
}

// A derived store that only says which store a planner was handed.
class TaggedStore final : public DerivedStore {
 public:
  std::shared_ptr<const void> Get(const std::string&, const DerivedRecipe&,
                                  DerivedStop&) override {
    return nullptr;
  }
};

// Plans with A* and remembers the store and grid of its last query.
class StoreRecordingPlanner final : public Planner {
 public:
  std::string_view name() const override { return "recording"; }
  const PlannerTraits& traits() const override { return Get("astar").traits(); }
  absl::StatusOr<PlanResult> Plan(const Grid& grid, const PlanRequest& request,
                                  const StopCondition& stop,
                                  SearchScratch& scratch) const override {
    seen_store = request.derived;
    seen_grid = &grid;
    return Get("astar").Plan(grid, request, stop, scratch);
  }
  mutable DerivedStore* seen_store = nullptr;
  mutable const Grid* seen_grid = nullptr;
};

TEST(PlanQueryTest, PlannersGetTheDerivedStoreOfThePlanningGrid) {
  const PlanSnapshot snapshot = Snapshot(MakeGrid({
      "......",
      "......",
      "...#..",
      "......",
  }));
  StoreRecordingPlanner planner;
  std::shared_ptr<const Grid> store_grid;
  double store_radius = -1.0;
  TaggedStore* handed = nullptr;
  PlanEngine engine;
  engine.planner = &planner;
  engine.derived = [&](const std::shared_ptr<const Grid>& grid, double radius) {
    store_grid = grid;
    store_radius = radius;
    auto store = std::make_unique<TaggedStore>();
    handed = store.get();
    return std::unique_ptr<DerivedStore>(std::move(store));
  };
  ASSERT_TRUE(Plan(Query({0, 0}, {5, 3}), snapshot, engine).ok());
  EXPECT_EQ(store_grid, snapshot.grid);
  EXPECT_EQ(store_radius, 0.0);
  EXPECT_EQ(planner.seen_store, handed);

  // With a robot radius the store belongs to the inflated grid.
  PlanQuery query = Query({0, 0}, {5, 0});
  query.robot_radius_cells = 1.0;
  ASSERT_TRUE(Plan(query, snapshot, engine).ok());
  EXPECT_NE(store_grid, snapshot.grid);
  EXPECT_EQ(store_grid.get(), planner.seen_grid);
  EXPECT_EQ(store_radius, 1.0);
  EXPECT_EQ(planner.seen_store, handed);
}

}  // namespace
}  // namespace pathd
