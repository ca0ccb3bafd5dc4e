// The one place where absl::Status codes become gRPC status codes, so every
// service answers the same error the same way.
#ifndef PATHD_SERVER_GRPC_STATUS_H_
#define PATHD_SERVER_GRPC_STATUS_H_

#include <cstdint>
#include <optional>

#include <grpcpp/server_context.h>
#include <grpcpp/support/status.h>

#include "absl/status/status.h"
#include "absl/time/time.h"

namespace pathd::server {

// The gRPC code for an absl code (the numeric values agree today, but the
// mapping is spelled out so neither side's enum can drift silently).
grpc::StatusCode ToGrpcCode(absl::StatusCode code);

// Converts a status keeping its message; OK maps to grpc::Status::OK.
grpc::Status ToGrpcStatus(const absl::Status& status);

// The trailing metadata key of the retry hint on a refused call: whole
// milliseconds, as decimal text, after which the request may be sent again.
inline constexpr char kRetryAfterMsKey[] = "retry-after-ms";

// `status` carrying a retry hint of `after` (rounded up to whole ms) as a
// payload, so the layer that refuses work (the worker pool) need not know
// the call it refuses.
absl::Status WithRetryAfter(absl::Status status, absl::Duration after);

// The hint WithRetryAfter attached, in ms; nullopt when there is none.
std::optional<int64_t> RetryAfterMs(const absl::Status& status);

// Adds the hint of `status`, if any, to the call's trailing metadata under
// kRetryAfterMsKey. Must run before the call is finished.
void AddRetryAfterTrailer(const absl::Status& status,
                          grpc::ServerContextBase& context);

}  // namespace pathd::server

#endif  // PATHD_SERVER_GRPC_STATUS_H_
