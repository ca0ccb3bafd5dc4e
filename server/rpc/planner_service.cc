// PlannerService implementation: per-call shared state, the reactor that
// forwards cancellation, the pool jobs that plan (or read a cached field) and
// answer, and the cache counters.
#include "server/rpc/planner_service.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <deque>
#include <exception>
#include <functional>
#include <initializer_list>
#include <memory>
#include <new>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "absl/container/flat_hash_map.h"
#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/synchronization/mutex.h"
#include "absl/time/clock.h"
#include "core/search/registry.h"
#include "core/search/path_measure.h"
#include "core/search/endpoints.h"
#include "core/map/cost_model.h"
#include "core/postprocess/path_simplify.h"
#include "core/postprocess/plan_through.h"
#include "core/search/planner.h"
#include "core/status_macros.h"
#include "server/convert.h"
#include "server/grpc_status.h"
#include "server/request_log.h"

namespace pathd::server {
namespace {

// Everything one Plan call needs, shared by the reactor (for OnCancel) and the
// pool job. gRPC owns request/response and keeps them valid until the reactor
// is done, which cannot happen before Finish; Finish is the last thing done
// with them. The shared_ptr keeps `cancelled` alive for a planner that is
// still polling it after the reactor was deleted.
struct PlanCall {
  // Set by OnCancel on a gRPC thread, polled by the planner on a worker.
  std::atomic<bool> cancelled{false};
  grpc::ServerUnaryReactor* reactor = nullptr;
  const v1::PlanRequest* request = nullptr;
  v1::PlanResponse* response = nullptr;
  absl::Time received;
  absl::Time deadline = absl::InfiniteFuture();

  // Filled by Prepare().
  std::shared_ptr<const MapSnapshot> snapshot;
  std::string_view planner_name = "-";
  // Set for registry planners; PLANNER_SPM and PLANNER_DSTAR_LITE set
  // `cached` instead and keep their state in the IncrementalCache.
  const Planner* planner = nullptr;
  std::optional<IncrementalCache::Kind> cached;
  PlanRequest core_request;
  // The goal as the client gave it; core_request.goal differs when the goal
  // tolerance substituted a free cell for it.
  Cell requested_goal;
  // 0: a blocked goal is an error.
  double goal_tolerance_cells = 0.0;
  int64_t max_expansions = 0;
  // Which setting max_expansions came from, for the outcome's reason.
  const char* expansion_limit_source = "";
  // --max_path_points, --max_message_bytes.
  int64_t max_path_points = 0;
  int64_t max_message_bytes = 0;
  // 0: plan on the map as stored.
  double robot_radius_cells = 0.0;
  bool simplify = false;

  // The RPC, for the request log ("Plan", "PlanStream", "PlanBatch").
  std::string_view rpc = "Plan";
  // For the trailing metadata of a rejected unary call; unset when
  // `on_finish` answers.
  grpc::CallbackServerContext* context = nullptr;
  // PlanStream: receives the search's progress; must outlive the job.
  ProgressSink* progress = nullptr;
  // PlanStream and PlanBatch answer through this instead of `reactor`
  // (reading `response` when the status is OK). Called exactly once, as the
  // call's last use of request/response.
  std::function<void(const absl::Status&)> on_finish;
  // Filled by PrepareViaAndExpansions(). PlanRequest.via as cells (empty: a
  // plain plan) and allow_partial.
  std::vector<Cell> via;
  bool allow_partial = false;
  // Set for options.return_expansions; core_request.expansion_recorder points
  // to it (PlanCall is never moved: it lives behind a shared_ptr).
  std::optional<ExpansionRecorder> recorder;

  // Filled by PlanJob for via plans: ThroughResult's leg fields.
  int32_t reached_goal_index = -1;
  std::vector<int32_t> leg_end_indices;
  int32_t failed_leg = -1;
};

// How close to its deadline a cancelled call counts as timed out (see
// CancellableReactor::OnCancel).
constexpr absl::Duration kDeadlineSlack = absl::Milliseconds(10);

// The reactor of a unary call that runs on the pool: forwards cancellation to
// the call's flag. `Call` has `std::atomic<bool> cancelled` and `absl::Time
// deadline`.
template <typename Call>
class CancellableReactor final : public grpc::ServerUnaryReactor {
 public:
  explicit CancellableReactor(std::shared_ptr<Call> call) : call_(std::move(call)) {}

  // The planner polls the flag every StopCondition::kPollInterval expansions;
  // a queued job sees it before it starts.
  void OnCancel() override {
    // A client whose own deadline fires cancels the call a moment before the
    // server's copy of that deadline (it travels as a relative timeout), so a
    // cancel this close to the deadline is the deadline: the planner's own
    // check stops it within kDeadlineSlack and it is reported as a TIMEOUT.
    if (absl::Now() + kDeadlineSlack >= call_->deadline) return;
    call_->cancelled.store(true, std::memory_order_relaxed);
  }
  void OnDone() override { delete this; }

