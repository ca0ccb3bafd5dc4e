// Robots with shape through the real gRPC service (issue 18's service half):
// poses and metres in every PlanResponse, footprints for grid planners,
// IsPathValid with an oriented footprint, and the map_server origin yaw
// convention (ignored as Nav2's costmap ignores it, unless honoured).
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "pathd/v1/map_service.grpc.pb.h"
#include "pathd/v1/planner_service.grpc.pb.h"
#include "server/server.h"
#include "tests/testing/in_process_server.h"
#include "tests/testing/requests.h"
#include "tests/testing/shared_server_test.h"

namespace pathd::server {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;
using testing::CellPos;
using testing::Context;
using testing::WorldPos;

constexpr double kPi = std::numbers::pi;

v1::Position WorldPosePos(double x, double y, double yaw) {
  v1::Position p;
  p.mutable_world_pose()->set_x(x);
  p.mutable_world_pose()->set_y(y);
  p.mutable_world_pose()->set_yaw(yaw);
  return p;
}

v1::Position CellPosePos(double x, double y, double yaw) {
  v1::Position p;
  p.mutable_cell_pose()->set_x(x);
  p.mutable_cell_pose()->set_y(y);
  p.mutable_cell_pose()->set_yaw(yaw);
  return p;
}

// A 0.6 x 0.4 m rectangle (Nav2's example footprint) on `options`.
void Rectangle(v1::PlanOptions* options, double half_length = 0.3, double half_width = 0.2) {
  for (const auto& [x, y] : {std::pair{half_length, half_width}, {half_length, -half_width},
                             {-half_length, -half_width}, {-half_length, half_width}}) {
    v1::WorldPoint* p = options->mutable_footprint()->add_polygon_m();
    p->set_x(x);
    p->set_y(y);
  }
}

class RobotShapeTest : public testing::SharedServerTest<RobotShapeTest> {
 public:
  static ServerOptions SuiteOptions() { return testing::TestServerOptions(); }

 protected:
  void SetUp() override {
    maps_ = &server_->maps();
    planner_ = &server_->planner();
  }

  // A free width x height map at `resolution` with `origin`, lethal cells at
  // `walls`.
  void CreateMap(const std::string& name, int width, int height, double resolution,
                 double ox, double oy, double oyaw, const std::vector<Cell>& walls = {}) {
    v1::CreateMapRequest request;
    request.set_name(name);
    request.set_replace(true);
    request.mutable_raw()->set_width(width);
    request.mutable_raw()->set_height(height);
    std::string cells(static_cast<size_t>(width) * height, '\0');
    for (const Cell& c : walls) cells[static_cast<size_t>(c.y) * width + c.x] = '\xfe';
    request.mutable_raw()->set_cells(cells);
    request.set_resolution(resolution);
    request.mutable_origin()->set_x(ox);
    request.mutable_origin()->set_y(oy);
    request.mutable_origin()->set_yaw(oyaw);
    v1::CreateMapResponse response;
    const grpc::Status s = maps_->CreateMap(Context().get(), request, &response);
    ASSERT_TRUE(s.ok()) << s.error_message();
  }

  grpc::Status Plan(const v1::PlanRequest& request, v1::PlanResponse* response) {
    return planner_->Plan(Context().get(), request, response);
  }

  grpc::Status Check(const std::string& map, const std::vector<v1::Position>& path,
                     const v1::PlanOptions& options, v1::IsPathValidResponse* response) {
    v1::IsPathValidRequest request;
    request.set_map(map);
    for (const v1::Position& p : path) *request.add_path() = p;
    *request.mutable_options() = options;
    return planner_->IsPathValid(Context().get(), request, response);
  }

