// PlanRequest.via / allow_partial and PlanOptions.return_expansions over a
// real gRPC channel to a PathdServer on 127.0.0.1:0 whose
// --max_returned_expansions is small enough to truncate. Maps are built per
// test from ASCII rows; the random case uses a fixed seed.
#include <chrono>
#include <cstdint>
#include <memory>
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

constexpr int64_t kMaxReturned = 200;

using testing::Context;

using testing::CellPos;

// A wall with a gap, and a walled-in pocket around (13, 2).
const std::vector<std::string> kRows = {
    "..........#.........",
    "..........#...#####.",
    "..........#...#...#.",
    ".....###..#...#####.",
    "....................",
    "..........#.........",
};

class PlanViaTest : public testing::SharedServerTest<PlanViaTest> {
 public:
  static ServerOptions SuiteOptions() {
    ServerOptions options = testing::TestServerOptions();
    options.max_returned_expansions = kMaxReturned;
    return options;
  }

 protected:
  void SetUp() override { CreateMap("rooms", kRows); }

  // '.' free, '#' lethal.
  void CreateMap(const std::string& name, const std::vector<std::string>& rows) {
    const grpc::Status s = server_->CreateMapFromRows(name, rows, 0.0, /*replace=*/true);
    ASSERT_TRUE(s.ok()) << s.error_message();
  }

  static v1::PlanRequest Request(const std::string& map, v1::Position start,
                                 v1::Position goal,
                                 const std::vector<v1::Position>& via = {},
                                 v1::Planner planner = v1::PLANNER_ASTAR) {
    v1::PlanRequest request;
    request.set_map(map);
    *request.mutable_start() = start;
    *request.mutable_goal() = goal;
    for (const v1::Position& p : via) *request.add_via() = p;
    request.set_planner(planner);
    return request;
  }

  grpc::Status Plan(const v1::PlanRequest& request, v1::PlanResponse* response) {
    return server_->planner().Plan(Context().get(), request, response);
  }
};

bool SameCell(const v1::Cell& a, const v1::Position& b) {
  return a.x() == b.cell().x() && a.y() == b.cell().y();
}

TEST_F(PlanViaTest, ViaPlanCostsTheSumOfItsLegsPlannedAlone) {
  std::mt19937 rng(4242);
  std::vector<v1::Position> free_cells;
  for (int y = 0; y < static_cast<int>(kRows.size()); ++y) {
    for (int x = 0; x < static_cast<int>(kRows[0].size()); ++x) {
      // Outside the pocket (the pocket is unreachable from anywhere else).
      const bool pocket = x >= 15 && x <= 17 && y == 2;
      if (kRows[y][x] == '.' && !pocket) free_cells.push_back(CellPos(x, y));
    }
  }
  std::uniform_int_distribution<size_t> pick(0, free_cells.size() - 1);
  for (int round = 0; round < 20; ++round) {
    SCOPED_TRACE(round);
    std::vector<v1::Position> points;  // start, via..., goal
    for (int i = 0; i < 2 + round % 4; ++i) points.push_back(free_cells[pick(rng)]);
    const std::vector<v1::Position> via(points.begin() + 1, points.end() - 1);
    double legs_cost = 0.0;
    for (size_t i = 0; i + 1 < points.size(); ++i) {
      v1::PlanResponse leg;
      ASSERT_TRUE(Plan(Request("rooms", points[i], points[i + 1], {},
                               v1::PLANNER_DIJKSTRA),
                       &leg)
                      .ok());
      ASSERT_TRUE(leg.found());
      legs_cost += leg.cost();
    }
    v1::PlanResponse through;
    const grpc::Status s =
        Plan(Request("rooms", points.front(), points.back(), via), &through);
    ASSERT_TRUE(s.ok()) << s.error_message();
    ASSERT_TRUE(through.found()) << through.reason();
    EXPECT_NEAR(through.cost(), legs_cost, 1e-9);
    EXPECT_EQ(through.reached_goal_index(), static_cast<int>(via.size()));
    ASSERT_EQ(through.leg_end_indices_size(), static_cast<int>(via.size()) + 1);
    for (size_t i = 0; i < via.size(); ++i) {
      EXPECT_TRUE(SameCell(through.path(through.leg_end_indices(i)), via[i]));
    }
    EXPECT_EQ(through.leg_end_indices(static_cast<int>(via.size())),
              through.path_size() - 1);
    EXPECT_EQ(through.world_path_size(), through.path_size());
    for (int i = 1; i < through.path_size(); ++i) {
      EXPECT_FALSE(through.path(i).x() == through.path(i - 1).x() &&
                   through.path(i).y() == through.path(i - 1).y())
          << "junction cell repeated at " << i;
    }
  }
}

