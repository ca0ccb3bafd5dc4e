// PlannerService implementation: per-call shared state, the reactor that
// forwards cancellation, the pool jobs that plan (or read a cached field) and
// answer, and the cache counters.
#include "server/planner_service.h"

#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <initializer_list>
#include <memory>
#include <new>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "core/cost_model.h"
#include "core/path_simplify.h"
#include "core/plan_through.h"
#include "core/planner.h"
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
  // 0: plan on the map as stored.
  double robot_radius_cells = 0.0;
  bool simplify = false;

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

// The reactor of a unary call that runs on the pool: forwards cancellation to
// the call's flag. `Call` has `std::atomic<bool> cancelled`.
template <typename Call>
class CancellableReactor final : public grpc::ServerUnaryReactor {
 public:
  explicit CancellableReactor(std::shared_ptr<Call> call) : call_(std::move(call)) {}

  // The planner polls the flag every StopCondition::kPollInterval expansions;
  // a queued job sees it before it starts.
  void OnCancel() override { call_->cancelled.store(true, std::memory_order_relaxed); }
  void OnDone() override { delete this; }

 private:
  std::shared_ptr<Call> call_;
};

// Why a job that waited in the queue should not start: CANCELLED or
// DEADLINE_EXCEEDED, OK when it should.
absl::Status StillWanted(const std::atomic<bool>& cancelled, absl::Time deadline) {
  if (cancelled.load(std::memory_order_relaxed)) {
    return absl::CancelledError("cancelled before planning started");
  }
  if (absl::Now() >= deadline) {
    return absl::DeadlineExceededError(
        "deadline passed while the request waited for a worker");
  }
  return absl::OkStatus();
}

// INVALID_ARGUMENT when one of `endpoints` became inscribed by the robot
// radius (it is traversable on the stored map, so the request was accepted).
absl::Status CheckRadiusEndpoints(
    const Grid& stored, const Grid& inflated, double radius_cells,
    std::initializer_list<std::pair<Cell, const char*>> endpoints) {
  for (const auto& [cell, what] : endpoints) {
    if (inflated.InBounds(cell) && inflated.cost(cell) == kInscribedCost &&
        stored.cost(cell) != kInscribedCost) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "%s %s is within the robot radius (%g cells) of an obstacle", what,
          CellToString(cell), radius_cells));
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
  return absl::InvalidArgumentError(absl::StrFormat(
      "goal %s is on a blocked cell (cost %d) and no cell within the goal "
      "tolerance of %g cells is free%s",
      CellToString(requested), grid.cost(requested), tolerance_cells,
      radius_cells > 0.0
          ? absl::StrFormat(" for the robot radius (%g cells)", radius_cells)
          : std::string()));
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
  LogRequest("Plan", call.request->map(),
             absl::StrFormat("planner=%s outcome=%s", call.planner_name, outcome),
             status, call.received);
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

// A whole field is 8 bytes per cell in one Plan message and 4 in a CostToGo
// message; beyond this either would take tens of megabytes.
constexpr int64_t kMaxCostToGoCells = int64_t{1} << 22;

// Resolves everything that can fail before planning, on the gRPC thread, so
// a bad request never takes a queue slot.
absl::Status Prepare(const MapStore& store, int64_t server_max_expansions,
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
  if (call.core_request.want_cost_to_go &&
      grid.size() > static_cast<size_t>(kMaxCostToGoCells)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "options.return_cost_to_go: the map has %d cells; whole cost-to-go "
        "fields are returned for maps of up to %d cells (32 MiB)",
        grid.size(), kMaxCostToGoCells));
  }
  PATHD_ASSIGN_OR_RETURN(call.max_expansions,
                         EffectiveMaxExpansions(request.options(),
                                                server_max_expansions));
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
    const StopCondition stop(call.deadline, &call.cancelled, call.max_expansions);
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
    v1::PlanResponse* response = call.response;
    FillPlanResponse(*result, call.core_request, *source.grid, call.max_expansions,
                     response);
    response->set_robot_radius_cells(call.robot_radius_cells);
    response->set_map_version(source.map_version);
    response->set_planner(std::string(call.planner_name));
    response->set_cache_hit(source.cache_hit);
    response->set_repaired_cells(source.repaired_cells);
    *response->mutable_requested_goal() = ToProto(call.requested_goal);
    response->set_goal_substituted(
        !(call.core_request.goal == call.requested_goal));
    FillLegsAndExpansions(call, *result, response);
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
};

void FinishCostToGo(CostToGoCall& call, const absl::Status& status,
                    std::string_view outcome) {
  LogRequest("CostToGo", call.request->map(), absl::StrFormat("outcome=%s", outcome),
             status, call.received);
  call.reactor->Finish(ToGrpcStatus(status));
}

