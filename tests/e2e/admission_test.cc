// End-to-end admission control through the real pathd binary, driven over
// gRPC so the test can cancel calls, read trailing metadata and keep calls in
// flight while it signals the daemon: cancellation, deadlines (running and
// queued), a full queue's retry hint, drain on SIGTERM with a long and a short
// grace, and every per-request limit set low by its flag. Outcomes are decided
// by ordering and by the daemon's request log (--log_level=debug, written to a
// file); durations are printed, never asserted.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <future>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <grpcpp/client_context.h>
#include <grpcpp/grpcpp.h>

#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/strip.h"
#include "client/client.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "pathd/v1/map_service.grpc.pb.h"
#include "pathd/v1/planner_service.grpc.pb.h"
#include "grpc/health/v1/health.grpc.pb.h"
#include "tests/e2e/process.h"
#include "tests/testing/temp_dir.h"
#include "tests/testing/requests.h"

namespace pathd {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using ::testing::AnyOf;
using ::testing::HasSubstr;

// Hang guards only (see e2e_fixture.h): a broken daemon fails instead of
// hanging the test.
constexpr auto kBound = std::chrono::seconds(120);

std::chrono::system_clock::time_point In(std::chrono::milliseconds ms) {
  return std::chrono::system_clock::now() + ms;
}

using testing::CellPos;

v1::PlanRequest PlanRequest(const std::string& map, int sx, int sy, int gx, int gy,
                            v1::Planner planner = v1::PLANNER_ASTAR) {
  return testing::PlanBetween(map, sx, sy, gx, gy, planner);
}

// An async Plan whose answer and duration the test collects later.
struct AsyncPlan {
  grpc::ClientContext context;
  v1::PlanRequest request;
  v1::PlanResponse response;
  std::promise<grpc::Status> done;
  std::future<grpc::Status> result = done.get_future();
  std::optional<grpc::Status> status;
  Clock::time_point answered;

  // The call's status, waiting for it; may be called again.
  grpc::Status Get() {
    if (!status.has_value()) {
      if (result.wait_for(kBound) != std::future_status::ready) {
        ADD_FAILURE() << "no answer to " << request.ShortDebugString();
        context.TryCancel();
      }
      status = result.get();
    }
    return *status;
  }
  // The retry-after-ms trailer; -1 when absent or not a number.
  int64_t RetryAfterMs() const {
    const auto& trailers = context.GetServerTrailingMetadata();
    const auto it = trailers.find("retry-after-ms");
    int64_t ms = -1;
    if (it == trailers.end() ||
        !absl::SimpleAtoi(absl::string_view(it->second.data(), it->second.size()),
                          &ms)) {
      return -1;
    }
    return ms;
  }
};

class AdmissionTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_FALSE(temp_dir_.empty()) << scratch_.error();
  }
  void TearDown() override {
    // A daemon a test did not stop must still exit cleanly on SIGTERM.
    if (daemon_ != nullptr) StopDaemon(0);
  }

  // pathd with its request log (--log_level=debug) in a file the test reads.
  void StartDaemon(const std::vector<std::string>& flags) {
    std::vector<std::string> all = {"--log_level=debug"};
    all.insert(all.end(), flags.begin(), flags.end());
    daemon_ = std::make_unique<e2e::PathdProcess>(e2e::PathdProcessOptions{
        .binary = PATHD_BIN, .flags = all, .log_file = temp_dir_ / "pathd.log"});
    ASSERT_TRUE(daemon_->listening()) << daemon_->status();
    channel_ = client::MakeChannel(daemon_->address());
    client_ = std::make_unique<client::PathdClient>(channel_, absl::Seconds(60));
    planner_ = v1::PlannerService::NewStub(channel_);
  }

  // SIGTERM (unless already sent) and expect exit `code`.
  void StopDaemon(int code, bool signal = true) {
    if (signal) {
      // The server's drain waits for every connected client to acknowledge
      // its GOAWAY ping, and an idle synchronous gRPC client only reads its
      // socket on the backup poll (every 5 s): close ours first.
      planner_.reset();
      client_.reset();
      channel_.reset();
      daemon_->Signal(SIGTERM);
    }
    EXPECT_EQ(daemon_->WaitForExit(), code) << daemon_->Log();
    daemon_.reset();
  }

  // A map of open cells, created from raw cells.
  absl::Status CreateOpenMap(const std::string& name, int width, int height) {
    v1::CreateMapRequest request;
    request.set_name(name);
    v1::RawCells* raw = request.mutable_raw();
    raw->set_width(width);
    raw->set_height(height);
    raw->set_cells(std::string(static_cast<size_t>(width) * height, '\0'));
    return client_->CreateMap(request).status();
  }

  std::unique_ptr<AsyncPlan> StartPlan(const v1::PlanRequest& request,
                                       std::chrono::milliseconds timeout) {
    auto call = std::make_unique<AsyncPlan>();
    call->request = request;
    call->context.set_deadline(In(timeout));
    AsyncPlan* raw = call.get();
    planner_->async()->Plan(&raw->context, &raw->request, &raw->response,
                            [raw](grpc::Status s) {
                              raw->answered = Clock::now();
                              raw->done.set_value(std::move(s));
                            });
    return call;
  }

  // A quick plan answers OK: the daemon still serves.
  void ExpectStillServes() {
    const absl::StatusOr<v1::PlanResponse> small =
        client_->Plan(PlanRequest("small", 0, 0, 9, 9));
    ASSERT_TRUE(small.ok()) << small.status();
    EXPECT_TRUE(small->found());
  }

  // Removed with the fixture, after TearDown has stopped the daemon.
  testing::TempDir scratch_{"pathd_admission"};
  fs::path temp_dir_ = scratch_.path();
  std::unique_ptr<e2e::PathdProcess> daemon_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<client::PathdClient> client_;
  std::unique_ptr<v1::PlannerService::Stub> planner_;
};

