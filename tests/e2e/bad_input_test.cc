// Bad input through the real pathd binary: a table of malformed requests to
// every RPC of MapService, PlannerService and Health (bad names, dimensions,
// cell arrays, coordinates, non-finite numbers, unknown enum values, empty
// batches, oversized messages, map file garbage, --map_dir escapes), each
// expecting a status code and a message naming the problem. After every case
// a good request must still succeed, and the daemon must be alive at the end;
// map files are also tried at start-up and through bad --map_dir flags. The
// test prints how many cases it tried.
#include <grpcpp/client_context.h>
#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/grpcpp.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <tuple>
#include <utility>
#include <vector>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/strip.h"
#include "gmock/gmock.h"
#include "grpc/health/v1/health.grpc.pb.h"
#include "gtest/gtest.h"
#include "pathd/v1/map_service.grpc.pb.h"
#include "pathd/v1/planner_service.grpc.pb.h"
#include "tests/e2e/process.h"
#include "tests/testing/temp_dir.h"
#include "tests/testing/call_context.h"
#include "tests/testing/requests.h"

namespace pathd {
namespace {

namespace fs = std::filesystem;
using e2e::ReadFile;
using e2e::WriteFile;
using Clock = std::chrono::steady_clock;
using grpc::StatusCode;
using ::testing::HasSubstr;

// Hang guards only: a broken daemon fails the test instead of hanging it.
constexpr auto kBound = absl::Seconds(60);

// Limits the daemon runs with, small so that crossing them is cheap.
constexpr int64_t kMaxMessageBytes = 1536 * 1024;
constexpr int64_t kMaxMapCells = int64_t{1} << 21;
constexpr int kMaxPathPoints = 1000;
constexpr int kMaxCostToGoCells = 10000;
// "big" (kBigSide^2 cells) fits --max_map_cells but not one message.
constexpr int kBigSide = 1300;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr int32_t kIntMax = std::numeric_limits<int32_t>::max();
constexpr int32_t kIntMin = std::numeric_limits<int32_t>::min();



// A width x height Moving AI map, open except for the blocked cell (5, 5)
// when the map is big enough to hold it.
std::string MovingAiMap(int width, int height) {
  std::string text = absl::StrCat("type octile\nheight ", height, "\nwidth ",
                                  width, "\nmap\n");
  for (int y = 0; y < height; ++y) {
    std::string row(static_cast<size_t>(width), '.');
    if (y == 5 && width > 5) row[5] = '@';
    text += row + "\n";
  }
  return text;
}

// pathd with its request log (--log_level=debug) in `log_file` and `flags`;
// address() is empty when the daemon exited before listening.
std::unique_ptr<e2e::PathdProcess> StartPathd(const fs::path& log_file,
                                              const std::vector<std::string>& flags) {
  std::vector<std::string> all = {"--log_level=debug"};
  all.insert(all.end(), flags.begin(), flags.end());
  return std::make_unique<e2e::PathdProcess>(e2e::PathdProcessOptions{
      .binary = PATHD_BIN, .flags = all, .log_file = log_file, .bound = kBound});
}

using testing::CellPos;
using testing::WorldPos;

// A plan on "room" from (1, 1) to (14, 14) that succeeds; cases break one
// thing in it.
v1::PlanRequest GoodPlan() {
  v1::PlanRequest request;
  request.set_map("room");
  *request.mutable_start() = CellPos(1, 1);
  *request.mutable_goal() = CellPos(14, 14);
  return request;
}

v1::CreateMapRequest RawMap(const std::string& name, int32_t width,
                            int32_t height, size_t cells) {
  v1::CreateMapRequest request;
  request.set_name(name);
  request.mutable_raw()->set_width(width);
  request.mutable_raw()->set_height(height);
  request.mutable_raw()->set_cells(std::string(cells, '\0'));
  return request;
}

// One row of the table: a call and what it must answer.
struct Case {
  std::string rpc;
  std::string what;
  std::function<grpc::Status()> call;
  StatusCode code;
  // Part of the status message that names the problem.
  std::string message;
};

// A marker the raw-bytes cases replace in a serialized request, the same
// length as kNonUtf8.
constexpr char kUtf8Marker[] = "@@UTF8@@";
constexpr char kNonUtf8[] = "ab\xff\xfe\xc0\x80yz";
static_assert(sizeof(kUtf8Marker) == sizeof(kNonUtf8));

// `message` serialized with kUtf8Marker replaced by invalid UTF-8 bytes: a
// request no protobuf library would build for a `string` field.
grpc::ByteBuffer WithNonUtf8(const google::protobuf::Message& message) {
  std::string bytes = message.SerializeAsString();
  const size_t at = bytes.find(kUtf8Marker);
  EXPECT_NE(at, std::string::npos);
  if (at != std::string::npos)
    bytes.replace(at, sizeof(kNonUtf8) - 1, kNonUtf8);
  grpc::Slice slice(bytes);
  return grpc::ByteBuffer(&slice, 1);
}

class BadInputTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_FALSE(temp_.empty()) << scratch_.error();
    ASSERT_NO_FATAL_FAILURE(WriteMapDir());
  }
  void TearDown() override {
    map_.reset();
    planner_.reset();
    health_.reset();
    generic_.reset();
    channel_.reset();
    daemon_.reset();
  }

  fs::path map_dir() const { return temp_ / "maps"; }
  fs::path outside() const { return temp_ / "outside"; }

  // Good maps, garbage and escapes, keyed by file name: what start-up must
  // say about each skipped file.
  void WriteMapDir() {
    fs::create_directories(map_dir() / "sub");
    fs::create_directories(outside());
    const std::string pgm_4x4 =
        std::string("P5\n4 4\n255\n") + std::string(16, '\xfe');
    WriteFile(outside() / "secret.map", MovingAiMap(4, 4));
    WriteFile(outside() / "secret.pgm", pgm_4x4);
    WriteFile(map_dir() / "room.map", MovingAiMap(16, 16));
    WriteFile(map_dir() / "big.map", MovingAiMap(kBigSide, kBigSide));
    WriteFile(map_dir() / "sub" / "inner.map", MovingAiMap(4, 4));
    WriteFile(map_dir() / "good.pgm", pgm_4x4);
    WriteFile(map_dir() / "notes.txt", "not a map");
    const auto yaml = [](const std::string& image,
                         const std::string& extra = "") {
      return absl::StrCat("image: ", image,
                          "\nresolution: 0.05\norigin: [0.0, 0.0, 0.0]\n",
                          extra);
    };
    bad_files_ = {
        {"garbage.map", std::string("hello world\n\0\xff\xfe", 15),
         "garbage.map"},
        {"empty.map", "", "empty.map"},
        {"negative.map", "type octile\nheight -3\nwidth 4\nmap\n", "height"},
        {"overflow.map", "type octile\nheight 65536\nwidth 65536\nmap\n",
         "exceeds the limit"},
        {"huge_number.map",
         "type octile\nheight 99999999999999999999\nwidth 4\nmap\n", "height"},
        {"short_rows.map",
         "type octile\nheight 3\nwidth 4\nmap\n...\n...\n...\n",
         "short_rows.map"},
        {"few_rows.map", "type octile\nheight 3\nwidth 2\nmap\n..\n",
         "few_rows.map"},
        {"bad_char.map", "type octile\nheight 1\nwidth 2\nmap\n.\x01\n",
         "bad_char.map"},
        {"bad name.map", MovingAiMap(4, 4), "character 0x20"},
        {"..map", MovingAiMap(4, 4), "must not start with '.'"},
        {"garbage.yaml", "{{{{ ::: ]]", "garbage.yaml"},
        {"deep.yaml", std::string(100000, '['), "deep.yaml"},
        {"deep_block.yaml",
         [] {
           std::string s;
           for (int i = 0; i < 20000; ++i) s += "- ";
           return s + "x\n";
         }(),
         "deep_block.yaml"},
        {"nan_resolution.yaml",
         absl::StrCat("image: good.pgm\nresolution: .nan\n",
                      "origin: [0.0, 0.0, 0.0]\n"),
         "resolution"},
        {"negative_resolution.yaml",
         "image: good.pgm\nresolution: -1\norigin: [0.0, 0.0, 0.0]\n",
         "resolution"},
        {"inf_origin.yaml",
         "image: good.pgm\nresolution: 1\norigin: [.inf, 0.0, 0.0]\n",
         "origin"},
        {"short_origin.yaml", "image: good.pgm\nresolution: 1\norigin: [0.0]\n",
         "origin"},
        {"no_image.yaml", "resolution: 1\norigin: [0, 0, 0]\n", "image"},
        {"bad_thresh.yaml", yaml("good.pgm", "occupied_thresh: 7\n"),
         "occupied_thresh"},
        {"image_escape.yaml", yaml("../outside/secret.pgm"),
         "outside --map_dir"},
        {"image_absolute.yaml", yaml((outside() / "secret.pgm").string()),
         "outside --map_dir"},
        {"image_missing.yaml", yaml("missing.pgm"), "not found"},
        {"garbage_pgm.yaml", yaml("garbage.pgm"), "garbage.pgm"},
        {"negative_pgm.yaml", yaml("negative.pgm"), "negative.pgm"},
        {"huge_pgm.yaml", yaml("huge.pgm"), "exceeds the limit"},
        {"truncated_pgm.yaml", yaml("truncated.pgm"), "truncated.pgm"},
        {"maxval_pgm.yaml", yaml("maxval.pgm"), "maxval.pgm"},
        {"ascii_pgm.yaml", yaml("ascii.pgm"), "ascii.pgm"},
    };
    for (const File& f : bad_files_) WriteFile(map_dir() / f.name, f.contents);
    WriteFile(map_dir() / "garbage.pgm", "P9 what\n\x01\x02");
    WriteFile(map_dir() / "negative.pgm", "P5\n-4 4\n255\n");
    WriteFile(map_dir() / "huge.pgm", "P5\n65536 65536\n255\n");
    WriteFile(map_dir() / "truncated.pgm",
              std::string("P5\n4 4\n255\n") + "\x01\x02\x03");
    WriteFile(map_dir() / "maxval.pgm",
              std::string("P5\n4 4\n0\n") + std::string(16, '\0'));
    WriteFile(map_dir() / "ascii.pgm", "P2\n2 2\n255\n1 2 3 x\n");
    // Links escaping the directory, and one pointing nowhere.
    fs::create_symlink(outside() / "secret.map", map_dir() / "escape.map");
    fs::create_symlink("../outside/secret.map",
                       map_dir() / "escape_relative.map");
    fs::create_symlink(outside() / "missing.map", map_dir() / "dangling.map");
    fs::create_directory_symlink(outside(), map_dir() / "out_dir");
    bad_files_.push_back({"escape.map", "", "resolves outside --map_dir"});
    bad_files_.push_back(
        {"escape_relative.map", "", "resolves outside --map_dir"});
  }

