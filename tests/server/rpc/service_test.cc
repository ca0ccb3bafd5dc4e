// MapService and PlannerService end to end over a real gRPC channel to a
// PathdServer on 127.0.0.1:0, with a temporary --map_dir. Deadlines are
// generous and nothing asserts on timing.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <future>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <grpcpp/create_channel.h>
#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/security/credentials.h>

#include "core/search/path_measure.h"
#include "core/map/cost_model.h"
#include "core/search/planner.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "pathd/v1/map_service.grpc.pb.h"
#include "pathd/v1/planner_service.grpc.pb.h"
#include "server/server.h"
#include "tests/testing/in_process_server.h"
#include "tests/testing/shared_server_test.h"
#include "tests/testing/temp_dir.h"
#include "tests/testing/requests.h"

namespace pathd::server {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

constexpr char kSmallMovingAi[] =
    "type octile\n"
    "height 4\n"
    "width 5\n"
    "map\n"
    ".....\n"
    ".@@@.\n"
    ".....\n"
    "T....\n";

void WriteFile(const fs::path& path, const std::string& contents) {
  std::ofstream out(path, std::ios::binary);
  out << contents;
  ASSERT_TRUE(out.good()) << path;
}

// A 3 x 2 plain PGM: top row white-black-white, bottom row all white. With
// trinary mode and no negate, white is free and black is lethal; rows flip,
// so the black pixel lands in grid row 1.
constexpr char kRosYaml[] =
    "image: room.pgm\n"
    "resolution: 0.5\n"
    "origin: [1.0, -2.0, 0.0]\n"
    "negate: 0\n"
    "occupied_thresh: 0.65\n"
    "free_thresh: 0.196\n";
constexpr char kRosPgm[] = "P2\n3 2\n255\n255 0 255\n255 255 255\n";

class ServiceTest : public testing::SharedServerTest<ServiceTest> {
 public:
  static ServerOptions SuiteOptions() {
    ServerOptions options = testing::TestServerOptions();
    options.max_map_cells = 1 << 16;
    options.map_dir = (*root_ / "maps").string();
    return options;
  }

 protected:
  static void SetUpTestSuite() {
    scratch_ = new testing::TempDir("pathd_service_test");
    ASSERT_FALSE(scratch_->path().empty()) << scratch_->error();
    root_ = &scratch_->path();
    const fs::path dir = *root_ / "maps";
    fs::create_directories(dir / "sub");
    WriteFile(dir / "small.map", kSmallMovingAi);
    WriteFile(dir / "sub" / "inner.map", kSmallMovingAi);
    WriteFile(dir / "room.yaml", kRosYaml);
    WriteFile(dir / "room.pgm", kRosPgm);
    WriteFile(dir / "broken.map", "type octile\nheight x\n");
    // A valid map outside the directory, reachable only by escaping it.
    WriteFile(*root_ / "secret.map", kSmallMovingAi);
    fs::create_symlink(*root_ / "secret.map", dir / "link_out.map");
    // A YAML inside whose image lies outside.
    WriteFile(*root_ / "secret.pgm", kRosPgm);
    WriteFile(dir / "sneaky.yaml",
              "image: ../secret.pgm\nresolution: 1.0\norigin: [0, 0, 0]\n");

    SharedServerTest::SetUpTestSuite();
    ASSERT_GT(server_->port(), 0);
    channel_ = &server_->channel();
  }

  static void TearDownTestSuite() {
    SharedServerTest::TearDownTestSuite();  // shuts down
    delete scratch_;
    scratch_ = nullptr;
  }

  void SetUp() override {
    maps_ = &server_->maps();
    planner_ = &server_->planner();
  }

  static void Prepare(grpc::ClientContext& context) { testing::SetDeadline(context); }

  grpc::Status CreateRaw(const std::string& name, int w, int h,
                         const std::string& cells, v1::CreateMapResponse* out,
                         double resolution = 0.0, bool replace = false) {
    return server_->CreateRawMap(name, w, h, cells, resolution, replace, out);
  }

  grpc::Status CreateFree(const std::string& name, int w, int h) {
    return server_->CreateFreeMap(name, w, h);
  }

  grpc::Status Plan(const v1::PlanRequest& request, v1::PlanResponse* response) {
    grpc::ClientContext context;
    Prepare(context);
    return planner_->Plan(&context, request, response);
  }

  static v1::PlanRequest CellRequest(const std::string& map, int sx, int sy, int gx,
                                     int gy) {
    return testing::PlanBetween(map, sx, sy, gx, gy, v1::PLANNER_UNSPECIFIED);
  }