// Dijkstra from corner to corner of an open 4096 x 4096 map settles all 16 Mi
// cells: seconds of work, so every call below is still planning when the
// test acts on it.
constexpr int kBig = 4096;

TEST_F(AdmissionTest, CancelStopsALongDijkstra) {
  ASSERT_NO_FATAL_FAILURE(StartDaemon({"--threads=1"}));
  ASSERT_TRUE(CreateOpenMap("big", kBig, kBig).ok());
  ASSERT_TRUE(CreateOpenMap("small", 10, 10).ok());
  auto call = StartPlan(
      PlanRequest("big", 0, 0, kBig - 1, kBig - 1, v1::PLANNER_DIJKSTRA),
      std::chrono::seconds(120));
  // Time to leave the queue and allocate the search; the log line below says
  // which phase the cancel found it in.
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  const Clock::time_point cancelled = Clock::now();
  call->context.TryCancel();
  EXPECT_EQ(call->Get().error_code(), grpc::StatusCode::CANCELLED);
  const std::string line =
      daemon_->WaitForLogLine({"rpc=Plan", "planner=dijkstra", "status=CANCELLED"});
  EXPECT_THAT(line, HasSubstr("outcome=CANCELLED"));
  EXPECT_THAT(line, HasSubstr("cancelled while planning"));
  // The worker is free again: the next plan needs it.
  const Clock::time_point next = Clock::now();
  ExpectStillServes();
  std::printf(
      "cancel latency: client saw CANCELLED %.2f ms after TryCancel; the next "
      "plan on the single worker answered %.2f ms after it was sent\nserver: %s\n",
      std::chrono::duration<double, std::milli>(call->answered - cancelled).count(),
      std::chrono::duration<double, std::milli>(Clock::now() - next).count(),
      line.c_str());
}

TEST_F(AdmissionTest, DeadlinesStopRunningPlansAndDropQueuedOnes) {
  ASSERT_NO_FATAL_FAILURE(StartDaemon({"--threads=1"}));
  ASSERT_TRUE(CreateOpenMap("big", kBig, kBig).ok());
  ASSERT_TRUE(CreateOpenMap("small", 10, 10).ok());
  // The running plan's deadline passes while it searches; the queued one's
  // passes while it waits behind it, so it must be answered without running.
  auto running = StartPlan(
      PlanRequest("big", 0, 0, kBig - 1, kBig - 1, v1::PLANNER_DIJKSTRA),
      std::chrono::milliseconds(1500));
  // The two calls travel independently, so give the long one time to reach
  // the single worker first (it then holds it for its whole 1.5 s deadline).
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  auto queued = StartPlan(PlanRequest("small", 0, 0, 9, 9, v1::PLANNER_DIJKSTRA),
                          std::chrono::milliseconds(300));
  EXPECT_EQ(queued->Get().error_code(), grpc::StatusCode::DEADLINE_EXCEEDED);
  EXPECT_EQ(running->Get().error_code(), grpc::StatusCode::DEADLINE_EXCEEDED);

  const std::string stopped =
      daemon_->WaitForLogLine({"rpc=Plan", "map=big", "planner=dijkstra"});
  EXPECT_THAT(stopped, HasSubstr("outcome=TIMEOUT status=DEADLINE_EXCEEDED"));
  EXPECT_THAT(stopped, HasSubstr("deadline passed after"));
  const std::string dropped = daemon_->WaitForLogLine({"rpc=Plan", "map=small"});
  EXPECT_THAT(dropped, HasSubstr("outcome=TIMEOUT status=DEADLINE_EXCEEDED"));
  EXPECT_THAT(dropped, HasSubstr("deadline passed while the request waited for a worker"));
  ExpectStillServes();
  std::printf("server: %s\nserver: %s\n", stopped.c_str(), dropped.c_str());
}

