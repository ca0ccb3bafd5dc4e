// The fixture of service_test, whose tests are split by topic over
// tests/server/rpc/service_*_test.cc: MapService and PlannerService end to end
// over a real gRPC channel to a PathdServer on 127.0.0.1:0, with a temporary
// --map_dir. Deadlines are generous and nothing asserts on timing.
#ifndef PATHD_TESTS_SERVER_RPC_SERVICE_FIXTURE_H_
#define PATHD_TESTS_SERVER_RPC_SERVICE_FIXTURE_H_

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

namespace pathd::server::service_test {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

inline constexpr char kSmallMovingAi[] =
    "type octile\n"
    "height 4\n"
    "width 5\n"
    "map\n"
    ".....\n"
    ".@@@.\n"
    ".....\n"
    "T....\n";

inline void WriteFile(const fs::path& path, const std::string& contents) {
  std::ofstream out(path, std::ios::binary);
  out << contents;
  ASSERT_TRUE(out.good()) << path;
}

// A 3 x 2 plain PGM: top row white-black-white, bottom row all white. With
// trinary mode and no negate, white is free and black is lethal; rows flip,
// so the black pixel lands in grid row 1.
inline constexpr char kRosYaml[] =
    "image: room.pgm\n"
    "resolution: 0.5\n"
    "origin: [1.0, -2.0, 0.0]\n"
    "negate: 0\n"
    "occupied_thresh: 0.65\n"
    "free_thresh: 0.196\n";
inline constexpr char kRosPgm[] = "P2\n3 2\n255\n255 0 255\n255 255 255\n";

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

}  // namespace pathd::server::service_test

#endif  // PATHD_TESTS_SERVER_RPC_SERVICE_FIXTURE_H_