absl::Status PrepareCostToGo(const MapStore& store, int64_t server_max_expansions,
                             CostToGoCall& call) {
  const v1::CostToGoRequest& request = *call.request;
  PATHD_ASSIGN_OR_RETURN(call.snapshot, store.Get(request.map()));
  const Grid& grid = *call.snapshot->grid;
  PATHD_ASSIGN_OR_RETURN(const Cell goal, CellFromPosition(request.goal(), grid, "goal"));
  PATHD_ASSIGN_OR_RETURN(const CostParams cost, CostParamsFromOptions(request.options()));
  PATHD_ASSIGN_OR_RETURN(const double radius, RobotRadiusCells(request.options(), grid));
  PATHD_ASSIGN_OR_RETURN(call.max_expansions,
                         EffectiveMaxExpansions(request.options(), server_max_expansions));
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
  const int64_t cells = int64_t{call.width} * call.height;
  if (cells > kMaxCostToGoCells) {
    return absl::ResourceExhaustedError(absl::StrFormat(
        "%s has %d cells; cost-to-go is returned for up to %d cells (16 MiB) per "
        "call: ask for windows",
        request.has_window() ? "the window" : "the map", cells, kMaxCostToGoCells));
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
            "expansion limit of %d reached while building the field",
            call.max_expansions));
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
    return absl::OkStatus();
  }

  std::shared_ptr<CostToGoCall> call_;
  InflationCache& inflation_;
  IncrementalCache& cache_;
};

// Longest path IsPathValid checks: about 6-10 MiB of request, checked in
// 60-90 ms on the gRPC thread (README), which is where this bound should stay.
constexpr int kMaxCheckedPoses = 1 << 20;

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

absl::Status PreparePathCheck(const MapStore& store, PathCheckCall& call) {
  const v1::IsPathValidRequest& request = *call.request;
  PATHD_ASSIGN_OR_RETURN(call.snapshot, store.Get(request.map()));
  const Grid& grid = *call.snapshot->grid;
  PATHD_ASSIGN_OR_RETURN(call.cost, CostParamsFromOptions(request.options()));
  PATHD_ASSIGN_OR_RETURN(call.robot_radius_cells,
                         RobotRadiusCells(request.options(), grid));
  if (request.path().empty()) {
    return absl::InvalidArgumentError("path is empty (give at least one pose)");
  }
  if (request.path_size() > kMaxCheckedPoses) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "path has %d poses; IsPathValid checks up to %d (1 Mi) per call",
        request.path_size(), kMaxCheckedPoses));
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
  return sessions_.Start(context);
}

grpc::ServerUnaryReactor* PlannerServiceImpl::Plan(
    grpc::CallbackServerContext* context, const v1::PlanRequest* request,
    v1::PlanResponse* response) {
  auto call = std::make_shared<PlanCall>();
  call->received = absl::Now();
  call->request = request;
  call->response = response;
  call->deadline = DeadlineOf(*context);
  auto* reactor = new CancellableReactor<PlanCall>(call);
  call->reactor = reactor;

  if (absl::Status s = Prepare(store_, options_.max_expansions, *call); !s.ok()) {
    FinishCall(*call, s, "REJECTED");
    return reactor;
  }
  if (absl::Status s =
          PrepareViaAndExpansions(options_.max_returned_expansions, *call);
      !s.ok()) {
    FinishCall(*call, s, "REJECTED");
    return reactor;
  }
  // Once submitted, the job owns the answer and may already have finished the
  // call on a worker, so nothing below may touch `call` on success.
  if (absl::Status s = pool_.Submit(std::make_unique<PlanJob>(call, inflation_, cache_));
      !s.ok()) {
    FinishCall(*call, s, "REJECTED");
  }
  return reactor;
}

grpc::ServerUnaryReactor* PlannerServiceImpl::CostToGo(
    grpc::CallbackServerContext* context, const v1::CostToGoRequest* request,
    v1::CostToGoResponse* response) {
  auto call = std::make_shared<CostToGoCall>();
  call->received = absl::Now();
  call->request = request;
  call->response = response;
  call->deadline = DeadlineOf(*context);
  auto* reactor = new CancellableReactor<CostToGoCall>(call);
  call->reactor = reactor;

  if (absl::Status s = PrepareCostToGo(store_, options_.max_expansions, *call);
      !s.ok()) {
    FinishCostToGo(*call, s, "REJECTED");
    return reactor;
  }
  // As in Plan: after a successful submit the job owns the call.
  if (absl::Status s =
          pool_.Submit(std::make_unique<CostToGoJob>(call, inflation_, cache_));
      !s.ok()) {
    FinishCostToGo(*call, s, "REJECTED");
  }
  return reactor;
}

grpc::ServerUnaryReactor* PlannerServiceImpl::IsPathValid(
    grpc::CallbackServerContext* context, const v1::IsPathValidRequest* request,
    v1::IsPathValidResponse* response) {
  auto call = std::make_shared<PathCheckCall>();
  call->received = absl::Now();
  call->request = request;
  call->response = response;
  call->deadline = DeadlineOf(*context);
  auto* reactor = new CancellableReactor<PathCheckCall>(call);
  call->reactor = reactor;

  if (absl::Status s = PreparePathCheck(store_, *call); !s.ok()) {
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
    FinishPathCheck(*call, s, "REJECTED");
  }
  return reactor;
}

grpc::ServerUnaryReactor* PlannerServiceImpl::GetCacheStats(
    grpc::CallbackServerContext* context, const v1::GetCacheStatsRequest* /*request*/,
    v1::GetCacheStatsResponse* response) {
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

}  // namespace pathd::server
