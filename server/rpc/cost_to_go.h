// CostToGo: the cached shortest path map's field, or a window of it, built or
// repaired on a worker like a plan.
#ifndef PATHD_SERVER_RPC_COST_TO_GO_H_
#define PATHD_SERVER_RPC_COST_TO_GO_H_

#include "pathd/v1/planner_service.grpc.pb.h"
#include "server/rpc/plan_call.h"

namespace pathd::server {

// The CostToGo RPC (errors as documented in planner_service.proto).
grpc::ServerUnaryReactor* ServeCostToGo(const PlanDeps& deps,
                                        grpc::CallbackServerContext* context,
                                        const v1::CostToGoRequest* request,
                                        v1::CostToGoResponse* response);

}  // namespace pathd::server

#endif  // PATHD_SERVER_RPC_COST_TO_GO_H_