TEST_F(PlanViaTest, PlainPlansReportOneLeg) {
  v1::PlanResponse response;
  ASSERT_TRUE(Plan(Request("rooms", CellPos(0, 0), CellPos(19, 5)), &response).ok());
  ASSERT_TRUE(response.found());
  EXPECT_EQ(response.reached_goal_index(), 0);
  EXPECT_THAT(response.leg_end_indices(), ElementsAre(response.path_size() - 1));
  EXPECT_THAT(response.expanded(), IsEmpty());
}

TEST_F(PlanViaTest, AFailedLegFailsThePlanAndIsNamed) {
  v1::PlanResponse response;
  ASSERT_TRUE(Plan(Request("rooms", CellPos(0, 0), CellPos(16, 2),
                           {CellPos(12, 0), CellPos(19, 5)}),
                   &response)
                  .ok());
  EXPECT_FALSE(response.found());
  EXPECT_EQ(response.outcome(), v1::PLAN_OUTCOME_NO_PATH);
  EXPECT_EQ(response.reason(), "leg 2 (via[1] -> goal): no path from (19, 5) to (16, 2)");
  EXPECT_THAT(response.path(), IsEmpty());
  EXPECT_EQ(response.reached_goal_index(), -1);
  EXPECT_THAT(response.leg_end_indices(), IsEmpty());
  EXPECT_GT(response.expansions(), 0);
}

TEST_F(PlanViaTest, AllowPartialReturnsThePathToTheLastReachedGoal) {
  v1::PlanRequest request =
      Request("rooms", CellPos(0, 0), CellPos(16, 2), {CellPos(12, 0), CellPos(19, 5)});
  request.set_allow_partial(true);
  v1::PlanResponse response;
  ASSERT_TRUE(Plan(request, &response).ok());
  EXPECT_FALSE(response.found());
  EXPECT_EQ(response.outcome(), v1::PLAN_OUTCOME_NO_PATH);
  EXPECT_THAT(response.reason(), HasSubstr("leg 2 (via[1] -> goal)"));
  EXPECT_EQ(response.reached_goal_index(), 1);
  ASSERT_EQ(response.leg_end_indices_size(), 2);
  ASSERT_GT(response.path_size(), 0);
  EXPECT_TRUE(SameCell(response.path(response.leg_end_indices(0)), CellPos(12, 0)));
  EXPECT_TRUE(SameCell(response.path(response.path_size() - 1), CellPos(19, 5)));
  EXPECT_EQ(response.leg_end_indices(1), response.path_size() - 1);
  EXPECT_EQ(response.world_path_size(), response.path_size());
  EXPECT_GT(response.cost(), 0.0);

  // The first leg failing leaves nothing to return.
  v1::PlanRequest first = Request("rooms", CellPos(0, 0), CellPos(0, 5), {CellPos(16, 2)});
  first.set_allow_partial(true);
  ASSERT_TRUE(Plan(first, &response).ok());
  EXPECT_EQ(response.reached_goal_index(), -1);
  EXPECT_THAT(response.path(), IsEmpty());
  EXPECT_THAT(response.reason(), HasSubstr("leg 0 (start -> via[0])"));
}

TEST_F(PlanViaTest, BadViaRequestsAreInvalidArgumentNamingTheField) {
  const auto rejected = [&](const v1::PlanRequest& request) {
    v1::PlanResponse response;
    const grpc::Status s = Plan(request, &response);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << s.error_message();
    return s.error_message();
  };
  EXPECT_EQ(rejected(Request("rooms", CellPos(0, 0), CellPos(19, 5),
                             {CellPos(1, 1), CellPos(30, 1)})),
            "via[1] (30, 1) is outside the 20 x 6 map");
  EXPECT_EQ(rejected(Request("rooms", CellPos(0, 0), CellPos(19, 5), {CellPos(10, 0)})),
            "via[0] (10, 0) is on a blocked cell (cost 254)");
  v1::Position unset;
  EXPECT_THAT(rejected(Request("rooms", CellPos(0, 0), CellPos(19, 5), {unset})),
              HasSubstr("via[0] is not set"));
  v1::Position far;
  far.mutable_world()->set_x(500.0);
  far.mutable_world()->set_y(0.5);
  EXPECT_THAT(
      rejected(Request("rooms", CellPos(0, 0), CellPos(19, 5), {CellPos(1, 1), far})),
      HasSubstr("via[1] world point (500, 0.5) is outside the map"));
  // The cap: 256 via points plan, 257 do not.
  v1::PlanResponse response;
  const std::vector<v1::Position> many(256, CellPos(1, 1));
  ASSERT_TRUE(Plan(Request("rooms", CellPos(0, 0), CellPos(2, 2), many), &response).ok());
  EXPECT_TRUE(response.found());
  EXPECT_EQ(response.reached_goal_index(), 256);
  std::vector<v1::Position> too_many = many;
  too_many.push_back(CellPos(1, 1));
  EXPECT_EQ(rejected(Request("rooms", CellPos(0, 0), CellPos(2, 2), too_many)),
            "via has 257 points; a plan may pass through at most 256");
  // Planners whose state belongs to one goal.
  for (const v1::Planner cached : {v1::PLANNER_SPM, v1::PLANNER_DSTAR_LITE}) {
    EXPECT_THAT(
        rejected(Request("rooms", CellPos(0, 0), CellPos(19, 5), {CellPos(1, 1)}, cached)),
        HasSubstr("via: planner"));
  }
  v1::PlanRequest field = Request("rooms", CellPos(0, 0), CellPos(19, 5), {CellPos(1, 1)},
                                  v1::PLANNER_DISTANCE_TRANSFORM_EXACT);
  field.mutable_options()->set_return_cost_to_go(true);
  EXPECT_THAT(rejected(field), HasSubstr("options.return_cost_to_go"));
  // A via point the robot radius makes inscribed.
  v1::PlanRequest radius =
      Request("rooms", CellPos(0, 0), CellPos(19, 5), {CellPos(1, 1), CellPos(9, 0)});
  radius.mutable_options()->set_robot_radius_cells(1.0);
  EXPECT_THAT(rejected(radius), HasSubstr("via[1] (9, 0) is within the robot radius"));
}

