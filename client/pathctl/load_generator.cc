// Implementation of the closed-loop load generator.
#include "client/pathctl/load_generator.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <thread>
#include <utility>

#include "absl/strings/numbers.h"
#include "absl/strings/str_format.h"
#include "absl/synchronization/notification.h"
#include "client/client.h"
#include "grpc/grpc.h"
#include "grpcpp/support/channel_arguments.h"
#include "pathd/v1/planner_service.grpc.pb.h"

namespace pathd::client {
namespace {

using Clock = std::chrono::steady_clock;

// What one worker saw in the measured phase; merged after the join, so
// workers never share a cache line while running.
struct WorkerTally {
  std::vector<absl::Duration> latencies;
  std::array<int64_t, 17> errors_by_code{};
  int64_t requests = 0;
  int64_t ok = 0;
  int64_t no_path = 0;
  int64_t backoff_waits = 0;
  absl::Duration backoff_time;
  Clock::time_point last_answer{};
};

size_t CodeIndex(absl::StatusCode code) {
  const auto index = static_cast<size_t>(code);
  // Unknown numbers are counted as UNKNOWN rather than dropped.
  return index < 17 ? index : static_cast<size_t>(absl::StatusCode::kUnknown);
}

// The retry hint trailer pathd adds to RESOURCE_EXHAUSTED (server/grpc_status.h
// kRetryAfterMsKey; the client does not include server headers).
constexpr char kRetryAfterMsKey[] = "retry-after-ms";

std::optional<absl::Duration> RetryAfterFromTrailers(
    const std::multimap<grpc::string_ref, grpc::string_ref>& trailers) {
  const auto it = trailers.find(kRetryAfterMsKey);
  if (it == trailers.end()) return std::nullopt;
  int64_t ms = 0;
  if (!absl::SimpleAtoi(absl::string_view(it->second.data(), it->second.size()), &ms) ||
      ms < 0) {
    return std::nullopt;
  }
  return absl::Milliseconds(ms);
}

}  // namespace

absl::Duration BackoffDelay(const BackoffPolicy& policy, const CallResult& result,
                            int failures, double uniform01) {
  if (!policy.enabled) return absl::ZeroDuration();
  const bool refused = result.code == absl::StatusCode::kResourceExhausted;
  if (refused && result.retry_after.has_value()) {
    return *result.retry_after * (1.0 + policy.hint_jitter * uniform01);
  }
  if (!refused && result.code != absl::StatusCode::kUnavailable) {
    return absl::ZeroDuration();
  }
  absl::Duration step = policy.initial;
  for (int i = 1; i < failures && step < policy.max; ++i) step *= policy.multiplier;
  step = std::min(step, policy.max);
  return step / 2 + step / 2 * uniform01;
}

absl::Duration NearestRankPercentile(const std::vector<absl::Duration>& sorted,
                                     double percent) {
  if (sorted.empty()) return absl::ZeroDuration();
  const double n = static_cast<double>(sorted.size());
  // Rank ceil(p/100 * n), 1-based; at least 1 so tiny percentiles pick the
  // minimum.
  auto rank = static_cast<size_t>(std::ceil(percent / 100.0 * n));
  rank = std::clamp<size_t>(rank, 1, sorted.size());
  return sorted[rank - 1];
}

LatencySummary SummarizeLatencies(std::vector<absl::Duration> samples) {
  LatencySummary summary;
  if (samples.empty()) return summary;
  std::sort(samples.begin(), samples.end());
  summary.count = static_cast<int64_t>(samples.size());
  summary.min = samples.front();
  summary.max = samples.back();
  absl::Duration total;
  for (absl::Duration d : samples) total += d;
  summary.mean = total / summary.count;
  summary.p50 = NearestRankPercentile(samples, 50);
  summary.p95 = NearestRankPercentile(samples, 95);
  summary.p99 = NearestRankPercentile(samples, 99);
  return summary;
}

absl::StatusOr<LoadReport> RunClosedLoop(
    const LoadOptions& options, const LoadCall& call,
    const std::function<void(const LoadProgress&)>& progress) {
  if (options.concurrency < 1) {
    return absl::InvalidArgumentError(
        absl::StrFormat("concurrency must be at least 1, not %d", options.concurrency));
  }
  if (options.duration < absl::ZeroDuration() || options.warmup < absl::ZeroDuration()) {
    return absl::InvalidArgumentError("duration and warmup must not be negative");
  }
  if (options.max_requests < 0) {
    return absl::InvalidArgumentError("max_requests must not be negative");
  }
  if (options.duration == absl::ZeroDuration() && options.max_requests == 0) {
    return absl::InvalidArgumentError(
        "give a duration or a request count, or the load never ends");
  }

  const Clock::time_point start = Clock::now();
  const Clock::time_point measure_start =
      start + absl::ToChronoNanoseconds(options.warmup);
  const Clock::time_point measure_end =
      options.duration > absl::ZeroDuration()
          ? measure_start + absl::ToChronoNanoseconds(options.duration)
          : Clock::time_point::max();

  // Query indices and progress counters of both phases. Only these atomics
  // are shared while running.
  std::atomic<int64_t> warmup_next{0};
  std::atomic<int64_t> measured_next{0};
  std::atomic<int64_t> warmup_answered{0};
  std::atomic<int64_t> warmup_errors{0};
  std::atomic<int64_t> measured_answered{0};
  std::atomic<int64_t> measured_errors{0};
  std::atomic<int> running{options.concurrency};
  absl::Notification finished;

  std::vector<WorkerTally> tallies(static_cast<size_t>(options.concurrency));
  std::vector<std::thread> workers;
  workers.reserve(tallies.size());
  for (int w = 0; w < options.concurrency; ++w) {
    workers.emplace_back([&, w] {
      WorkerTally& tally = tallies[static_cast<size_t>(w)];
      std::mt19937_64 rng(static_cast<uint64_t>(w) * 0x9E3779B97F4A7C15ull + 1);
      std::uniform_real_distribution<double> uniform01(0.0, 1.0);
      int failures = 0;
      // Waits after `r` as options.backoff says, never past the end of the
      // measured phase; returns the time waited.
      const auto back_off = [&](const CallResult& r) {
        const bool counts = r.code == absl::StatusCode::kUnavailable ||
                            r.code == absl::StatusCode::kResourceExhausted;
        failures = counts ? failures + 1 : 0;
        const absl::Duration delay =
            BackoffDelay(options.backoff, r, failures, uniform01(rng));
        if (delay <= absl::ZeroDuration()) return absl::ZeroDuration();
        const Clock::time_point until =
            std::min(Clock::now() + absl::ToChronoNanoseconds(delay), measure_end);
        const Clock::time_point before = Clock::now();
        if (until > before) std::this_thread::sleep_until(until);
        return absl::FromChrono(Clock::now() - before);
      };
      while (true) {
        const Clock::time_point now = Clock::now();
        if (now < measure_start) {
          const CallResult r = call(w, warmup_next.fetch_add(1));
          warmup_answered.fetch_add(1, std::memory_order_relaxed);
          if (r.code != absl::StatusCode::kOk) {
            warmup_errors.fetch_add(1, std::memory_order_relaxed);
          }
          back_off(r);
          continue;
        }
        if (now >= measure_end) break;
        const int64_t index = measured_next.fetch_add(1);
        if (options.max_requests > 0 && index >= options.max_requests) break;
        const Clock::time_point sent = Clock::now();
        const CallResult r = call(w, index);
        const Clock::time_point answered = Clock::now();
        tally.last_answer = answered;
        ++tally.requests;
        measured_answered.fetch_add(1, std::memory_order_relaxed);
        if (r.code == absl::StatusCode::kOk) {
          ++tally.ok;
          if (!r.found) ++tally.no_path;
          tally.latencies.push_back(absl::FromChrono(answered - sent));
        } else {
          ++tally.errors_by_code[CodeIndex(r.code)];
          measured_errors.fetch_add(1, std::memory_order_relaxed);
        }
        if (const absl::Duration waited = back_off(r); waited > absl::ZeroDuration()) {
          ++tally.backoff_waits;
          tally.backoff_time += waited;
        }
      }
      if (running.fetch_sub(1) == 1) finished.Notify();
    });
  }
  while (!finished.WaitForNotificationWithTimeout(absl::Seconds(1))) {
    if (!progress) continue;
    LoadProgress p;
    const Clock::time_point now = Clock::now();
    p.warming_up = now < measure_start;
    if (p.warming_up) {
      p.elapsed = absl::FromChrono(now - start);
      p.requests = warmup_answered.load(std::memory_order_relaxed);
      p.errors = warmup_errors.load(std::memory_order_relaxed);
    } else {
      p.elapsed = absl::FromChrono(now - measure_start);
      p.requests = measured_answered.load(std::memory_order_relaxed);
      p.errors = measured_errors.load(std::memory_order_relaxed);
    }
    progress(p);
  }
  for (std::thread& t : workers) t.join();

  LoadReport report;
  std::vector<absl::Duration> latencies;
  Clock::time_point last_answer = measure_start;
  for (WorkerTally& tally : tallies) {
    report.requests += tally.requests;
    report.ok += tally.ok;
    report.no_path += tally.no_path;
    report.backoff_waits += tally.backoff_waits;
    report.backoff_time += tally.backoff_time;
    for (size_t c = 0; c < tally.errors_by_code.size(); ++c) {
      report.errors_by_code[c] += tally.errors_by_code[c];
    }
    if (tally.requests > 0) last_answer = std::max(last_answer, tally.last_answer);
    latencies.insert(latencies.end(), tally.latencies.begin(), tally.latencies.end());
  }
  report.elapsed = absl::FromChrono(last_answer - measure_start);
  if (report.elapsed > absl::ZeroDuration()) {
    report.requests_per_second =
        static_cast<double>(report.requests) / absl::ToDoubleSeconds(report.elapsed);
    report.goodput_per_second =
        static_cast<double>(report.ok) / absl::ToDoubleSeconds(report.elapsed);
  }
  report.latency = SummarizeLatencies(std::move(latencies));
  report.warmup_requests = warmup_answered.load();
  return report;
}

absl::StatusOr<LoadReport> RunPlanLoad(
    const std::string& address, int channels, absl::Duration timeout,
    const std::vector<v1::PlanRequest>& requests, const LoadOptions& options,
    const std::function<void(const LoadProgress&)>& progress) {
  return RunPlanLoad(address, ClientCredentials{}, channels, timeout, requests,
                     options, progress);
}

absl::StatusOr<LoadReport> RunPlanLoad(
    const std::string& address, const ClientCredentials& credentials, int channels,
    absl::Duration timeout, const std::vector<v1::PlanRequest>& requests,
    const LoadOptions& options,
    const std::function<void(const LoadProgress&)>& progress) {
  if (requests.empty()) return absl::InvalidArgumentError("no requests to send");
  if (channels < 1) {
    return absl::InvalidArgumentError(
        absl::StrFormat("channels must be at least 1, not %d", channels));
  }
  std::vector<std::unique_ptr<v1::PlannerService::Stub>> stubs;
  for (int c = 0; c < channels; ++c) {
    grpc::ChannelArguments args;
    // Channels with equal arguments would share one connection through
    // gRPC's global subchannel pool; a local pool gives each its own.
    args.SetInt(GRPC_ARG_USE_LOCAL_SUBCHANNEL_POOL, 1);
    stubs.push_back(
        v1::PlannerService::NewStub(MakeChannel(address, credentials, args)));
  }
  // One response per worker, reused: parsing into it clears it first.
  std::vector<v1::PlanResponse> responses(
      static_cast<size_t>(std::max(options.concurrency, 1)));
  const auto count = static_cast<int64_t>(requests.size());
  return RunClosedLoop(
      options,
      [&](int worker, int64_t index) {
        const v1::PlanRequest& request = requests[static_cast<size_t>(index % count)];
        grpc::ClientContext context;
        context.set_deadline(absl::ToChronoTime(absl::Now() + timeout));
        SetMapHeader(context, request.map());
        v1::PlanResponse& response = responses[static_cast<size_t>(worker)];
        const grpc::Status status =
            stubs[static_cast<size_t>(worker % channels)]->Plan(&context, request,
                                                                 &response);
        CallResult result;
        result.code = static_cast<absl::StatusCode>(status.error_code());
        result.found = status.ok() && response.found();
        if (status.error_code() == grpc::StatusCode::RESOURCE_EXHAUSTED) {
          result.retry_after =
              RetryAfterFromTrailers(context.GetServerTrailingMetadata());
        }
        return result;
      },
      progress);
}

}  // namespace pathd::client