TEST_F(AdmissionTest, FullQueueAnswersResourceExhaustedWithARetryHint) {
  ASSERT_NO_FATAL_FAILURE(StartDaemon({"--threads=1", "--queue_depth=1"}));
  ASSERT_TRUE(CreateOpenMap("big", kBig, kBig).ok());
  ASSERT_TRUE(CreateOpenMap("small", 10, 10).ok());
  // One worker and one queue slot: of four slow plans sent together at most
  // two are admitted (one running, one waiting); the rest are refused at
  // once. An admitted plan may also have finished by the time it is looked at.
  std::vector<std::unique_ptr<AsyncPlan>> calls;
  for (int i = 0; i < 4; ++i) {
    calls.push_back(StartPlan(
        PlanRequest("big", 0, 0, kBig - 1, kBig - 1 - i, v1::PLANNER_DIJKSTRA),
        std::chrono::seconds(120)));
  }
  int refused = 0;
  for (auto& call : calls) {
    // A refusal comes straight from the gRPC thread; an admitted plan
    // takes seconds.
    if (call->result.wait_for(std::chrono::seconds(2)) != std::future_status::ready) {
      continue;
    }
    const grpc::Status status = call->Get();
    if (status.ok()) continue;
    ASSERT_EQ(status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED)
        << status.error_message();
    EXPECT_THAT(status.error_message(),
                HasSubstr("interactive work queue full (1 jobs waiting, the limit "
                          "set by --queue_depth); retry in about"));
    EXPECT_GT(call->RetryAfterMs(), 0);
    std::printf("refused: %s [retry-after-ms: %lld]\n", status.error_message().c_str(),
                static_cast<long long>(call->RetryAfterMs()));
    ++refused;
  }
  EXPECT_GE(refused, 2);
  for (auto& call : calls) call->context.TryCancel();
  for (auto& call : calls) call->Get();
  // A cancelled plan still holds its queue slot until the worker takes it
  // off the queue (and drops it unrun): retry as a client told "retry in
  // about N ms" would, then the daemon must serve.
  for (int attempt = 0; attempt < 100; ++attempt) {
    const absl::StatusOr<v1::PlanResponse> small =
        client_->Plan(PlanRequest("small", 0, 0, 9, 9));
    if (!absl::IsResourceExhausted(small.status())) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ExpectStillServes();
}

// Reads health Watch updates until NOT_SERVING (true) or the stream ends.
bool WatchSeesNotServing(
    grpc::ClientReaderInterface<grpc::health::v1::HealthCheckResponse>& watch) {
  grpc::health::v1::HealthCheckResponse update;
  while (watch.Read(&update)) {
    if (update.status() == grpc::health::v1::HealthCheckResponse::NOT_SERVING) {
      return true;
    }
  }
  return false;
}

TEST_F(AdmissionTest, SigtermWithALongGraceLetsTheInFlightPlanFinish) {
  ASSERT_NO_FATAL_FAILURE(StartDaemon({"--threads=1", "--shutdown_grace=120s"}));
  ASSERT_TRUE(CreateOpenMap("big", 2048, 2048).ok());
  ASSERT_TRUE(CreateOpenMap("small", 10, 10).ok());
  auto health = grpc::health::v1::Health::NewStub(channel_);
  grpc::ClientContext watch_context;
  auto watch = health->Watch(&watch_context, grpc::health::v1::HealthCheckRequest());
  grpc::health::v1::HealthCheckResponse first;
  ASSERT_TRUE(watch->Read(&first));
  EXPECT_EQ(first.status(), grpc::health::v1::HealthCheckResponse::SERVING);

  auto call = StartPlan(PlanRequest("big", 0, 0, 2047, 2047, v1::PLANNER_DIJKSTRA),
                        std::chrono::seconds(120));
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  const Clock::time_point signalled = Clock::now();
  daemon_->Signal(SIGTERM);
  // Probes see NOT_SERVING as the drain starts.
  EXPECT_TRUE(WatchSeesNotServing(*watch));
  watch_context.TryCancel();
  watch->Finish();
  // New calls are refused while the plan finishes. NOT_SERVING is set just
  // before gRPC stops accepting, so a call may still slip in right after it.
  absl::StatusOr<v1::ListMapsResponse> refused = client_->ListMaps();
  bool plan_done = false;
  while (refused.ok() && !plan_done) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    refused = client_->ListMaps();
    plan_done =
        call->result.wait_for(std::chrono::seconds(0)) == std::future_status::ready;
  }
  if (!plan_done) {
    // UNAVAILABLE once gRPC has stopped accepting; a call that reached the
    // server in the instant Shutdown began is cancelled by gRPC itself
    // (CANCELLED, seen about once in five runs). Either way it is refused.
    EXPECT_THAT(refused.status().code(),
                ::testing::AnyOf(absl::StatusCode::kUnavailable, absl::StatusCode::kCancelled))
        << refused.status();
  }
  const grpc::Status status = call->Get();
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_TRUE(call->response.found());
  StopDaemon(0, /*signal=*/false);
  std::printf("the plan answered OK %.0f ms after SIGTERM; a new call during the "
              "drain got: %s\n",
              std::chrono::duration<double, std::milli>(call->answered - signalled)
                  .count(),
              refused.status().ToString().c_str());
}

