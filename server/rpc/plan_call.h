// One plan as Plan, PlanStream and every PlanBatch item run it: the call's
// state, the preparation on the gRPC thread (DecodePlanQuery, then the
// façade's CheckPlanQuery), the pool job (the façade's RunPlanQuery, then the
// one response builder) and the answer. The Plan handler itself is ServePlan.
#ifndef PATHD_SERVER_RPC_PLAN_CALL_H_
#define PATHD_SERVER_RPC_PLAN_CALL_H_

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string_view>

#include "absl/status/status.h"
#include "core/search/plan_types.h"
#include "core/search/planner.h"
#include "core/search/stop_condition.h"
#include "pathd/v1/planner_service.pb.h"
#include "server/convert.h"
#include "server/incremental_cache.h"
#include "server/inflation_cache.h"
#include "server/map_store.h"
#include "server/rpc/planner_service.h"
#include "server/rpc/unary_call.h"
#include "server/worker_pool.h"

namespace pathd::server {

// What a plan needs from the service. All references outlive the calls.
struct PlanDeps {
  const MapStore& store;
  WorkerPool& pool;
  InflationCache& inflation;
  IncrementalCache& cache;
  const PlannerServiceImpl::Options& limits;
  // limits.derived: null = planners build derived values per query.
  DerivedCache* derived() const { return limits.derived; }
};

// Everything one plan needs, shared by the reactor (for OnCancel) and the
// pool job. PlanStream and PlanBatch leave `reactor` and `context` unset and
// answer through `on_finish`.
struct PlanCall : UnaryCall<v1::PlanRequest, v1::PlanResponse> {
  // The RPC, for the request log ("Plan", "PlanStream", "PlanBatch").
  std::string_view rpc = "Plan";
  // For the log and metrics; "-" until the planner is known.
  std::string_view planner_name = "-";
  // Filled by PreparePlan().
  DecodedQuery decoded;
  // Set for registry planners; PLANNER_SPM and PLANNER_DSTAR_LITE set
  // `cached` instead and keep their state in the IncrementalCache.
  const Planner* planner = nullptr;
  std::optional<IncrementalCache::Kind> cached;
  // Set for options.return_expansions; the query's request points to it
  // (PlanCall is never moved: it lives behind a shared_ptr).
  std::optional<ExpansionRecorder> recorder;
  // PlanStream: receives the search's progress; must outlive the job.
  ProgressSink* progress = nullptr;
  // PlanStream and PlanBatch answer through this instead of `reactor`
  // (reading `response` when the status is OK). Called exactly once, as the
  // call's last use of request/response.
  std::function<void(const absl::Status&)> on_finish;
};

// Resolves everything that can fail before planning, on the gRPC thread, so
// a bad request never takes a queue slot: DecodePlanQuery, the planner,
// CheckPlanQuery on the stored map, the expansion recorder.
absl::Status PreparePlan(const PlanDeps& deps, PlanCall& call);

// The pool job of a prepared call: plans through the façade and answers.
std::unique_ptr<Job> MakePlanJob(const PlanDeps& deps, std::shared_ptr<PlanCall> call);

// Answers the call (through on_finish, or the unary reactor with the
// rejection's typed outcome as trailing metadata) and logs it. Must be the
// last use of call.request/response/reactor.
void FinishPlanCall(PlanCall& call, const absl::Status& status,
                    std::string_view outcome);

// What a failed plan reports on a stream (PlanStream's final event, a
// PlanBatch item's answer).
v1::PlanError ToPlanError(const absl::Status& status);

// The Plan RPC: prepare, submit, answer from the worker.
grpc::ServerUnaryReactor* ServePlan(const PlanDeps& deps,
                                    grpc::CallbackServerContext* context,
                                    const v1::PlanRequest* request,
                                    v1::PlanResponse* response);

}  // namespace pathd::server

#endif  // PATHD_SERVER_RPC_PLAN_CALL_H_
