// The one log line every RPC writes when it answers, so the daemon's request
// log has a single greppable shape; it is also the one place where requests
// are counted and timed for the metrics (server/metrics.h).
#ifndef PATHD_SERVER_REQUEST_LOG_H_
#define PATHD_SERVER_REQUEST_LOG_H_

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <string_view>

#include "absl/base/thread_annotations.h"
#include "absl/status/status.h"
#include "absl/synchronization/mutex.h"
#include "absl/time/time.h"

namespace pathd::server {

// What the caller of LogRequest knows beyond the line itself.
struct RequestLabels {
  // The planner that answered a single plan (Plan, one PlanStream or PlanBatch
  // item); empty when the request has none. Feeds the per-planner latency.
  std::string_view planner;
  // A long-lived stream (Navigate, WatchMap) whose duration is the client's
  // choice: never reported as slow.
  bool stream = false;
};

// Everything a RequestObserver learns about one answered request.
struct RequestRecord {
  std::string_view rpc;
  std::string_view map;
  std::string_view planner;  // empty: none
  absl::StatusCode code = absl::StatusCode::kOk;
  absl::Duration elapsed;
  bool stream = false;
  // Logged as slow (at or over the slow-request threshold).
  bool slow = false;
};

// Sees every request LogRequest logs. Called on the answering thread (gRPC or
// pool), so it must be thread-safe and cheap.
class RequestObserver {
 public:
  virtual ~RequestObserver() = default;
  virtual void Observe(const RequestRecord& record) = 0;
};

// Logs "rpc=<rpc> map=<map> [<detail> ]status=<code> us=<elapsed>" (with the
// status message when not OK): at warn level, prefixed "slow request", when a
// non-stream request took at least the slow-request threshold, else at debug
// level. `detail` is free-form "key=value" text, may be empty. Then hands the
// request to the observer, if one is set. Cheap when neither applies.
void LogRequest(std::string_view rpc, std::string_view map, std::string_view detail,
                const absl::Status& status, absl::Time received,
                const RequestLabels& labels);
// The same for a request with no planner that is not a stream.
void LogRequest(std::string_view rpc, std::string_view map, std::string_view detail,
                const absl::Status& status, absl::Time received);

// Process-wide settings of LogRequest (a daemon runs one server; see
// docs/decisions.md "Metrics and request logs"). Thread-safe.
//
// Requests taking at least `threshold` log at warn level; zero or less = off.
void SetSlowRequestThreshold(absl::Duration threshold);
// Replaces the observer (null: none). LogRequest calls in flight may still
// reach the previous one, which the shared_ptr keeps alive.
void SetRequestObserver(std::shared_ptr<RequestObserver> observer);
// Clears the observer only if it is still `observer`, so one server stopping
// does not unhook another's.
void ClearRequestObserver(const RequestObserver* observer);

// Bounds log lines that callers can cause at will (refused calls): at most one
// line per `interval` for each key (the reason), the rest counted and the
// count reported on the next line let through for that key. Distinct keys
// beyond `max_keys` share one bucket, so neither the lines nor this object's
// memory grow with what callers send. Thread-safe.
class LogRateLimiter {
 public:
  explicit LogRateLimiter(absl::Duration interval = absl::Seconds(1),
                          size_t max_keys = 64);

  // True when a line for `key` may be written at `now`; then `*suppressed`
  // is set to the lines held back for this key since the last one written
  // (0 for the first). False when the line must be dropped (it is counted).
  bool ShouldLog(std::string_view key, absl::Time now, int64_t* suppressed);

  // Lines dropped so far, over all keys.
  int64_t suppressed_total() const;

 private:
  struct Bucket {
    absl::Time last_logged = absl::InfinitePast();
    int64_t suppressed = 0;
  };

  const absl::Duration interval_;
  const size_t max_keys_;
  mutable absl::Mutex mu_;
  std::map<std::string, Bucket, std::less<>> buckets_ ABSL_GUARDED_BY(mu_);
  int64_t suppressed_total_ ABSL_GUARDED_BY(mu_) = 0;
};

}  // namespace pathd::server

#endif  // PATHD_SERVER_REQUEST_LOG_H_