 private:
  std::shared_ptr<Call> call_;
};

// Why a job that waited in the queue should not start: DEADLINE_EXCEEDED or
// CANCELLED, OK when it should. The deadline is checked first because gRPC
// also cancels a call whose deadline passed, and the log should say why.
absl::Status StillWanted(const std::atomic<bool>& cancelled, absl::Time deadline) {
  if (absl::Now() >= deadline) {
    return absl::DeadlineExceededError(
        "deadline passed while the request waited for a worker");
  }
  if (cancelled.load(std::memory_order_relaxed)) {
    return absl::CancelledError("cancelled before planning started");
  }
  return absl::OkStatus();
}

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

// RESOURCE_EXHAUSTED when `response` would not fit in one gRPC message
// (max_bytes 0: unchecked). Checked here because gRPC's own refusal, "Sent
// message larger than max", names neither the response nor the flag.
absl::Status CheckResponseSize(const google::protobuf::Message& response,
                               std::string_view what, int64_t max_bytes) {
  const size_t bytes = response.ByteSizeLong();
  if (max_bytes <= 0 || bytes <= static_cast<size_t>(max_bytes)) {
    return absl::OkStatus();
  }
  return absl::ResourceExhaustedError(absl::StrFormat(
      "the %s would be %d bytes, more than the limit of %d bytes "
      "(--max_message_bytes)",
      what, bytes, max_bytes));
}

// Names where an expansion cap came from, for the messages that report it.
const char* ExpansionLimitSource(const v1::PlanOptions& options,
                                 int64_t server_limit) {
  const bool server_binds =
      server_limit > 0 &&
      (options.max_expansions() == 0 || options.max_expansions() >= server_limit);
  return server_binds ? "--max_expansions" : "options.max_expansions";
}

// INVALID_ARGUMENT when one of `endpoints` became inscribed by the robot
// radius (it is traversable on the stored map, so the request was accepted).
absl::Status CheckRadiusEndpoints(
    const Grid& stored, const Grid& inflated, double radius_cells,
    std::initializer_list<std::pair<Cell, const char*>> endpoints) {
  for (const auto& [cell, what] : endpoints) {
    if (inflated.InBounds(cell) && inflated.cost(cell) == kInscribedCost &&
        stored.cost(cell) != kInscribedCost) {
      absl::Status inscribed = absl::InvalidArgumentError(absl::StrFormat(
          "%s %s is within the robot radius (%g cells) of an obstacle", what,
          CellToString(cell), radius_cells));
      if (const auto fault = EndpointFaultFor(what, /*outside=*/false)) {
        return WithEndpointFault(std::move(inscribed), *fault);
      }
      return inscribed;
    }
  }
  return absl::OkStatus();
}

// The goal to plan to: `requested` when the tolerance is 0, the cell is off
// the grid (ValidateEndpoints reports it) or the robot centre may occupy it;
// otherwise the nearest cell within the tolerance that it may occupy
// (NearestTraversableCell), or INVALID_ARGUMENT naming the tolerance when
// there is none. `grid` is inflated when radius_cells > 0.
absl::StatusOr<Cell> GoalWithinTolerance(const Grid& grid, Cell requested,
                                         double tolerance_cells,
                                         const CostParams& cost,
                                         double radius_cells) {
  if (tolerance_cells <= 0.0 || !grid.InBounds(requested) ||
      Traversable(grid.cost(requested), cost.unknown_is_free)) {
    return requested;
  }
  if (std::optional<Cell> nearest =
          NearestTraversableCell(grid, requested, tolerance_cells, cost)) {
    return *nearest;
  }
  return WithEndpointFault(
      absl::InvalidArgumentError(absl::StrFormat(
          "goal %s is on a blocked cell (cost %d) and no cell within the goal "
          "tolerance of %g cells is free%s",
          CellToString(requested), grid.cost(requested), tolerance_cells,
          radius_cells > 0.0
              ? absl::StrFormat(" for the robot radius (%g cells)", radius_cells)
              : std::string())),
      EndpointFault::kGoalBlocked);
}

// A cache key from validated request parts.
IncrementalCache::Key CacheKey(const std::string& map, Cell goal, const CostParams& cost,
                               double robot_radius_cells) {
  IncrementalCache::Key key;
  key.map = map;
  key.goal = goal;
  key.cost = cost;
  key.robot_radius_cells = robot_radius_cells;
  return key;
}

// Answers the call. Must be the last use of call.request/response/reactor.
void FinishCall(PlanCall& call, const absl::Status& status, std::string_view outcome) {
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

absl::Time DeadlineOf(const grpc::CallbackServerContext& context) {
  const auto deadline = context.deadline();
  // gRPC reports "no deadline" as time_point::max(), which absl::FromChrono
  // would have to saturate; say what it means instead.
  if (deadline == std::chrono::system_clock::time_point::max()) {
    return absl::InfiniteFuture();
  }
  return absl::FromChrono(deadline);
}

// The map, endpoints, options and planner of a request: the part of
// Prepare() every plan has.
absl::Status PrepareEndpointsAndPlanner(const MapStore& store,
                                        const PlannerServiceImpl::Options& limits,
                                        PlanCall& call) {
  const v1::PlanRequest& request = *call.request;
  PATHD_ASSIGN_OR_RETURN(call.planner_name, PlannerName(request.planner()));
  PATHD_ASSIGN_OR_RETURN(call.snapshot, store.Get(request.map()));
  const Grid& grid = *call.snapshot->grid;
  PATHD_ASSIGN_OR_RETURN(call.core_request.start,
                         CellFromPosition(request.start(), grid, "start"));
  PATHD_ASSIGN_OR_RETURN(call.core_request.goal,
                         CellFromPosition(request.goal(), grid, "goal"));
  PATHD_RETURN_IF_ERROR(PlanOptionsToRequest(request.options(), &call.core_request));
  PATHD_ASSIGN_OR_RETURN(call.robot_radius_cells,
                         RobotRadiusCells(request.options(), grid));
  call.simplify = request.options().simplify();
  // A whole field is 8 bytes per cell in a Plan message.
  if (call.core_request.want_cost_to_go &&
      grid.size() > static_cast<size_t>(limits.max_cost_to_go_cells)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "options.return_cost_to_go: the map has %d cells; whole cost-to-go "
        "fields are returned for maps of up to %d cells (--max_cost_to_go_cells)",
        grid.size(), limits.max_cost_to_go_cells));
  }
  PATHD_ASSIGN_OR_RETURN(call.max_expansions,
                         EffectiveMaxExpansions(request.options(),
                                                limits.max_expansions));
  call.expansion_limit_source =
      ExpansionLimitSource(request.options(), limits.max_expansions);
  call.max_path_points = limits.max_path_points;
  call.max_message_bytes = limits.max_message_bytes;
  // Substituted here, before anything keys on the goal, so every planner
  // (and the SPM / D* Lite cache entries) sees the cell actually planned to.
  // With a robot radius the worker substitutes again on the inflated map; the
  // stored map's answer still rejects early when nothing near is free at all.
  call.requested_goal = call.core_request.goal;
  PATHD_ASSIGN_OR_RETURN(call.goal_tolerance_cells,
                         GoalToleranceCells(request.options(), grid));
  PATHD_ASSIGN_OR_RETURN(
      call.core_request.goal,
      GoalWithinTolerance(grid, call.requested_goal, call.goal_tolerance_cells,
                          call.core_request.cost, 0.0));
  PATHD_RETURN_IF_ERROR(ValidateEndpoints(grid, call.core_request));
  if (request.planner() == v1::PLANNER_SPM) {
    call.cached = IncrementalCache::Kind::kSpm;
    return absl::OkStatus();
  }
  if (request.planner() == v1::PLANNER_DSTAR_LITE) {
    call.cached = IncrementalCache::Kind::kDStarLite;
    return absl::OkStatus();
  }
  call.planner = PlannerRegistry::Default().Get(call.planner_name);
  if (call.planner == nullptr) {
    return absl::UnimplementedError(absl::StrFormat(
        "planner '%s' is not available on this server", call.planner_name));
  }
  return absl::OkStatus();
}

// The via points and the expansion recorder, after Prepare() succeeded: on
// the gRPC thread too, so a bad via point never takes a queue slot.
absl::Status PrepareViaAndExpansions(int64_t max_returned_expansions,
                                     PlanCall& call) {
  const v1::PlanRequest& request = *call.request;
  if (request.options().return_expansions()) {
    call.recorder.emplace(static_cast<size_t>(max_returned_expansions));
    call.core_request.expansion_recorder = &*call.recorder;
  }
  call.allow_partial = request.allow_partial();
  if (request.via().empty()) return absl::OkStatus();
  if (call.cached.has_value()) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "via: planner %s keeps cached state for one goal and may answer on a "
        "newer map version, so it cannot plan through via points; use a "
        "planner such as astar or dijkstra",
        call.planner_name));
  }
  if (call.core_request.want_cost_to_go) {
    return absl::InvalidArgumentError(
        "options.return_cost_to_go: a cost-to-go field belongs to one goal, "
        "and a plan through via points has several");
  }
  // Counted before anything is sized by the request (ValidateVia repeats
  // the check for core's other callers).
  PATHD_RETURN_IF_ERROR(CheckViaCount(static_cast<size_t>(request.via_size())));
  const Grid& grid = *call.snapshot->grid;
  call.via.reserve(request.via_size());
  for (int i = 0; i < request.via_size(); ++i) {
    PATHD_ASSIGN_OR_RETURN(
        const Cell cell,
        CellFromPosition(request.via(i), grid, absl::StrFormat("via[%d]", i)));
    call.via.push_back(cell);
  }
  return ValidateVia(grid, call.via, call.core_request.cost);
}

// Resolves everything that can fail before planning, on the gRPC thread, so
// a bad request never takes a queue slot (Plan, PlanStream and every
// PlanBatch item).
absl::Status Prepare(const MapStore& store,
                     const PlannerServiceImpl::Options& limits, PlanCall& call) {
  PATHD_RETURN_IF_ERROR(PrepareEndpointsAndPlanner(store, limits, call));
  return PrepareViaAndExpansions(limits.max_returned_expansions, call);
}

