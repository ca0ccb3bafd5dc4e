// PlanBatch: many plans on one bidirectional stream, each item prepared and
// run as Plan's (server/rpc/plan_call.h), with a bound on items in flight.
#ifndef PATHD_SERVER_RPC_PLAN_BATCH_H_
#define PATHD_SERVER_RPC_PLAN_BATCH_H_

#include <cstddef>

#include "pathd/v1/planner_service.grpc.pb.h"
#include "server/rpc/plan_call.h"

namespace pathd::server {

// The PlanBatch RPC; at most `max_inflight` items read but not yet answered.
grpc::ServerBidiReactor<v1::PlanBatchRequest, v1::PlanBatchResponse>* ServePlanBatch(
    const PlanDeps& deps, size_t max_inflight, grpc::CallbackServerContext* context);

}  // namespace pathd::server

#endif  // PATHD_SERVER_RPC_PLAN_BATCH_H_