  void StartDaemon() {
    daemon_ = StartPathd(
        temp_ / "pathd.log",
        std::vector<std::string>{
            "--map_dir=" + map_dir().string(),
            absl::StrCat("--max_message_bytes=", kMaxMessageBytes),
            absl::StrCat("--max_map_cells=", kMaxMapCells),
            absl::StrCat("--max_path_points=", kMaxPathPoints),
            absl::StrCat("--max_cost_to_go_cells=", kMaxCostToGoCells),
            "--threads=2"});
    ASSERT_TRUE(daemon_->listening()) << daemon_->status();
    grpc::ChannelArguments args;
    // The client accepts anything, so every size refusal seen is the server's.
    args.SetMaxReceiveMessageSize(-1);
    args.SetMaxSendMessageSize(-1);
    channel_ = grpc::CreateCustomChannel(
        daemon_->address(), grpc::InsecureChannelCredentials(), args);
    map_ = v1::MapService::NewStub(channel_);
    planner_ = v1::PlannerService::NewStub(channel_);
    health_ = grpc::health::v1::Health::NewStub(channel_);
    generic_ = std::make_unique<grpc::GenericStub>(channel_);
  }

  std::unique_ptr<grpc::ClientContext> Context() { return testing::Context(kBound); }

  // ---- one helper per RPC, answering the call's status ----

  grpc::Status CreateMap(const v1::CreateMapRequest& request) {
    v1::CreateMapResponse response;
    return map_->CreateMap(Context().get(), request, &response);
  }
  grpc::Status GetMap(const std::string& name, bool include_cells = false) {
    v1::GetMapRequest request;
    request.set_name(name);
    request.set_include_cells(include_cells);
    v1::GetMapResponse response;
    return map_->GetMap(Context().get(), request, &response);
  }
  grpc::Status DeleteMap(const std::string& name) {
    v1::DeleteMapRequest request;
    request.set_name(name);
    v1::DeleteMapResponse response;
    return map_->DeleteMap(Context().get(), request, &response);
  }
  grpc::Status UpdateMap(const v1::UpdateMapRequest& request) {
    v1::UpdateMapResponse response;
    return map_->UpdateMap(Context().get(), request, &response);
  }
  // The status WatchMap ends with, or OK once the first event arrived (the
  // stream is then cancelled).
  grpc::Status WatchMap(const std::string& name, uint64_t from_version = 0) {
    v1::WatchMapRequest request;
    request.set_name(name);
    request.set_from_version(from_version);
    auto context = Context();
    auto reader = map_->WatchMap(context.get(), request);
    v1::MapEvent event;
    if (reader->Read(&event)) {
      context->TryCancel();
      reader->Finish().ok();
      return grpc::Status::OK;
    }
    return reader->Finish();
  }
  grpc::Status Plan(const v1::PlanRequest& request) {
    v1::PlanResponse response;
    return planner_->Plan(Context().get(), request, &response);
  }
  // PlanStream's final status, checked against its final event: an error
  // event must repeat the stream's status.
  grpc::Status PlanStream(const v1::PlanRequest& request) {
    auto context = Context();
    auto reader = planner_->PlanStream(context.get(), request);
    v1::PlanStreamEvent event, last;
    while (reader->Read(&event)) last = event;
    const grpc::Status status = reader->Finish();
    if (!status.ok() && last.has_error()) {
      EXPECT_EQ(last.error().code(), static_cast<int>(status.error_code()));
      EXPECT_EQ(last.error().message(), status.error_message());
    }
    return status;
  }
  // PlanBatch with the given items: the stream's status when not OK, else
  // the status of the item whose id is "bad" (OK when it has a result, or
  // when there is no such item: then the message counts the answers).
  grpc::Status PlanBatch(const std::vector<v1::PlanBatchRequest>& items) {
    auto context = Context();
    auto stream = planner_->PlanBatch(context.get());
    for (const v1::PlanBatchRequest& item : items) {
      if (!stream->Write(item)) break;
    }
    stream->WritesDone();
    std::vector<v1::PlanBatchResponse> answers;
    for (v1::PlanBatchResponse answer; stream->Read(&answer);)
      answers.push_back(answer);
    const grpc::Status status = stream->Finish();
    if (!status.ok()) return status;
    EXPECT_EQ(answers.size(), items.size());
    for (const v1::PlanBatchResponse& answer : answers) {
      if (answer.request_id() != "bad") continue;
      if (!answer.has_error()) return grpc::Status::OK;
      return grpc::Status(static_cast<StatusCode>(answer.error().code()),
                          answer.error().message());
    }
    return grpc::Status(StatusCode::OK,
                        absl::StrCat("answers=", answers.size()));
  }
  grpc::Status PlanBatchItem(const v1::PlanRequest& request,
                             const std::string& id = "bad") {
    v1::PlanBatchRequest good;
    good.set_request_id("good");
    *good.mutable_request() = GoodPlan();
    v1::PlanBatchRequest bad;
    bad.set_request_id(id);
    *bad.mutable_request() = request;
    return PlanBatch({good, bad});
  }
  // A Navigate session sending `messages`, then closing: the status it ends
  // with. Every answer before the end must be a plan.
  grpc::Status Navigate(const std::vector<v1::NavigateRequest>& messages) {
    auto context = Context();
    auto stream = planner_->Navigate(context.get());
    for (const v1::NavigateRequest& message : messages) {
      if (!stream->Write(message)) break;
    }
    stream->WritesDone();
    for (v1::NavigateResponse answer; stream->Read(&answer);) {
      EXPECT_TRUE(answer.has_plan()) << answer.ShortDebugString();
    }
    return stream->Finish();
  }
  v1::NavigateRequest NavigateOpen(const v1::PlanRequest& plan) {
    v1::NavigateRequest open;
    open.set_seq(1);
    open.mutable_open()->set_map(plan.map());
    *open.mutable_open()->mutable_start() = plan.start();
    *open.mutable_open()->mutable_goal() = plan.goal();
    *open.mutable_open()->mutable_options() = plan.options();
    return open;
  }
  // An open session on "room", then `message`.
  grpc::Status NavigateThen(const v1::NavigateRequest& message) {
    return Navigate({NavigateOpen(GoodPlan()), message});
  }
  grpc::Status IsPathValid(const v1::IsPathValidRequest& request) {
    v1::IsPathValidResponse response;
    return planner_->IsPathValid(Context().get(), request, &response);
  }
  v1::IsPathValidRequest PathCheck(std::vector<v1::Position> poses) {
    v1::IsPathValidRequest request;
    request.set_map("room");
    for (v1::Position& p : poses) *request.add_path() = std::move(p);
    return request;
  }
  grpc::Status CostToGo(const v1::CostToGoRequest& request) {
    v1::CostToGoResponse response;
    return planner_->CostToGo(Context().get(), request, &response);
  }
  v1::CostToGoRequest Field(const std::string& map = "room") {
    v1::CostToGoRequest request;
    request.set_map(map);
    *request.mutable_goal() = CellPos(14, 14);
    return request;
  }
  v1::CostToGoRequest Window(int32_t x, int32_t y, int32_t width,
                             int32_t height) {
    v1::CostToGoRequest request = Field();
    request.mutable_window()->set_x(x);
    request.mutable_window()->set_y(y);
    request.mutable_window()->set_width(width);
    request.mutable_window()->set_height(height);
    return request;
  }
  grpc::Status HealthCheck(const std::string& service) {
    grpc::health::v1::HealthCheckRequest request;
    request.set_service(service);
    grpc::health::v1::HealthCheckResponse response;
    return health_->Check(Context().get(), request, &response);
  }
  // Raw request bytes to `method` over a streaming call (works for every
  // kind of RPC on the wire): the status it ends with.
  grpc::Status Raw(const std::string& method, const grpc::ByteBuffer& request) {
    auto context = Context();
    grpc::CompletionQueue cq;
    auto call = generic_->PrepareCall(context.get(), method, &cq);
    void* tag = nullptr;
    bool ok = false;
    const auto step = [&] { return cq.Next(&tag, &ok) && ok; };
    call->StartCall(reinterpret_cast<void*>(1));
    if (step()) {
      call->Write(request, reinterpret_cast<void*>(2));
      if (step()) {
        call->WritesDone(reinterpret_cast<void*>(3));
        step();
      }
      grpc::ByteBuffer answer;
      do {
        call->Read(&answer, reinterpret_cast<void*>(4));
      } while (step());
    }
    grpc::Status status;
    call->Finish(&status, reinterpret_cast<void*>(5));
    cq.Next(&tag, &ok);
    cq.Shutdown();
    while (cq.Next(&tag, &ok)) {
    }
    return status;
  }