  v1::MapService::Stub* maps_ = nullptr;
  v1::PlannerService::Stub* planner_ = nullptr;
};

TEST_F(RobotShapeTest, EveryPlanCarriesPosesAndMetres) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("poses", 10, 6, 0.05, 1.0, 2.0, 0.0));
  v1::PlanRequest request = testing::PlanBetween("poses", 0, 0, 4, 0, v1::PLANNER_ASTAR);
  v1::PlanResponse plan;
  ASSERT_TRUE(Plan(request, &plan).ok());
  ASSERT_TRUE(plan.found());
  ASSERT_EQ(plan.poses_size(), 5);
  ASSERT_EQ(plan.world_poses_size(), 5);
  EXPECT_EQ(plan.frame_id(), "map");
  EXPECT_DOUBLE_EQ(plan.length_m(), plan.length() * 0.05);
  EXPECT_DOUBLE_EQ(plan.cost_m(), plan.cost() * 0.05);
  EXPECT_EQ(plan.reverse_size(), 0);
  for (int i = 0; i < 5; ++i) {
    EXPECT_DOUBLE_EQ(plan.poses(i).x(), i + 0.5);
    EXPECT_DOUBLE_EQ(plan.poses(i).y(), 0.5);
    EXPECT_DOUBLE_EQ(plan.poses(i).yaw(), 0.0);  // facing +x, the last too
    EXPECT_NEAR(plan.world_poses(i).x(), 1.0 + (i + 0.5) * 0.05, 1e-12);
    EXPECT_NEAR(plan.world_poses(i).y(), 2.0 + 0.5 * 0.05, 1e-12);
  }
  // Up the column: facing +y.
  request = testing::PlanBetween("poses", 0, 0, 0, 3, v1::PLANNER_ASTAR);
  ASSERT_TRUE(Plan(request, &plan).ok());
  ASSERT_EQ(plan.poses_size(), 4);
  EXPECT_NEAR(plan.poses(3).yaw(), kPi / 2, 1e-12);
}

TEST_F(RobotShapeTest, GridPlannersPlanForTheFootprintsInscribedRadius) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("inscribed", 40, 20, 0.05, 0, 0, 0, {{20, 10}}));
  v1::PlanRequest request = testing::PlanBetween("inscribed", 2, 10, 37, 10, v1::PLANNER_ASTAR);
  Rectangle(request.mutable_options());
  v1::PlanResponse plan;
  ASSERT_TRUE(Plan(request, &plan).ok());
  ASSERT_TRUE(plan.found());
  EXPECT_NEAR(plan.robot_radius_cells(), 4.0, 1e-9);  // 0.2 m at 0.05 m
  EXPECT_NEAR(plan.robot_radius_m(), 0.2, 1e-9);
  // An explicit robot radius wins.
  request.mutable_options()->set_robot_radius_m(0.1);
  ASSERT_TRUE(Plan(request, &plan).ok());
  EXPECT_NEAR(plan.robot_radius_cells(), 2.0, 1e-9);
}

// options.smooth on a grid planner through the service: poses smoothed for
// the footprint on the stored map, footprint_collision unset when it fits
// everywhere; a robot too long for the corner its centre turns gets the
// first pose where it does not; kinematic planners are not touched.
TEST_F(RobotShapeTest, SmoothedGridPathsComeAsPosesWithTheFirstCollision) {
  // A corridor 9 cells (0.45 m) wide turning a right angle, walls 1 cell.
  std::vector<Cell> walls;
  for (int y = 0; y < 40; ++y) {
    for (int x = 0; x < 40; ++x) {
      const bool corridor = (y >= 2 && y <= 10 && x >= 2 && x <= 30) ||
                            (x >= 22 && x <= 30 && y >= 2 && y <= 37);
      if (!corridor) walls.push_back(Cell{x, y});
    }
  }
  ASSERT_NO_FATAL_FAILURE(CreateMap("bend", 40, 40, 0.05, 0, 0, 0, walls));
  v1::PlanRequest request = testing::PlanBetween("bend", 6, 6, 26, 33, v1::PLANNER_ASTAR);
  request.mutable_options()->mutable_footprint()->set_radius_m(0.05);
  request.mutable_options()->set_robot_radius_m(0.15);
  request.mutable_options()->set_smooth(true);
  v1::PlanResponse plan;
  ASSERT_TRUE(Plan(request, &plan).ok());
  ASSERT_TRUE(plan.found()) << plan.reason();
  EXPECT_GT(plan.poses_size(), plan.path_size());
  EXPECT_FALSE(plan.has_footprint_collision());
  EXPECT_DOUBLE_EQ(plan.poses(0).x(), 6.5);
  EXPECT_DOUBLE_EQ(plan.poses(0).y(), 6.5);
  // Unsmoothed: one pose per cell.
  request.mutable_options()->clear_smooth();
  ASSERT_TRUE(Plan(request, &plan).ok());
  EXPECT_EQ(plan.poses_size(), plan.path_size());
  EXPECT_FALSE(plan.has_footprint_collision());
  // 0.6 m long, 0.1 m wide: planned for 0.05 m, it cannot turn the corner.
  request = testing::PlanBetween("bend", 6, 6, 26, 33, v1::PLANNER_ASTAR);
  Rectangle(request.mutable_options(), 0.3, 0.05);
  request.mutable_options()->set_smooth(true);
  ASSERT_TRUE(Plan(request, &plan).ok());
  ASSERT_TRUE(plan.found()) << plan.reason();
  ASSERT_TRUE(plan.has_footprint_collision());
  ASSERT_LT(plan.footprint_collision(), plan.poses_size());
  // IsPathValid (the exact oriented test) agrees: the poses before it are
  // free, the one named is not.
  v1::PlanOptions check_options;
  Rectangle(&check_options, 0.3, 0.05);
  const auto pose_valid = [&](int i) {
    v1::IsPathValidResponse valid;
    const grpc::Status s = Check(
        "bend", {CellPosePos(plan.poses(i).x(), plan.poses(i).y(), plan.poses(i).yaw())},
        check_options, &valid);
    EXPECT_TRUE(s.ok()) << s.error_message();
    return valid.valid();
  };
  EXPECT_FALSE(pose_valid(static_cast<int>(plan.footprint_collision())));
  for (int i = 0; i < plan.footprint_collision(); i += 5) EXPECT_TRUE(pose_valid(i)) << i;
}

