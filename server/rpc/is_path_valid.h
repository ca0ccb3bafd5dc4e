// IsPathValid: checks a client's path against a map version, on the gRPC
// thread (O(path)), or on a worker when a robot radius needs the map inflated.
#ifndef PATHD_SERVER_RPC_IS_PATH_VALID_H_
#define PATHD_SERVER_RPC_IS_PATH_VALID_H_

#include "pathd/v1/planner_service.grpc.pb.h"
#include "server/rpc/plan_call.h"

namespace pathd::server {

// The IsPathValid RPC (errors as documented in planner_service.proto).
grpc::ServerUnaryReactor* ServeIsPathValid(const PlanDeps& deps,
                                           grpc::CallbackServerContext* context,
                                           const v1::IsPathValidRequest* request,
                                           v1::IsPathValidResponse* response);

}  // namespace pathd::server

#endif  // PATHD_SERVER_RPC_IS_PATH_VALID_H_
