// The fixture of bad_input_test: a real pathd with a --map_dir of good and bad
// files, one helper per RPC answering the call's status, and the table of
// cases (Case) that Run tries, each followed by a good request. The test
// itself is bad_input_test.cc; the table is split over bad_input_*_cases.cc.
#ifndef PATHD_TESTS_E2E_BAD_INPUT_FIXTURE_H_
#define PATHD_TESTS_E2E_BAD_INPUT_FIXTURE_H_

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

namespace pathd::bad_input_test {

namespace fs = std::filesystem;
using e2e::ReadFile;
using e2e::WriteFile;
using Clock = std::chrono::steady_clock;
using grpc::StatusCode;
using ::testing::HasSubstr;

// Hang guards only: a broken daemon fails the test instead of hanging it.
inline constexpr auto kBound = absl::Seconds(60);

// Limits the daemon runs with, small so that crossing them is cheap.
inline constexpr int64_t kMaxMessageBytes = 1536 * 1024;
inline constexpr int64_t kMaxMapCells = int64_t{1} << 21;
inline constexpr int kMaxPathPoints = 1000;
inline constexpr int kMaxCostToGoCells = 10000;
// --max_table_entries and --max_trip_stops of the daemon under test.
inline constexpr int kMaxTableEntries = 100;
inline constexpr int kMaxTripStops = 16;
inline constexpr int kMaxFleetRobots = 8;
// "big" (kBigSide^2 cells) fits --max_map_cells but not one message.
inline constexpr int kBigSide = 1300;
inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
inline constexpr double kInf = std::numeric_limits<double>::infinity();
inline constexpr int32_t kIntMax = std::numeric_limits<int32_t>::max();
inline constexpr int32_t kIntMin = std::numeric_limits<int32_t>::min();

// A width x height Moving AI map, open except for the blocked cell (5, 5)
// when the map is big enough to hold it.
inline std::string MovingAiMap(int width, int height) {
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
inline std::unique_ptr<e2e::PathdProcess> StartPathd(const fs::path& log_file,
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
inline v1::PlanRequest GoodPlan() {
  v1::PlanRequest request;
  request.set_map("room");
  *request.mutable_start() = CellPos(1, 1);
  *request.mutable_goal() = CellPos(14, 14);
  return request;
}

inline v1::CreateMapRequest RawMap(const std::string& name, int32_t width,
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
inline constexpr char kUtf8Marker[] = "@@UTF8@@";
inline constexpr char kNonUtf8[] = "ab\xff\xfe\xc0\x80yz";
static_assert(sizeof(kUtf8Marker) == sizeof(kNonUtf8));

// `message` serialized with kUtf8Marker replaced by invalid UTF-8 bytes: a
// request no protobuf library would build for a `string` field.
inline grpc::ByteBuffer WithNonUtf8(const google::protobuf::Message& message) {
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
            absl::StrCat("--max_table_entries=", kMaxTableEntries),
            absl::StrCat("--max_trip_stops=", kMaxTripStops),
            absl::StrCat("--max_fleet_robots=", kMaxFleetRobots),
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
  // The status UploadMap ends with after `messages` and a half-close (or
  // after the first write the server refused).
  grpc::Status UploadMap(const std::vector<v1::UploadMapRequest>& messages) {
    auto context = Context();
    v1::CreateMapResponse response;
    auto writer = map_->UploadMap(context.get(), &response);
    bool open = true;
    for (const v1::UploadMapRequest& message : messages) {
      if (!(open = writer->Write(message))) break;
    }
    if (open) writer->WritesDone();
    return writer->Finish();
  }
  // The status DownloadMap ends with, every message read.
  grpc::Status DownloadMap(const std::string& name) {
    v1::DownloadMapRequest request;
    request.set_name(name);
    auto context = Context();
    auto reader = map_->DownloadMap(context.get(), request);
    v1::DownloadMapResponse message;
    while (reader->Read(&message)) {
    }
    return reader->Finish();
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
    open.mutable_open()->set_planner(plan.planner());
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

  // The table's rows in the order Run tries them: bad names and unparsable
  // requests on every RPC (bad_input_test.cc), MapService
  // (bad_input_map_cases.cc), PlannerService and Health
  // (bad_input_planner_cases.cc).
  void AddNameCases(std::vector<Case>& cases);
  void AddMapCases(std::vector<Case>& cases);
  void AddPlannerCases(std::vector<Case>& cases);
  void AddFleetCases(std::vector<Case>& cases);
  void AddControlCases(std::vector<Case>& cases);

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

}  // namespace pathd::bad_input_test

#endif  // PATHD_TESTS_E2E_BAD_INPUT_FIXTURE_H_
