// The load generator's statistics (exact nearest-rank percentiles) and its
// closed loop: every measured query index sent exactly once, answers tallied
// by status code, warm-up kept out of the figures, bad options refused, and
// its back-off: a server's retry-after-ms hint and an unreachable server
// bound the attempts (counted, never timed).
#include "client/pathctl/load_generator.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <memory>
#include <thread>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/synchronization/mutex.h"
#include "absl/time/clock.h"
#include "grpcpp/server.h"
#include "grpcpp/server_builder.h"
#include "gtest/gtest.h"
#include "pathd/v1/planner_service.grpc.pb.h"

namespace pathd::client {
namespace {

std::vector<absl::Duration> Millis(std::initializer_list<int> values) {
  std::vector<absl::Duration> out;
  for (int v : values) out.push_back(absl::Milliseconds(v));
  return out;
}

TEST(NearestRankPercentileTest, OneToHundredGivesThePercentItself) {
  std::vector<absl::Duration> sorted;
  for (int i = 1; i <= 100; ++i) sorted.push_back(absl::Milliseconds(i));
  EXPECT_EQ(NearestRankPercentile(sorted, 50), absl::Milliseconds(50));
  EXPECT_EQ(NearestRankPercentile(sorted, 95), absl::Milliseconds(95));
  EXPECT_EQ(NearestRankPercentile(sorted, 99), absl::Milliseconds(99));
  EXPECT_EQ(NearestRankPercentile(sorted, 99.5), absl::Milliseconds(100));
  EXPECT_EQ(NearestRankPercentile(sorted, 100), absl::Milliseconds(100));
}

TEST(NearestRankPercentileTest, FewSamplesRoundTheRankUp) {
  const std::vector<absl::Duration> sorted = Millis({10, 20, 30});
  // Rank ceil(p * n / 100): 1.5 -> 2, 2.97 -> 3, 0.03 -> 1.
  EXPECT_EQ(NearestRankPercentile(sorted, 50), absl::Milliseconds(20));
  EXPECT_EQ(NearestRankPercentile(sorted, 99), absl::Milliseconds(30));
  EXPECT_EQ(NearestRankPercentile(sorted, 1), absl::Milliseconds(10));
}

TEST(NearestRankPercentileTest, EmptyIsZero) {
  EXPECT_EQ(NearestRankPercentile({}, 50), absl::ZeroDuration());
}

TEST(SummarizeLatenciesTest, SortsAndSummarises) {
  // A long tail: one slow sample among 99 fast ones lands above p99 only.
  std::vector<absl::Duration> samples(99, absl::Milliseconds(1));
  samples.insert(samples.begin() + 40, absl::Milliseconds(901));
  const LatencySummary s = SummarizeLatencies(samples);
  EXPECT_EQ(s.count, 100);
  EXPECT_EQ(s.min, absl::Milliseconds(1));
  EXPECT_EQ(s.max, absl::Milliseconds(901));
  EXPECT_EQ(s.p50, absl::Milliseconds(1));
  EXPECT_EQ(s.p99, absl::Milliseconds(1));
  EXPECT_EQ(s.mean, absl::Milliseconds(10));
}

TEST(SummarizeLatenciesTest, UnsortedInput) {
  const LatencySummary s = SummarizeLatencies(Millis({7, 3, 9, 1, 5}));
  EXPECT_EQ(s.min, absl::Milliseconds(1));
  EXPECT_EQ(s.p50, absl::Milliseconds(5));
  EXPECT_EQ(s.p95, absl::Milliseconds(9));
  EXPECT_EQ(s.mean, absl::Milliseconds(5));
}

TEST(SummarizeLatenciesTest, EmptyIsAllZero) {
  const LatencySummary s = SummarizeLatencies({});
  EXPECT_EQ(s.count, 0);
  EXPECT_EQ(s.p99, absl::ZeroDuration());
  EXPECT_EQ(s.max, absl::ZeroDuration());
}

TEST(RunClosedLoopTest, SendsEveryMeasuredIndexOnceAndTalliesByCode) {
  constexpr int kRequests = 1000;
  absl::Mutex mu;
  std::vector<int> seen(kRequests, 0);
  std::atomic<int> max_worker{-1};
  LoadOptions options;
  options.concurrency = 4;
  options.duration = absl::ZeroDuration();
  options.max_requests = kRequests;
  absl::StatusOr<LoadReport> report = RunClosedLoop(options, [&](int worker, int64_t i) {
    {
      absl::MutexLock lock(&mu);
      ++seen.at(static_cast<size_t>(i));
    }
    int m = max_worker.load();
    while (worker > m && !max_worker.compare_exchange_weak(m, worker)) {
    }
    CallResult r;
    if (i % 10 == 0) {
      r.code = absl::StatusCode::kUnavailable;
    } else if (i % 10 == 1) {
      r.code = absl::StatusCode::kResourceExhausted;
    } else {
      r.found = i % 10 != 2;
    }
    return r;
  });
  ASSERT_TRUE(report.ok()) << report.status();
  for (int i = 0; i < kRequests; ++i) EXPECT_EQ(seen[i], 1) << "index " << i;
  EXPECT_LE(max_worker.load(), 3);
  EXPECT_EQ(report->requests, kRequests);
  EXPECT_EQ(report->ok, 800);
  EXPECT_EQ(report->no_path, 100);
  EXPECT_EQ(report->errors(), 200);
  EXPECT_EQ(report->errors_by_code[static_cast<size_t>(absl::StatusCode::kUnavailable)],
            100);
  EXPECT_EQ(
      report->errors_by_code[static_cast<size_t>(absl::StatusCode::kResourceExhausted)],
      100);
  // Latencies are of the OK answers only.
  EXPECT_EQ(report->latency.count, 800);
  EXPECT_GT(report->requests_per_second, 0);
}

TEST(RunClosedLoopTest, WarmUpIsSentButNotCounted) {
  std::atomic<int64_t> calls{0};
  LoadOptions options;
  options.concurrency = 2;
  options.duration = absl::ZeroDuration();
  options.max_requests = 50;
  options.warmup = absl::Milliseconds(500);
  absl::StatusOr<LoadReport> report = RunClosedLoop(options, [&](int, int64_t) {
    calls.fetch_add(1);
    absl::SleepFor(absl::Milliseconds(1));
    return CallResult{absl::StatusCode::kOk, true};
  });
  ASSERT_TRUE(report.ok()) << report.status();
  EXPECT_EQ(report->requests, 50);
  // The warm-up's calls come on top.
  EXPECT_GT(calls.load(), 50);
}

TEST(RunClosedLoopTest, StopsAtTheDuration) {
  LoadOptions options;
  options.concurrency = 3;
  options.duration = absl::Milliseconds(200);
  absl::StatusOr<LoadReport> report = RunClosedLoop(options, [](int, int64_t) {
    absl::SleepFor(absl::Milliseconds(2));
    return CallResult{absl::StatusCode::kOk, true};
  });
  ASSERT_TRUE(report.ok()) << report.status();
  EXPECT_GT(report->requests, 0);
  EXPECT_EQ(report->ok, report->requests);
}

TEST(RunClosedLoopTest, ReportsProgressWhileRunning) {
  std::vector<LoadProgress> seen;
  LoadOptions options;
  options.concurrency = 1;
  options.duration = absl::ZeroDuration();
  options.max_requests = 2;
  // Two calls of 700 ms: the run outlasts the first one-second tick however
  // the machine schedules it.
  absl::StatusOr<LoadReport> report = RunClosedLoop(
      options,
      [](int, int64_t) {
        absl::SleepFor(absl::Milliseconds(700));
        return CallResult{absl::StatusCode::kDeadlineExceeded, false};
      },
      [&](const LoadProgress& p) { seen.push_back(p); });
  ASSERT_TRUE(report.ok()) << report.status();
  ASSERT_FALSE(seen.empty());
  for (const LoadProgress& p : seen) {
    EXPECT_FALSE(p.warming_up);
    EXPECT_LE(p.requests, 2);
    EXPECT_EQ(p.errors, p.requests);
  }
  EXPECT_EQ(report->errors_by_code[static_cast<size_t>(absl::StatusCode::kDeadlineExceeded)],
            2);
  EXPECT_EQ(report->latency.count, 0);
}

TEST(RunClosedLoopTest, RefusesLoadsThatCannotRunOrNeverEnd) {
  const LoadCall call = [](int, int64_t) { return CallResult{}; };
  LoadOptions options;
  options.concurrency = 0;
  EXPECT_EQ(RunClosedLoop(options, call).status().code(),
            absl::StatusCode::kInvalidArgument);
  options.concurrency = 1;
  options.duration = absl::ZeroDuration();
  options.max_requests = 0;
  EXPECT_EQ(RunClosedLoop(options, call).status().code(),
            absl::StatusCode::kInvalidArgument);
  options.duration = -absl::Seconds(1);
  options.max_requests = 1;
  EXPECT_EQ(RunClosedLoop(options, call).status().code(),
            absl::StatusCode::kInvalidArgument);
}

TEST(RunPlanLoadTest, RefusesNoRequestsAndNoChannels) {
  LoadOptions options;
  EXPECT_EQ(RunPlanLoad("127.0.0.1:1", 1, absl::Seconds(1), {}, options).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(RunPlanLoad("127.0.0.1:1", 0, absl::Seconds(1), {v1::PlanRequest()}, options)
                .status()
                .code(),
            absl::StatusCode::kInvalidArgument);
}

TEST(BackoffDelayTest, HintIsAFloorAndFailuresDoubleUpToTheCap) {
  BackoffPolicy policy;
  CallResult refused{absl::StatusCode::kResourceExhausted, false,
                     absl::Milliseconds(200)};
  EXPECT_EQ(BackoffDelay(policy, refused, 1, 0.0), absl::Milliseconds(200));
  EXPECT_GT(BackoffDelay(policy, refused, 9, 0.999), absl::Milliseconds(239));
  EXPECT_LT(BackoffDelay(policy, refused, 9, 0.999), absl::Milliseconds(240));
  const CallResult down{absl::StatusCode::kUnavailable, false, std::nullopt};
  EXPECT_EQ(BackoffDelay(policy, down, 1, 0.0), absl::Milliseconds(5));
  EXPECT_EQ(BackoffDelay(policy, down, 2, 0.0), absl::Milliseconds(10));
  EXPECT_EQ(BackoffDelay(policy, down, 3, 1.0), absl::Milliseconds(40));
  EXPECT_EQ(BackoffDelay(policy, down, 40, 0.0), absl::Milliseconds(500));
  EXPECT_EQ(BackoffDelay(policy, down, 40, 1.0), absl::Seconds(1));
  // A refusal without a hint backs off like UNAVAILABLE.
  refused.retry_after.reset();
  EXPECT_EQ(BackoffDelay(policy, refused, 2, 0.0), absl::Milliseconds(10));
  for (absl::StatusCode code :
       {absl::StatusCode::kOk, absl::StatusCode::kNotFound,
        absl::StatusCode::kDeadlineExceeded, absl::StatusCode::kInvalidArgument}) {
    EXPECT_EQ(BackoffDelay(policy, CallResult{code, false, std::nullopt}, 5, 0.5),
              absl::ZeroDuration());
  }
  policy.enabled = false;
  EXPECT_EQ(BackoffDelay(policy, down, 5, 0.5), absl::ZeroDuration());
}

// A PlannerService whose Plan refuses every call as pathd's full queue does:
// RESOURCE_EXHAUSTED with a retry-after-ms trailer. Counts the calls.
class RefusingPlanner final : public v1::PlannerService::Service {
 public:
  explicit RefusingPlanner(int retry_after_ms) : retry_after_ms_(retry_after_ms) {}

  grpc::Status Plan(grpc::ServerContext* context, const v1::PlanRequest*,
                    v1::PlanResponse*) override {
    calls.fetch_add(1);
    context->AddTrailingMetadata("retry-after-ms", absl::StrCat(retry_after_ms_));
    return grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED, "queue full");
  }

  std::atomic<int64_t> calls{0};

 private:
  const int retry_after_ms_;
};

// pathctl bench against an overloaded server: with retry-after-ms=200 a
// worker of a 1 s run may attempt at t=0, 200, 400, 600, 800 ms, i.e. at most
// 5 times (6 allowed for rounding); a tight loop makes thousands. Sleeping
// never ends early, so a slow machine can only lower the count.
TEST(RunPlanLoadTest, HonoursTheServersRetryAfterHint) {
  RefusingPlanner planner(200);
  grpc::ServerBuilder builder;
  int port = 0;
  builder.AddListeningPort("127.0.0.1:0", grpc::InsecureServerCredentials(), &port);
  builder.RegisterService(&planner);
  std::unique_ptr<grpc::Server> server = builder.BuildAndStart();
  ASSERT_NE(server, nullptr);
  LoadOptions options;
  options.concurrency = 2;
  options.duration = absl::Seconds(1);
  v1::PlanRequest request;
  request.set_map("m");
  absl::StatusOr<LoadReport> report =
      RunPlanLoad(absl::StrCat("127.0.0.1:", port), 1, absl::Seconds(5), {request},
                  options);
  server->Shutdown();
  ASSERT_TRUE(report.ok()) << report.status();
  EXPECT_GE(report->requests, options.concurrency);
  EXPECT_LE(report->requests, 6 * options.concurrency);
  EXPECT_EQ(planner.calls.load(), report->requests);
  EXPECT_EQ(report->ok, 0);
  EXPECT_EQ(report->goodput_per_second, 0);
  EXPECT_EQ(
      report->errors_by_code[static_cast<size_t>(absl::StatusCode::kResourceExhausted)],
      report->requests);
  EXPECT_GE(report->backoff_waits, report->requests - options.concurrency);
}

// A port nobody listens on: bound, read, closed.
int ClosedPort() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t length = sizeof(address);
  if (bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)) != 0 ||
      getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length) != 0) {
    close(fd);
    return 0;
  }
  close(fd);
  return ntohs(address.sin_port);
}

// pathctl bench after the server exited: UNAVAILABLE backs off exponentially.
// The n-th wait is at least min(1 s, 10 ms * 2^(n-1)) / 2, and the first 8
// waits alone sum to 5+10+20+40+80+160+320+500 ms > 1 s, so a 1 s run makes at
// most 9 attempts per worker (12 allowed); a tight loop makes ~100k/s.
TEST(RunPlanLoadTest, BacksOffExponentiallyWhenTheServerIsUnreachable) {
  const int port = ClosedPort();
  ASSERT_NE(port, 0);
  LoadOptions options;
  options.concurrency = 2;
  options.duration = absl::Seconds(1);
  v1::PlanRequest request;
  request.set_map("m");
  absl::StatusOr<LoadReport> report = RunPlanLoad(
      absl::StrCat("127.0.0.1:", port), 1, absl::Seconds(5), {request}, options);
  ASSERT_TRUE(report.ok()) << report.status();
  EXPECT_GE(report->requests, options.concurrency);
  EXPECT_LE(report->requests, 12 * options.concurrency);
  EXPECT_EQ(report->errors_by_code[static_cast<size_t>(absl::StatusCode::kUnavailable)],
            report->requests);
}

}  // namespace
}  // namespace pathd::client
