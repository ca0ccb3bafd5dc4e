// service_test: PlannerService.Plan: costs, outcomes, bad requests, world
// points, snapshots under concurrent updates and the planner caches.
#include "tests/server/rpc/service_fixture.h"

namespace pathd::server::service_test {

TEST_F(ServiceTest, PlanOnOpenGridHasOctileCost) {
  ASSERT_TRUE(CreateFree("open", 10, 10).ok());
  const double octile = 9.0 + 5.0 * (std::sqrt(2.0) - 1.0);
  for (const auto planner : {v1::PLANNER_UNSPECIFIED, v1::PLANNER_ASTAR,
                             v1::PLANNER_DIJKSTRA}) {
    v1::PlanRequest request = CellRequest("open", 0, 0, 9, 5);
    request.set_planner(planner);
    v1::PlanResponse response;
    const grpc::Status status = Plan(request, &response);
    ASSERT_TRUE(status.ok()) << status.error_message();
    EXPECT_TRUE(response.found());
    EXPECT_EQ(response.outcome(), v1::PLAN_OUTCOME_FOUND);
    EXPECT_NEAR(response.cost(), octile, 1e-9);
    EXPECT_NEAR(response.length(), octile, 1e-9);
    EXPECT_EQ(response.map_version(), 1u);
    EXPECT_EQ(response.planner(), planner == v1::PLANNER_DIJKSTRA ? "dijkstra" : "astar");
    ASSERT_GE(response.path_size(), 2);
    EXPECT_EQ(response.path(0).x(), 0);
    EXPECT_EQ(response.path(response.path_size() - 1).x(), 9);
    EXPECT_EQ(response.path(response.path_size() - 1).y(), 5);
    ASSERT_EQ(response.world_path_size(), response.path_size());
    // Resolution 1, origin 0: the centre of cell (x, y) is (x + .5, y + .5).
    EXPECT_DOUBLE_EQ(response.world_path(0).x(), 0.5);
    EXPECT_DOUBLE_EQ(response.world_path(0).y(), 0.5);
    EXPECT_GT(response.expansions(), 0);
  }

  v1::PlanRequest bfs = CellRequest("open", 0, 0, 9, 5);
  bfs.set_planner(v1::PLANNER_BFS);
  v1::PlanResponse response;
  ASSERT_TRUE(Plan(bfs, &response).ok());
  EXPECT_TRUE(response.found());
  EXPECT_EQ(response.planner(), "bfs");
  EXPECT_EQ(response.path_size(), 10);  // 9 moves: the fewest possible

  v1::PlanRequest four = CellRequest("open", 0, 0, 9, 5);
  four.mutable_options()->set_connectivity(v1::CONNECTIVITY_FOUR);
  ASSERT_TRUE(Plan(four, &response).ok());
  EXPECT_NEAR(response.cost(), 14.0, 1e-9);
}

TEST_F(ServiceTest, NoPathIsOkWithFoundFalse) {
  // A full wall at column 2.
  std::string cells(25, '\0');
  for (int y = 0; y < 5; ++y) cells[static_cast<size_t>(y * 5 + 2)] = static_cast<char>(254);
  v1::CreateMapResponse created;
  ASSERT_TRUE(CreateRaw("walled", 5, 5, cells, &created).ok());
  v1::PlanResponse response;
  const grpc::Status status = Plan(CellRequest("walled", 0, 0, 4, 4), &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_FALSE(response.found());
  EXPECT_EQ(response.outcome(), v1::PLAN_OUTCOME_NO_PATH);
  EXPECT_FALSE(response.reason().empty());
  EXPECT_EQ(response.path_size(), 0);
}

TEST_F(ServiceTest, ExpansionLimitIsAnOutcome) {
  ASSERT_TRUE(CreateFree("limit", 50, 50).ok());
  v1::PlanRequest request = CellRequest("limit", 0, 0, 49, 49);
  request.mutable_options()->set_max_expansions(3);
  v1::PlanResponse response;
  ASSERT_TRUE(Plan(request, &response).ok());
  EXPECT_FALSE(response.found());
  EXPECT_EQ(response.outcome(), v1::PLAN_OUTCOME_EXPANSION_LIMIT);
  EXPECT_THAT(response.reason(), HasSubstr("3"));
}

TEST_F(ServiceTest, PlanRejectsBadRequests) {
  std::string cells(16, '\0');
  cells[15] = static_cast<char>(254);  // (3, 3) lethal
  v1::CreateMapResponse created;
  ASSERT_TRUE(CreateRaw("bad-req", 4, 4, cells, &created).ok());
  v1::PlanResponse response;

  const grpc::Status unknown = Plan(CellRequest("nope", 0, 0, 1, 1), &response);
  EXPECT_EQ(unknown.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_EQ(unknown.error_message(), "map 'nope' not found");

  const grpc::Status off = Plan(CellRequest("bad-req", -1, 0, 1, 1), &response);
  EXPECT_EQ(off.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(off.error_message(), HasSubstr("start"));

  const grpc::Status blocked = Plan(CellRequest("bad-req", 0, 0, 3, 3), &response);
  EXPECT_EQ(blocked.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(blocked.error_message(), HasSubstr("goal"));

  v1::PlanRequest planner = CellRequest("bad-req", 0, 0, 1, 1);
  planner.set_planner(static_cast<v1::Planner>(99));
  const grpc::Status bad_planner = Plan(planner, &response);
  EXPECT_EQ(bad_planner.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(bad_planner.error_message(), "unknown planner 99");

  v1::PlanRequest weight = CellRequest("bad-req", 0, 0, 1, 1);
  weight.mutable_options()->set_cost_weight(-1.0);
  const grpc::Status bad_weight = Plan(weight, &response);
  EXPECT_EQ(bad_weight.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(bad_weight.error_message(), HasSubstr("cost_weight"));

  v1::PlanRequest no_goal = CellRequest("bad-req", 0, 0, 1, 1);
  no_goal.clear_goal();
  const grpc::Status missing = Plan(no_goal, &response);
  EXPECT_EQ(missing.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(missing.error_message(), HasSubstr("goal"));

  v1::PlanRequest nan_start = CellRequest("bad-req", 0, 0, 1, 1);
  nan_start.mutable_start()->mutable_world()->set_x(std::nan(""));
  const grpc::Status nan = Plan(nan_start, &response);
  EXPECT_EQ(nan.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(nan.error_message(), HasSubstr("start"));

  v1::PlanRequest far_goal = CellRequest("bad-req", 0, 0, 1, 1);
  far_goal.mutable_goal()->mutable_world()->set_x(100.0);
  far_goal.mutable_goal()->mutable_world()->set_y(0.5);
  const grpc::Status far = Plan(far_goal, &response);
  EXPECT_EQ(far.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(far.error_message(), HasSubstr("goal"));
}

TEST_F(ServiceTest, WorldPointStartResolvesToItsCell) {
  v1::CreateMapRequest create;
  create.set_name("world");
  create.mutable_raw()->set_width(10);
  create.mutable_raw()->set_height(10);
  create.mutable_raw()->set_cells(std::string(100, '\0'));
  create.set_resolution(0.5);
  create.mutable_origin()->set_x(1.0);
  create.mutable_origin()->set_y(2.0);
  v1::CreateMapResponse created;
  grpc::ClientContext context;
  Prepare(context);
  ASSERT_TRUE(maps_->CreateMap(&context, create, &created).ok());

  v1::PlanRequest request = CellRequest("world", 0, 0, 9, 9);
  // Inside cell (3, 4): x in [2.5, 3.0), y in [4.0, 4.5).
  request.mutable_start()->mutable_world()->set_x(2.7);
  request.mutable_start()->mutable_world()->set_y(4.2);
  v1::PlanResponse response;
  const grpc::Status status = Plan(request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(response.start().x(), 3);
  EXPECT_EQ(response.start().y(), 4);
  ASSERT_GT(response.path_size(), 0);
  EXPECT_EQ(response.path(0).x(), 3);
  EXPECT_EQ(response.path(0).y(), 4);
  EXPECT_DOUBLE_EQ(response.world_path(0).x(), 2.75);
  EXPECT_DOUBLE_EQ(response.world_path(0).y(), 4.25);
}

// Plans run on whatever version was current when they arrived. Updates flip a
// wall on and off while plans run; each response must be a legal, optimally
// costed path on the version it reports, which only holds if the plan saw
// one whole version.
TEST_F(ServiceTest, PlansUseOneSnapshotWhileTheMapChanges) {
  constexpr int kSize = 32;
  constexpr int kUpdates = 30;
  ASSERT_TRUE(CreateFree("flip", kSize, kSize).ok());
  Grid open = *Grid::Create(kSize, kSize);
  Grid walled = open;
  for (int y = 0; y < kSize - 1; ++y) walled.set_cost(kSize / 2, y, kLethalCost);
  auto grid_at = [&](uint64_t version) -> const Grid& {
    return version % 2 == 0 ? walled : open;  // v1 open, v2 walled, v3 open...
  };

  std::thread updater([&] {
    auto stub = v1::MapService::NewStub(*channel_);
    for (int i = 0; i < kUpdates; ++i) {
      v1::UpdateMapRequest request;
      request.set_name("flip");
      request.set_expected_version(static_cast<uint64_t>(i + 1));
      auto* change = request.add_changes();
      change->mutable_rect()->set_x_min(kSize / 2);
      change->mutable_rect()->set_x_max(kSize / 2);
      change->mutable_rect()->set_y_min(0);
      change->mutable_rect()->set_y_max(kSize - 2);
      change->set_cost(i % 2 == 0 ? 254 : 0);
      v1::UpdateMapResponse response;
      grpc::ClientContext context;
      Prepare(context);
      ASSERT_TRUE(stub->UpdateMap(&context, request, &response).ok());
    }
  });

  CostParams params;
  std::vector<uint64_t> versions;
  for (int i = 0; i < 40; ++i) {
    v1::PlanRequest request = CellRequest("flip", 0, 0, kSize - 1, 0);
    request.set_planner(i % 2 == 0 ? v1::PLANNER_ASTAR : v1::PLANNER_DIJKSTRA);
    v1::PlanResponse response;
    const grpc::Status status = Plan(request, &response);
    ASSERT_TRUE(status.ok()) << status.error_message();
    ASSERT_TRUE(response.found());
    std::vector<Cell> path;
    for (const auto& c : response.path()) path.push_back(Cell{c.x(), c.y()});
    const PathMeasure measure = MeasurePath(grid_at(response.map_version()), path, params);
    EXPECT_TRUE(measure.valid) << "version " << response.map_version();
    EXPECT_NEAR(measure.cost, response.cost(), 1e-6);
    const double straight = kSize - 1.0;
    if (response.map_version() % 2 == 0) {
      EXPECT_GT(response.cost(), straight + 10.0);  // around the wall
    } else {
      EXPECT_NEAR(response.cost(), straight, 1e-9);
    }
    versions.push_back(response.map_version());
  }
  updater.join();
  EXPECT_TRUE(std::is_sorted(versions.begin(), versions.end()));
}

TEST_F(ServiceTest, ConcurrentPlansAllAnswer) {
  ASSERT_TRUE(CreateFree("busy", 64, 64).ok());
  std::vector<std::thread> clients;
  std::atomic<int> ok{0};
  for (int t = 0; t < 4; ++t) {
    clients.emplace_back([&] {
      auto stub = v1::PlannerService::NewStub(*channel_);
      for (int i = 0; i < 10; ++i) {
        v1::PlanResponse response;
        grpc::ClientContext context;
        Prepare(context);
        if (stub->Plan(&context, CellRequest("busy", 0, 0, 63, 40), &response).ok() &&
            response.found()) {
          ++ok;
        }
      }
    });
  }
  for (auto& c : clients) c.join();
  EXPECT_EQ(ok.load(), 40);
}

// PLANNER_SPM and PLANNER_DSTAR_LITE keep their state between calls: the
// first call builds it, the second reuses it, and after an update the answer
// is on the new version and costs what Dijkstra says there.
TEST_F(ServiceTest, CachedPlannersReuseStateAndFollowUpdates) {
  ASSERT_TRUE(CreateFree("cached", 16, 16).ok());
  const double octile = 9.0 + 5.0 * (std::sqrt(2.0) - 1.0);
  for (const auto planner : {v1::PLANNER_SPM, v1::PLANNER_DSTAR_LITE}) {
    SCOPED_TRACE(v1::Planner_Name(planner));
    v1::PlanRequest request = CellRequest("cached", 0, 0, 9, 5);
    request.set_planner(planner);
    v1::PlanResponse first;
    const grpc::Status status = Plan(request, &first);
    ASSERT_TRUE(status.ok()) << status.error_message();
    EXPECT_TRUE(first.found());
    EXPECT_NEAR(first.cost(), octile, 1e-9);
    EXPECT_FALSE(first.cache_hit());
    EXPECT_EQ(first.map_version(), 1u);
    EXPECT_EQ(first.planner(), planner == v1::PLANNER_SPM ? "spm" : "dstar_lite");
    EXPECT_GT(first.expansions(), 0);

    request.mutable_start()->mutable_cell()->set_x(1);  // the robot moved
    v1::PlanResponse second;
    ASSERT_TRUE(Plan(request, &second).ok());
    EXPECT_TRUE(second.found());
    EXPECT_TRUE(second.cache_hit());
    EXPECT_EQ(second.path(0).x(), 1);
  }

  // A wall across most of the map, between start and goal.
  v1::UpdateMapRequest update;
  update.set_name("cached");
  auto* change = update.add_changes();
  change->mutable_rect()->set_x_min(5);
  change->mutable_rect()->set_x_max(5);
  change->mutable_rect()->set_y_min(0);
  change->mutable_rect()->set_y_max(13);
  change->set_cost(254);
  v1::UpdateMapResponse updated;
  grpc::ClientContext context;
  Prepare(context);
  ASSERT_TRUE(maps_->UpdateMap(&context, update, &updated).ok());

  v1::PlanRequest reference = CellRequest("cached", 1, 0, 9, 5);
  reference.set_planner(v1::PLANNER_DIJKSTRA);
  v1::PlanResponse dijkstra;
  ASSERT_TRUE(Plan(reference, &dijkstra).ok());
  ASSERT_TRUE(dijkstra.found());
  EXPECT_GT(dijkstra.cost(), octile + 5.0);
  for (const auto planner : {v1::PLANNER_SPM, v1::PLANNER_DSTAR_LITE}) {
    SCOPED_TRACE(v1::Planner_Name(planner));
    v1::PlanRequest request = CellRequest("cached", 1, 0, 9, 5);
    request.set_planner(planner);
    v1::PlanResponse response;
    ASSERT_TRUE(Plan(request, &response).ok());
    EXPECT_TRUE(response.found());
    EXPECT_TRUE(response.cache_hit());
    EXPECT_EQ(response.map_version(), 2u);
    EXPECT_NEAR(response.cost(), dijkstra.cost(), 1e-6);
  }
}

}  // namespace pathd::server::service_test