TEST_F(RobotShapeTest, BadFootprintsAreNamed) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("badfp", 20, 20, 0.05, 0, 0, 0));
  v1::PlanRequest request = testing::PlanBetween("badfp", 2, 2, 10, 10, v1::PLANNER_ASTAR);
  v1::PlanResponse plan;
  // A bow tie.
  for (const auto& [x, y] : {std::pair{0.0, 0.0}, {0.2, 0.2}, {0.2, 0.0}, {0.0, 0.2}}) {
    v1::WorldPoint* p = request.mutable_options()->mutable_footprint()->add_polygon_m();
    p->set_x(x);
    p->set_y(y);
  }
  grpc::Status s = Plan(request, &plan);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), HasSubstr("options.footprint: footprint edges"));
  request.mutable_options()->mutable_footprint()->set_radius_m(0.3);
  s = Plan(request, &plan);
  EXPECT_THAT(s.error_message(), HasSubstr("exactly one of"));
  request.mutable_options()->clear_footprint();
  request.mutable_options()->mutable_footprint()->set_radius_m(-1);
  s = Plan(request, &plan);
  EXPECT_THAT(s.error_message(), HasSubstr("footprint radius must be a positive"));
  // A pose that is not finite names itself.
  request.mutable_options()->clear_footprint();
  *request.mutable_start() = WorldPosePos(0.2, 0.2, std::nan(""));
  s = Plan(request, &plan);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), HasSubstr("start world pose (0.2, 0.2, nan) is not finite"));
}

// Nav2's costmap places a map_server map unrotated whatever its origin yaw,
// so a world goal lands on the cell it would without the yaw; the yaw is
// kept in the map's metadata.
TEST_F(RobotShapeTest, OriginYawIsIgnoredAsNav2Does) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("rotated", 40, 40, 0.1, -2.0, -2.0, 0.5));
  v1::PlanRequest request;
  request.set_map("rotated");
  *request.mutable_start() = WorldPos(-1.95, -1.95);
  // (1.65, 0.55) m from the origin: cell (16, 5) unrotated; rotated by 0.5
  // rad it would be below row 0, off the map.
  *request.mutable_goal() = WorldPos(-2.0 + 1.65, -2.0 + 0.55);
  v1::PlanResponse plan;
  ASSERT_TRUE(Plan(request, &plan).ok());
  EXPECT_EQ(plan.goal().x(), 16);
  EXPECT_EQ(plan.goal().y(), 5);
  // World poses out come back in the same frame, unrotated.
  ASSERT_GT(plan.world_poses_size(), 0);
  EXPECT_NEAR(plan.world_poses(plan.world_poses_size() - 1).x(), -2.0 + 1.65, 1e-9);
  // A world pose's heading is the grid's heading (frame_yaw 0).
  *request.mutable_goal() = WorldPosePos(-0.35, -1.45, 1.0);
  ASSERT_TRUE(Plan(request, &plan).ok());
  EXPECT_EQ(plan.goal().x(), 16);
  v1::GetMapRequest get;
  get.set_name("rotated");
  v1::GetMapResponse info;
  ASSERT_TRUE(maps_->GetMap(Context().get(), get, &info).ok());
  EXPECT_DOUBLE_EQ(info.info().origin().yaw(), 0.5);
}

