// PlannerService implementation: per-call shared state, the reactor that
// forwards cancellation, and the pool job that plans and answers.
#include "server/planner_service.h"

#include <atomic>
#include <chrono>
#include <exception>
#include <memory>
#include <new>
#include <string>
#include <utility>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "core/path_simplify.h"
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
  const Planner* planner = nullptr;
  PlanRequest core_request;
  int64_t max_expansions = 0;
  // 0: plan on the map as stored.
  double robot_radius_cells = 0.0;
  bool simplify = false;
};

class PlanReactor final : public grpc::ServerUnaryReactor {
 public:
  explicit PlanReactor(std::shared_ptr<PlanCall> call) : call_(std::move(call)) {}

  // The planner polls the flag every StopCondition::kPollInterval expansions;
  // a queued job sees it before it starts.
  void OnCancel() override { call_->cancelled.store(true, std::memory_order_relaxed); }
  void OnDone() override { delete this; }

 private:
  std::shared_ptr<PlanCall> call_;
};

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
  // A whole field is 8 bytes per cell in one message; beyond this it would
  // take hundreds of megabytes.
  constexpr size_t kMaxCostToGoCells = size_t{1} << 22;
  if (call.core_request.want_cost_to_go && grid.size() > kMaxCostToGoCells) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "options.return_cost_to_go: the map has %d cells; whole cost-to-go "
        "fields are returned for maps of up to %d cells (32 MiB)",
        grid.size(), kMaxCostToGoCells));
  }
  PATHD_ASSIGN_OR_RETURN(call.max_expansions,
                         EffectiveMaxExpansions(request.options(),
                                                server_max_expansions));
  PATHD_RETURN_IF_ERROR(ValidateEndpoints(grid, call.core_request));
  call.planner = PlannerRegistry::Default().Get(call.planner_name);
  if (call.planner == nullptr) {
    return absl::UnimplementedError(absl::StrFormat(
        "planner '%s' is not available on this server", call.planner_name));
  }
  return absl::OkStatus();
}

class PlanJob final : public Job {
 public:
  PlanJob(std::shared_ptr<PlanCall> call, InflationCache& inflation)
      : call_(std::move(call)), inflation_(inflation) {}

  void Run(SearchScratch& scratch) override {
    PlanCall& call = *call_;
    if (call.cancelled.load(std::memory_order_relaxed)) {
      FinishCall(call, absl::CancelledError("cancelled before planning started"),
                 "CANCELLED");
      return;
    }
    if (absl::Now() >= call.deadline) {
      FinishCall(call,
                 absl::DeadlineExceededError(
                     "deadline passed while the request waited for a worker"),
                 "TIMEOUT");
      return;
    }
    const StopCondition stop(call.deadline, &call.cancelled, call.max_expansions);
    absl::StatusOr<PlanResult> result;
    std::shared_ptr<const Grid> grid = call.snapshot->grid;
    try {
      result = PlanOn(call, scratch, stop, grid);
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
    FillPlanResponse(*result, call.core_request, *grid, call.max_expansions, response);
    response->set_robot_radius_cells(call.robot_radius_cells);
    response->set_map_version(call.snapshot->version);
    response->set_planner(std::string(call.planner_name));
    FinishCall(call, absl::OkStatus(), outcome);
  }

  // Inflates (cached), plans and simplifies. `grid` is set to the grid the
  // path was planned on, for the response's world points.
  absl::StatusOr<PlanResult> PlanOn(const PlanCall& call, SearchScratch& scratch,
                                    const StopCondition& stop,
                                    std::shared_ptr<const Grid>& grid) {
    if (call.robot_radius_cells > 0.0) {
      PATHD_ASSIGN_OR_RETURN(grid, inflation_.Get(grid, call.robot_radius_cells));
      for (const auto& [cell, what] : {std::pair{call.core_request.start, "start"},
                                       std::pair{call.core_request.goal, "goal"}}) {
        if (grid->InBounds(cell) && grid->cost(cell) == kInscribedCost &&
            call.snapshot->grid->cost(cell) != kInscribedCost) {
          return absl::InvalidArgumentError(absl::StrFormat(
              "%s %s is within the robot radius (%g cells) of an obstacle", what,
              CellToString(cell), call.robot_radius_cells));
        }
      }
    }
    PATHD_ASSIGN_OR_RETURN(PlanResult result,
                           call.planner->Plan(*grid, call.core_request, stop, scratch));
    if (call.simplify && result.found()) {
      SimplifyPath(*grid, call.core_request.cost, &result);
    }
    return result;
  }

  void Drop() override {
    FinishCall(*call_, absl::UnavailableError("server is shutting down"),
               "DROPPED");
  }

 private:
  std::shared_ptr<PlanCall> call_;
  InflationCache& inflation_;
};

}  // namespace

PlannerServiceImpl::PlannerServiceImpl(const MapStore& store, WorkerPool& pool,
                                       InflationCache& inflation,
                                       NavigationSessions& sessions, Options options)
    : store_(store),
      pool_(pool),
      inflation_(inflation),
      sessions_(sessions),
      options_(options) {}

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
  auto* reactor = new PlanReactor(call);
  call->reactor = reactor;

  if (absl::Status s = Prepare(store_, options_.max_expansions, *call); !s.ok()) {
    FinishCall(*call, s, "REJECTED");
    return reactor;
  }
  // Once submitted, the job owns the answer and may already have finished the
  // call on a worker, so nothing below may touch `call` on success.
  if (absl::Status s = pool_.Submit(std::make_unique<PlanJob>(call, inflation_)); !s.ok()) {
    FinishCall(*call, s, "REJECTED");
  }
  return reactor;
}

}  // namespace pathd::server
