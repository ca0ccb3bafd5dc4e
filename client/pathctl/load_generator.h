// A closed-loop load generator: N workers each send their next request as
// soon as the previous answer arrived (after a back-off when the server
// refused or could not be reached), for a time or a request count, while
// recording every latency. Drives pathd's Plan over a small pool of gRPC
// channels (pathctl bench), or any other call, such as the in-process planner
// the benchmark compares the server against.
#ifndef PATHD_CLIENT_PATHCTL_LOAD_GENERATOR_H_
#define PATHD_CLIENT_PATHCTL_LOAD_GENERATOR_H_

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
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
  // The server's hint on a refused call (the `retry-after-ms` trailer of a
  // RESOURCE_EXHAUSTED answer): do not send again before this much time.
  std::optional<absl::Duration> retry_after;
};

// How a worker waits after a refused or failed call, so an overloaded server
// is not hammered by instant retries and a stopped one by ~100k calls/s.
// RESOURCE_EXHAUSTED with a retry hint waits the hint (plus up to
// `hint_jitter` of it, so workers do not return in step); RESOURCE_EXHAUSTED
// without one and UNAVAILABLE wait an exponential back-off: the n-th
// consecutive failure waits d/2 + uniform(0, d/2) with d = min(max, initial *
// multiplier^(n-1)) ("equal jitter": never less than half the step, so the
// attempt count stays bounded). Any other answer resets the back-off.
struct BackoffPolicy {
  bool enabled = true;
  absl::Duration initial = absl::Milliseconds(10);
  absl::Duration max = absl::Seconds(1);
  double multiplier = 2.0;
  double hint_jitter = 0.2;
};

// The wait after `result`, the `failures`-th consecutive back-off failure
// (1 for the first), with `uniform01` a draw from [0, 1). Zero for an answer
// that needs no wait (OK, NOT_FOUND, DEADLINE_EXCEEDED, ...).
absl::Duration BackoffDelay(const BackoffPolicy& policy, const CallResult& result,
                            int failures, double uniform01);

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
  // Waits after refused and failed calls (see BackoffPolicy).
  BackoffPolicy backoff;
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
  // requests / elapsed: attempts, whatever their answer.
  double requests_per_second = 0.0;
  // ok / elapsed: the answers that did the work ("goodput"). Under overload
  // this is what the server delivers; requests_per_second also counts the
  // refusals.
  double goodput_per_second = 0.0;
  // Back-off waits in the measured phase, and their total time (summed over
  // workers).
  int64_t backoff_waits = 0;
  absl::Duration backoff_time;
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
// each; a RESOURCE_EXHAUSTED answer's `retry-after-ms` trailer becomes
// CallResult::retry_after. INVALID_ARGUMENT when `requests` is empty or channels < 1.
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
