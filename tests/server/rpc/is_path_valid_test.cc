// IsPathValid and PlanOptions.goal_tolerance over a real gRPC channel to a
// PathdServer on 127.0.0.1:0. Maps are built per test from ASCII rows; the
// random cases use fixed seeds.
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include <grpcpp/create_channel.h>
#include <grpcpp/security/credentials.h>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "pathd/v1/map_service.grpc.pb.h"
#include "pathd/v1/planner_service.grpc.pb.h"
#include "server/server.h"
#include "tests/testing/in_process_server.h"
#include "tests/testing/shared_server_test.h"
#include "tests/testing/requests.h"

namespace pathd::server {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::IsEmpty;

using testing::Context;

using testing::CellPos;
using testing::WorldPos;

class PathCheckTest : public testing::SharedServerTest<PathCheckTest> {
 public:
  static ServerOptions SuiteOptions() {
    ServerOptions options = testing::TestServerOptions();
    // Also sets the receive limit, which the over-long path must get past.
    options.max_map_cells = 1 << 24;
    return options;
  }

 protected:
  void SetUp() override {
    maps_ = &server_->maps();
    planner_ = &server_->planner();
  }

  // '.' free, '#' lethal, '5' cost 50, '?' unknown.
  void CreateMap(const std::string& name, const std::vector<std::string>& rows,
                 double resolution = 0.0) {
    const grpc::Status s =
        server_->CreateMapFromRows(name, rows, resolution, /*replace=*/true);
    ASSERT_TRUE(s.ok()) << s.error_message();
  }

  void CreateRawMap(const std::string& name, int width, int height,
                    const std::string& cells, double resolution = 0.0) {
    const grpc::Status s =
        server_->CreateRawMap(name, width, height, cells, resolution, /*replace=*/true);
    ASSERT_TRUE(s.ok()) << s.error_message();
  }

  uint64_t SetCell(const std::string& map, int x, int y, uint32_t cost) {
    v1::UpdateMapRequest request;
    request.set_name(map);
    v1::CellChange* change = request.add_changes();
    change->mutable_cell()->set_x(x);
    change->mutable_cell()->set_y(y);
    change->set_cost(cost);
    v1::UpdateMapResponse response;
    const grpc::Status s = maps_->UpdateMap(Context().get(), request, &response);
    EXPECT_TRUE(s.ok()) << s.error_message();
    return response.version();
  }

  grpc::Status Check(const std::string& map, const std::vector<v1::Position>& path,
                     v1::IsPathValidResponse* response,
                     const v1::PlanOptions& options = v1::PlanOptions()) {
    v1::IsPathValidRequest request;
    request.set_map(map);
    for (const v1::Position& p : path) *request.add_path() = p;
    *request.mutable_options() = options;
    return planner_->IsPathValid(Context().get(), request, response);
  }

  grpc::Status Plan(const v1::PlanRequest& request, v1::PlanResponse* response) {
    return planner_->Plan(Context().get(), request, response);
  }

  static v1::PlanRequest PlanBetween(const std::string& map, int sx, int sy, int gx,
                                     int gy) {
    return testing::PlanBetween(map, sx, sy, gx, gy, v1::PLANNER_UNSPECIFIED);
  }