TEST_F(AdmissionTest, SigtermWithAShortGraceCancelsTheInFlightPlan) {
  ASSERT_NO_FATAL_FAILURE(StartDaemon({"--threads=1", "--shutdown_grace=200ms"}));
  ASSERT_TRUE(CreateOpenMap("big", kBig, kBig).ok());
  auto call = StartPlan(
      PlanRequest("big", 0, 0, kBig - 1, kBig - 1, v1::PLANNER_DIJKSTRA),
      std::chrono::seconds(120));
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  const Clock::time_point signalled = Clock::now();
  daemon_->Signal(SIGTERM);
  const grpc::Status status = call->Get();
  EXPECT_THAT(status.error_code(),
              AnyOf(grpc::StatusCode::CANCELLED, grpc::StatusCode::UNAVAILABLE))
      << status.error_message();
  const Clock::time_point answered = call->answered;
  // gRPC cancelled the call after the grace; the planner saw it and stopped
  // (its log line is written before the daemon exits).
  const std::string line = daemon_->WaitForLogLine({"rpc=Plan", "map=big"});
  EXPECT_THAT(line, HasSubstr("outcome=CANCELLED status=CANCELLED"));
  StopDaemon(0, /*signal=*/false);
  std::printf("grace 200ms: the plan ended %s (%s) %.0f ms after SIGTERM\nserver: %s\n",
              status.error_code() == grpc::StatusCode::CANCELLED ? "CANCELLED"
                                                                 : "UNAVAILABLE",
              status.error_message().c_str(),
              std::chrono::duration<double, std::milli>(answered - signalled).count(),
              line.c_str());
}