  // A good request on each service answers OK.
  void ExpectStillServes(const std::string& after) {
    v1::PlanResponse plan;
    const grpc::Status planned =
        planner_->Plan(Context().get(), GoodPlan(), &plan);
    ASSERT_TRUE(planned.ok())
        << "after " << after << ": " << planned.error_message();
    ASSERT_TRUE(plan.found()) << "after " << after;
    ASSERT_TRUE(GetMap("room").ok()) << "after " << after;
  }

  void Run(const std::vector<Case>& cases) {
    for (const Case& c : cases) {
      const std::string label = absl::StrCat(c.rpc, ": ", c.what);
      const grpc::Status status = c.call();
      EXPECT_EQ(status.error_code(), c.code)
          << label << ": got " << status.error_code() << " "
          << status.error_message();
      EXPECT_THAT(status.error_message(), HasSubstr(c.message)) << label;
      // A message quoting a whole huge request would be no better than none.
      EXPECT_LE(status.error_message().size(), 1024u) << label;
      ++tried_;
      ASSERT_NO_FATAL_FAILURE(ExpectStillServes(label));
    }
  }

  // A map file start-up must skip.
  struct File {
    std::string name;
    std::string contents;
    // Part of the start-up log line skipping it.
    std::string complaint;
  };
  // Removed with the fixture, after TearDown has stopped the daemon.
  testing::TempDir scratch_{"pathd_bad_input"};
  fs::path temp_ = scratch_.path();
  std::vector<File> bad_files_;
  std::unique_ptr<e2e::PathdProcess> daemon_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::MapService::Stub> map_;
  std::unique_ptr<v1::PlannerService::Stub> planner_;
  std::unique_ptr<grpc::health::v1::Health::Stub> health_;
  std::unique_ptr<grpc::GenericStub> generic_;
  int tried_ = 0;
};

