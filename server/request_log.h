// The one debug-level log line every RPC writes when it answers, so the
// daemon's request log has a single greppable shape.
#ifndef PATHD_SERVER_REQUEST_LOG_H_
#define PATHD_SERVER_REQUEST_LOG_H_

#include <string_view>

#include "absl/status/status.h"
#include "absl/time/time.h"

namespace pathd::server {

// Logs "rpc=<rpc> map=<map> [<detail> ]status=<code> us=<elapsed>" at debug
// level (with the status message when not OK). `detail` is free-form
// "key=value" text, may be empty. Cheap when debug logging is off.
void LogRequest(std::string_view rpc, std::string_view map, std::string_view detail,
                const absl::Status& status, absl::Time received);

}  // namespace pathd::server

#endif  // PATHD_SERVER_REQUEST_LOG_H_