  v1::MapService::Stub* maps_ = nullptr;
  v1::PlannerService::Stub* planner_ = nullptr;
};

// --- IsPathValid -------------------------------------------------------------

TEST_F(PathCheckTest, PlannedPathIsValidWithThePlansCost) {
  CreateMap("valid", {
                         "..........",
                         ".####.55..",
                         "....#.55..",
                         "....#.....",
                         "..........",
                     });
  v1::PlanResponse plan;
  ASSERT_TRUE(Plan(PlanBetween("valid", 0, 0, 9, 4), &plan).ok());
  ASSERT_TRUE(plan.found());
  std::vector<v1::Position> path;
  for (const v1::Cell& c : plan.path()) path.push_back(CellPos(c.x(), c.y()));

  v1::IsPathValidResponse check;
  ASSERT_TRUE(Check("valid", path, &check).ok());
  EXPECT_TRUE(check.valid()) << check.reason();
  EXPECT_THAT(check.invalid_indices(), IsEmpty());
  EXPECT_THAT(check.invalid_steps(), IsEmpty());
  EXPECT_TRUE(check.reason().empty());
  EXPECT_EQ(check.map_version(), plan.map_version());
  EXPECT_DOUBLE_EQ(check.cost(), plan.cost());
  EXPECT_DOUBLE_EQ(check.length(), plan.length());

  // The same path as world points (resolution 1, origin 0: cell centres).
  std::vector<v1::Position> world;
  for (const v1::Cell& c : plan.path()) world.push_back(WorldPos(c.x() + 0.5, c.y() + 0.5));
  v1::IsPathValidResponse world_check;
  ASSERT_TRUE(Check("valid", world, &world_check).ok());
  EXPECT_TRUE(world_check.valid()) << world_check.reason();
  EXPECT_DOUBLE_EQ(world_check.cost(), plan.cost());
}

TEST_F(PathCheckTest, BlockedPosesAreListed) {
  CreateMap("blocked", {
                           "..#..",
                           "..#..",
                           "..?..",
                       });
  // Straight along row 0 then down column 2: poses 2, 3 (lethal) and 4
  // (unknown) are blocked; every step is one straight move.
  const std::vector<v1::Position> path = {CellPos(0, 0), CellPos(1, 0), CellPos(2, 0),
                                          CellPos(2, 1), CellPos(2, 2), CellPos(3, 2)};
  v1::IsPathValidResponse check;
  ASSERT_TRUE(Check("blocked", path, &check).ok());
  EXPECT_FALSE(check.valid());
  EXPECT_THAT(check.invalid_indices(), ElementsAre(2, 3, 4));
  EXPECT_THAT(check.invalid_steps(), IsEmpty());
  EXPECT_THAT(check.reason(), HasSubstr("pose 2 (2, 0) is on a blocked cell (cost 254)"));
  EXPECT_DOUBLE_EQ(check.cost(), 0.0);

  // unknown_is_free clears pose 4 only.
  v1::PlanOptions options;
  options.set_unknown_is_free(true);
  ASSERT_TRUE(Check("blocked", path, &check, options).ok());
  EXPECT_THAT(check.invalid_indices(), ElementsAre(2, 3));
}

TEST_F(PathCheckTest, OffMapPosesAreInvalidNotErrors) {
  CreateMap("offmap", {"...", "..."});
  const std::vector<v1::Position> path = {CellPos(-1, 0), CellPos(0, 0), CellPos(1, 0),
                                          WorldPos(50.0, 0.5), CellPos(2, 1),
                                          CellPos(3, 1)};
  v1::IsPathValidResponse check;
  ASSERT_TRUE(Check("offmap", path, &check).ok());
  EXPECT_FALSE(check.valid());
  EXPECT_THAT(check.invalid_indices(), ElementsAre(0, 3, 5));
  // Steps next to the world point off the map are not checked; the rest are
  // single moves.
  EXPECT_THAT(check.invalid_steps(), IsEmpty());
  EXPECT_THAT(check.reason(), HasSubstr("pose 0 (-1, 0) is outside the 3 x 2 map"));
}

TEST_F(PathCheckTest, IllegalStepsAreListed) {
  CreateMap("steps", {
                         "....",
                         ".#..",
                         "....",
                     });
  // 0->1 cuts the corner of (1,1); 1->2 repeats a cell; 2->3 jumps two
  // columns; 3->4 is a legal diagonal; 4->5 is straight.
  const std::vector<v1::Position> path = {CellPos(0, 1), CellPos(1, 0), CellPos(1, 0),
                                          CellPos(3, 0), CellPos(2, 1), CellPos(2, 2)};
  v1::IsPathValidResponse check;
  ASSERT_TRUE(Check("steps", path, &check).ok());
  EXPECT_FALSE(check.valid());
  EXPECT_THAT(check.invalid_indices(), IsEmpty());
  EXPECT_THAT(check.invalid_steps(), ElementsAre(1, 2, 3));
  EXPECT_EQ(check.reason(), "step 0 -> 1 from (0, 1) to (1, 0): cuts a corner");

  // 4-connected, the legal diagonal 3->4 is illegal too.
  v1::PlanOptions four;
  four.set_connectivity(v1::CONNECTIVITY_FOUR);
  ASSERT_TRUE(Check("steps", path, &check, four).ok());
  EXPECT_THAT(check.invalid_steps(), ElementsAre(1, 2, 3, 4));
  EXPECT_THAT(check.reason(), HasSubstr("diagonal on a 4-connected grid"));
}

TEST_F(PathCheckTest, PathBecomesInvalidAfterUpdateAndNamesTheVersion) {
  CreateMap("update", {".....", ".....", "....."});
  const std::vector<v1::Position> path = {CellPos(0, 1), CellPos(1, 1), CellPos(2, 1),
                                          CellPos(3, 1), CellPos(4, 1)};
  v1::IsPathValidResponse before;
  ASSERT_TRUE(Check("update", path, &before).ok());
  EXPECT_TRUE(before.valid());
  EXPECT_DOUBLE_EQ(before.cost(), 4.0);

  const uint64_t version = SetCell("update", 2, 1, 254);
  ASSERT_GT(version, before.map_version());
  v1::IsPathValidResponse after;
  ASSERT_TRUE(Check("update", path, &after).ok());
  EXPECT_FALSE(after.valid());
  EXPECT_EQ(after.map_version(), version);
  EXPECT_THAT(after.invalid_indices(), ElementsAre(2));
}

TEST_F(PathCheckTest, RobotRadiusInvalidatesPosesNearObstacles) {
  CreateMap("radius", {
                          ".......",
                          ".......",
                          "...#...",
                          ".......",
                          ".......",
                      });
  // Row 1 passes one cell above the obstacle at (3,2).
  std::vector<v1::Position> path;
  for (int x = 0; x < 7; ++x) path.push_back(CellPos(x, 1));
  v1::IsPathValidResponse check;
  ASSERT_TRUE(Check("radius", path, &check).ok());
  EXPECT_TRUE(check.valid());

  // Radius 1 inscribes the four neighbours of (3,2); radius 1.5 also the
  // diagonal ones.
  v1::PlanOptions options;
  options.set_robot_radius_cells(1.0);
  ASSERT_TRUE(Check("radius", path, &check, options).ok());
  EXPECT_FALSE(check.valid());
  EXPECT_THAT(check.invalid_indices(), ElementsAre(3));
  EXPECT_DOUBLE_EQ(check.robot_radius_cells(), 1.0);
  EXPECT_THAT(check.reason(),
              HasSubstr("pose 3 (3, 1) is within the robot radius (1 cells)"));
  options.set_robot_radius_cells(1.5);
  ASSERT_TRUE(Check("radius", path, &check, options).ok());
  EXPECT_THAT(check.invalid_indices(), ElementsAre(2, 3, 4));
}

TEST_F(PathCheckTest, BadRequestsAreInvalidArgument) {
  CreateMap("bad", {"...", "..."});
  v1::IsPathValidResponse check;
  grpc::Status s = Check("bad", {}, &check);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), HasSubstr("path is empty"));

  s = Check("bad", {CellPos(0, 0), v1::Position()}, &check);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), HasSubstr("path[1] is not set"));

  s = Check("bad", {CellPos(0, 0), WorldPos(NAN, 0.0)}, &check);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), HasSubstr("path[1] world point"));

  v1::PlanOptions options;
  options.set_robot_radius_cells(-1.0);
  s = Check("bad", {CellPos(0, 0)}, &check, options);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), HasSubstr("robot_radius_cells"));

  s = Check("no_such_map", {CellPos(0, 0)}, &check);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::NOT_FOUND);
}