// Fills the leg fields and the expanded cells of a response that
// FillPlanResponse filled; for a failed via plan, says which leg failed.
void FillLegsAndExpansions(const PlanCall& call, const PlanResult& result,
                           v1::PlanResponse* response) {
  if (call.via.empty()) {
    // A plain plan is a plan with one leg.
    response->set_reached_goal_index(result.found() ? 0 : -1);
    if (result.found()) {
      response->add_leg_end_indices(static_cast<int32_t>(result.path.size()) - 1);
    }
  } else {
    response->set_reached_goal_index(call.reached_goal_index);
    response->mutable_leg_end_indices()->Add(call.leg_end_indices.begin(),
                                             call.leg_end_indices.end());
  }
  if (call.failed_leg >= 0) {
    const auto n = static_cast<int32_t>(call.via.size());
    const Cell to = call.failed_leg == n ? call.core_request.goal
                                         : call.via[call.failed_leg];
    const Cell from = call.failed_leg == 0 ? call.core_request.start
                                           : call.via[call.failed_leg - 1];
    // FillPlanResponse's "no path" names the whole plan's ends.
    const std::string why =
        result.outcome == PlanOutcome::kNoPath
            ? absl::StrFormat("no path from %s to %s", CellToString(from),
                              CellToString(to))
            : response->reason();
    response->set_reason(
        absl::StrFormat("%s: %s", LegName(call.failed_leg, n), why));
  }
  if (call.recorder.has_value()) {
    auto* expanded = response->mutable_expanded();
    expanded->Reserve(static_cast<int>(call.recorder->cells().size()));
    for (const Cell& c : call.recorder->cells()) *expanded->Add() = ToProto(c);
    response->set_expanded_truncated(call.recorder->truncated());
  }
}

// Where a plan came from, for the response.
struct PlanSource {
  // The grid the path was planned on (inflated for a robot radius), for the
  // simplification and the response's world points.
  std::shared_ptr<const Grid> grid;
  uint64_t map_version = 0;
  bool cache_hit = false;
  int64_t repaired_cells = 0;
};

class PlanJob final : public Job {
 public:
  PlanJob(std::shared_ptr<PlanCall> call, InflationCache& inflation,
          IncrementalCache& cache)
      : call_(std::move(call)), inflation_(inflation), cache_(cache) {}

  void Run(SearchScratch& scratch) override {
    PlanCall& call = *call_;
    if (absl::Status s = StillWanted(call.cancelled, call.deadline); !s.ok()) {
      FinishCall(call, s, absl::IsCancelled(s) ? "CANCELLED" : "TIMEOUT");
      return;
    }
    const StopCondition stop(call.deadline, &call.cancelled, call.max_expansions,
                             call.progress);
    absl::StatusOr<PlanResult> result;
    PlanSource source{call.snapshot->grid, call.snapshot->version};
    try {
      result = PlanOn(call, scratch, stop, source);
    } catch (const std::bad_alloc&) {
      result = absl::ResourceExhaustedError("out of memory while planning");
    } catch (const std::exception& e) {
      result = absl::InternalError(absl::StrFormat("planner failed: %s", e.what()));
    }
    if (!result.ok()) {
      FinishCall(call, result.status(), "ERROR");
      return;
    }
    const std::string_view outcome = PlanOutcomeName(result->outcome);
    // The client is gone or past caring in these two cases, so they end the
    // call with the matching status rather than an OK that nobody reads.
    if (result->outcome == PlanOutcome::kCancelled) {
      FinishCall(call, absl::CancelledError("cancelled while planning"), outcome);
      return;
    }
    if (result->outcome == PlanOutcome::kTimeout) {
      FinishCall(call,
                 absl::DeadlineExceededError(absl::StrFormat(
                     "deadline passed after %d expansions", result->expansions)),
                 outcome);
      return;
    }
    if (absl::Status s = CheckPathPoints(*result, call.max_path_points); !s.ok()) {
      FinishCall(call, s, outcome);
      return;
    }
    v1::PlanResponse* response = call.response;
    FillPlanResponse(*result, call.core_request, *source.grid, call.max_expansions,
                     response);
    if (result->outcome == PlanOutcome::kExpansionLimit) {
      response->set_reason(absl::StrCat(response->reason(), " (",
                                        call.expansion_limit_source, ")"));
    }
    response->set_robot_radius_cells(call.robot_radius_cells);
    response->set_map_version(source.map_version);
    response->set_planner(std::string(call.planner_name));
    response->set_cache_hit(source.cache_hit);
    response->set_repaired_cells(source.repaired_cells);
    *response->mutable_requested_goal() = ToProto(call.requested_goal);
    response->set_goal_substituted(
        !(call.core_request.goal == call.requested_goal));
    FillLegsAndExpansions(call, *result, response);
    if (absl::Status s =
            CheckResponseSize(*response, "plan response", call.max_message_bytes);
        !s.ok()) {
      response->Clear();
      FinishCall(call, s, outcome);
      return;
    }
    FinishCall(call, absl::OkStatus(), outcome);
  }

  // Inflates (cached), plans and simplifies. `source` starts as the request's
  // snapshot and is set to what the plan actually used. With a robot radius
  // and a goal tolerance, call.core_request.goal is re-chosen on the inflated
  // map, where an inscribed goal is blocked too.
  absl::StatusOr<PlanResult> PlanOn(PlanCall& call, SearchScratch& scratch,
                                    const StopCondition& stop,
                                    PlanSource& source) {
    if (call.robot_radius_cells > 0.0) {
      PATHD_ASSIGN_OR_RETURN(source.grid,
                             inflation_.Get(source.grid, call.robot_radius_cells));
      PATHD_ASSIGN_OR_RETURN(
          call.core_request.goal,
          GoalWithinTolerance(*source.grid, call.requested_goal,
                              call.goal_tolerance_cells, call.core_request.cost,
                              call.robot_radius_cells));
      PATHD_RETURN_IF_ERROR(CheckRadiusEndpoints(
          *call.snapshot->grid, *source.grid, call.robot_radius_cells,
          {{call.core_request.start, "start"}, {call.core_request.goal, "goal"}}));
      for (size_t i = 0; i < call.via.size(); ++i) {
        const std::string what = absl::StrFormat("via[%d]", i);
        PATHD_RETURN_IF_ERROR(CheckRadiusEndpoints(
            *call.snapshot->grid, *source.grid, call.robot_radius_cells,
            {{call.via[i], what.c_str()}}));
      }
    }
    if (!call.via.empty()) {
      // One grid for every leg: the snapshot (or its inflation) taken once.
      PATHD_ASSIGN_OR_RETURN(
          ThroughResult through,
          PlanThrough(*call.planner, *source.grid, call.core_request, call.via,
                      stop, scratch,
                      ThroughOptions{.allow_partial = call.allow_partial,
                                     .simplify = call.simplify}));
      call.reached_goal_index = through.reached_goal_index;
      call.leg_end_indices = std::move(through.leg_end_indices);
      call.failed_leg = through.failed_leg;
      return std::move(through.plan);
    }
    PlanResult result;
    if (call.cached.has_value()) {
      PATHD_ASSIGN_OR_RETURN(result, PlanCached(call, stop, source));
    } else {
      PATHD_ASSIGN_OR_RETURN(
          result, call.planner->Plan(*source.grid, call.core_request, stop, scratch));
    }
    if (call.simplify && result.found()) {
      SimplifyPath(*source.grid, call.core_request.cost, &result);
    }
    return result;
  }

