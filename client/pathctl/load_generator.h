// A closed-loop load generator: N workers each send their next request as
// soon as the previous answer arrived, for a time or a request count, while
// recording every latency. Drives pathd's Plan over a small pool of gRPC
// channels (pathctl bench), or any other call, such as the in-process planner
// the benchmark compares the server against.
#ifndef PATHD_CLIENT_PATHCTL_LOAD_GENERATOR_H_
#define PATHD_CLIENT_PATHCTL_LOAD_GENERATOR_H_

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "client/client.h"
#include "pathd/v1/planner_service.pb.h"

namespace pathd::client {

// Latency figures of a set of samples. Percentiles are exact: nearest rank
// over every recorded sample (no histogram buckets).
struct LatencySummary {
  int64_t count = 0;
  absl::Duration min;
  absl::Duration mean;
  absl::Duration p50;
  absl::Duration p95;
  absl::Duration p99;
  absl::Duration max;
};

// The nearest-rank `percent` percentile (0 < percent <= 100) of `sorted`
// (ascending): the smallest sample with at least `percent`% of the samples at
// or below it. Zero for an empty vector.
absl::Duration NearestRankPercentile(const std::vector<absl::Duration>& sorted,
                                     double percent);

// Sorts `samples` and summarises them; all zero when empty.
LatencySummary SummarizeLatencies(std::vector<absl::Duration> samples);

// How one call ended: a status code (absl and gRPC share the numbering) and,
// for OK plan answers, whether a path was found.
struct CallResult {
  absl::StatusCode code = absl::StatusCode::kOk;
  bool found = false;
};

struct LoadOptions {
  // Workers, each with one request in flight at a time. At least 1.
  int concurrency = 1;
  // Measured phase: no worker starts a request after this much time.
  // Zero: no time bound (max_requests must then be set).
  absl::Duration duration = absl::Seconds(10);
  // Measured phase: at most this many requests; 0 = no count bound. The
  // measured requests are queries 0, 1, ..., so max_requests = queries
  // runs each query exactly once.
  int64_t max_requests = 0;
  // Requests before the measured phase that are sent but not counted
  // (connection set-up, page faults, caches). Also query indices from 0.
  absl::Duration warmup = absl::ZeroDuration();
};

// A snapshot for the live progress line.
struct LoadProgress {
  bool warming_up = false;
  // Since the measured phase began (since warm-up began while warming up).
  absl::Duration elapsed;
  // Requests answered in the current phase.
  int64_t requests = 0;
  int64_t errors = 0;
};

struct LoadReport {
  // Measured requests answered, OK or not.
  int64_t requests = 0;
  // OK answers, and those among them without a path.
  int64_t ok = 0;
  int64_t no_path = 0;
  // Non-OK answers by status code, indexed by the code's number.
  std::array<int64_t, 17> errors_by_code{};
  // From the start of the measured phase to its last answer.
  absl::Duration elapsed;
  // requests / elapsed.
  double requests_per_second = 0.0;
  // Of the OK answers only: a fast error would flatter the figures.
  LatencySummary latency;
  // Warm-up requests answered; in no other figure.
  int64_t warmup_requests = 0;

  int64_t errors() const { return requests - ok; }
};

// Runs `call(worker, query_index)` in a closed loop on options.concurrency
// threads; query indices count up from 0 in each phase (the caller maps them
// onto its queries, e.g. modulo their number). `call` must be thread-safe
// across workers; `worker` (0..concurrency-1) lets it keep per-worker state.
// `progress`, when set, is called on the calling thread about once a second
// until the workers finish. INVALID_ARGUMENT for bad options.
using LoadCall = std::function<CallResult(int worker, int64_t query_index)>;
absl::StatusOr<LoadReport> RunClosedLoop(
    const LoadOptions& options, const LoadCall& call,
    const std::function<void(const LoadProgress&)>& progress = nullptr);

// Opens `channels` connections to `address`: each channel gets its own
// subchannel pool, so they are separate TCP connections rather than one
// shared by gRPC's global pool. Worker w uses channel w % channels.
// Sends requests[query_index % requests.size()] with a deadline of `timeout`
// each. INVALID_ARGUMENT when `requests` is empty or channels < 1.
absl::StatusOr<LoadReport> RunPlanLoad(
    const std::string& address, int channels, absl::Duration timeout,
    const std::vector<v1::PlanRequest>& requests, const LoadOptions& options,
    const std::function<void(const LoadProgress&)>& progress = nullptr);
// The same over TLS and / or with a token (client/client.h MakeChannel).
absl::StatusOr<LoadReport> RunPlanLoad(
    const std::string& address, const ClientCredentials& credentials, int channels,
    absl::Duration timeout, const std::vector<v1::PlanRequest>& requests,
    const LoadOptions& options,
    const std::function<void(const LoadProgress&)>& progress = nullptr);

}  // namespace pathd::client

#endif  // PATHD_CLIENT_PATHCTL_LOAD_GENERATOR_H_
