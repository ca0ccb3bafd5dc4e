// service_test: CostToGo, GetCacheStats and ReplacePort.
#include "tests/server/rpc/service_fixture.h"

namespace pathd::server::service_test {

TEST_F(ServiceTest, CostToGoReturnsTheFieldOrAWindow) {
  // Free 6 x 4 map with one lethal cell at (2, 1).
  std::string cells(24, '\0');
  cells[1 * 6 + 2] = static_cast<char>(254);
  v1::CreateMapResponse created;
  ASSERT_TRUE(CreateRaw("ctg", 6, 4, cells, &created).ok());

  v1::CostToGoRequest request;
  request.set_map("ctg");
  request.mutable_goal()->mutable_cell()->set_x(5);
  request.mutable_goal()->mutable_cell()->set_y(3);
  v1::CostToGoResponse whole;
  {
    grpc::ClientContext context;
    Prepare(context);
    const grpc::Status status = planner_->CostToGo(&context, request, &whole);
    ASSERT_TRUE(status.ok()) << status.error_message();
  }
  EXPECT_EQ(whole.map_version(), 1u);
  EXPECT_EQ(whole.goal().x(), 5);
  EXPECT_EQ(whole.window().width(), 6);
  EXPECT_EQ(whole.window().height(), 4);
  ASSERT_EQ(whole.cost_size(), 24);
  EXPECT_EQ(whole.cost(3 * 6 + 5), 0.0f);
  EXPECT_TRUE(std::isinf(whole.cost(1 * 6 + 2)));
  // Cells the lethal one does not shadow are at their octile distance.
  EXPECT_NEAR(whole.cost(0 * 6 + 5), 3.0f, 1e-5);
  EXPECT_NEAR(whole.cost(3 * 6 + 0), 5.0f, 1e-5);
  EXPECT_NEAR(whole.cost(0 * 6 + 3), 1.0f + 2.0f * std::sqrt(2.0f), 1e-5);

  // Every field value is the cost of the optimal path from that cell.
  for (int y = 0; y < 4; ++y) {
    for (int x = 0; x < 6; ++x) {
      if (x == 2 && y == 1) continue;
      v1::PlanRequest plan = CellRequest("ctg", x, y, 5, 3);
      plan.set_planner(v1::PLANNER_DIJKSTRA);
      v1::PlanResponse response;
      ASSERT_TRUE(Plan(plan, &response).ok());
      EXPECT_NEAR(whole.cost(y * 6 + x), response.cost(), 1e-5) << x << "," << y;
    }
  }

  v1::CostToGoRequest windowed = request;
  windowed.mutable_window()->set_x(1);
  windowed.mutable_window()->set_y(1);
  windowed.mutable_window()->set_width(3);
  windowed.mutable_window()->set_height(2);
  v1::CostToGoResponse part;
  {
    grpc::ClientContext context;
    Prepare(context);
    ASSERT_TRUE(planner_->CostToGo(&context, windowed, &part).ok());
  }
  EXPECT_TRUE(part.cache_hit());
  EXPECT_EQ(part.expansions(), 0);
  EXPECT_EQ(part.window().x(), 1);
  EXPECT_EQ(part.window().width(), 3);
  ASSERT_EQ(part.cost_size(), 6);
  for (int y = 0; y < 2; ++y) {
    for (int x = 0; x < 3; ++x) {
      const float expected = whole.cost((y + 1) * 6 + (x + 1));
      if (std::isinf(expected)) {
        EXPECT_TRUE(std::isinf(part.cost(y * 3 + x)));
      } else {
        EXPECT_EQ(part.cost(y * 3 + x), expected);
      }
    }
  }
}

TEST_F(ServiceTest, CostToGoRejectsBadRequests) {
  std::string cells(16, '\0');
  cells[15] = static_cast<char>(254);  // (3, 3) lethal
  v1::CreateMapResponse created;
  ASSERT_TRUE(CreateRaw("ctg-bad", 4, 4, cells, &created).ok());
  const auto call = [&](const v1::CostToGoRequest& request) {
    v1::CostToGoResponse response;
    grpc::ClientContext context;
    Prepare(context);
    return planner_->CostToGo(&context, request, &response);
  };
  v1::CostToGoRequest base;
  base.set_map("ctg-bad");
  base.mutable_goal()->mutable_cell()->set_x(0);
  base.mutable_goal()->mutable_cell()->set_y(0);

  v1::CostToGoRequest unknown = base;
  unknown.set_map("nope");
  const grpc::Status not_found = call(unknown);
  EXPECT_EQ(not_found.error_code(), grpc::StatusCode::NOT_FOUND);

  v1::CostToGoRequest blocked = base;
  blocked.mutable_goal()->mutable_cell()->set_x(3);
  blocked.mutable_goal()->mutable_cell()->set_y(3);
  const grpc::Status on_wall = call(blocked);
  EXPECT_EQ(on_wall.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(on_wall.error_message(), HasSubstr("goal (3, 3)"));

  v1::CostToGoRequest empty = base;
  empty.mutable_window()->set_width(0);
  empty.mutable_window()->set_height(2);
  const grpc::Status zero = call(empty);
  EXPECT_EQ(zero.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(zero.error_message(), HasSubstr("window.width"));

  v1::CostToGoRequest off = base;
  off.mutable_window()->set_x(0);
  off.mutable_window()->set_y(3);
  off.mutable_window()->set_width(4);
  off.mutable_window()->set_height(2);
  const grpc::Status outside = call(off);
  EXPECT_EQ(outside.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(outside.error_message(), HasSubstr("window.y"));

  v1::CostToGoRequest radius = base;
  radius.mutable_options()->set_robot_radius_cells(-1.0);
  EXPECT_EQ(call(radius).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
}

TEST_F(ServiceTest, CostToGoRefusesFieldsOverFourMiCells) {
  ServerOptions options = testing::TestServerOptions();
  options.threads = 1;
  options.max_map_cells = int64_t{1} << 23;
  testing::InProcessServer big(options);
  ASSERT_TRUE(big.Start().ok());
  v1::MapService::Stub* maps = &big.maps();
  v1::PlannerService::Stub* planner = &big.planner();
  v1::CreateMapRequest create;
  create.set_name("big");
  create.mutable_raw()->set_width(2048);
  create.mutable_raw()->set_height(2049);
  create.mutable_raw()->set_cells(std::string(size_t{2048} * 2049, '\0'));
  v1::CreateMapResponse created;
  {
    grpc::ClientContext context;
    Prepare(context);
    ASSERT_TRUE(maps->CreateMap(&context, create, &created).ok());
  }
  v1::CostToGoRequest request;
  request.set_map("big");
  request.mutable_goal()->mutable_cell()->set_x(0);
  request.mutable_goal()->mutable_cell()->set_y(0);
  v1::CostToGoResponse response;
  grpc::ClientContext context;
  Prepare(context);
  const grpc::Status status = planner->CostToGo(&context, request, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_THAT(status.error_message(), HasSubstr("4194304"));
}

TEST_F(ServiceTest, GetCacheStatsCountsHitsAndMisses) {
  const auto stats = [&] {
    v1::GetCacheStatsResponse response;
    grpc::ClientContext context;
    Prepare(context);
    EXPECT_TRUE(planner_->GetCacheStats(&context, v1::GetCacheStatsRequest(), &response).ok());
    return response;
  };
  const v1::GetCacheStatsResponse before = stats();
  ASSERT_EQ(before.caches_size(), 2);
  EXPECT_EQ(before.caches(0).name(), "spm");
  EXPECT_EQ(before.caches(1).name(), "dstar_lite");
  EXPECT_EQ(before.caches(0).budget_bytes(), int64_t{1} << 29);

  ASSERT_TRUE(CreateFree("stats", 8, 8).ok());
  v1::PlanRequest request = CellRequest("stats", 0, 0, 7, 7);
  request.set_planner(v1::PLANNER_SPM);
  v1::PlanResponse response;
  ASSERT_TRUE(Plan(request, &response).ok());
  ASSERT_TRUE(Plan(request, &response).ok());
  const v1::GetCacheStatsResponse after = stats();
  EXPECT_EQ(after.caches(0).misses(), before.caches(0).misses() + 1);
  EXPECT_EQ(after.caches(0).hits(), before.caches(0).hits() + 1);
  EXPECT_GE(after.caches(0).entries(), 1);
  EXPECT_GT(after.caches(0).bytes(), before.caches(0).bytes());
  EXPECT_EQ(after.caches(1).misses(), before.caches(1).misses());
}

TEST(ReplacePortTest, KeepsHostAndSwapsPort) {
  EXPECT_EQ(ReplacePort("127.0.0.1:0", 4242), "127.0.0.1:4242");
  EXPECT_EQ(ReplacePort("localhost:50051", 7), "localhost:7");
  EXPECT_EQ(ReplacePort("[::1]:0", 9), "[::1]:9");
  EXPECT_EQ(ReplacePort("0.0.0.0", 9), "0.0.0.0:9");
}

}  // namespace pathd::server::service_test