  // D* Lite or shortest path map from the cache. The map version may be newer
  // than the request's snapshot when a queued repair got there first.
  absl::StatusOr<PlanResult> PlanCached(const PlanCall& call, const StopCondition& stop,
                                        PlanSource& source) {
    const absl::Time started = absl::Now();
    const PlanRequest& request = call.core_request;
    const IncrementalCache::Key key = CacheKey(call.request->map(), request.goal,
                                               request.cost, call.robot_radius_cells);
    PlanResult result;
    if (*call.cached == IncrementalCache::Kind::kDStarLite) {
      PATHD_ASSIGN_OR_RETURN(IncrementalCache::DStarAnswer answer,
                             cache_.PlanDStarLite(key, call.snapshot, request.start, stop));
      result = std::move(answer.result);
      source = PlanSource{answer.grid, answer.map_version, answer.cache_hit,
                          answer.repaired_cells};
    } else {
      PATHD_ASSIGN_OR_RETURN(const IncrementalCache::SpmAnswer answer,
                             cache_.GetSpm(key, call.snapshot, stop));
      if (answer.outcome != PlanOutcome::kFound) {
        // The field's build was stopped: the request ends as a search would.
        result.outcome = answer.outcome;
        result.expansions = stop.max_expansions();
      } else {
        PATHD_ASSIGN_OR_RETURN(result, answer.field->PathFrom(request.start));
        result.expansions += answer.expansions;
        if (request.want_cost_to_go) {
          const absl::Span<const float> field = answer.field->field();
          result.cost_to_go.assign(field.begin(), field.end());
        }
        source = PlanSource{answer.grid, answer.map_version, answer.cache_hit,
                            answer.repaired_cells};
      }
    }
    result.planning_time = absl::Now() - started;
    return result;
  }

  void Drop() override {
    FinishCall(*call_, absl::UnavailableError("server is shutting down"),
               "DROPPED");
  }
  // Run threw (WorkerPool answers every failed job through Fail).
  void Fail(const absl::Status& status) override { FinishCall(*call_, status, "ERROR"); }

 private:
  std::shared_ptr<PlanCall> call_;
  InflationCache& inflation_;
  IncrementalCache& cache_;
};

// Everything one CostToGo call needs; shared like PlanCall.
struct CostToGoCall {
  std::atomic<bool> cancelled{false};
  grpc::ServerUnaryReactor* reactor = nullptr;
  const v1::CostToGoRequest* request = nullptr;
  v1::CostToGoResponse* response = nullptr;
  absl::Time received;
  absl::Time deadline = absl::InfiniteFuture();

  // Filled by PrepareCostToGo().
  std::shared_ptr<const MapSnapshot> snapshot;
  IncrementalCache::Key key;
  // The window's corner and size, inside the map.
  int32_t x = 0;
  int32_t y = 0;
  int32_t width = 0;
  int32_t height = 0;
  int64_t max_expansions = 0;
  // Which setting max_expansions came from, for the error.
  const char* expansion_limit_source = "";
  // --max_message_bytes.
  int64_t max_message_bytes = 0;
};

void FinishCostToGo(CostToGoCall& call, const absl::Status& status,
                    std::string_view outcome) {
  LogRequest("CostToGo", call.request->map(), absl::StrFormat("outcome=%s", outcome),
             status, call.received);
  call.reactor->Finish(ToGrpcStatus(status));
}

absl::Status PrepareCostToGo(const MapStore& store,
                             const PlannerServiceImpl::Options& limits,
                             CostToGoCall& call) {
  const v1::CostToGoRequest& request = *call.request;
  PATHD_ASSIGN_OR_RETURN(call.snapshot, store.Get(request.map()));
  const Grid& grid = *call.snapshot->grid;
  PATHD_ASSIGN_OR_RETURN(const Cell goal, CellFromPosition(request.goal(), grid, "goal"));
  PATHD_ASSIGN_OR_RETURN(const CostParams cost, CostParamsFromOptions(request.options()));
  PATHD_ASSIGN_OR_RETURN(const double radius, RobotRadiusCells(request.options(), grid));
  PATHD_ASSIGN_OR_RETURN(call.max_expansions,
                         EffectiveMaxExpansions(request.options(), limits.max_expansions));
  call.expansion_limit_source =
      ExpansionLimitSource(request.options(), limits.max_expansions);
  call.max_message_bytes = limits.max_message_bytes;
  if (!grid.InBounds(goal)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "goal %s is outside the %d x %d map", CellToString(goal), grid.width(),
        grid.height()));
  }
  if (!Traversable(grid.cost(goal), cost.unknown_is_free)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "goal %s is on a blocked cell (cost %d)", CellToString(goal), grid.cost(goal)));
  }
  call.key = CacheKey(request.map(), goal, cost, radius);

  call.x = 0;
  call.y = 0;
  call.width = grid.width();
  call.height = grid.height();
  if (request.has_window()) {
    const v1::CellWindow& w = request.window();
    // int64: x + width must not overflow on hostile values.
    const auto check = [](int64_t lo, int64_t size, int64_t limit, const char* lo_name,
                          const char* size_name) -> absl::Status {
      if (size <= 0) {
        return absl::InvalidArgumentError(
            absl::StrFormat("window.%s %d must be > 0", size_name, size));
      }
      if (lo < 0 || lo + size > limit) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "window.%s %d + window.%s %d reaches outside the map's 0..%d", lo_name, lo,
            size_name, size, limit));
      }
      return absl::OkStatus();
    };
    PATHD_RETURN_IF_ERROR(check(w.x(), w.width(), grid.width(), "x", "width"));
    PATHD_RETURN_IF_ERROR(check(w.y(), w.height(), grid.height(), "y", "height"));
    call.x = w.x();
    call.y = w.y();
    call.width = w.width();
    call.height = w.height();
  }
  // 4 bytes per cell in a CostToGo message.
  const int64_t cells = int64_t{call.width} * call.height;
  if (cells > limits.max_cost_to_go_cells) {
    return absl::ResourceExhaustedError(absl::StrFormat(
        "%s has %d cells; cost-to-go is returned for up to %d cells per call "
        "(--max_cost_to_go_cells): ask for windows",
        request.has_window() ? "the window" : "the map", cells,
        limits.max_cost_to_go_cells));
  }
  return absl::OkStatus();
}

class CostToGoJob final : public Job {
 public:
  CostToGoJob(std::shared_ptr<CostToGoCall> call, InflationCache& inflation,
              IncrementalCache& cache)
      : call_(std::move(call)), inflation_(inflation), cache_(cache) {}

  void Run(SearchScratch&) override {
    CostToGoCall& call = *call_;
    if (absl::Status s = StillWanted(call.cancelled, call.deadline); !s.ok()) {
      FinishCostToGo(call, s, absl::IsCancelled(s) ? "CANCELLED" : "TIMEOUT");
      return;
    }
    absl::Status status;
    try {
      status = Answer(call);
    } catch (const std::bad_alloc&) {
      status = absl::ResourceExhaustedError("out of memory while building the field");
    } catch (const std::exception& e) {
      status = absl::InternalError(absl::StrFormat("field build failed: %s", e.what()));
    }
    FinishCostToGo(call, status, status.ok() ? "OK" : "ERROR");
  }

  void Drop() override {
    FinishCostToGo(*call_, absl::UnavailableError("server is shutting down"),
                   "DROPPED");
  }
  void Fail(const absl::Status& status) override {
    FinishCostToGo(*call_, status, "ERROR");
  }

