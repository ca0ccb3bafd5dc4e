// Request log line, slow-request warnings and the metrics hook.
#include "server/request_log.h"

#include <algorithm>
#include <string>
#include <utility>

#include "absl/base/thread_annotations.h"
#include "absl/strings/escaping.h"
#include "absl/strings/str_cat.h"
#include "absl/synchronization/mutex.h"
#include "absl/time/clock.h"
#include "spdlog/spdlog.h"

namespace pathd::server {
namespace {

// Both are read on every request and written at server start and stop, so a
// reader lock keeps the hot path uncontended.
struct RequestLogSettings {
  absl::Mutex mu;
  absl::Duration slow_threshold ABSL_GUARDED_BY(mu) = absl::ZeroDuration();
  std::shared_ptr<RequestObserver> observer ABSL_GUARDED_BY(mu);
};

// Leaked on purpose: requests may still log while static destructors run.
RequestLogSettings& Settings() {
  static auto* const settings = new RequestLogSettings();
  return *settings;
}

// The map name as a request gave it may be anything (1 MiB long, NUL bytes,
// newlines that would forge log lines): quote at most kMaxLoggedName bytes of
// it, C-escaped, when it is not plain.
std::string LoggableName(std::string_view map) {
  constexpr size_t kMaxLoggedName = 128;
  const bool plain =
      map.size() <= kMaxLoggedName &&
      std::all_of(map.begin(), map.end(), [](char c) { return c > ' ' && c < 0x7f; });
  if (plain) return std::string(map);
  std::string out = absl::CHexEscape(
      absl::string_view(map.data(), std::min(map.size(), kMaxLoggedName)));
  if (map.size() > kMaxLoggedName) absl::StrAppend(&out, "...(", map.size(), " bytes)");
  return out;
}

}  // namespace

void LogRequest(std::string_view rpc, std::string_view map, std::string_view detail,
                const absl::Status& status, absl::Time received,
                const RequestLabels& labels) {
  const absl::Duration elapsed = absl::Now() - received;
  absl::Duration slow_threshold;
  std::shared_ptr<RequestObserver> observer;
  {
    RequestLogSettings& settings = Settings();
    absl::ReaderMutexLock lock(&settings.mu);
    slow_threshold = settings.slow_threshold;
    observer = settings.observer;
  }
  const bool slow = !labels.stream && slow_threshold > absl::ZeroDuration() &&
                    elapsed >= slow_threshold;
  if (observer != nullptr) {
    observer->Observe(RequestRecord{rpc, map, labels.planner, status.code(), elapsed,
                                    labels.stream, slow});
  }

  const spdlog::level::level_enum level = slow ? spdlog::level::warn : spdlog::level::debug;
  if (!spdlog::should_log(level)) return;
  const int64_t us = absl::ToInt64Microseconds(elapsed);
  const std::string code = absl::StatusCodeToString(status.code());
  const std::string error =
      status.ok() ? std::string() : "error=\"" + std::string(status.message()) + "\"";
  spdlog::log(level, "{}rpc={} map={} {}{}status={} us={}{}{}",
              slow ? "slow request: " : "", rpc, LoggableName(map), detail, detail.empty() ? "" : " ",
              code, us, error.empty() ? "" : " ", error);
}

void LogRequest(std::string_view rpc, std::string_view map, std::string_view detail,
                const absl::Status& status, absl::Time received) {
  LogRequest(rpc, map, detail, status, received, RequestLabels{});
}

LogRateLimiter::LogRateLimiter(absl::Duration interval, size_t max_keys)
    : interval_(interval), max_keys_(std::max<size_t>(max_keys, 1)) {}

bool LogRateLimiter::ShouldLog(std::string_view key, absl::Time now,
                               int64_t* suppressed) {
  // The shared bucket for keys beyond max_keys_; cannot collide with a
  // reason, which is never empty.
  constexpr std::string_view kOverflowKey = "";
  absl::MutexLock lock(&mu_);
  auto it = buckets_.find(key);
  if (it == buckets_.end()) {
    if (buckets_.size() + 1 >= max_keys_) key = kOverflowKey;
    it = buckets_.try_emplace(std::string(key)).first;
  }
  Bucket& bucket = it->second;
  if (now - bucket.last_logged < interval_) {
    ++bucket.suppressed;
    ++suppressed_total_;
    return false;
  }
  bucket.last_logged = now;
  *suppressed = bucket.suppressed;
  bucket.suppressed = 0;
  return true;
}

int64_t LogRateLimiter::suppressed_total() const {
  absl::MutexLock lock(&mu_);
  return suppressed_total_;
}

void SetSlowRequestThreshold(absl::Duration threshold) {
  RequestLogSettings& settings = Settings();
  absl::MutexLock lock(&settings.mu);
  settings.slow_threshold = threshold;
}

void SetRequestObserver(std::shared_ptr<RequestObserver> observer) {
  RequestLogSettings& settings = Settings();
  absl::MutexLock lock(&settings.mu);
  settings.observer = std::move(observer);
}

void ClearRequestObserver(const RequestObserver* observer) {
  std::shared_ptr<RequestObserver> dropped;  // released outside the lock
  RequestLogSettings& settings = Settings();
  absl::MutexLock lock(&settings.mu);
  if (settings.observer.get() == observer) dropped = std::move(settings.observer);
}

}  // namespace pathd::server