TEST_F(PathCheckTest, PathOverTheLimitNamesTheLimit) {
  CreateMap("long", {"..", ".."});
  v1::IsPathValidRequest request;
  request.set_map("long");
  for (int i = 0; i < (1 << 20) + 1; ++i) *request.add_path() = CellPos(i & 1, 0);
  v1::IsPathValidResponse check;
  const grpc::Status s = planner_->IsPathValid(Context().get(), request, &check);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(),
              HasSubstr("the limit of 1048576 (--max_path_points)"));

  // Exactly at the limit it is checked: back and forth along row 0.
  request.mutable_path()->RemoveLast();
  ASSERT_TRUE(planner_->IsPathValid(Context().get(), request, &check).ok());
  EXPECT_TRUE(check.valid());
  EXPECT_DOUBLE_EQ(check.length(), (1 << 20) - 1);
}

// --- goal tolerance ----------------------------------------------------------

// The nearest traversable cell within `tolerance` by (squared distance, y,
// x), by looking at every cell.
std::optional<std::pair<int, int>> BruteNearest(const std::string& cells, int width,
                                                int height, int gx, int gy,
                                                double tolerance) {
  std::optional<std::pair<int, int>> best;
  int64_t best_d2 = 0;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      if (static_cast<uint8_t>(cells[y * width + x]) >= 253) continue;
      const int64_t d2 = int64_t{x - gx} * (x - gx) + int64_t{y - gy} * (y - gy);
      if (static_cast<double>(d2) > tolerance * tolerance) continue;
      // Row-major order already breaks ties by y, then x.
      if (!best.has_value() || d2 < best_d2) {
        best = {x, y};
        best_d2 = d2;
      }
    }
  }
  return best;
}