 private:
  absl::Status Answer(CostToGoCall& call) {
    const IncrementalCache::Key& key = call.key;
    if (key.robot_radius_cells > 0.0) {
      PATHD_ASSIGN_OR_RETURN(std::shared_ptr<const Grid> inflated,
                             inflation_.Get(call.snapshot->grid, key.robot_radius_cells));
      PATHD_RETURN_IF_ERROR(CheckRadiusEndpoints(*call.snapshot->grid, *inflated,
                                                 key.robot_radius_cells,
                                                 {{key.goal, "goal"}}));
    }
    const StopCondition stop(call.deadline, &call.cancelled, call.max_expansions);
    PATHD_ASSIGN_OR_RETURN(const IncrementalCache::SpmAnswer answer,
                           cache_.GetSpm(key, call.snapshot, stop));
    switch (answer.outcome) {
      case PlanOutcome::kFound:
        break;
      case PlanOutcome::kCancelled:
        return absl::CancelledError("cancelled while building the field");
      case PlanOutcome::kExpansionLimit:
        return absl::ResourceExhaustedError(absl::StrFormat(
            "expansion limit of %d (%s) reached while building the field",
            call.max_expansions, call.expansion_limit_source));
      default:
        return absl::DeadlineExceededError("deadline passed while building the field");
    }
    v1::CostToGoResponse& response = *call.response;
    response.set_map_version(answer.map_version);
    *response.mutable_goal() = ToProto(key.goal);
    v1::CellWindow* window = response.mutable_window();
    window->set_x(call.x);
    window->set_y(call.y);
    window->set_width(call.width);
    window->set_height(call.height);
    response.set_cache_hit(answer.cache_hit);
    response.set_expansions(answer.expansions);
    // Same map id, so the field has the request's dimensions.
    const absl::Span<const float> field = answer.field->field();
    const size_t stride = static_cast<size_t>(answer.grid->width());
    auto* cost = response.mutable_cost();
    cost->Reserve(call.width * call.height);
    for (int32_t row = call.y; row < call.y + call.height; ++row) {
      const size_t begin = static_cast<size_t>(row) * stride + static_cast<size_t>(call.x);
      cost->Add(field.begin() + begin, field.begin() + begin + call.width);
    }
    if (absl::Status s = CheckResponseSize(response, "cost-to-go response",
                                           call.max_message_bytes);
        !s.ok()) {
      response.Clear();
      return s;
    }
    return absl::OkStatus();
  }

  std::shared_ptr<CostToGoCall> call_;
  InflationCache& inflation_;
  IncrementalCache& cache_;
};

// Everything one IsPathValid call needs; shared like PlanCall when it runs on
// the pool.
struct PathCheckCall {
  std::atomic<bool> cancelled{false};
  grpc::ServerUnaryReactor* reactor = nullptr;
  const v1::IsPathValidRequest* request = nullptr;
  v1::IsPathValidResponse* response = nullptr;
  absl::Time received;
  absl::Time deadline = absl::InfiniteFuture();

  // Filled by PreparePathCheck().
  std::shared_ptr<const MapSnapshot> snapshot;
  // One per pose; nullopt for a world point outside the map.
  std::vector<std::optional<Cell>> cells;
  CostParams cost;
  // 0: check on the map as stored.
  double robot_radius_cells = 0.0;
};

void FinishPathCheck(PathCheckCall& call, const absl::Status& status,
                     std::string_view outcome) {
  LogRequest("IsPathValid", call.request->map(),
             absl::StrFormat("poses=%d outcome=%s", call.request->path_size(),
                             outcome),
             status, call.received);
  call.reactor->Finish(ToGrpcStatus(status));
}

// A path of the default --max_path_points (1 Mi poses) is about 6-10 MiB of
// request and is checked in 60-90 ms on the gRPC thread (README).
absl::Status PreparePathCheck(const MapStore& store, int64_t max_path_points,
                              PathCheckCall& call) {
  const v1::IsPathValidRequest& request = *call.request;
  PATHD_ASSIGN_OR_RETURN(call.snapshot, store.Get(request.map()));
  const Grid& grid = *call.snapshot->grid;
  PATHD_ASSIGN_OR_RETURN(call.cost, CostParamsFromOptions(request.options()));
  PATHD_ASSIGN_OR_RETURN(call.robot_radius_cells,
                         RobotRadiusCells(request.options(), grid));
  if (request.path().empty()) {
    return absl::InvalidArgumentError("path is empty (give at least one pose)");
  }
  if (request.path_size() > max_path_points) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "path has %d poses, more than the limit of %d (--max_path_points)",
        request.path_size(), max_path_points));
  }
  call.cells.reserve(request.path_size());
  for (int i = 0; i < request.path_size(); ++i) {
    const v1::Position& pose = request.path(i);
    const std::string what = absl::StrFormat("path[%d]", i);
    if (pose.kind_case() == v1::Position::kWorld) {
      // Off the map is a verdict on the path, not a bad request.
      const WorldPoint p{pose.world().x(), pose.world().y()};
      if (std::isfinite(p.x) && std::isfinite(p.y)) {
        absl::StatusOr<Cell> cell = grid.WorldToCell(p);
        call.cells.push_back(cell.ok() ? std::optional<Cell>(*cell)
                                       : std::nullopt);
        continue;
      }
    }
    PATHD_ASSIGN_OR_RETURN(const Cell cell, CellFromPosition(pose, grid, what));
    call.cells.push_back(cell);
  }
  return absl::OkStatus();
}

// Checks call.cells on `grid` (the snapshot, inflated when a robot radius was
// given) and fills the verdict into call.response.
void CheckPathOn(const Grid& grid, const PathCheckCall& call) {
  const Grid& stored = *call.snapshot->grid;
  v1::IsPathValidResponse& response = *call.response;
  response.set_map_version(call.snapshot->version);
  response.set_robot_radius_cells(call.robot_radius_cells);
  std::string reason;
  const auto note = [&reason](std::string text) {
    if (reason.empty()) reason = std::move(text);
  };
  for (size_t i = 0; i < call.cells.size(); ++i) {
    const std::optional<Cell>& cell = call.cells[i];
    const int index = static_cast<int>(i);
    if (!cell.has_value()) {
      response.add_invalid_indices(index);
      note(absl::StrFormat("pose %d: the world point is outside the map",
                           index));
    } else if (!grid.InBounds(*cell)) {
      response.add_invalid_indices(index);
      note(absl::StrFormat("pose %d %s is outside the %d x %d map", index,
                           CellToString(*cell), grid.width(), grid.height()));
    } else if (const uint8_t c = grid.cost(*cell);
               !Traversable(c, call.cost.unknown_is_free)) {
      response.add_invalid_indices(index);
      note(c == kInscribedCost && stored.cost(*cell) != kInscribedCost
               ? absl::StrFormat("pose %d %s is within the robot radius (%g "
                                 "cells) of an obstacle",
                                 index, CellToString(*cell),
                                 call.robot_radius_cells)
               : absl::StrFormat("pose %d %s is on a blocked cell (cost %d)",
                                 index, CellToString(*cell), c));
    }
    if (i == 0 || !cell.has_value() || !call.cells[i - 1].has_value()) continue;
    const Cell from = *call.cells[i - 1];
    if (const MoveFault fault = CheckMove(grid, from, *cell, call.cost);
        fault != MoveFault::kNone) {
      response.add_invalid_steps(index);
      note(absl::StrFormat("step %d -> %d from %s to %s: %s", index - 1, index,
                           CellToString(from), CellToString(*cell),
                           MoveFaultName(fault)));
    }
  }
  response.set_valid(reason.empty());
  response.set_reason(reason);
  if (!response.valid()) return;
  std::vector<Cell> path;
  path.reserve(call.cells.size());
  for (const std::optional<Cell>& cell : call.cells) path.push_back(*cell);
  // The same rule as the checks above, so the path measures as valid.
  const PathMeasure measure = MeasurePath(grid, path, call.cost);
  response.set_cost(measure.cost);
  response.set_length(measure.length);
}

// Inflates (cached) and checks, on a worker: inflating a map version for the
// first time is O(map), too much for a gRPC thread.
absl::Status CheckPathInflated(InflationCache& inflation, PathCheckCall& call) {
  PATHD_ASSIGN_OR_RETURN(
      const std::shared_ptr<const Grid> inflated,
      inflation.Get(call.snapshot->grid, call.robot_radius_cells));
  CheckPathOn(*inflated, call);
  return absl::OkStatus();
}

void FillCacheStats(IncrementalCache::Kind kind, const IncrementalCache::Stats& s,
                    v1::CacheStats* out) {
  out->set_name(std::string(IncrementalCache::KindName(kind)));
  out->set_entries(s.entries);
  out->set_bytes(s.bytes);
  out->set_budget_bytes(s.budget_bytes);
  out->set_hits(s.hits);
  out->set_misses(s.misses);
  out->set_evictions(s.evictions);
  out->set_repairs(s.repairs);
  out->set_rebuilds(s.rebuilds);
}

