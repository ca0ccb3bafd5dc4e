// Limits of the real pathd binary against read-only clients and operators'
// mistakes (issue 15): Navigate sessions and WatchMap streams bounded by the
// memory budget (RESOURCE_EXHAUSTED naming the flag, per-caller shares), the
// process's RSS (from /proc/PID/status) returning towards its baseline after
// the streams close, and a second pathd on a busy port failing to start.
// Waits are hang guards; the RSS bounds are halfway marks that a leak or a
// heap kept at its peak cannot meet and a freed one always does.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/strip.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "pathd/v1/map_service.grpc.pb.h"
#include "pathd/v1/planner_service.grpc.pb.h"
#include "tests/e2e/process.h"
#include "tests/testing/pathd_process.h"

namespace pathd {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using ::testing::HasSubstr;

constexpr auto kHangGuard = std::chrono::seconds(90);
#if defined(__SANITIZE_ADDRESS__)
constexpr bool kRssReturns = false;  // ASan quarantines freed memory
#else
constexpr bool kRssReturns = true;
#endif
constexpr int kSide = 1024;  // 1 Mi cells: a session reserves 16 MiB

std::chrono::system_clock::time_point Deadline() {
  return std::chrono::system_clock::now() + std::chrono::seconds(120);
}

// VmRSS of `pid` in bytes; 0 when unreadable.
int64_t RssBytes(pid_t pid) {
  std::istringstream status(e2e::ReadFile(absl::StrCat("/proc/", pid, "/status")));
  for (std::string line; std::getline(status, line);) {
    absl::string_view rest = line;
    if (!absl::ConsumePrefix(&rest, "VmRSS:")) continue;
    rest = absl::StripAsciiWhitespace(rest);
    absl::ConsumeSuffix(&rest, " kB");
    int64_t kb = 0;
    if (absl::SimpleAtoi(rest, &kb)) return kb * 1024;
  }
  return 0;
}

class LimitsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    char dir_template[] = "/tmp/pathd_limits_XXXXXX";
    ASSERT_NE(mkdtemp(dir_template), nullptr);
    dir_ = dir_template;
  }
  void TearDown() override {
    daemon_.reset();
    fs::remove_all(dir_);
  }

  void Start(const std::vector<std::string>& flags) {
    testing::PathdProcessOptions options;
    options.binary = PATHD_BIN;
    options.flags = {"--threads=1"};
    options.flags.insert(options.flags.end(), flags.begin(), flags.end());
    options.log_file = dir_ / "pathd.log";
    daemon_ = std::make_unique<testing::PathdProcess>(std::move(options));
    ASSERT_TRUE(daemon_->listening()) << daemon_->status();
    channel_ = grpc::CreateChannel(daemon_->address(), grpc::InsecureChannelCredentials());
    maps_ = v1::MapService::NewStub(channel_);
    planner_ = v1::PlannerService::NewStub(channel_);
  }

  void Authorize(grpc::ClientContext& context, const std::string& token) {
    context.set_deadline(Deadline());
    if (!token.empty()) context.AddMetadata("authorization", "Bearer " + token);
  }

  void CreateOpenMap(const std::string& name, const std::string& token = "") {
    v1::CreateMapRequest request;
    request.set_name(name);
    request.mutable_raw()->set_width(kSide);
    request.mutable_raw()->set_height(kSide);
    request.mutable_raw()->set_cells(std::string(size_t{kSide} * kSide, '\0'));
    v1::CreateMapResponse response;
    grpc::ClientContext context;
    Authorize(context, token);
    const grpc::Status status = maps_->CreateMap(&context, request, &response);
    ASSERT_TRUE(status.ok()) << status.error_message();
  }

  // Blocks (or frees) a band of rows: a large change every watcher queues.
  void Update(const std::string& name, int row, uint32_t cost) {
    v1::UpdateMapRequest request;
    request.set_name(name);
    v1::CellChange* change = request.add_changes();
    change->mutable_rect()->set_x_min(0);
    change->mutable_rect()->set_x_max(kSide - 1);
    change->mutable_rect()->set_y_min(row);
    change->mutable_rect()->set_y_max(row + kSide / 4 - 1);
    change->set_cost(cost);
    v1::UpdateMapResponse response;
    grpc::ClientContext context;
    Authorize(context, "");
    const grpc::Status status = maps_->UpdateMap(&context, request, &response);
    ASSERT_TRUE(status.ok()) << status.error_message();
  }

  // A Navigate stream and its open message's answer.
  struct Session {
    grpc::ClientContext context;
    std::unique_ptr<grpc::ClientReaderWriter<v1::NavigateRequest, v1::NavigateResponse>>
        stream;
    bool opened = false;
    grpc::Status refusal;
  };

  std::unique_ptr<Session> OpenSession(const std::string& map, const std::string& token = "") {
    auto session = std::make_unique<Session>();
    Authorize(session->context, token);
    session->stream = planner_->Navigate(&session->context);
    v1::NavigateRequest open;
    open.set_seq(1);
    open.mutable_open()->set_map(map);
    open.mutable_open()->mutable_start()->mutable_cell()->set_x(0);
    open.mutable_open()->mutable_start()->mutable_cell()->set_y(0);
    open.mutable_open()->mutable_goal()->mutable_cell()->set_x(kSide - 1);
    open.mutable_open()->mutable_goal()->mutable_cell()->set_y(0);
    session->stream->Write(open);
    v1::NavigateResponse response;
    session->opened = session->stream->Read(&response);
    if (!session->opened) session->refusal = session->stream->Finish();
    return session;
  }

  static void Close(Session& session) {
    if (!session.opened) return;
    session.stream->WritesDone();
    v1::NavigateResponse response;
    while (session.stream->Read(&response)) {
    }
    session.stream->Finish();
  }

  fs::path dir_;
  std::unique_ptr<testing::PathdProcess> daemon_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::MapService::Stub> maps_;
  std::unique_ptr<v1::PlannerService::Stub> planner_;
};