TEST_F(PathCheckTest, GoalToleranceSubstitutesTheNearestFreeCell) {
  std::mt19937 rng(20240611);
  int substituted = 0;
  int none = 0;
  for (int trial = 0; trial < 120; ++trial) {
    const int width = 5 + static_cast<int>(rng() % 20);
    const int height = 5 + static_cast<int>(rng() % 20);
    // Dense enough that blocked goals with distant substitutes and goals
    // with nothing in reach both occur.
    const double density = 0.3 + 0.5 * (rng() % 100) / 100.0;
    std::string cells(static_cast<size_t>(width * height), '\0');
    for (char& c : cells) {
      if ((rng() % 1000) / 1000.0 < density) c = static_cast<char>(254);
    }
    const int sx = static_cast<int>(rng() % width);
    const int sy = static_cast<int>(rng() % height);
    // Anywhere but the start.
    const int goal_index = (sy * width + sx + 1 +
                            static_cast<int>(rng() % (width * height - 1))) %
                           (width * height);
    const int gx = goal_index % width;
    const int gy = goal_index / width;
    cells[sy * width + sx] = '\0';
    cells[gy * width + gx] = static_cast<char>(254);
    const double tolerance = 0.5 + (rng() % 40) / 10.0;
    const std::string name = "tolerance" + std::to_string(trial);
    CreateRawMap(name, width, height, cells);

    v1::PlanRequest request = PlanBetween(name, sx, sy, gx, gy);
    request.mutable_options()->set_goal_tolerance_cells(tolerance);
    v1::PlanResponse plan;
    const grpc::Status s = Plan(request, &plan);
    const auto expected = BruteNearest(cells, width, height, gx, gy, tolerance);
    if (!expected.has_value()) {
      ++none;
      EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << trial;
      EXPECT_THAT(s.error_message(), HasSubstr("goal tolerance")) << trial;
      continue;
    }
    ++substituted;
    ASSERT_TRUE(s.ok()) << trial << ": " << s.error_message();
    EXPECT_TRUE(plan.goal_substituted()) << trial;
    EXPECT_EQ(plan.requested_goal().x(), gx) << trial;
    EXPECT_EQ(plan.requested_goal().y(), gy) << trial;
    EXPECT_EQ(plan.goal().x(), expected->first) << trial;
    EXPECT_EQ(plan.goal().y(), expected->second) << trial;
    if (plan.found()) {
      EXPECT_EQ(plan.path().rbegin()->x(), expected->first) << trial;
      EXPECT_EQ(plan.path().rbegin()->y(), expected->second) << trial;
    } else {
      // Nearest, not nearest reachable: an unreachable substitute is NO_PATH.
      EXPECT_EQ(plan.outcome(), v1::PLAN_OUTCOME_NO_PATH) << trial;
    }
    v1::DeleteMapRequest del;
    del.set_name(name);
    v1::DeleteMapResponse deleted;
    ASSERT_TRUE(maps_->DeleteMap(Context().get(), del, &deleted).ok());
  }
  // Both branches were exercised.
  EXPECT_GT(substituted, 20);
  EXPECT_GT(none, 5);
}