// ---- PlanStream and PlanBatch ----
//
// Both run the same PlanCall/PlanJob as Plan; they answer through
// PlanCall::on_finish instead of a unary reactor. Their mutable state lives
// in a shared object held by the reactor and by the pool jobs' on_finish, so
// a job that is still returning from the call that led to Finish never uses
// a reactor gRPC has already deleted (OnDone may run on another thread as
// soon as Finish is called). gRPC never runs reactions inline from
// Start*/Finish, so those are called with the state's mutex held.

// What a failed plan reports on a stream.
v1::PlanError ToPlanError(const absl::Status& status) {
  v1::PlanError error;
  error.set_code(static_cast<int32_t>(ToGrpcCode(status.code())));
  error.set_message(std::string(status.message()));
  error.set_outcome(OutcomeOfStatus(status));
  return error;
}

// One PlanStream call's writer side: receives progress (as the stop
// condition's ProgressSink, on the worker) and the final answer, and writes
// them one at a time. A progress event arriving while a write is in flight
// replaces any unsent one, so a slow reader costs one pending event, not a
// backlog; the final event replaces an unsent progress event. Thread-safe.
class PlanStreamState final : public ProgressSink {
 public:
  PlanStreamState(absl::Duration interval, grpc::CallbackServerContext* context,
                  absl::Time received)
      : ProgressSink(interval), context_(context), received_(received) {}

  // Must be called before the plan can finish; `reactor` must stay valid
  // until this state calls its Finish.
  void Attach(grpc::ServerWriteReactor<v1::PlanStreamEvent>* reactor) {
    absl::MutexLock lock(&mu_);
    reactor_ = reactor;
  }

  // Where the plan job writes its response.
  v1::PlanResponse* response() { return &response_; }

  // The plan's answer (PlanCall::on_finish): queues the final event.
  void OnPlanFinished(const absl::Status& status) {
    absl::MutexLock lock(&mu_);
    final_.emplace();
    if (status.ok()) {
      *final_->mutable_result() = std::move(response_);
    } else {
      *final_->mutable_error() = ToPlanError(status);
      if (const v1::PlanOutcome typed = OutcomeOfStatus(status);
          IsRejectionOutcome(typed)) {
        context_->AddTrailingMetadata(kPlanOutcomeMetadataKey,
                                      v1::PlanOutcome_Name(typed));
      }
    }
    final_status_ = ToGrpcStatus(status);
    progress_.reset();
    PumpLocked();
  }

  void OnWriteDone(bool ok) {
    absl::MutexLock lock(&mu_);
    writing_ = false;
    if (!ok) broken_ = true;
    PumpLocked();
  }

 private:
  void Report(int64_t expansions, double best_f, absl::Time now) override {
    v1::PlanStreamEvent event;
    v1::PlanProgress* progress = event.mutable_progress();
    progress->set_expansions(expansions);
    if (!std::isnan(best_f)) progress->set_best_f(best_f);
    progress->set_elapsed_us(absl::ToInt64Microseconds(now - received_));
    absl::MutexLock lock(&mu_);
    progress_ = std::move(event);
    PumpLocked();
  }

  // Starts the next write, or finishes once the final event is written (or
  // can no longer be).
  void PumpLocked() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
    if (writing_ || finished_) return;
    if (final_.has_value() && (final_sent_ || broken_)) {
      finished_ = true;
      reactor_->Finish(final_status_);
      return;
    }
    if (broken_) return;  // the plan is being cancelled; wait for its end
    if (final_.has_value()) {
      out_ = std::move(*final_);
      final_sent_ = true;
    } else if (progress_.has_value()) {
      out_ = std::move(*progress_);
      progress_.reset();
    } else {
      return;
    }
    writing_ = true;
    reactor_->StartWrite(&out_);
  }

  grpc::CallbackServerContext* const context_;
  const absl::Time received_;
  // Written by the plan job before on_finish, read by on_finish.
  v1::PlanResponse response_;

  absl::Mutex mu_;
  grpc::ServerWriteReactor<v1::PlanStreamEvent>* reactor_ ABSL_GUARDED_BY(mu_) =
      nullptr;
  std::optional<v1::PlanStreamEvent> progress_ ABSL_GUARDED_BY(mu_);
  std::optional<v1::PlanStreamEvent> final_ ABSL_GUARDED_BY(mu_);
  grpc::Status final_status_ ABSL_GUARDED_BY(mu_);
  // Owned by gRPC between StartWrite and OnWriteDone.
  v1::PlanStreamEvent out_ ABSL_GUARDED_BY(mu_);
  bool writing_ ABSL_GUARDED_BY(mu_) = false;
  bool final_sent_ ABSL_GUARDED_BY(mu_) = false;
  // A write failed: the client is gone.
  bool broken_ ABSL_GUARDED_BY(mu_) = false;
  bool finished_ ABSL_GUARDED_BY(mu_) = false;
};

class PlanStreamReactor final : public grpc::ServerWriteReactor<v1::PlanStreamEvent> {
 public:
  PlanStreamReactor(std::shared_ptr<PlanCall> call,
                    std::shared_ptr<PlanStreamState> state)
      : call_(std::move(call)), state_(std::move(state)) {}

  void OnCancel() override { call_->cancelled.store(true, std::memory_order_relaxed); }
  void OnWriteDone(bool ok) override {
    // A failed write means nobody reads the rest: stop planning.
    if (!ok) call_->cancelled.store(true, std::memory_order_relaxed);
    state_->OnWriteDone(ok);
  }
  void OnDone() override { delete this; }

 private:
  std::shared_ptr<PlanCall> call_;
  std::shared_ptr<PlanStreamState> state_;
};

// One PlanBatch stream. Items are read while fewer than `max_inflight` are
// outstanding (read, answer not yet written), so a client that sends faster
// than the workers plan, or reads its answers slowly, is held back by gRPC
// flow control instead of growing the server's queues. Answers are written
// in the order they finish. The stream finishes when the client has
// half-closed and every item is answered, or, once the client cancelled or
// stopped reading, when every running item has stopped. Thread-safe.
class PlanBatchState final : public std::enable_shared_from_this<PlanBatchState> {
 public:
  struct Deps {
    const MapStore& store;
    WorkerPool& pool;
    InflationCache& inflation;
    IncrementalCache& cache;
    const PlannerServiceImpl::Options& limits;
    size_t max_inflight;
  };

  PlanBatchState(Deps deps, absl::Time deadline)
      : deps_(deps), deadline_(deadline), opened_(absl::Now()) {}

  // Starts reading; `reactor` must stay valid until this state calls its
  // Finish.
  void Start(grpc::ServerBidiReactor<v1::PlanBatchRequest, v1::PlanBatchResponse>*
                 reactor) {
    absl::MutexLock lock(&mu_);
    reactor_ = reactor;
    reading_ = true;
    reactor_->StartRead(&read_);
  }

  void OnReadDone(bool ok) {
    v1::PlanBatchRequest message;
    {
      absl::MutexLock lock(&mu_);
      reading_ = false;
      if (broken_ || !ok) {
        reads_done_ = true;
        PumpLocked();
        return;
      }
      ++outstanding_;
      ++items_;
      ++accepting_;
      message = std::move(read_);
      read_.Clear();
    }
    Accept(std::move(message));
    absl::MutexLock lock(&mu_);
    ResumeReadingLocked();
    PumpLocked();
  }

  void OnWriteDone(bool ok) {
    absl::MutexLock lock(&mu_);
    writing_ = false;
    --outstanding_;
    if (!ok) BreakLocked(absl::CancelledError("the client stopped reading"));
    ResumeReadingLocked();
    PumpLocked();
  }