// --honour_origin_yaw: world coordinates turn with the yaw.
TEST(RobotShapeOwnServerTest, HonouredOriginYawRotatesWorldCoordinates) {
  ServerOptions options = testing::TestServerOptions();
  options.honour_origin_yaw = true;
  testing::InProcessServer server(options);
  ASSERT_TRUE(server.Start().ok());
  v1::CreateMapRequest create;
  create.set_name("rotated");
  create.mutable_raw()->set_width(40);
  create.mutable_raw()->set_height(40);
  create.mutable_raw()->set_cells(std::string(1600, '\0'));
  create.set_resolution(0.1);
  create.mutable_origin()->set_yaw(kPi / 2);
  v1::CreateMapResponse created;
  const grpc::Status made = server.maps().CreateMap(Context().get(), create, &created);
  ASSERT_TRUE(made.ok()) << made.error_message();
  v1::PlanRequest request;
  request.set_map("rotated");
  *request.mutable_start() = CellPos(0, 0);
  // The grid's x axis points along world +y: world (-0.55, 1.65) is grid
  // (1.65, 0.55) m, cell (16, 5).
  *request.mutable_goal() = WorldPos(-0.55, 1.65);
  v1::PlanResponse plan;
  const grpc::Status planned = server.planner().Plan(Context().get(), request, &plan);
  ASSERT_TRUE(planned.ok()) << planned.error_message();
  ASSERT_TRUE(plan.found()) << plan.reason();
  ASSERT_GT(plan.poses_size(), 0);
  EXPECT_EQ(plan.goal().x(), 16);
  EXPECT_EQ(plan.goal().y(), 5);
  // Headings turn too: the last pose faces along the grid's +x or +y, so in
  // the world frame a quarter turn more.
  const v1::CellPose& last = plan.poses(plan.poses_size() - 1);
  EXPECT_NEAR(std::remainder(plan.world_poses(plan.poses_size() - 1).yaw() - last.yaw(), 2 * kPi),
              kPi / 2, 1e-9);
}

TEST_F(RobotShapeTest, IsPathValidChecksTheOrientedFootprintExactly) {
  // A 60 x 20 corridor at 0.05 m: a lethal cell at (30, 14).
  ASSERT_NO_FATAL_FAILURE(CreateMap("corridor", 60, 20, 0.05, 0, 0, 0, {{30, 14}}));
  v1::PlanOptions options;
  Rectangle(&options);  // 12 x 8 cells
  v1::IsPathValidResponse check;
  // Along y = 9.9: the top edge at 13.9, 0.1 cell below the cell's bottom.
  ASSERT_TRUE(Check("corridor", {CellPosePos(20.5, 9.9, 0), CellPosePos(40.5, 9.9, 0)}, options,
                    &check)
                  .ok());
  EXPECT_TRUE(check.valid()) << check.reason();
  EXPECT_TRUE(check.footprint_checked());
  EXPECT_NEAR(check.length(), 20.0, 1e-12);
  EXPECT_NEAR(check.length_m(), 1.0, 1e-12);
  // Touching the cell at y = 14 is a collision, of the poses and the step.
  ASSERT_TRUE(Check("corridor", {CellPosePos(29.5, 10.0, 0)}, options, &check).ok());
  EXPECT_FALSE(check.valid());
  EXPECT_THAT(check.invalid_indices(), ElementsAre(0));
  ASSERT_TRUE(Check("corridor", {CellPosePos(20.5, 10.0, 0), CellPosePos(40.5, 10.0, 0)},
                    options, &check)
                  .ok());
  EXPECT_THAT(check.invalid_steps(), ElementsAre(1));
  EXPECT_THAT(check.invalid_indices(), ::testing::IsEmpty());
  EXPECT_THAT(check.reason(), HasSubstr("step 0 -> 1"));
  // Turned a quarter, the robot is 12 cells tall: its top at 9.9 + 6.
  ASSERT_TRUE(Check("corridor", {CellPosePos(30.5, 9.9, kPi / 2)}, options, &check).ok());
  EXPECT_FALSE(check.valid());
  // Cells without headings face the next pose (here +x, lengthwise).
  ASSERT_TRUE(Check("corridor", {CellPos(10, 9), CellPos(11, 9), CellPos(12, 9)}, options, &check)
                  .ok());
  EXPECT_TRUE(check.valid()) << check.reason();
  // Off the map is a verdict, not an error.
  ASSERT_TRUE(Check("corridor", {CellPosePos(3.0, 9.9, 0)}, options, &check).ok());
  EXPECT_FALSE(check.valid());
  EXPECT_THAT(check.reason(), HasSubstr("leaves the map"));
}

}  // namespace
}  // namespace pathd::server