TEST_F(PathCheckTest, GoalToleranceLeavesFreeGoalsAlone) {
  CreateMap("free_goal", {".....", ".....", "....."});
  v1::PlanRequest request = PlanBetween("free_goal", 0, 0, 4, 2);
  request.mutable_options()->set_goal_tolerance_cells(3.0);
  v1::PlanResponse plan;
  ASSERT_TRUE(Plan(request, &plan).ok());
  EXPECT_FALSE(plan.goal_substituted());
  EXPECT_EQ(plan.goal().x(), 4);
  EXPECT_EQ(plan.requested_goal().x(), 4);
}

TEST_F(PathCheckTest, WithoutToleranceABlockedGoalStaysAnError) {
  CreateMap("no_tolerance", {"...#", "...."});
  v1::PlanResponse plan;
  grpc::Status s = Plan(PlanBetween("no_tolerance", 0, 0, 3, 0), &plan);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), HasSubstr("goal (3, 0) is on a blocked cell"));

  // Tolerance 0.5 reaches no other cell centre.
  v1::PlanRequest request = PlanBetween("no_tolerance", 0, 0, 3, 0);
  request.mutable_options()->set_goal_tolerance_cells(0.5);
  s = Plan(request, &plan);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(),
              HasSubstr("goal (3, 0) is on a blocked cell (cost 254) and no cell "
                        "within the goal tolerance of 0.5 cells is free"));

  // Off the map stays an error whatever the tolerance.
  request = PlanBetween("no_tolerance", 0, 0, 9, 0);
  request.mutable_options()->set_goal_tolerance_cells(10.0);
  s = Plan(request, &plan);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), HasSubstr("goal (9, 0) is outside"));
}

TEST_F(PathCheckTest, BadToleranceNamesTheField) {
  CreateMap("bad_tolerance", {"...#", "...."});
  v1::PlanRequest request = PlanBetween("bad_tolerance", 0, 0, 3, 0);
  request.mutable_options()->set_goal_tolerance_cells(-1.0);
  v1::PlanResponse plan;
  grpc::Status s = Plan(request, &plan);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), HasSubstr("options.goal_tolerance_cells -1"));
  request.mutable_options()->set_goal_tolerance_m(2000.0);
  s = Plan(request, &plan);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), HasSubstr("the limit is 1024 cells"));
}