  void OnCancel() {
    absl::MutexLock lock(&mu_);
    BreakLocked(absl::CancelledError("the client cancelled the batch"));
    PumpLocked();
  }

 private:
  // An item's request and response; the item's PlanCall points into it.
  struct Item {
    v1::PlanBatchRequest request;
    v1::PlanResponse response;
  };

  // Validates and submits one item; every path ends in exactly one answer
  // (FinishCall -> ItemDone, or an immediate error).
  void Accept(v1::PlanBatchRequest message) {
    auto item = std::make_shared<Item>();
    item->request = std::move(message);
    const std::string& id = item->request.request_id();
    auto call = std::make_shared<PlanCall>();
    call->received = absl::Now();
    call->request = &item->request.request();
    call->response = &item->response;
    call->deadline = deadline_;
    call->rpc = "PlanBatch";
    call->on_finish = [state = shared_from_this(), item](const absl::Status& s) {
      state->ItemDone(*item, s);
    };
    {
      absl::MutexLock lock(&mu_);
      absl::Status refused;
      if (id.empty()) {
        refused = absl::InvalidArgumentError(
            "request_id is empty (give each item a non-empty id)");
      } else if (running_.contains(id)) {
        refused = absl::InvalidArgumentError(absl::StrFormat(
            "request_id '%s' is already in flight on this stream", id));
      } else if (broken_) {
        refused = absl::CancelledError("the batch was cancelled");
      }
      // From here the item is either answered or in running_, both of which
      // keep the stream open.
      --accepting_;
      if (!refused.ok()) {
        v1::PlanBatchResponse answer;
        answer.set_request_id(id);
        *answer.mutable_error() = ToPlanError(refused);
        AnswerLocked(std::move(answer));
        return;
      }
      // Registered before submitting: the job may answer at once.
      running_.emplace(id, call);
    }
    if (absl::Status s = Prepare(deps_.store, deps_.limits, *call); !s.ok()) {
      FinishCall(*call, s, "REJECTED");
      return;
    }
    if (absl::Status s = deps_.pool.Submit(
            std::make_unique<PlanJob>(call, deps_.inflation, deps_.cache),
            WorkerPool::Priority::kBatch);
        !s.ok()) {
      FinishCall(*call, s, "REJECTED");
    }
  }

  // PlanCall::on_finish of an accepted item, on a worker or gRPC thread.
  void ItemDone(Item& item, const absl::Status& status) {
    // Released after the lock: the caller still holds the call.
    std::shared_ptr<PlanCall> finished;
    absl::MutexLock lock(&mu_);
    const std::string& id = item.request.request_id();
    if (auto it = running_.find(id); it != running_.end()) {
      finished = std::move(it->second);
      running_.erase(it);
    }
    v1::PlanBatchResponse answer;
    answer.set_request_id(id);
    if (status.ok()) {
      *answer.mutable_result() = std::move(item.response);
    } else {
      *answer.mutable_error() = ToPlanError(status);
    }
    AnswerLocked(std::move(answer));
  }

  void AnswerLocked(v1::PlanBatchResponse answer) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
    if (broken_) {
      --outstanding_;  // nobody will read it
    } else {
      pending_.push_back(std::move(answer));
    }
    PumpLocked();
  }

  // The client is gone: cancel what runs, drop what waits, read no more.
  void BreakLocked(const absl::Status& why) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
    if (broken_) return;
    broken_ = true;
    end_status_ = why;
    reads_done_ = true;
    outstanding_ -= pending_.size();
    pending_.clear();
    for (auto& [id, call] : running_) {
      call->cancelled.store(true, std::memory_order_relaxed);
    }
  }

  void ResumeReadingLocked() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
    if (reading_ || reads_done_ || finished_ || outstanding_ >= deps_.max_inflight) {
      return;
    }
    reading_ = true;
    reactor_->StartRead(&read_);
  }

  void PumpLocked() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
    if (finished_ || writing_) return;
    if (!pending_.empty()) {
      out_ = std::move(pending_.front());
      pending_.pop_front();
      writing_ = true;
      reactor_->StartWrite(&out_);
      return;
    }
    // Every running item must have answered first: their on_finish holds
    // this state, but the reactor is deleted soon after Finish. An item
    // still being accepted counts too: a write completing meanwhile may
    // already have started the read that sees the client's half-close.
    if (!reads_done_ || !running_.empty() || accepting_ > 0) return;
    finished_ = true;
    LogRequest("PlanBatch", "-", absl::StrFormat("items=%d", items_), end_status_,
               opened_);
    reactor_->Finish(ToGrpcStatus(end_status_));
  }

  const Deps deps_;
  const absl::Time deadline_;
  const absl::Time opened_;

  absl::Mutex mu_;
  grpc::ServerBidiReactor<v1::PlanBatchRequest, v1::PlanBatchResponse>* reactor_
      ABSL_GUARDED_BY(mu_) = nullptr;
  // Owned by gRPC between StartRead and OnReadDone.
  v1::PlanBatchRequest read_ ABSL_GUARDED_BY(mu_);
  // Owned by gRPC between StartWrite and OnWriteDone.
  v1::PlanBatchResponse out_ ABSL_GUARDED_BY(mu_);
  std::deque<v1::PlanBatchResponse> pending_ ABSL_GUARDED_BY(mu_);
  // Items submitted or being prepared, by request id (for duplicates and
  // cancellation); an item leaves when it is answered.
  absl::flat_hash_map<std::string, std::shared_ptr<PlanCall>> running_
      ABSL_GUARDED_BY(mu_);
  // Items read whose answer is not yet written (or dropped).
  size_t outstanding_ ABSL_GUARDED_BY(mu_) = 0;
  // Items read but not yet answered or registered in running_ (Accept runs
  // outside the lock).
  int accepting_ ABSL_GUARDED_BY(mu_) = 0;
  int64_t items_ ABSL_GUARDED_BY(mu_) = 0;
  bool reading_ ABSL_GUARDED_BY(mu_) = false;
  // The client half-closed, or the stream broke.
  bool reads_done_ ABSL_GUARDED_BY(mu_) = false;
  bool writing_ ABSL_GUARDED_BY(mu_) = false;
  bool broken_ ABSL_GUARDED_BY(mu_) = false;
  bool finished_ ABSL_GUARDED_BY(mu_) = false;
  absl::Status end_status_ ABSL_GUARDED_BY(mu_);
};

class PlanBatchReactor final
    : public grpc::ServerBidiReactor<v1::PlanBatchRequest, v1::PlanBatchResponse> {
 public:
  explicit PlanBatchReactor(std::shared_ptr<PlanBatchState> state)
      : state_(std::move(state)) {}

  void OnReadDone(bool ok) override { state_->OnReadDone(ok); }
  void OnWriteDone(bool ok) override { state_->OnWriteDone(ok); }
  void OnCancel() override { state_->OnCancel(); }
  void OnDone() override { delete this; }

 private:
  std::shared_ptr<PlanBatchState> state_;
};

}  // namespace

PlannerServiceImpl::PlannerServiceImpl(const MapStore& store, WorkerPool& pool,
                                       InflationCache& inflation,
                                       IncrementalCache& cache,
                                       NavigationSessions& sessions, Options options)
    : store_(store),
      pool_(pool),
      inflation_(inflation),
      cache_(cache),
      sessions_(sessions),
      options_(std::move(options)) {}

grpc::ServerBidiReactor<v1::NavigateRequest, v1::NavigateResponse>*
PlannerServiceImpl::Navigate(grpc::CallbackServerContext* context) {
  if (auto* refused = RefuseUnauthorized<
          grpc::ServerBidiReactor<v1::NavigateRequest, v1::NavigateResponse>>(
          options_.authenticator, context, kMethodNavigate)) {
    return refused;
  }
  // Decided now, while the call's metadata is at hand; the session applies
  // it to each observation that would write the shared map.
  return sessions_.Start(context, Authorize(options_.authenticator, *context,
                                            kNavigateSharedObservation));
}