TEST_F(PlanViaTest, GoalToleranceAppliesToTheFinalGoalOnly) {
  v1::PlanRequest request =
      Request("rooms", CellPos(0, 0), CellPos(10, 1), {CellPos(3, 5)});
  request.mutable_options()->set_goal_tolerance_cells(1.0);
  v1::PlanResponse response;
  ASSERT_TRUE(Plan(request, &response).ok());
  EXPECT_TRUE(response.found());
  EXPECT_TRUE(response.goal_substituted());
  EXPECT_EQ(response.reached_goal_index(), 1);

  v1::PlanRequest blocked_via =
      Request("rooms", CellPos(0, 0), CellPos(19, 5), {CellPos(10, 1)});
  blocked_via.mutable_options()->set_goal_tolerance_cells(1.0);
  const grpc::Status s = Plan(blocked_via, &response);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), HasSubstr("via[0] (10, 1) is on a blocked cell"));
}

TEST_F(PlanViaTest, ReturnedExpansionsMatchTheCountUntilTheCap) {
  v1::PlanRequest request = Request("rooms", CellPos(0, 0), CellPos(19, 0));
  request.mutable_options()->set_return_expansions(true);
  v1::PlanResponse response;
  ASSERT_TRUE(Plan(request, &response).ok());
  ASSERT_TRUE(response.found());
  ASSERT_LE(response.expansions(), kMaxReturned);
  EXPECT_EQ(response.expanded_size(), response.expansions());
  EXPECT_FALSE(response.expanded_truncated());
  EXPECT_EQ(response.expanded(0).x(), 0);
  EXPECT_EQ(response.expanded(0).y(), 0);

  // Dijkstra floods the map (more than kMaxReturned cells): truncated.
  CreateMap("big", std::vector<std::string>(20, std::string(20, '.')));
  request = Request("big", CellPos(0, 0), CellPos(19, 19), {}, v1::PLANNER_DIJKSTRA);
  request.mutable_options()->set_return_expansions(true);
  ASSERT_TRUE(Plan(request, &response).ok());
  ASSERT_GT(response.expansions(), kMaxReturned);
  EXPECT_EQ(response.expanded_size(), kMaxReturned);
  EXPECT_TRUE(response.expanded_truncated());

  // Via plans return every leg's.
  v1::PlanRequest via =
      Request("rooms", CellPos(0, 0), CellPos(19, 5), {CellPos(12, 0)});
  via.mutable_options()->set_return_expansions(true);
  ASSERT_TRUE(Plan(via, &response).ok());
  ASSERT_TRUE(response.found());
  ASSERT_LE(response.expansions(), kMaxReturned);
  EXPECT_EQ(response.expanded_size(), response.expansions());

  // The cached planners have no expansions to return.
  v1::PlanRequest spm = Request("rooms", CellPos(0, 0), CellPos(19, 5), {},
                                v1::PLANNER_SPM);
  spm.mutable_options()->set_return_expansions(true);
  ASSERT_TRUE(Plan(spm, &response).ok());
  EXPECT_TRUE(response.found());
  EXPECT_THAT(response.expanded(), IsEmpty());
  EXPECT_FALSE(response.expanded_truncated());
}

}  // namespace
}  // namespace pathd::server