TEST_F(BadInputTest, EveryRpcAnswersBadInputAndKeepsServing) {
  ASSERT_NO_FATAL_FAILURE(StartDaemon());

  // ---- start-up: every bad --map_dir file is skipped with a reason ----
  {
    const std::string log = daemon_->Log();
    for (const File& f : bad_files_) {
      const std::string prefix =
          absl::StrCat("skipping map file ", f.name, ": ");
      const size_t at = log.find(prefix);
      EXPECT_NE(at, std::string::npos) << f.name << "\n" << log;
      if (at == std::string::npos) continue;
      const std::string line = log.substr(at, log.find('\n', at) - at);
      EXPECT_THAT(line, HasSubstr(f.complaint)) << f.name;
      ++tried_;
    }
    v1::ListMapsResponse list;
    ASSERT_TRUE(
        map_->ListMaps(Context().get(), v1::ListMapsRequest(), &list).ok());
    std::set<std::string> names;
    for (const v1::MapInfo& info : list.maps()) names.insert(info.name());
    EXPECT_EQ(names, (std::set<std::string>{"big", "room"}));
  }

  const std::string huge_name(size_t{1} << 20, 'm');
  const std::string nul_name("ro\0om", 5);
  // Bad names, tried on every RPC that takes one.
  struct Name {
    std::string what;
    std::string name;
    StatusCode code;
    std::string message;
  };
  const std::vector<Name> names = {
      {"empty name", "", StatusCode::INVALID_ARGUMENT, "map name is empty"},
      {"1 MiB name", huge_name, StatusCode::INVALID_ARGUMENT,
       "map name is 1048576 characters long; the limit is 128"},
      {"name with '/'", "maps/room", StatusCode::INVALID_ARGUMENT,
       "character 0x2f"},
      {"name '..'", "..", StatusCode::INVALID_ARGUMENT,
       "must not start with '.'"},
      {"name '../room'", "../room", StatusCode::INVALID_ARGUMENT,
       "must not start with '.'"},
      {"name with NUL", nul_name, StatusCode::INVALID_ARGUMENT,
       "character 0x00"},
      {"unknown name", "nosuchmap", StatusCode::NOT_FOUND,
       "map 'nosuchmap' not found"},
  };
  std::vector<Case> cases;
  for (const Name& n : names) {
    const std::string name = n.name;
    const auto add = [&](const std::string& rpc,
                         std::function<grpc::Status()> call) {
      cases.push_back({rpc, n.what, std::move(call), n.code, n.message});
    };
    if (n.code != StatusCode::NOT_FOUND) {
      add("CreateMap", [=, this] { return CreateMap(RawMap(name, 2, 2, 4)); });
    }
    add("GetMap", [=, this] { return GetMap(name); });
    add("DeleteMap", [=, this] { return DeleteMap(name); });
    add("UpdateMap", [=, this] {
      v1::UpdateMapRequest request;
      request.set_name(name);
      v1::CellChange* change = request.add_changes();
      *change->mutable_cell() = CellPos(0, 0).cell();
      return UpdateMap(request);
    });
    add("WatchMap", [=, this] { return WatchMap(name); });
    v1::PlanRequest plan = GoodPlan();
    plan.set_map(name);
    add("Plan", [=, this] { return Plan(plan); });
    add("PlanStream", [=, this] { return PlanStream(plan); });
    add("PlanBatch", [=, this] { return PlanBatchItem(plan); });
    add("Navigate", [=, this] { return Navigate({NavigateOpen(plan)}); });
    add("IsPathValid", [=, this] {
      v1::IsPathValidRequest request = PathCheck({CellPos(1, 1)});
      request.set_map(name);
      return IsPathValid(request);
    });
    add("CostToGo", [=, this] { return CostToGo(Field(name)); });
  }

  // Non-UTF-8 bytes in a `string` field: the request does not parse. gRPC's
  // own answer would be UNIMPLEMENTED with no message.
  {
    const auto raw = [&](const std::string& rpc, const std::string& method,
                         const google::protobuf::Message& request,
                         StatusCode code = StatusCode::INVALID_ARGUMENT,
                         const std::string& message =
                             "does not parse as its protobuf") {
      const grpc::ByteBuffer bytes = WithNonUtf8(request);
      cases.push_back({rpc, "non-UTF-8 name",
                       [=, this] { return Raw(method, bytes); }, code,
                       message});
    };
    v1::CreateMapRequest create = RawMap(kUtf8Marker, 2, 2, 4);
    raw("CreateMap", "/pathd.v1.MapService/CreateMap", create);
    v1::GetMapRequest get;
    get.set_name(kUtf8Marker);
    raw("GetMap", "/pathd.v1.MapService/GetMap", get);
    v1::DeleteMapRequest del;
    del.set_name(kUtf8Marker);
    raw("DeleteMap", "/pathd.v1.MapService/DeleteMap", del);
    v1::UpdateMapRequest update;
    update.set_name(kUtf8Marker);
    raw("UpdateMap", "/pathd.v1.MapService/UpdateMap", update);
    v1::WatchMapRequest watch;
    watch.set_name(kUtf8Marker);
    raw("WatchMap", "/pathd.v1.MapService/WatchMap", watch);
    v1::PlanRequest plan = GoodPlan();
    plan.set_map(kUtf8Marker);
    raw("Plan", "/pathd.v1.PlannerService/Plan", plan);
    raw("PlanStream", "/pathd.v1.PlannerService/PlanStream", plan);
    v1::PlanBatchRequest item;
    item.set_request_id(kUtf8Marker);
    *item.mutable_request() = GoodPlan();
    // On a bidi stream gRPC hands the handler a message that does not parse
    // as the end of the client's stream, with nothing to tell the two apart:
    // the stream ends OK with nothing answered (docs/decisions.md).
    raw("PlanBatch", "/pathd.v1.PlannerService/PlanBatch", item, StatusCode::OK,
        "");
    v1::NavigateRequest open = NavigateOpen(plan);
    raw("Navigate", "/pathd.v1.PlannerService/Navigate", open, StatusCode::OK,
        "");
    v1::IsPathValidRequest check = PathCheck({CellPos(1, 1)});
    check.set_map(kUtf8Marker);
    raw("IsPathValid", "/pathd.v1.PlannerService/IsPathValid", check);
    v1::CostToGoRequest field = Field(kUtf8Marker);
    raw("CostToGo", "/pathd.v1.PlannerService/CostToGo", field);
    grpc::health::v1::HealthCheckRequest health;
    health.set_service(kUtf8Marker);
    // gRPC's own health service parses its requests itself.
    raw("Health.Check", "/grpc.health.v1.Health/Check", health,
        StatusCode::INVALID_ARGUMENT, "could not parse request");
  }
  // Bytes that are no protobuf message at all (a truncated field).
  {
    grpc::Slice slice(std::string("\x0a\xff\xff\xff\x0f", 5));
    const grpc::ByteBuffer junk(&slice, 1);
    for (const std::string method :
         {"/pathd.v1.MapService/ListMaps",
          "/pathd.v1.PlannerService/GetCacheStats",
          "/pathd.v1.MapService/GetMap", "/pathd.v1.MapService/WatchMap"}) {
      cases.push_back(
          {method, "unparsable bytes", [=, this] { return Raw(method, junk); },
           StatusCode::INVALID_ARGUMENT,
           absl::StrCat("the request to ", method, " does not parse")});
    }
    const std::string health = "/grpc.health.v1.Health/Check";
    cases.push_back({health, "unparsable bytes",
                     [=, this] { return Raw(health, junk); },
                     StatusCode::INVALID_ARGUMENT, "could not parse request"});
  }

  // ---- CreateMap: dimensions, cell arrays, poses, sources ----
  const auto create = [&](const std::string& what, v1::CreateMapRequest request,
                          StatusCode code, const std::string& message) {
    cases.push_back({"CreateMap", what,
                     [=, this] { return CreateMap(request); }, code, message});
  };
  create("negative width", RawMap("m", -1, 4, 4), StatusCode::INVALID_ARGUMENT,
         "width -1 and height 4 must be positive");
  create("zero height", RawMap("m", 4, 0, 0), StatusCode::INVALID_ARGUMENT,
         "must be positive");
  create("INT32_MIN dimensions", RawMap("m", kIntMin, kIntMin, 0),
         StatusCode::INVALID_ARGUMENT, "must be positive");
  create("width * height overflowing int32", RawMap("m", kIntMax, kIntMax, 4),
         StatusCode::RESOURCE_EXHAUSTED, "--max_map_cells");
  create("65536 x 65536 without cells", RawMap("m", 65536, 65536, 0),
         StatusCode::RESOURCE_EXHAUSTED, "--max_map_cells");
  create("width over the grid limit", RawMap("m", 65537, 1, 65537),
         StatusCode::INVALID_ARGUMENT, "width 65537 is out of range");
  create("too few cells", RawMap("m", 2, 2, 3), StatusCode::INVALID_ARGUMENT,
         "needs 4 cells, got 3");
  create("too many cells", RawMap("m", 2, 2, 5), StatusCode::INVALID_ARGUMENT,
         "needs 4 cells, got 5");
  create("no cells", RawMap("m", 2, 2, 0), StatusCode::INVALID_ARGUMENT,
         "needs 4 cells, got 0");
  {
    v1::CreateMapRequest none;
    none.set_name("m");
    create("no source", none, StatusCode::INVALID_ARGUMENT,
           "source is not set");
  }
  for (const auto& [what, resolution] :
       std::vector<std::pair<std::string, double>>{
           {"NaN resolution", kNaN},
           {"infinite resolution", kInf},
           {"negative resolution", -0.5}}) {
    v1::CreateMapRequest request = RawMap("m", 2, 2, 4);
    request.set_resolution(resolution);
    create(what, request, StatusCode::INVALID_ARGUMENT, "resolution");
  }
  for (const auto& [what, field, value] :
       std::vector<std::tuple<std::string, std::string, double>>{
           {"NaN origin.x", "origin.x", kNaN},
           {"infinite origin.y", "origin.y", -kInf},
           {"NaN origin.yaw", "origin.yaw", kNaN}}) {
    v1::CreateMapRequest request = RawMap("m", 2, 2, 4);
    v1::Origin* origin = request.mutable_origin();
    if (field == "origin.x") origin->set_x(value);
    if (field == "origin.y") origin->set_y(value);
    if (field == "origin.yaw") origin->set_yaw(value);
    create(what, request, StatusCode::INVALID_ARGUMENT, field);
  }
  {
    v1::CreateMapRequest exists = RawMap("room", 2, 2, 4);
    create("existing name without replace", exists, StatusCode::ALREADY_EXISTS,
           "map 'room' already exists");
  }
  // Moving AI text.
  const auto movingai = [&](const std::string& what, const std::string& text,
                            StatusCode code, const std::string& message) {
    v1::CreateMapRequest request;
    request.set_name("m");
    request.set_movingai_text(text);
    create(what, request, code, message);
  };
  movingai("empty Moving AI text", "", StatusCode::INVALID_ARGUMENT,
           "movingai_text");
  movingai("Moving AI garbage", "\x01\x02 garbage\n",
           StatusCode::INVALID_ARGUMENT, "movingai_text");
  movingai("negative Moving AI height",
           "type octile\nheight -3\nwidth 4\nmap\n",
           StatusCode::INVALID_ARGUMENT, "height");
  movingai("Moving AI height beyond int64",
           "type octile\nheight 1e99\nwidth 4\nmap\n",
           StatusCode::INVALID_ARGUMENT, "height");
  movingai("Moving AI 65536 x 65536",
           "type octile\nheight 65536\nwidth 65536\nmap\n",
           StatusCode::RESOURCE_EXHAUSTED,
           "65536 = 4294967296 cells exceeds the limit of 2097152 cells "
           "(--max_map_cells)");
  movingai("Moving AI short row",
           "type octile\nheight 2\nwidth 3\nmap\n...\n..\n",
           StatusCode::INVALID_ARGUMENT, "movingai_text");
  movingai("Moving AI missing rows",
           "type octile\nheight 3\nwidth 3\nmap\n...\n",
           StatusCode::INVALID_ARGUMENT, "movingai_text");
  movingai("Moving AI unknown terrain",
           "type octile\nheight 1\nwidth 2\nmap\n.\x7f\n",
           StatusCode::INVALID_ARGUMENT, "movingai_text");
  // ROS map_server YAML + PGM.
  const auto ros = [&](const std::string& what, const std::string& yaml,
                       const std::string& pgm, StatusCode code,
                       const std::string& message) {
    v1::CreateMapRequest request;
    request.set_name("m");
    request.mutable_ros_map()->set_yaml(yaml);
    request.mutable_ros_map()->set_image(pgm);
    create(what, request, code, message);
  };
  const std::string good_yaml =
      "image: x.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n";
  const std::string good_pgm =
      std::string("P5\n2 2\n255\n") + std::string(4, '\xfe');
  ros("empty YAML", "", good_pgm, StatusCode::INVALID_ARGUMENT, "ros_map.yaml");
  ros("YAML garbage", "{{{{ ::: ]]", good_pgm, StatusCode::INVALID_ARGUMENT,
      "ros_map.yaml");
  ros("YAML nested 100000 deep", std::string(100000, '['), good_pgm,
      StatusCode::INVALID_ARGUMENT, "ros_map.yaml");
  ros("YAML with NUL", std::string("image: x\0\nresolution: 1\n", 24), good_pgm,
      StatusCode::INVALID_ARGUMENT, "ros_map.yaml");
  ros("YAML NaN resolution",
      "image: x.pgm\nresolution: .nan\norigin: [0, 0, 0]\n", good_pgm,
      StatusCode::INVALID_ARGUMENT, "resolution");
  ros("YAML zero resolution",
      "image: x.pgm\nresolution: 0\norigin: [0, 0, 0]\n", good_pgm,
      StatusCode::INVALID_ARGUMENT, "resolution");
  ros("YAML infinite origin",
      "image: x.pgm\nresolution: 1\norigin: [0, -.inf, 0]\n", good_pgm,
      StatusCode::INVALID_ARGUMENT, "origin");
  ros("YAML string origin", "image: x.pgm\nresolution: 1\norigin: [a, b, c]\n",
      good_pgm, StatusCode::INVALID_ARGUMENT, "origin");
  ros("YAML negate 7", good_yaml + "negate: 7\n", good_pgm,
      StatusCode::INVALID_ARGUMENT, "negate");
  ros("YAML thresholds crossed",
      good_yaml + "occupied_thresh: 0.1\nfree_thresh: 0.9\n", good_pgm,
      StatusCode::INVALID_ARGUMENT, "thresh");
  ros("YAML unknown mode", good_yaml + "mode: sideways\n", good_pgm,
      StatusCode::INVALID_ARGUMENT, "mode");
  ros("empty PGM", good_yaml, "", StatusCode::INVALID_ARGUMENT,
      "ros_map.image");
  ros("PGM garbage", good_yaml, "P9 \x01\x02", StatusCode::INVALID_ARGUMENT,
      "ros_map.image");
  ros("PGM negative width", good_yaml, "P5\n-2 2\n255\n\x01\x01\x01\x01",
      StatusCode::INVALID_ARGUMENT, "ros_map.image");
  ros("PGM 65536 x 65536", good_yaml, "P5\n65536 65536\n255\n",
      StatusCode::RESOURCE_EXHAUSTED,
      "exceeds the limit of 2097152 cells (--max_map_cells)");
  ros("PGM width beyond int64", good_yaml, "P5\n99999999999999999999 2\n255\n",
      StatusCode::INVALID_ARGUMENT, "ros_map.image");
  ros("PGM truncated", good_yaml, "P5\n4 4\n255\n\x01\x02",
      StatusCode::INVALID_ARGUMENT, "ros_map.image");
  ros("PGM maxval 0", good_yaml,
      std::string("P5\n2 2\n0\n") + std::string(4, '\0'),
      StatusCode::INVALID_ARGUMENT, "ros_map.image");
  ros("PGM maxval 70000", good_yaml, "P2\n1 1\n70000\n1\n",
      StatusCode::INVALID_ARGUMENT, "ros_map.image");
  ros("P2 sample over maxval", good_yaml, "P2\n1 1\n10\n11\n",
      StatusCode::INVALID_ARGUMENT, "ros_map.image");
  // Files in --map_dir, named by the client.
  const auto from_dir = [&](const std::string& what, const std::string& file,
                            StatusCode code, const std::string& message) {
    v1::CreateMapRequest request;
    request.set_name("m");
    request.set_map_dir_file(file);
    create(what, request, code, message);
  };
  from_dir("map_dir_file '..' escape", "../outside/secret.map",
           StatusCode::INVALID_ARGUMENT, "resolves outside --map_dir");
  from_dir("map_dir_file folded '..' escape", "sub/../../outside/secret.map",
           StatusCode::INVALID_ARGUMENT, "resolves outside --map_dir");
  from_dir("map_dir_file absolute path", (outside() / "secret.map").string(),
           StatusCode::INVALID_ARGUMENT,
           "must be a path relative to --map_dir");
  from_dir("map_dir_file symlink out", "escape.map",
           StatusCode::INVALID_ARGUMENT, "resolves outside --map_dir");
  from_dir("map_dir_file relative symlink out", "escape_relative.map",
           StatusCode::INVALID_ARGUMENT, "resolves outside --map_dir");
  from_dir("map_dir_file through a linked directory", "out_dir/secret.map",
           StatusCode::INVALID_ARGUMENT, "resolves outside --map_dir");
  from_dir("map_dir_file the directory itself", ".",
           StatusCode::INVALID_ARGUMENT, "resolves outside --map_dir");
  // A link to nothing is a missing file, wherever it would point.
  from_dir("map_dir_file dangling symlink", "dangling.map",
           StatusCode::NOT_FOUND, "map_dir_file 'dangling.map' not found");
  from_dir("map_dir_file empty", "", StatusCode::INVALID_ARGUMENT,
           "map_dir_file is empty");
  from_dir("map_dir_file with NUL", std::string("room\0.map", 9),
           StatusCode::INVALID_ARGUMENT, "NUL");
  from_dir("map_dir_file missing", "missing.map", StatusCode::NOT_FOUND,
           "not found");
  from_dir("map_dir_file a directory", "sub", StatusCode::INVALID_ARGUMENT,
           "not a regular file");
  from_dir("map_dir_file unknown extension", "notes.txt",
           StatusCode::INVALID_ARGUMENT, "unknown extension");
  from_dir("map_dir_file 1 MiB long", std::string(size_t{1} << 20, 'f'),
           StatusCode::INVALID_ARGUMENT,
           "map_dir_file is 1048576 bytes long; the limit is 4096");
  for (const File& f : bad_files_) {
    // Start-up derives the name from the file; here the client names it.
    if (f.name == "bad name.map" || f.name == "..map") continue;
    const StatusCode code =
        f.complaint == "exceeds the limit" ? StatusCode::RESOURCE_EXHAUSTED
        : f.complaint == "not found"       ? StatusCode::NOT_FOUND
                                           : StatusCode::INVALID_ARGUMENT;
    from_dir(absl::StrCat("map_dir_file ", f.name), f.name, code, f.complaint);
  }
  // The request-supplied pose is checked for map_dir Moving AI maps too.
  {
    v1::CreateMapRequest request;
    request.set_name("m");
    request.set_map_dir_file("sub/inner.map");
    request.set_resolution(kNaN);
    create("map_dir_file with NaN resolution", request,
           StatusCode::INVALID_ARGUMENT, "resolution");
  }
  // Oversized: one byte of cells per map cell, beyond --max_message_bytes.
  create("message over --max_message_bytes",
         RawMap("m", 1500, 1500, 1500 * 1500), StatusCode::RESOURCE_EXHAUSTED,
         "larger than max");

  // ---- GetMap / WatchMap answers larger than one message ----
  cases.push_back({"GetMap", "cells of a map larger than one message",
                   [this] { return GetMap("big", /*include_cells=*/true); },
                   StatusCode::RESOURCE_EXHAUSTED, "--max_message_bytes"});
  cases.push_back({"WatchMap", "RESYNC of a map larger than one message",
                   [this] { return WatchMap("big"); },
                   StatusCode::RESOURCE_EXHAUSTED, "--max_message_bytes"});

  // ---- UpdateMap ----
  const auto update = [&](const std::string& what,
                          std::function<void(v1::UpdateMapRequest&)> fill,
                          StatusCode code, const std::string& message) {
    v1::UpdateMapRequest request;
    request.set_name("room");
    fill(request);
    cases.push_back({"UpdateMap", what,
                     [=, this] { return UpdateMap(request); }, code, message});
  };
  const auto cell = [](int32_t x, int32_t y, uint32_t cost = 254) {
    return [=](v1::UpdateMapRequest& r) {
      v1::CellChange* c = r.add_changes();
      *c->mutable_cell() = CellPos(x, y).cell();
      c->set_cost(cost);
    };
  };
  const auto rect = [](int32_t x0, int32_t y0, int32_t x1, int32_t y1,
                       int count = 1) {
    return [=](v1::UpdateMapRequest& r) {
      for (int i = 0; i < count; ++i) {
        v1::CellChange* c = r.add_changes();
        c->mutable_rect()->set_x_min(x0);
        c->mutable_rect()->set_y_min(y0);
        c->mutable_rect()->set_x_max(x1);
        c->mutable_rect()->set_y_max(y1);
        c->set_cost(static_cast<uint32_t>(i % 2 == 0 ? 254 : 0));
      }
    };
  };
  update(
      "empty batch", [](v1::UpdateMapRequest&) {}, StatusCode::INVALID_ARGUMENT,
      "has no changes");
  update(
      "change with no target", [](v1::UpdateMapRequest& r) { r.add_changes(); },
      StatusCode::INVALID_ARGUMENT, "change 0: neither cell nor rect");
  update("cell (-1, 0)", cell(-1, 0), StatusCode::INVALID_ARGUMENT,
         "change 0: cell (-1, 0) is outside the 16 x 16 map");
  update("cell (16, 3)", cell(16, 3), StatusCode::INVALID_ARGUMENT, "outside");
  update("cell (INT32_MIN, INT32_MAX)", cell(kIntMin, kIntMax),
         StatusCode::INVALID_ARGUMENT, "outside");
  update("cost 256", cell(1, 1, 256), StatusCode::INVALID_ARGUMENT,
         "cost 256 is out of range 0..255");
  update("cost UINT32_MAX", cell(1, 1, 0xffffffffu),
         StatusCode::INVALID_ARGUMENT, "out of range 0..255");
  update("rect min > max", rect(5, 5, 4, 4), StatusCode::INVALID_ARGUMENT,
         "min > max");
  update("rect off the map", rect(0, 0, 16, 15), StatusCode::INVALID_ARGUMENT,
         "reaches outside");
  update("rect INT32_MIN..INT32_MAX", rect(kIntMin, kIntMin, kIntMax, kIntMax),
         StatusCode::INVALID_ARGUMENT, "reaches outside");
  update(
      "bad change after good ones",
      [&](v1::UpdateMapRequest& r) {
        cell(2, 2)(r);
        cell(3, 3)(r);
        cell(99, 3)(r);
      },
      StatusCode::INVALID_ARGUMENT, "change 2:");
  update(
      "stale expected_version",
      [&](v1::UpdateMapRequest& r) {
        cell(2, 2)(r);
        r.set_expected_version(999999);
      },
      StatusCode::ABORTED, "expected 999999");
  // 100 000 whole-map rectangles (about 1 MiB of request): each is legal,
  // but together they would write every cell 100 000 times.
  update("100000 overlapping whole-map rects", rect(0, 0, 15, 15, 100000),
         StatusCode::RESOURCE_EXHAUSTED, "cells in total");

  // ---- Plan, and the same through PlanStream and PlanBatch ----
  const auto plan_case = [&](const std::string& what,
                             std::function<void(v1::PlanRequest&)> change,
                             StatusCode code, const std::string& message) {
    v1::PlanRequest request = GoodPlan();
    change(request);
    cases.push_back(
        {"Plan", what, [=, this] { return Plan(request); }, code, message});
    cases.push_back({"PlanStream", what,
                     [=, this] { return PlanStream(request); }, code, message});
    cases.push_back({"PlanBatch", what,
                     [=, this] { return PlanBatchItem(request); }, code,
                     message});
  };
  using P = v1::PlanRequest;
  plan_case(
      "start unset", [](P& r) { r.clear_start(); },
      StatusCode::INVALID_ARGUMENT, "start is not set");
  plan_case(
      "goal unset", [](P& r) { r.clear_goal(); }, StatusCode::INVALID_ARGUMENT,
      "goal is not set");
  plan_case(
      "start cell (-1, 3)", [](P& r) { *r.mutable_start() = CellPos(-1, 3); },
      StatusCode::INVALID_ARGUMENT, "start");
  plan_case(
      "goal cell (INT32_MAX, INT32_MIN)",
      [](P& r) { *r.mutable_goal() = CellPos(kIntMax, kIntMin); },
      StatusCode::INVALID_ARGUMENT, "goal");
  plan_case(
      "start on a blocked cell",
      [](P& r) { *r.mutable_start() = CellPos(5, 5); },
      StatusCode::INVALID_ARGUMENT, "start");
  plan_case(
      "NaN start world point",
      [](P& r) { *r.mutable_start() = WorldPos(kNaN, 1); },
      StatusCode::INVALID_ARGUMENT, "start world point (nan, 1) is not finite");
  plan_case(
      "infinite goal world point",
      [](P& r) { *r.mutable_goal() = WorldPos(1, -kInf); },
      StatusCode::INVALID_ARGUMENT, "goal world point (1, -inf) is not finite");
  plan_case(
      "goal world point 1e300 off the map",
      [](P& r) { *r.mutable_goal() = WorldPos(1e300, 1e300); },
      StatusCode::INVALID_ARGUMENT, "is outside the map");
  plan_case(
      "unknown planner 99",
      [](P& r) { r.set_planner(static_cast<v1::Planner>(99)); },
      StatusCode::INVALID_ARGUMENT, "unknown planner 99");
  plan_case(
      "unknown planner -1",
      [](P& r) { r.set_planner(static_cast<v1::Planner>(-1)); },
      StatusCode::INVALID_ARGUMENT, "unknown planner -1");
  plan_case(
      "unknown connectivity 6",
      [](P& r) {
        r.mutable_options()->set_connectivity(static_cast<v1::Connectivity>(6));
      },
      StatusCode::INVALID_ARGUMENT, "unknown connectivity 6");
  plan_case(
      "unknown attractive potential 9",
      [](P& r) {
        r.mutable_options()->mutable_potential_field()->set_attractive(
            static_cast<v1::AttractivePotential>(9));
      },
      StatusCode::INVALID_ARGUMENT, "unknown shape 9");
  plan_case(
      "NaN cost_weight",
      [](P& r) { r.mutable_options()->set_cost_weight(kNaN); },
      StatusCode::INVALID_ARGUMENT, "options.cost_weight nan");
  plan_case(
      "negative cost_weight",
      [](P& r) { r.mutable_options()->set_cost_weight(-1); },
      StatusCode::INVALID_ARGUMENT, "options.cost_weight");
  plan_case(
      "heuristic_weight 0.5",
      [](P& r) { r.mutable_options()->set_heuristic_weight(0.5); },
      StatusCode::INVALID_ARGUMENT, "options.heuristic_weight");
  plan_case(
      "infinite heuristic_weight",
      [](P& r) { r.mutable_options()->set_heuristic_weight(kInf); },
      StatusCode::INVALID_ARGUMENT, "options.heuristic_weight");
  plan_case(
      "negative max_expansions",
      [](P& r) { r.mutable_options()->set_max_expansions(-5); },
      StatusCode::INVALID_ARGUMENT, "options.max_expansions");
  plan_case(
      "negative lookahead",
      [](P& r) { r.mutable_options()->set_lookahead(-1); },
      StatusCode::INVALID_ARGUMENT, "options.lookahead");
  plan_case(
      "NaN robot_radius_m",
      [](P& r) { r.mutable_options()->set_robot_radius_m(kNaN); },
      StatusCode::INVALID_ARGUMENT, "options.robot_radius_m");
  plan_case(
      "infinite robot_radius_cells",
      [](P& r) { r.mutable_options()->set_robot_radius_cells(kInf); },
      StatusCode::INVALID_ARGUMENT, "options.robot_radius_cells");
  plan_case(
      "goal_tolerance_cells 1e9",
      [](P& r) { r.mutable_options()->set_goal_tolerance_cells(1e9); },
      StatusCode::INVALID_ARGUMENT, "the limit is 1024 cells");
  plan_case(
      "NaN goal_tolerance_m",
      [](P& r) { r.mutable_options()->set_goal_tolerance_m(kNaN); },
      StatusCode::INVALID_ARGUMENT, "options.goal_tolerance_m");
  plan_case(
      "NaN potential step_size",
      [](P& r) {
        r.mutable_options()->mutable_potential_field()->set_step_size(kNaN);
      },
      StatusCode::INVALID_ARGUMENT, "options.potential_field.step_size");
  plan_case(
      "negative potential max_steps",
      [](P& r) {
        r.mutable_options()->mutable_potential_field()->set_max_steps(-1);
      },
      StatusCode::INVALID_ARGUMENT, "options.potential_field.max_steps");
  plan_case(
      "via off the map", [](P& r) { *r.add_via() = CellPos(3, 99); },
      StatusCode::INVALID_ARGUMENT, "via[0]");
  plan_case(
      "via unset", [](P& r) { r.add_via(); }, StatusCode::INVALID_ARGUMENT,
      "via[0] is not set");
  plan_case(
      "NaN via world point", [](P& r) { *r.add_via() = WorldPos(kNaN, kNaN); },
      StatusCode::INVALID_ARGUMENT, "via[0] world point");
  plan_case(
      "257 via points",
      [](P& r) {
        for (int i = 0; i < 257; ++i) *r.add_via() = CellPos(2, 2);
      },
      StatusCode::INVALID_ARGUMENT, "at most 256");
  plan_case(
      "200000 unset via points",
      [](P& r) {
        for (int i = 0; i < 200000; ++i) r.add_via();
      },
      StatusCode::INVALID_ARGUMENT, "at most 256");
  plan_case(
      "via with spm",
      [](P& r) {
        r.set_planner(v1::PLANNER_SPM);
        *r.add_via() = CellPos(2, 2);
      },
      StatusCode::INVALID_ARGUMENT, "via");
  plan_case(
      "cost-to-go field of a map over --max_cost_to_go_cells",
      [](P& r) {
        r.set_map("big");
        r.set_planner(v1::PLANNER_DISTANCE_TRANSFORM);
        r.mutable_options()->set_return_cost_to_go(true);
      },
      StatusCode::INVALID_ARGUMENT, "--max_cost_to_go_cells");
  // PlanBatch items of their own.
  cases.push_back({"PlanBatch", "empty batch", [this] { return PlanBatch({}); },
                   StatusCode::OK, "answers=0"});
  cases.push_back({"PlanBatch", "empty request_id",
                   [this] {
                     v1::PlanBatchRequest item;
                     *item.mutable_request() = GoodPlan();
                     std::vector<v1::PlanBatchRequest> items = {item};
                     // The answer carries the empty id; find it by renaming.
                     auto context = Context();
                     auto stream = planner_->PlanBatch(context.get());
                     stream->Write(item);
                     stream->WritesDone();
                     v1::PlanBatchResponse answer;
                     grpc::Status item_status = grpc::Status::OK;
                     while (stream->Read(&answer)) {
                       if (answer.has_error()) {
                         item_status = grpc::Status(
                             static_cast<StatusCode>(answer.error().code()),
                             answer.error().message());
                       }
                     }
                     const grpc::Status status = stream->Finish();
                     return status.ok() ? item_status : status;
                   },
                   StatusCode::INVALID_ARGUMENT, "request_id"});
  cases.push_back({"PlanBatch", "item without a request",
                   [this] { return PlanBatchItem(v1::PlanRequest()); },
                   StatusCode::INVALID_ARGUMENT, "map name is empty"});
  cases.push_back({"PlanBatch", "1 MiB request_id",
                   [this] {
                     v1::PlanRequest request = GoodPlan();
                     request.set_planner(static_cast<v1::Planner>(77));
                     return PlanBatchItem(request,
                                          std::string(size_t{1} << 20, 'r'));
                   },
                   StatusCode::OK, "answers=2"});

  // ---- Navigate ----
  const auto nav = [&](const std::string& what,
                       std::function<grpc::Status()> call, StatusCode code,
                       const std::string& message) {
    cases.push_back({"Navigate", what, std::move(call), code, message});
  };
  nav(
      "no messages", [this] { return Navigate({}); }, StatusCode::OK, "");
  nav(
      "pose before open",
      [this] {
        v1::NavigateRequest pose;
        *pose.mutable_pose() = CellPos(1, 1);
        return Navigate({pose});
      },
      StatusCode::INVALID_ARGUMENT,
      "the first message of a session must be 'open'");
  nav(
      "message with no kind",
      [this] { return Navigate({v1::NavigateRequest()}); },
      StatusCode::INVALID_ARGUMENT, "sets none of open, pose, observe");
  nav(
      "open twice", [this] { return NavigateThen(NavigateOpen(GoodPlan())); },
      StatusCode::INVALID_ARGUMENT, "already open");
  {
    v1::PlanRequest p = GoodPlan();
    *p.mutable_start() = WorldPos(kInf, 0);
    nav(
        "open with infinite start",
        [=, this] { return Navigate({NavigateOpen(p)}); },
        StatusCode::INVALID_ARGUMENT,
        "start world point (inf, 0) is not finite");
    p = GoodPlan();
    *p.mutable_goal() = CellPos(16, 16);
    nav(
        "open with goal off the map",
        [=, this] { return Navigate({NavigateOpen(p)}); },
        StatusCode::INVALID_ARGUMENT, "goal");
    p = GoodPlan();
    p.mutable_options()->set_connectivity(static_cast<v1::Connectivity>(3));
    nav(
        "open with unknown connectivity",
        [=, this] { return Navigate({NavigateOpen(p)}); },
        StatusCode::INVALID_ARGUMENT, "unknown connectivity 3");
  }
  nav(
      "pose off the map",
      [this] {
        v1::NavigateRequest pose;
        *pose.mutable_pose() = CellPos(-7, 2);
        return NavigateThen(pose);
      },
      StatusCode::INVALID_ARGUMENT, "pose (-7, 2) is outside");
  nav(
      "NaN pose",
      [this] {
        v1::NavigateRequest pose;
        *pose.mutable_pose() = WorldPos(kNaN, 0);
        return NavigateThen(pose);
      },
      StatusCode::INVALID_ARGUMENT, "pose world point (nan, 0) is not finite");
  nav(
      "unset pose",
      [this] {
        v1::NavigateRequest pose;
        pose.mutable_pose();
        return NavigateThen(pose);
      },
      StatusCode::INVALID_ARGUMENT, "pose is not set");
  nav(
      "empty observation",
      [this] {
        v1::NavigateRequest observe;
        observe.mutable_observe();
        return NavigateThen(observe);
      },
      StatusCode::INVALID_ARGUMENT, "observation has no changes");
  for (const bool session_only : {false, true}) {
    const std::string where = session_only ? " (session only)" : "";
    nav(
        "observation off the map" + where,
        [=, this] {
          v1::NavigateRequest observe;
          observe.mutable_observe()->set_session_only(session_only);
          v1::CellChange* c = observe.mutable_observe()->add_changes();
          *c->mutable_cell() = CellPos(3, 16).cell();
          return NavigateThen(observe);
        },
        StatusCode::INVALID_ARGUMENT, "change 0: cell (3, 16) is outside");
    nav(
        "observation cost 300" + where,
        [=, this] {
          v1::NavigateRequest observe;
          observe.mutable_observe()->set_session_only(session_only);
          v1::CellChange* c = observe.mutable_observe()->add_changes();
          *c->mutable_cell() = CellPos(3, 3).cell();
          c->set_cost(300);
          return NavigateThen(observe);
        },
        StatusCode::INVALID_ARGUMENT, "cost 300 is out of range");
    nav(
        "100000 overlapping whole-map rects" + where,
        [=, this] {
          v1::NavigateRequest observe;
          observe.mutable_observe()->set_session_only(session_only);
          for (int i = 0; i < 100000; ++i) {
            v1::CellChange* c = observe.mutable_observe()->add_changes();
            c->mutable_rect()->set_x_max(15);
            c->mutable_rect()->set_y_max(15);
            c->set_cost(i % 2 == 0 ? 0 : 100);
          }
          return NavigateThen(observe);
        },
        StatusCode::RESOURCE_EXHAUSTED, "cells in total");
  }

  // ---- IsPathValid ----
  const auto check = [&](const std::string& what,
                         v1::IsPathValidRequest request, StatusCode code,
                         const std::string& message) {
    cases.push_back({"IsPathValid", what,
                     [=, this] { return IsPathValid(request); }, code,
                     message});
  };
  check("empty path", PathCheck({}), StatusCode::INVALID_ARGUMENT,
        "path is empty");
  check("unset pose", PathCheck({CellPos(1, 1), v1::Position()}),
        StatusCode::INVALID_ARGUMENT, "path[1]");
  check("NaN pose", PathCheck({CellPos(1, 1), WorldPos(kNaN, 2)}),
        StatusCode::INVALID_ARGUMENT, "path[1]");
  check("infinite pose", PathCheck({WorldPos(-kInf, kInf)}),
        StatusCode::INVALID_ARGUMENT, "path[0]");
  {
    std::vector<v1::Position> many(kMaxPathPoints + 1, CellPos(1, 1));
    check("path over --max_path_points", PathCheck(many),
          StatusCode::INVALID_ARGUMENT, "--max_path_points");
    v1::IsPathValidRequest request = PathCheck({CellPos(1, 1)});
    request.mutable_options()->set_connectivity(
        static_cast<v1::Connectivity>(-8));
    check("unknown connectivity -8", request, StatusCode::INVALID_ARGUMENT,
          "unknown connectivity -8");
    request = PathCheck({CellPos(1, 1)});
    request.mutable_options()->set_robot_radius_cells(-2);
    check("negative robot radius", request, StatusCode::INVALID_ARGUMENT,
          "options.robot_radius_cells");
  }
  // Off-map poses are a verdict (valid = false), not an error.
  check("poses off the map",
        PathCheck({CellPos(-1, -1), CellPos(kIntMax, kIntMax)}), StatusCode::OK,
        "");

  // ---- CostToGo ----
  const auto field = [&](const std::string& what, v1::CostToGoRequest request,
                         StatusCode code, const std::string& message) {
    cases.push_back({"CostToGo", what, [=, this] { return CostToGo(request); },
                     code, message});
  };
  {
    v1::CostToGoRequest request = Field();
    request.clear_goal();
    field("goal unset", request, StatusCode::INVALID_ARGUMENT,
          "goal is not set");
    request = Field();
    *request.mutable_goal() = WorldPos(kNaN, kInf);
    field("NaN goal", request, StatusCode::INVALID_ARGUMENT, "not finite");
    request = Field();
    *request.mutable_goal() = CellPos(16, 0);
    field("goal off the map", request, StatusCode::INVALID_ARGUMENT, "goal");
    request = Field();
    request.mutable_options()->set_connectivity(
        static_cast<v1::Connectivity>(5));
    field("unknown connectivity 5", request, StatusCode::INVALID_ARGUMENT,
          "unknown connectivity 5");
  }
  field("window width 0", Window(0, 0, 0, 4), StatusCode::INVALID_ARGUMENT,
        "window.width 0 must be > 0");
  field("window height -3", Window(0, 0, 4, -3), StatusCode::INVALID_ARGUMENT,
        "window.height -3 must be > 0");
  field("window x -1", Window(-1, 0, 4, 4), StatusCode::INVALID_ARGUMENT,
        "window.x -1");
  field("window x + width overflowing int32", Window(kIntMax, 0, kIntMax, 4),
        StatusCode::INVALID_ARGUMENT, "reaches outside");
  field("window beyond the map", Window(10, 10, 7, 1),
        StatusCode::INVALID_ARGUMENT, "reaches outside");
  field("whole field over --max_cost_to_go_cells", Field("big"),
        StatusCode::RESOURCE_EXHAUSTED, "--max_cost_to_go_cells");

  // ---- Health ----
  cases.push_back({"Health.Check", "unknown service",
                   [this] { return HealthCheck("pathd.v1.NoSuchService"); },
                   StatusCode::NOT_FOUND, ""});
  // gRPC's health service refuses service names over 200 bytes.
  cases.push_back(
      {"Health.Check", "1 MiB service name",
       [this] { return HealthCheck(std::string(size_t{1} << 20, 's')); },
       StatusCode::INVALID_ARGUMENT, "could not parse request"});

  // GetCacheStats and ListMaps take no fields, so unknown fields are all a
  // client can add: ignored, as proto3 requires.
  cases.push_back({"GetCacheStats", "unknown fields",
                   [this] {
                     grpc::Slice slice(
                         std::string("\x08\x01\x12\x03"
                                     "abc",
                                     7));
                     return Raw("/pathd.v1.PlannerService/GetCacheStats",
                                grpc::ByteBuffer(&slice, 1));
                   },
                   StatusCode::OK, ""});

  ASSERT_NO_FATAL_FAILURE(Run(cases));

  // The maps the good requests use were never changed by a bad one.
  v1::GetMapRequest get;
  get.set_name("room");
  v1::GetMapResponse room;
  ASSERT_TRUE(map_->GetMap(Context().get(), get, &room).ok());
  EXPECT_EQ(room.info().version(), 1u);
  EXPECT_TRUE(daemon_->Running());

  // The request log quotes bad names escaped and cut short: one line each,
  // none holding the 1 MiB name.
  const std::string log = daemon_->Log();
  std::istringstream lines(log);
  for (std::string line; std::getline(lines, line);) {
    EXPECT_LE(line.size(), 2048u) << line.substr(0, 200);
  }
  EXPECT_THAT(log, HasSubstr("rpc=GetMap map=ro\\x00om "));
  EXPECT_THAT(log, HasSubstr("(1048576 bytes)"));
  EXPECT_THAT(
      log,
      HasSubstr(
          "rpc=ListMaps map=- unparsable request status=INVALID_ARGUMENT"));
  std::printf("bad_input_test: tried %d bad-input cases; pathd kept serving\n",
              tried_);
}

// --map_dir itself is bad: the daemon refuses to start and says why.
TEST_F(BadInputTest, BadMapDirFlagStopsStartUp) {
  WriteFile(temp_ / "plain_file", "x");
  const std::vector<std::pair<std::string, std::string>> dirs = {
      {(temp_ / "plain_file").string(), "is not a directory"},
      {(temp_ / "missing").string(), "does not exist"},
  };
  for (const auto& [dir, message] : dirs) {
    const std::unique_ptr<e2e::PathdProcess> daemon =
        StartPathd(temp_ / "refused.log", {"--map_dir=" + dir});
    EXPECT_TRUE(daemon->address().empty());
    EXPECT_NE(daemon->WaitForExit(), 0);
    EXPECT_THAT(daemon->Log(), HasSubstr(message)) << dir;
  }
  std::printf("bad_input_test: %zu bad --map_dir flags refused\n", dirs.size());
}

}  // namespace
}  // namespace pathd
