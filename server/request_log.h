// The one log line every RPC writes when it answers, so the daemon's request
// log has a single greppable shape; it is also the one place where requests
// are counted and timed for the metrics (server/metrics.h).
#ifndef PATHD_SERVER_REQUEST_LOG_H_
#define PATHD_SERVER_REQUEST_LOG_H_

#include <memory>
#include <string_view>

#include "absl/status/status.h"
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

}  // namespace pathd::server

#endif  // PATHD_SERVER_REQUEST_LOG_H_