// Issue 15: sessions were bounded only by count (1000 sessions took 4.2 GB)
// and watchers not at all (300 unread ones took RSS to 2.8 GB), and RSS
// stayed at its peak after they closed.
TEST_F(LimitsTest, SessionsAndWatchersAreBoundedAndTheirMemoryReturns) {
  ASSERT_NO_FATAL_FAILURE(Start({"--session_memory_bytes=75497472",
                                 "--caller_memory_share=1", "--max_watchers=40",
                                 "--cache_bytes=1048576"}));
  ASSERT_NO_FATAL_FAILURE(CreateOpenMap("big"));
  const int64_t baseline = RssBytes(daemon_->pid());
  ASSERT_GT(baseline, 0);

  // Two rounds: the first also raises glibc's dynamic mmap threshold (a
  // large block freed makes later ones of its size come from the heap), as a
  // long-running daemon's would be; the second is measured.
  struct Watcher {
    grpc::ClientContext context;
    std::unique_ptr<grpc::ClientReader<v1::MapEvent>> reader;
  };
  v1::WatchMapRequest watch;
  watch.set_name("big");
  watch.set_from_version(0);  // not the current one: a RESYNC first
  int64_t peak = 0;
  for (int round = 0; round < 2; ++round) {
    SCOPED_TRACE(absl::StrCat("round ", round));
    // 72 MiB hold four sessions of 16 MiB and a little more; the fifth is
    // refused naming the flag.
    std::vector<std::unique_ptr<Session>> sessions;
    for (int i = 0; i < 4; ++i) {
      sessions.push_back(OpenSession("big"));
      ASSERT_TRUE(sessions.back()->opened) << sessions.back()->refusal.error_message();
    }
    const std::unique_ptr<Session> refused = OpenSession("big");
    EXPECT_FALSE(refused->opened);
    EXPECT_EQ(refused->refusal.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
    EXPECT_THAT(refused->refusal.error_message(), HasSubstr("--session_memory_bytes"));

    // Unread watchers, each starting with a whole-map event it never reads.
    std::vector<std::unique_ptr<Watcher>> watchers;
    for (int i = 0; i < 40; ++i) {
      auto watcher = std::make_unique<Watcher>();
      Authorize(watcher->context, "");
      watcher->reader = maps_->WatchMap(&watcher->context, watch);
      watchers.push_back(std::move(watcher));
    }
    // Updates fill the watchers' backlogs (each update is a quarter of the
    // map: four block the map band by band, four free it again).
    for (int i = 0; i < 8; ++i) {
      ASSERT_NO_FATAL_FAILURE(Update("big", (i % 4) * (kSide / 4), i < 4 ? 254 : 0));
    }
    // The 41st is refused naming --max_watchers.
    {
      grpc::ClientContext context;
      Authorize(context, "");
      auto reader = maps_->WatchMap(&context, watch);
      v1::MapEvent event;
      EXPECT_FALSE(reader->Read(&event));
      const grpc::Status status = reader->Finish();
      EXPECT_EQ(status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
      EXPECT_THAT(status.error_message(), HasSubstr("--max_watchers"));
    }
    peak = RssBytes(daemon_->pid());

    for (auto& session : sessions) Close(*session);
    for (auto& watcher : watchers) {
      watcher->context.TryCancel();
      watcher->reader->Finish();
    }
  }
  // Freed memory goes back to the system: RSS falls at least halfway from
  // the peak to the baseline (a heap kept at its peak never does).
  const int64_t halfway = baseline + (peak - baseline) / 2;
  int64_t after = RssBytes(daemon_->pid());
  const Clock::time_point guard = Clock::now() + kHangGuard;
  while (kRssReturns && after > halfway && Clock::now() < guard) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    after = RssBytes(daemon_->pid());
  }
  std::printf("pathd RSS: baseline %.1f MiB, with 4 sessions + 40 unread watchers "
              "%.1f MiB (second round), after they closed %.1f MiB\n",
              baseline / 1048576.0, peak / 1048576.0, after / 1048576.0);
  ASSERT_GT(peak - baseline, int64_t{64} << 20)
      << "the streams cost too little for the check below to mean anything";
  if (kRssReturns) {
    EXPECT_LE(after, halfway);
  } else {
    // ASan's allocator quarantines freed memory and malloc_trim does not
    // reach it: RSS cannot fall here, so only the budget is checked.
    std::printf("RSS return not checked under AddressSanitizer\n");
  }
  // And the budget is free again: a session opens.
  const std::unique_ptr<Session> again = OpenSession("big");
  EXPECT_TRUE(again->opened) << again->refusal.error_message();
  Close(*again);
}

TEST_F(LimitsTest, OneCallerCannotTakeTheWholeBudget) {
  const std::string writer = "writer-token-0123456789abcdef";
  const std::string reader = "reader-token-0123456789abcdef";
  e2e::WriteFile(dir_ / "tokens.yaml",
                 absl::StrCat("tokens:\n  - {name: a, role: write, token: ", writer,
                              "}\n  - {name: b, role: read, token: ", reader, "}\n"));
  fs::permissions(dir_ / "tokens.yaml", fs::perms::owner_read | fs::perms::owner_write);
  ASSERT_NO_FATAL_FAILURE(Start({"--session_memory_bytes=75497472",
                                 "--caller_memory_share=0.5", "--cache_bytes=1048576",
                                 absl::StrCat("--auth_tokens=", (dir_ / "tokens.yaml").string())}));
  ASSERT_NO_FATAL_FAILURE(CreateOpenMap("big", writer));
  // Half of 72 MiB: two sessions of 16 MiB and a little more for the first
  // token...
  std::vector<std::unique_ptr<Session>> sessions;
  for (int i = 0; i < 2; ++i) {
    sessions.push_back(OpenSession("big", writer));
    ASSERT_TRUE(sessions.back()->opened) << sessions.back()->refusal.error_message();
  }
  const std::unique_ptr<Session> third = OpenSession("big", writer);
  EXPECT_EQ(third->refusal.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_THAT(third->refusal.error_message(), HasSubstr("--caller_memory_share"));
  // ... and the rest still for another.
  for (int i = 0; i < 2; ++i) {
    sessions.push_back(OpenSession("big", reader));
    EXPECT_TRUE(sessions.back()->opened) << sessions.back()->refusal.error_message();
  }
  for (auto& session : sessions) Close(*session);
}

// Issue 15: with gRPC's SO_REUSEPORT a second pathd bound the same port and
// the kernel split the clients between the two.
TEST_F(LimitsTest, SecondPathdOnABusyPortExitsNamingTheAddress) {
  ASSERT_NO_FATAL_FAILURE(Start({}));
  // It either exits (right) or says it listens (wrong).
  testing::PathdProcessOptions options;
  options.binary = PATHD_BIN;
  options.address = daemon_->address();
  options.flags = {"--threads=1"};
  options.log_file = dir_ / "second.log";
  testing::PathdProcess second(std::move(options));
  ASSERT_FALSE(second.listening())
      << "a second pathd started on the busy " << daemon_->address();
  EXPECT_NE(second.WaitForExit(), 0);
  EXPECT_THAT(second.Log(), HasSubstr(daemon_->address()));
  EXPECT_THAT(second.Log(), HasSubstr("in use"));
}

}  // namespace
}  // namespace pathd