// Every limit set low by its flag: the code, and a message naming the limit
// and the flag.
TEST_F(AdmissionTest, EveryLimitNamesItsFlag) {
  ASSERT_NO_FATAL_FAILURE(StartDaemon(
      {"--max_map_cells=10000", "--max_expansions=50", "--max_path_points=20",
       "--max_cost_to_go_cells=6000", "--max_message_bytes=20000"}));
  ASSERT_TRUE(CreateOpenMap("small", 10, 10).ok());
  ASSERT_TRUE(CreateOpenMap("room", 100, 100).ok());

  // --max_map_cells: one row more than 10000 cells (and under the message
  // limit, so the map store is what refuses).
  absl::Status status = CreateOpenMap("wide", 101, 100);
  EXPECT_EQ(status.code(), absl::StatusCode::kResourceExhausted) << status;
  EXPECT_THAT(status.message(), HasSubstr("limit of 10000 cells (--max_map_cells)"));

  // --max_message_bytes, request side: gRPC refuses it unread; the client
  // names the flag.
  status = CreateOpenMap("huge", 150, 150);
  EXPECT_EQ(status.code(), absl::StatusCode::kResourceExhausted) << status;
  EXPECT_THAT(status.message(), HasSubstr("Received message larger than max"));
  EXPECT_THAT(status.message(), HasSubstr("--max_message_bytes"));

  // --max_expansions: a search that runs out is an outcome, not an error.
  absl::StatusOr<v1::PlanResponse> plan =
      client_->Plan(PlanRequest("room", 0, 0, 99, 99, v1::PLANNER_DIJKSTRA));
  ASSERT_TRUE(plan.ok()) << plan.status();
  EXPECT_EQ(plan->outcome(), v1::PLAN_OUTCOME_EXPANSION_LIMIT);
  EXPECT_THAT(plan->reason(), HasSubstr("expansion limit of 50"));
  EXPECT_THAT(plan->reason(), HasSubstr("(--max_expansions)"));
  v1::CostToGoRequest field;
  field.set_map("room");
  *field.mutable_goal() = CellPos(0, 0);
  field.mutable_window()->set_width(10);
  field.mutable_window()->set_height(10);
  absl::StatusOr<v1::CostToGoResponse> ctg = client_->CostToGo(field);
  EXPECT_EQ(ctg.status().code(), absl::StatusCode::kResourceExhausted) << ctg.status();
  EXPECT_THAT(ctg.status().message(),
              HasSubstr("expansion limit of 50 (--max_expansions)"));

  // --max_path_points: 21 cells on the diagonal, one more than allowed; a
  // client-held path of 21 poses is refused before it is checked.
  plan = client_->Plan(PlanRequest("small", 0, 0, 9, 9));  // 10 points: fine
  ASSERT_TRUE(plan.ok()) << plan.status();
  // A* on the open room expands about the 21 diagonal cells, under the cap
  // of 50 expansions.
  plan = client_->Plan(PlanRequest("room", 0, 0, 20, 20));
  EXPECT_EQ(plan.status().code(), absl::StatusCode::kResourceExhausted) << plan.status();
  EXPECT_THAT(plan.status().message(),
              HasSubstr("the path has 21 points, more than the limit of 20 "
                        "(--max_path_points)"));
  v1::IsPathValidRequest check;
  check.set_map("room");
  for (int i = 0; i < 21; ++i) *check.add_path() = CellPos(i, 0);
  const absl::StatusOr<v1::IsPathValidResponse> checked = client_->IsPathValid(check);
  EXPECT_EQ(checked.status().code(), absl::StatusCode::kInvalidArgument)
      << checked.status();
  EXPECT_THAT(checked.status().message(),
              HasSubstr("path has 21 poses, more than the limit of 20 "
                        "(--max_path_points)"));

  // --max_cost_to_go_cells: the whole 100 x 100 field is 10000 cells.
  v1::PlanRequest with_field = PlanRequest("room", 0, 0, 5, 5, v1::PLANNER_DISTANCE_TRANSFORM);
  with_field.mutable_options()->set_return_cost_to_go(true);
  plan = client_->Plan(with_field);
  EXPECT_EQ(plan.status().code(), absl::StatusCode::kInvalidArgument) << plan.status();
  EXPECT_THAT(plan.status().message(),
              HasSubstr("up to 6000 cells (--max_cost_to_go_cells)"));
  // Refused before any expansion: the window is checked first.
  field.mutable_window()->set_width(80);
  field.mutable_window()->set_height(80);
  ctg = client_->CostToGo(field);
  EXPECT_EQ(ctg.status().code(), absl::StatusCode::kResourceExhausted) << ctg.status();
  EXPECT_THAT(ctg.status().message(),
              HasSubstr("the window has 6400 cells; cost-to-go is returned for up "
                        "to 6000 cells per call (--max_cost_to_go_cells)"));
}

// The response side of --max_message_bytes, on its own daemon so no other
// limit interferes: a 75 x 75 cost-to-go window is ~22 KB of floats.
TEST_F(AdmissionTest, AResponseOverTheMessageLimitNamesTheFlag) {
  ASSERT_NO_FATAL_FAILURE(StartDaemon({"--max_message_bytes=20000"}));
  ASSERT_TRUE(CreateOpenMap("room", 100, 100).ok());
  v1::CostToGoRequest field;
  field.set_map("room");
  *field.mutable_goal() = CellPos(0, 0);
  field.mutable_window()->set_width(75);
  field.mutable_window()->set_height(75);
  const absl::StatusOr<v1::CostToGoResponse> ctg = client_->CostToGo(field);
  EXPECT_EQ(ctg.status().code(), absl::StatusCode::kResourceExhausted) << ctg.status();
  EXPECT_THAT(ctg.status().message(),
              HasSubstr("more than the limit of 20000 bytes (--max_message_bytes)"));
  field.mutable_window()->set_width(50);
  field.mutable_window()->set_height(50);
  EXPECT_TRUE(client_->CostToGo(field).ok());
}

}  // namespace
}  // namespace pathd
