// The one place where absl::Status codes become gRPC status codes, so every
// service answers the same error the same way.
#ifndef PATHD_SERVER_GRPC_STATUS_H_
#define PATHD_SERVER_GRPC_STATUS_H_

#include <grpcpp/support/status.h>

#include "absl/status/status.h"

namespace pathd::server {

// The gRPC code for an absl code (the numeric values agree today, but the
// mapping is spelled out so neither side's enum can drift silently).
grpc::StatusCode ToGrpcCode(absl::StatusCode code);

// Converts a status keeping its message; OK maps to grpc::Status::OK.
grpc::Status ToGrpcStatus(const absl::Status& status);

}  // namespace pathd::server

#endif  // PATHD_SERVER_GRPC_STATUS_H_
