// PlanStream: one plan, run as Plan's (server/rpc/plan_call.h), with
// progress events from its stop condition and the result as the final event.
#ifndef PATHD_SERVER_RPC_PLAN_STREAM_H_
#define PATHD_SERVER_RPC_PLAN_STREAM_H_

#include "absl/time/time.h"
#include "pathd/v1/planner_service.grpc.pb.h"
#include "server/rpc/plan_call.h"

namespace pathd::server {

// The PlanStream RPC; at most one progress event per `progress_interval`.
grpc::ServerWriteReactor<v1::PlanStreamEvent>* ServePlanStream(
    const PlanDeps& deps, absl::Duration progress_interval,
    grpc::CallbackServerContext* context, const v1::PlanRequest* request);

}  // namespace pathd::server

#endif  // PATHD_SERVER_RPC_PLAN_STREAM_H_