TEST_F(PathCheckTest, GoalToleranceInMetres) {
  // Resolution 0.5: 0.7 m is 1.4 cells, which reaches (3,1) from (3,2) but
  // not the diagonal (2,1) or (4,1); 0.2 m reaches nothing.
  CreateMap("metres",
            {
                ".....",
                ".....",
                ".####",
            },
            0.5);
  v1::PlanRequest request = PlanBetween("metres", 0, 0, 3, 2);
  request.mutable_options()->set_goal_tolerance_m(0.7);
  v1::PlanResponse plan;
  ASSERT_TRUE(Plan(request, &plan).ok());
  // Within 1.4 cells of (3,2): (3,1) at distance 1.
  EXPECT_EQ(plan.goal().x(), 3);
  EXPECT_EQ(plan.goal().y(), 1);
  request.mutable_options()->set_goal_tolerance_m(0.2);
  EXPECT_EQ(Plan(request, &plan).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
}

TEST_F(PathCheckTest, GoalToleranceWorksWithTheCachedPlanners) {
  CreateMap("cached", {
                          "........",
                          "...###..",
                          "...###..",
                          "...###..",
                          "........",
                      });
  for (const v1::Planner planner : {v1::PLANNER_SPM, v1::PLANNER_DSTAR_LITE}) {
    SCOPED_TRACE(v1::Planner_Name(planner));
    // (4,2) is the block's centre: the nearest free cells, (4,0), (2,2),
    // (6,2) and (4,4), are all 2 away; (4,0) wins on y.
    v1::PlanRequest request = PlanBetween("cached", 0, 4, 4, 2);
    request.set_planner(planner);
    request.mutable_options()->set_goal_tolerance_cells(2.0);
    v1::PlanResponse plan;
    ASSERT_TRUE(Plan(request, &plan).ok());
    ASSERT_TRUE(plan.found());
    EXPECT_TRUE(plan.goal_substituted());
    EXPECT_EQ(plan.goal().x(), 4);
    EXPECT_EQ(plan.goal().y(), 0);
    EXPECT_EQ(plan.path().rbegin()->x(), 4);
    EXPECT_EQ(plan.path().rbegin()->y(), 0);
    // The cache entry is keyed on the substitute: asking for it directly hits.
    v1::PlanRequest direct = PlanBetween("cached", 0, 4, 4, 0);
    direct.set_planner(planner);
    v1::PlanResponse again;
    ASSERT_TRUE(Plan(direct, &again).ok());
    EXPECT_TRUE(again.cache_hit());
    EXPECT_DOUBLE_EQ(again.cost(), plan.cost());
  }
}

TEST_F(PathCheckTest, GoalToleranceWithRobotRadiusAvoidsInscribedCells) {
  CreateMap("radius_goal", {
                               "........",
                               "........",
                               "....#...",
                               "........",
                               "........",
                           });
  // (4,1) is free but within radius 1.5 of (4,2), as are (3,1) and (5,1);
  // the nearest clear cell is (4,0) at distance 1.
  v1::PlanRequest request = PlanBetween("radius_goal", 0, 4, 4, 1);
  request.mutable_options()->set_robot_radius_cells(1.5);
  v1::PlanResponse plan;
  grpc::Status s = Plan(request, &plan);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), HasSubstr("within the robot radius"));

  request.mutable_options()->set_goal_tolerance_cells(1.0);
  ASSERT_TRUE(Plan(request, &plan).ok());
  EXPECT_TRUE(plan.found());
  EXPECT_TRUE(plan.goal_substituted());
  EXPECT_EQ(plan.goal().x(), 4);
  EXPECT_EQ(plan.goal().y(), 0);

  // The lethal cell itself with too small a tolerance: every cell within 1
  // of it is inscribed.
  request = PlanBetween("radius_goal", 0, 4, 4, 2);
  request.mutable_options()->set_robot_radius_cells(1.5);
  request.mutable_options()->set_goal_tolerance_cells(1.0);
  s = Plan(request, &plan);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(),
              HasSubstr("goal tolerance of 1 cells is free for the robot radius "
                        "(1.5 cells)"));
}

}  // namespace
}  // namespace pathd::server
