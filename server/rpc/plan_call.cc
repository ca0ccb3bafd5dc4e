// One plan: proto -> DecodePlanQuery -> CheckPlanQuery (gRPC thread) ->
// RunPlanQuery (worker) -> BuildPlanResponse.
#include "server/rpc/plan_call.h"

#include <algorithm>
#include <optional>
#include <string>
#include <utility>

#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "core/planning/plan_query.h"
#include "core/search/registry.h"
#include "core/status_macros.h"
#include "server/request_log.h"

namespace pathd::server {
namespace {

// RESOURCE_EXHAUSTED when the plan's path (or a potential field's
// trajectory) has more points than --max_path_points allows, checked before
// the response is filled.
absl::Status CheckPathPoints(const PlanResult& result, int64_t max_points) {
  const size_t points = std::max(result.path.size(), result.trajectory.size());
  if (max_points <= 0 || points <= static_cast<size_t>(max_points)) {
    return absl::OkStatus();
  }
  return absl::ResourceExhaustedError(absl::StrFormat(
      "the path has %d points, more than the limit of %d (--max_path_points)",
      points, max_points));
}

// PLANNER_SPM and PLANNER_DSTAR_LITE: the façade's stateful search, answered
// from the IncrementalCache. The map version may be newer than the request's
// snapshot when a queued repair got there first.
class CachedSearch final : public StatefulSearch {
 public:
  CachedSearch(IncrementalCache& cache, IncrementalCache::Kind kind,
               const PlanCall& call)
      : cache_(cache), kind_(kind), call_(call) {}

  absl::Status Plan(const PlanQuery& query, const StopCondition& stop,
                    PlanAnswer* answer) override {
    const absl::Time started = absl::Now();
    const PlanRequest& request = query.request;
    const IncrementalCache::Key key{.map = call_.request->map(),
                                    .goal = request.goal,
                                    .cost = request.cost,
                                    .robot_radius_cells = query.robot_radius_cells,
                                    .inflation_radius_cells = query.inflation_radius_cells,
                                    .cost_scaling_per_cell = query.cost_scaling_per_cell,
                                    .min_clearance_cells = query.min_clearance_cells};
    const std::shared_ptr<const MapSnapshot>& snapshot = call_.decoded.snapshot;
    PlanResult& result = answer->result;
    if (kind_ == IncrementalCache::Kind::kDStarLite) {
      PATHD_ASSIGN_OR_RETURN(IncrementalCache::DStarAnswer found,
                             cache_.PlanDStarLite(key, snapshot, request.start, stop));
      result = std::move(found.result);
      answer->source = PlanSource{found.grid, found.map_version, found.cache_hit,
                                  found.repaired_cells};
    } else {
      PATHD_ASSIGN_OR_RETURN(const IncrementalCache::SpmAnswer found,
                             cache_.GetSpm(key, snapshot, stop));
      if (found.outcome != PlanOutcome::kFound) {
        // The field's build was stopped: the request ends as a search would.
        result.outcome = found.outcome;
        result.expansions = stop.max_expansions();
      } else {
        PATHD_ASSIGN_OR_RETURN(result, found.field->PathFrom(request.start));
        result.expansions += found.expansions;
        // Shared, not copied: the response builder reads it once.
        if (request.want_cost_to_go) answer->cost_to_go_field = found.field;
        answer->source = PlanSource{found.grid, found.map_version, found.cache_hit,
                                    found.repaired_cells};
      }
    }
    result.planning_time = absl::Now() - started;
    return absl::OkStatus();
  }

 private:
  IncrementalCache& cache_;
  const IncrementalCache::Kind kind_;
  const PlanCall& call_;
};

// Sees the client's cancel (or the server's, at shutdown) at every poll of
// the search. A Plan run on the gRPC thread that received it
// (WorkerPool::SubmitShort) has no reactor bound yet, so gRPC cannot tell it
// through OnCancel; the context can. Near the deadline a cancel is the
// deadline's, as CancellableReactor::OnCancel decides, and the search's own
// deadline check reports it.
class CancelWatch final : public ProgressSink {
 public:
  explicit CancelWatch(PlanCall& call) : ProgressSink(absl::ZeroDuration()), call_(call) {}