grpc::ServerUnaryReactor* PlannerServiceImpl::Plan(
    grpc::CallbackServerContext* context, const v1::PlanRequest* request,
    v1::PlanResponse* response) {
  if (auto* refused = RefuseUnauthorized(options_.authenticator, context, kMethodPlan)) {
    return refused;
  }
  auto call = std::make_shared<PlanCall>();
  call->received = absl::Now();
  call->request = request;
  call->response = response;
  call->deadline = DeadlineOf(*context);
  call->context = context;
  auto* reactor = new CancellableReactor<PlanCall>(call);
  call->reactor = reactor;

  if (absl::Status s = Prepare(store_, options_, *call); !s.ok()) {
    FinishCall(*call, s, "REJECTED");
    return reactor;
  }
  // Once submitted, the job owns the answer and may already have finished the
  // call on a worker, so nothing below may touch `call` on success.
  if (absl::Status s = pool_.Submit(std::make_unique<PlanJob>(call, inflation_, cache_));
      !s.ok()) {
    AddRetryAfterTrailer(s, *context);
    FinishCall(*call, s, "REJECTED");
  }
  return reactor;
}

grpc::ServerUnaryReactor* PlannerServiceImpl::CostToGo(
    grpc::CallbackServerContext* context, const v1::CostToGoRequest* request,
    v1::CostToGoResponse* response) {
  if (auto* refused =
          RefuseUnauthorized(options_.authenticator, context, kMethodCostToGo)) {
    return refused;
  }
  auto call = std::make_shared<CostToGoCall>();
  call->received = absl::Now();
  call->request = request;
  call->response = response;
  call->deadline = DeadlineOf(*context);
  auto* reactor = new CancellableReactor<CostToGoCall>(call);
  call->reactor = reactor;

  if (absl::Status s = PrepareCostToGo(store_, options_, *call);
      !s.ok()) {
    FinishCostToGo(*call, s, "REJECTED");
    return reactor;
  }
  // As in Plan: after a successful submit the job owns the call.
  if (absl::Status s =
          pool_.Submit(std::make_unique<CostToGoJob>(call, inflation_, cache_));
      !s.ok()) {
    AddRetryAfterTrailer(s, *context);
    FinishCostToGo(*call, s, "REJECTED");
  }
  return reactor;
}

grpc::ServerUnaryReactor* PlannerServiceImpl::IsPathValid(
    grpc::CallbackServerContext* context, const v1::IsPathValidRequest* request,
    v1::IsPathValidResponse* response) {
  if (auto* refused =
          RefuseUnauthorized(options_.authenticator, context, kMethodIsPathValid)) {
    return refused;
  }
  auto call = std::make_shared<PathCheckCall>();
  call->received = absl::Now();
  call->request = request;
  call->response = response;
  call->deadline = DeadlineOf(*context);
  auto* reactor = new CancellableReactor<PathCheckCall>(call);
  call->reactor = reactor;

  if (absl::Status s = PreparePathCheck(store_, options_.max_path_points, *call);
      !s.ok()) {
    FinishPathCheck(*call, s, "REJECTED");
    return reactor;
  }
  if (call->robot_radius_cells <= 0.0) {
    // O(path): answered here rather than queued behind plans.
    CheckPathOn(*call->snapshot->grid, *call);
    FinishPathCheck(*call, absl::OkStatus(),
                    response->valid() ? "VALID" : "INVALID");
    return reactor;
  }
  InflationCache& inflation = inflation_;
  auto run = [call, &inflation](SearchScratch&) {
    if (absl::Status s = StillWanted(call->cancelled, call->deadline);
        !s.ok()) {
      FinishPathCheck(*call, s, absl::IsCancelled(s) ? "CANCELLED" : "TIMEOUT");
      return;
    }
    absl::Status status;
    try {
      status = CheckPathInflated(inflation, *call);
    } catch (const std::bad_alloc&) {
      status =
          absl::ResourceExhaustedError("out of memory while inflating the map");
    }
    const char* outcome = "ERROR";
    if (status.ok()) outcome = call->response->valid() ? "VALID" : "INVALID";
    FinishPathCheck(*call, status, outcome);
  };
  auto drop = [call] {
    FinishPathCheck(*call, absl::UnavailableError("server is shutting down"),
                    "DROPPED");
  };
  // As in Plan: after a successful submit the job owns the call.
  if (absl::Status s = pool_.Submit(MakeJob(std::move(run), std::move(drop)));
      !s.ok()) {
    AddRetryAfterTrailer(s, *context);
    FinishPathCheck(*call, s, "REJECTED");
  }
  return reactor;
}

grpc::ServerUnaryReactor* PlannerServiceImpl::GetCacheStats(
    grpc::CallbackServerContext* context, const v1::GetCacheStatsRequest* /*request*/,
    v1::GetCacheStatsResponse* response) {
  if (auto* refused =
          RefuseUnauthorized(options_.authenticator, context, kMethodGetCacheStats)) {
    return refused;
  }
  const absl::Time received = absl::Now();
  for (const IncrementalCache::Kind kind :
       {IncrementalCache::Kind::kSpm, IncrementalCache::Kind::kDStarLite}) {
    FillCacheStats(kind, cache_.stats(kind), response->add_caches());
  }
  response->set_sessions(sessions_.count());
  response->set_session_bytes(sessions_.bytes());
  LogRequest("GetCacheStats", "-", "", absl::OkStatus(), received);
  grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
  reactor->Finish(grpc::Status::OK);
  return reactor;
}

grpc::ServerWriteReactor<v1::PlanStreamEvent>* PlannerServiceImpl::PlanStream(
    grpc::CallbackServerContext* context, const v1::PlanRequest* request) {
  if (auto* refused = RefuseUnauthorized<grpc::ServerWriteReactor<v1::PlanStreamEvent>>(
          options_.authenticator, context, kMethodPlanStream)) {
    return refused;
  }
  auto call = std::make_shared<PlanCall>();
  call->received = absl::Now();
  call->request = request;
  call->deadline = DeadlineOf(*context);
  call->rpc = "PlanStream";
  auto state = std::make_shared<PlanStreamState>(options_.progress_interval,
                                                 context, call->received);
  call->response = state->response();
  call->progress = state.get();
  call->on_finish = [state](const absl::Status& s) { state->OnPlanFinished(s); };
  auto* reactor = new PlanStreamReactor(call, state);
  state->Attach(reactor);

  if (absl::Status s = Prepare(store_, options_, *call); !s.ok()) {
    FinishCall(*call, s, "REJECTED");
    return reactor;
  }
  if (absl::Status s = pool_.Submit(std::make_unique<PlanJob>(call, inflation_, cache_));
      !s.ok()) {
    FinishCall(*call, s, "REJECTED");
  }
  return reactor;
}

grpc::ServerBidiReactor<v1::PlanBatchRequest, v1::PlanBatchResponse>*
PlannerServiceImpl::PlanBatch(grpc::CallbackServerContext* context) {
  if (auto* refused = RefuseUnauthorized<
          grpc::ServerBidiReactor<v1::PlanBatchRequest, v1::PlanBatchResponse>>(
          options_.authenticator, context, kMethodPlanBatch)) {
    return refused;
  }
  const size_t max_inflight =
      options_.batch_max_inflight > 0
          ? static_cast<size_t>(options_.batch_max_inflight)
          : static_cast<size_t>(2 * pool_.threads());
  auto state = std::make_shared<PlanBatchState>(
      PlanBatchState::Deps{store_, pool_, inflation_, cache_, options_,
                           max_inflight},
      DeadlineOf(*context));
  auto* reactor = new PlanBatchReactor(state);
  state->Start(reactor);
  return reactor;
}

}  // namespace pathd::server