  static const std::shared_ptr<grpc::Channel>* channel_;
  static testing::TempDir* scratch_;
  static const fs::path* root_;
  v1::MapService::Stub* maps_ = nullptr;
  v1::PlannerService::Stub* planner_ = nullptr;
};

testing::TempDir* ServiceTest::scratch_ = nullptr;
const std::shared_ptr<grpc::Channel>* ServiceTest::channel_ = nullptr;
const fs::path* ServiceTest::root_ = nullptr;

TEST_F(ServiceTest, HealthServiceReportsServing) {
  // grpc.health.v1.Health/Check with an empty request (service ""); the reply
  // HealthCheckResponse{status: SERVING} encodes as field 1 varint 1.
  grpc::GenericStub stub(*channel_);
  grpc::Slice empty("");
  grpc::ByteBuffer request(&empty, 1);
  grpc::ByteBuffer response;
  grpc::ClientContext context;
  Prepare(context);
  std::promise<grpc::Status> done;
  stub.UnaryCall(&context, "/grpc.health.v1.Health/Check", grpc::StubOptions(),
                 &request, &response,
                 [&done](grpc::Status s) { done.set_value(std::move(s)); });
  const grpc::Status status = done.get_future().get();
  ASSERT_TRUE(status.ok()) << status.error_message();
  std::vector<grpc::Slice> slices;
  ASSERT_TRUE(response.Dump(&slices).ok());
  std::string bytes;
  for (const auto& s : slices) bytes.append(reinterpret_cast<const char*>(s.begin()), s.size());
  EXPECT_EQ(bytes, std::string("\x08\x01", 2));
}

TEST_F(ServiceTest, StartUpLoadsMapDirAndSkipsBadFiles) {
  v1::ListMapsResponse list;
  grpc::ClientContext context;
  Prepare(context);
  ASSERT_TRUE(maps_->ListMaps(&context, v1::ListMapsRequest(), &list).ok());
  std::vector<std::string> names;
  for (const auto& info : list.maps()) names.push_back(info.name());
  EXPECT_THAT(names, ::testing::IsSupersetOf({"room", "small"}));
  // broken.map does not parse, link_out.map and sneaky.yaml escape the dir.
  EXPECT_THAT(names, ::testing::Not(::testing::Contains("broken")));
  EXPECT_THAT(names, ::testing::Not(::testing::Contains("link_out")));
  EXPECT_THAT(names, ::testing::Not(::testing::Contains("sneaky")));
}

TEST_F(ServiceTest, CreateFromRawGetListDelete) {
  v1::CreateMapResponse created;
  std::string cells(12, '\0');
  cells[5] = static_cast<char>(254);
  ASSERT_TRUE(CreateRaw("raw-a", 4, 3, cells, &created, 0.25).ok());
  EXPECT_EQ(created.info().name(), "raw-a");
  EXPECT_EQ(created.info().version(), 1u);
  EXPECT_EQ(created.info().width(), 4);
  EXPECT_EQ(created.info().height(), 3);
  EXPECT_DOUBLE_EQ(created.info().resolution(), 0.25);
  EXPECT_EQ(created.info().free_cells(), 11);
  EXPECT_EQ(created.info().blocked_cells(), 1);

  v1::CreateMapResponse dup;
  EXPECT_EQ(CreateRaw("raw-a", 4, 3, cells, &dup).error_code(),
            grpc::StatusCode::ALREADY_EXISTS);

  {
    v1::GetMapRequest request;
    request.set_name("raw-a");
    v1::GetMapResponse response;
    grpc::ClientContext context;
    Prepare(context);
    ASSERT_TRUE(maps_->GetMap(&context, request, &response).ok());
    EXPECT_EQ(response.info().version(), 1u);
    EXPECT_TRUE(response.cells().empty());
  }
  {
    v1::GetMapRequest request;
    request.set_name("raw-a");
    request.set_include_cells(true);
    v1::GetMapResponse response;
    grpc::ClientContext context;
    Prepare(context);
    ASSERT_TRUE(maps_->GetMap(&context, request, &response).ok());
    EXPECT_EQ(response.cells(), cells);
  }
  {
    ASSERT_TRUE(CreateFree("raw-0", 2, 2).ok());
    v1::ListMapsResponse list;
    grpc::ClientContext context;
    Prepare(context);
    ASSERT_TRUE(maps_->ListMaps(&context, v1::ListMapsRequest(), &list).ok());
    std::vector<std::string> names;
    for (const auto& info : list.maps()) names.push_back(info.name());
    EXPECT_TRUE(std::is_sorted(names.begin(), names.end()));
    EXPECT_THAT(names, ::testing::IsSupersetOf({"raw-0", "raw-a"}));
  }
  {
    v1::DeleteMapRequest request;
    request.set_name("raw-a");
    v1::DeleteMapResponse response;
    grpc::ClientContext context;
    Prepare(context);
    ASSERT_TRUE(maps_->DeleteMap(&context, request, &response).ok());
    EXPECT_EQ(response.last_version(), 1u);
  }
  {
    v1::GetMapRequest request;
    request.set_name("raw-a");
    v1::GetMapResponse response;
    grpc::ClientContext context;
    Prepare(context);
    const grpc::Status status = maps_->GetMap(&context, request, &response);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::NOT_FOUND);
    EXPECT_EQ(status.error_message(), "map 'raw-a' not found");
  }
}

