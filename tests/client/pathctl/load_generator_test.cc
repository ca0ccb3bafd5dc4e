// The load generator's statistics (exact nearest-rank percentiles) and its
// closed loop: every measured query index sent exactly once, answers tallied
// by status code, warm-up kept out of the figures, bad options refused.
#include "client/pathctl/load_generator.h"

#include <atomic>
#include <thread>
#include <vector>

#include "absl/synchronization/mutex.h"
#include "absl/time/clock.h"
#include "gtest/gtest.h"

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

}  // namespace
}  // namespace pathd::client