 private:
  void Report(int64_t, double, absl::Time now) override {
    if (call_.context->IsCancelled() && now + kDeadlineSlack < call_.deadline) {
      call_.cancelled.store(true, std::memory_order_relaxed);
    }
  }
  PlanCall& call_;
};

// The job's work: the façade plans, the one builder fills the response.
Verdict RunPlanAndAnswer(PlanCall& call, SearchScratch& scratch,
                         InflationCache& inflation, IncrementalCache& cache,
                         DerivedCache* derived, int64_t max_path_points,
                         int64_t max_message_bytes) {
  const PlanQuery& query = call.decoded.query;
  std::optional<CancelWatch> watch;
  ProgressSink* progress = call.progress;
  if (progress == nullptr && call.context != nullptr) progress = &watch.emplace(call);
  const StopCondition stop(call.deadline, &call.cancelled, query.max_expansions, progress);
  std::optional<CachedSearch> cached;
  if (call.cached.has_value()) cached.emplace(cache, *call.cached, call);
  const std::shared_ptr<const MapSnapshot>& shared_snapshot = call.decoded.snapshot;
  PlanEngine engine;
  engine.planner = call.planner;
  engine.stateful = cached.has_value() ? &*cached : nullptr;
  engine.inflate = [&inflation, &shared_snapshot](
                       const std::shared_ptr<const Grid>& stored,
                       const GridShape& shape) -> absl::StatusOr<std::shared_ptr<const Grid>> {
    // The cache keys on the snapshot (its map and version say what to
    // advance from); RunPlanQuery shapes the snapshot's own grid.
    if (stored != shared_snapshot->grid) {
      return absl::InternalError("the façade shaped a grid that is not the snapshot's");
    }
    return inflation.Get(*shared_snapshot, shape);
  };
  if (derived != nullptr) {
    engine.derived = [derived, &shared_snapshot](const std::shared_ptr<const Grid>& grid,
                                                 double radius) {
      return derived->For(shared_snapshot, grid, radius);
    };
  }
  const MapSnapshot& snapshot = *shared_snapshot;
  absl::StatusOr<PlanAnswer> answer =
      RunPlanQuery(query, PlanSnapshot{snapshot.grid, snapshot.version}, engine, stop,
                   scratch);
  if (!answer.ok()) return {answer.status(), "ERROR"};
  const PlanResult& result = answer->result;
  const std::string_view outcome = PlanOutcomeName(result.outcome);
  // The client is gone or past caring in these two cases, so they end the
  // call with the matching status rather than an OK that nobody reads.
  // stopped_while names a structure derived from the map that was being
  // built (or waited for) when the query stopped.
  if (result.outcome == PlanOutcome::kCancelled) {
    return {absl::CancelledError(result.stopped_while.empty()
                                     ? std::string("cancelled while planning")
                                     : "cancelled while " + result.stopped_while),
            outcome};
  }
  if (result.outcome == PlanOutcome::kTimeout) {
    return {absl::DeadlineExceededError(
                result.stopped_while.empty()
                    ? absl::StrFormat("deadline passed after %d expansions",
                                      result.expansions)
                    : result.stopped_while + " did not finish before the deadline"),
            outcome};
  }
  if (absl::Status s = CheckPathPoints(result, max_path_points); !s.ok()) {
    return {s, outcome};
  }
  BuildPlanResponse(query, *answer, call.decoded.expansion_limit_source,
                    call.decoded.path_encoding, call.response);
  if (absl::Status s =
          CheckResponseSize(*call.response, "plan response", max_message_bytes);
      !s.ok()) {
    call.response->Clear();
    return {s, outcome};
  }
  return {absl::OkStatus(), outcome};
}

}  // namespace

absl::Status PreparePlan(const PlanDeps& deps, PlanCall& call) {
  const v1::PlanRequest& request = *call.request;
  absl::StatusOr<DecodedQuery> decoded = DecodePlanQuery(
      WireQueryOf(request), deps.store,
      QueryLimits{.max_expansions = deps.limits.max_expansions,
                  .max_cost_to_go_cells = deps.limits.max_cost_to_go_cells});
  if (!decoded.ok()) {
    // Only for the log: the planner is named even when the request is not.
    if (absl::StatusOr<std::string_view> name = PlannerName(request.planner());
        name.ok()) {
      call.planner_name = *name;
    }
    return decoded.status();
  }
  call.decoded = *std::move(decoded);
  PlanQuery& query = call.decoded.query;
  call.planner_name = query.planner;
  if (request.planner() == v1::PLANNER_SPM) {
    call.cached = IncrementalCache::Kind::kSpm;
  } else if (request.planner() == v1::PLANNER_DSTAR_LITE) {
    call.cached = IncrementalCache::Kind::kDStarLite;
  } else {
    call.planner = PlannerRegistry::Default().Get(query.planner);
    if (call.planner == nullptr) {
      return absl::UnimplementedError(absl::StrFormat(
          "planner '%s' is not available on this server", query.planner));
    }
  }
  PATHD_RETURN_IF_ERROR(CheckPlanQuery(*call.decoded.snapshot->grid,
                                       call.cached.has_value(), &query));
  if (call.decoded.return_expansions) {
    call.recorder.emplace(static_cast<size_t>(deps.limits.max_returned_expansions));
    query.request.expansion_recorder = &*call.recorder;
  }
  return absl::OkStatus();
}

void FinishPlanCall(PlanCall& call, const absl::Status& status,
                    std::string_view outcome) {
  LogRequest(call.rpc, call.request->map(),
             absl::StrFormat("planner=%s outcome=%s", call.planner_name, outcome),
             status, call.received,
             // "-": rejected before the planner was known.
             RequestLabels{.planner = call.planner_name == "-" ? std::string_view()
                                                               : call.planner_name});
  if (call.on_finish) {
    call.on_finish(status);
    return;
  }
  if (const v1::PlanOutcome typed = OutcomeOfStatus(status);
      call.context != nullptr && IsRejectionOutcome(typed)) {
    call.context->AddTrailingMetadata(kPlanOutcomeMetadataKey,
                                      v1::PlanOutcome_Name(typed));
  }
  call.reactor->Finish(ToGrpcStatus(status));
}

std::unique_ptr<Job> MakePlanJob(const PlanDeps& deps, std::shared_ptr<PlanCall> call) {
  // The caches outlive every job (PlanDeps' rule); `deps` itself may not.
  auto work = [inflation = &deps.inflation, cache = &deps.cache,
               derived = deps.derived(), max_path_points = deps.limits.max_path_points,
               max_message_bytes = deps.limits.max_message_bytes](
                  PlanCall& call, SearchScratch& scratch) -> Verdict {
    return RunPlanAndAnswer(call, scratch, *inflation, *cache, derived,
                            max_path_points, max_message_bytes);
  };
  return std::make_unique<CallJob<PlanCall>>(
      std::move(call), std::move(work), &FinishPlanCall,
      JobFailureText{"out of memory while planning", "planner failed"});
}

v1::PlanError ToPlanError(const absl::Status& status) {
  v1::PlanError error;
  error.set_code(static_cast<int32_t>(ToGrpcCode(status.code())));
  error.set_message(std::string(status.message()));
  error.set_outcome(OutcomeOfStatus(status));
  return error;
}

grpc::ServerUnaryReactor* ServePlan(const PlanDeps& deps,
                                    grpc::CallbackServerContext* context,
                                    const v1::PlanRequest* request,
                                    v1::PlanResponse* response) {
  std::shared_ptr<PlanCall> call =
      StartUnaryCall<PlanCall>(context, request, response);
  const absl::Status prepared = PreparePlan(deps, *call);
  std::unique_ptr<Job> job = prepared.ok() ? MakePlanJob(deps, call) : nullptr;
  return AdmitUnaryCall(deps.pool, std::move(call), prepared, std::move(job),
                        &FinishPlanCall, JobLength::kUsuallyShort);
}

}  // namespace pathd::server