TEST_F(ServiceTest, CreateRejectsBadInput) {
  v1::CreateMapResponse response;
  const grpc::Status bad_name = CreateRaw("no/slash", 1, 1, std::string(1, '\0'), &response);
  EXPECT_EQ(bad_name.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(bad_name.error_message(), HasSubstr("map name"));

  const grpc::Status short_cells = CreateRaw("short", 3, 3, std::string(8, '\0'), &response);
  EXPECT_EQ(short_cells.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(short_cells.error_message(), HasSubstr("needs 9 cells, got 8"));

  const grpc::Status too_big =
      CreateRaw("huge", 300, 300, std::string(90000, '\0'), &response);
  EXPECT_EQ(too_big.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_THAT(too_big.error_message(), HasSubstr("max_map_cells"));

  const grpc::Status bad_resolution =
      CreateRaw("res", 1, 1, std::string(1, '\0'), &response, -1.0);
  EXPECT_EQ(bad_resolution.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(bad_resolution.error_message(), HasSubstr("resolution"));

  v1::CreateMapRequest no_source;
  no_source.set_name("nosrc");
  grpc::ClientContext context;
  Prepare(context);
  EXPECT_EQ(maps_->CreateMap(&context, no_source, &response).error_code(),
            grpc::StatusCode::INVALID_ARGUMENT);
}

TEST_F(ServiceTest, CreateFromMovingAiText) {
  v1::CreateMapRequest request;
  request.set_name("mai");
  request.set_movingai_text(kSmallMovingAi);
  request.set_resolution(2.0);
  request.mutable_origin()->set_x(10.0);
  v1::CreateMapResponse response;
  grpc::ClientContext context;
  Prepare(context);
  const grpc::Status status = maps_->CreateMap(&context, request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(response.info().width(), 5);
  EXPECT_EQ(response.info().height(), 4);
  EXPECT_EQ(response.info().blocked_cells(), 4);
  EXPECT_DOUBLE_EQ(response.info().resolution(), 2.0);
  EXPECT_DOUBLE_EQ(response.info().origin().x(), 10.0);

  v1::CreateMapRequest broken;
  broken.set_name("mai-broken");
  broken.set_movingai_text("type octile\nwidth 3\nheight 3\nmap\n...\n");
  grpc::ClientContext context2;
  Prepare(context2);
  const grpc::Status bad = maps_->CreateMap(&context2, broken, &response);
  EXPECT_EQ(bad.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(bad.error_message(), HasSubstr("movingai_text"));
}

TEST_F(ServiceTest, CreateFromRosMap) {
  v1::CreateMapRequest request;
  request.set_name("ros");
  request.mutable_ros_map()->set_yaml(kRosYaml);
  request.mutable_ros_map()->set_image(kRosPgm);
  v1::CreateMapResponse response;
  grpc::ClientContext context;
  Prepare(context);
  const grpc::Status status = maps_->CreateMap(&context, request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(response.info().width(), 3);
  EXPECT_EQ(response.info().height(), 2);
  EXPECT_DOUBLE_EQ(response.info().resolution(), 0.5);
  EXPECT_DOUBLE_EQ(response.info().origin().x(), 1.0);
  EXPECT_DOUBLE_EQ(response.info().origin().y(), -2.0);
  EXPECT_EQ(response.info().blocked_cells(), 1);

  v1::GetMapRequest get;
  get.set_name("ros");
  get.set_include_cells(true);
  v1::GetMapResponse map;
  grpc::ClientContext context2;
  Prepare(context2);
  ASSERT_TRUE(maps_->GetMap(&context2, get, &map).ok());
  // Image top row is grid row 1 (OccupancyGrid order): its middle is lethal.
  ASSERT_EQ(map.cells().size(), 6u);
  EXPECT_EQ(static_cast<uint8_t>(map.cells()[4]), kLethalCost);
  EXPECT_EQ(static_cast<uint8_t>(map.cells()[1]), kFreeCost);
}

TEST_F(ServiceTest, CreateFromMapDirFile) {
  v1::CreateMapRequest request;
  request.set_name("from-dir");
  request.set_map_dir_file("sub/inner.map");
  v1::CreateMapResponse response;
  grpc::ClientContext context;
  Prepare(context);
  const grpc::Status status = maps_->CreateMap(&context, request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(response.info().width(), 5);

  // ".." that stays inside the directory is fine.
  request.set_name("from-dir-2");
  request.set_map_dir_file("sub/../room.yaml");
  grpc::ClientContext context2;
  Prepare(context2);
  const grpc::Status inside = maps_->CreateMap(&context2, request, &response);
  ASSERT_TRUE(inside.ok()) << inside.error_message();
  EXPECT_DOUBLE_EQ(response.info().resolution(), 0.5);
}

TEST_F(ServiceTest, MapDirFileCannotEscapeTheDirectory) {
  const std::string secret = (*root_ / "secret.map").string();
  for (const std::string& file :
       {std::string("../secret.map"), std::string("sub/../../secret.map"), secret,
        std::string("link_out.map"), std::string("sneaky.yaml"), std::string("..")}) {
    v1::CreateMapRequest request;
    request.set_name("escape");
    request.set_map_dir_file(file);
    v1::CreateMapResponse response;
    grpc::ClientContext context;
    Prepare(context);
    const grpc::Status status = maps_->CreateMap(&context, request, &response);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT)
        << file << ": " << status.error_message();
  }
  v1::CreateMapRequest missing;
  missing.set_name("missing");
  missing.set_map_dir_file("nope.map");
  v1::CreateMapResponse response;
  grpc::ClientContext context;
  Prepare(context);
  const grpc::Status status = maps_->CreateMap(&context, missing, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_THAT(status.error_message(), HasSubstr("nope.map"));
}

TEST_F(ServiceTest, MapDirFileWithoutMapDirIsFailedPrecondition) {
  ServerOptions options = testing::TestServerOptions();
  options.threads = 1;
  testing::InProcessServer bare(options);
  ASSERT_TRUE(bare.Start().ok());
  v1::MapService::Stub* stub = &bare.maps();
  v1::CreateMapRequest request;
  request.set_name("x");
  request.set_map_dir_file("small.map");
  v1::CreateMapResponse response;
  grpc::ClientContext context;
  Prepare(context);
  EXPECT_EQ(stub->CreateMap(&context, request, &response).error_code(),
            grpc::StatusCode::FAILED_PRECONDITION);
}

TEST_F(ServiceTest, UpdateBumpsVersionAndRejectsStaleExpectedVersion) {
  ASSERT_TRUE(CreateFree("upd", 8, 8).ok());
  v1::UpdateMapRequest request;
  request.set_name("upd");
  auto* change = request.add_changes();
  change->mutable_rect()->set_x_min(2);
  change->mutable_rect()->set_y_min(0);
  change->mutable_rect()->set_x_max(2);
  change->mutable_rect()->set_y_max(6);
  change->set_cost(254);
  request.set_expected_version(1);
  v1::UpdateMapResponse response;
  {
    grpc::ClientContext context;
    Prepare(context);
    const grpc::Status status = maps_->UpdateMap(&context, request, &response);
    ASSERT_TRUE(status.ok()) << status.error_message();
    EXPECT_EQ(response.version(), 2u);
    EXPECT_EQ(response.cells_changed(), 7);
  }
  {
    grpc::ClientContext context;
    Prepare(context);
    const grpc::Status stale = maps_->UpdateMap(&context, request, &response);
    EXPECT_EQ(stale.error_code(), grpc::StatusCode::ABORTED);
    EXPECT_EQ(stale.error_message(), "map 'upd' is at version 2, expected 1");
  }
  {
    v1::UpdateMapRequest off = request;
    off.clear_expected_version();
    off.add_changes()->mutable_cell()->set_x(8);
    grpc::ClientContext context;
    Prepare(context);
    const grpc::Status status = maps_->UpdateMap(&context, off, &response);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_THAT(status.error_message(), HasSubstr("change 1"));
  }
  {
    v1::UpdateMapRequest empty;
    empty.set_name("upd");
    grpc::ClientContext context;
    Prepare(context);
    EXPECT_EQ(maps_->UpdateMap(&context, empty, &response).error_code(),
              grpc::StatusCode::INVALID_ARGUMENT);
  }
  {
    v1::UpdateMapRequest unknown = request;
    unknown.set_name("nope");
    grpc::ClientContext context;
    Prepare(context);
    EXPECT_EQ(maps_->UpdateMap(&context, unknown, &response).error_code(),
              grpc::StatusCode::NOT_FOUND);
  }
}

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

}  // namespace
}  // namespace pathd::server
