// CostToGo: DecodePlanQuery and the window on the gRPC thread, the field
// from the IncrementalCache on a worker, copied once into the response.
#include "server/rpc/cost_to_go.h"

#include <memory>
#include <utility>

#include "absl/strings/str_format.h"
#include "core/planning/plan_query.h"
#include "core/search/endpoints.h"
#include "core/status_macros.h"
#include "server/convert.h"
#include "server/request_log.h"
#include "server/rpc/unary_call.h"

namespace pathd::server {
namespace {

// Everything one CostToGo call needs; shared like PlanCall.
struct CostToGoCall : UnaryCall<v1::CostToGoRequest, v1::CostToGoResponse> {
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
};

void FinishCostToGo(CostToGoCall& call, const absl::Status& status,
                    std::string_view outcome) {
  LogRequest("CostToGo", call.request->map(), absl::StrFormat("outcome=%s", outcome),
             status, call.received);
  call.reactor->Finish(ToGrpcStatus(status));
}

// INVALID_ARGUMENT naming the window's field when it is empty or reaches
// outside the map.
absl::Status CheckWindow(const v1::CellWindow& w, const Grid& grid) {
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
  return check(w.y(), w.height(), grid.height(), "y", "height");
}

absl::Status PrepareCostToGo(const PlanDeps& deps, CostToGoCall& call) {
  const v1::CostToGoRequest& request = *call.request;
  PATHD_ASSIGN_OR_RETURN(
      DecodedQuery decoded,
      DecodePlanQuery(WireQueryOf(request), deps.store,
                      QueryLimits{.max_expansions = deps.limits.max_expansions}));
  call.snapshot = std::move(decoded.snapshot);
  const PlanQuery& query = decoded.query;
  call.max_expansions = query.max_expansions;
  call.expansion_limit_source = decoded.expansion_limit_source;
  const Grid& grid = *call.snapshot->grid;
  PATHD_RETURN_IF_ERROR(
      ValidateEndpoint(grid, query.request.goal, "goal", query.request.cost));
  PATHD_RETURN_IF_ERROR(CheckCostShaping(query));
  call.key = IncrementalCache::Key{.map = request.map(),
                                   .goal = query.request.goal,
                                   .cost = query.request.cost,
                                   .robot_radius_cells = query.robot_radius_cells,
                                   .inflation_radius_cells = query.inflation_radius_cells,
                                   .cost_scaling_per_cell = query.cost_scaling_per_cell,
                                   .min_clearance_cells = query.min_clearance_cells};
  call.x = 0;
  call.y = 0;
  call.width = grid.width();
  call.height = grid.height();
  if (request.has_window()) {
    const v1::CellWindow& w = request.window();
    PATHD_RETURN_IF_ERROR(CheckWindow(w, grid));
    call.x = w.x();
    call.y = w.y();
    call.width = w.width();
    call.height = w.height();
  }
  // 4 bytes per cell in a CostToGo message.
  const int64_t cells = int64_t{call.width} * call.height;
  if (cells > deps.limits.max_cost_to_go_cells) {
    return absl::ResourceExhaustedError(absl::StrFormat(
        "%s has %d cells; cost-to-go is returned for up to %d cells per call "
        "(--max_cost_to_go_cells): ask for windows",
        request.has_window() ? "the window" : "the map", cells,
        deps.limits.max_cost_to_go_cells));
  }
  return absl::OkStatus();
}

// The job's work: the field from the cache, its window into the response.
absl::Status AnswerCostToGo(CostToGoCall& call, InflationCache& inflation,
                            IncrementalCache& cache, int64_t max_message_bytes) {
  const IncrementalCache::Key& key = call.key;
  if (key.robot_radius_cells > 0.0) {
    PATHD_ASSIGN_OR_RETURN(std::shared_ptr<const Grid> inflated,
                           inflation.Get(*call.snapshot, key.robot_radius_cells));
    PATHD_RETURN_IF_ERROR(CheckRadiusEndpoints(*call.snapshot->grid, *inflated,
                                               key.robot_radius_cells,
                                               {{key.goal, "goal"}}));
  }
  const StopCondition stop(call.deadline, &call.cancelled, call.max_expansions);
  PATHD_ASSIGN_OR_RETURN(const IncrementalCache::SpmAnswer answer,
                         cache.GetSpm(key, call.snapshot, stop));
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
  if (absl::Status s =
          CheckResponseSize(response, "cost-to-go response", max_message_bytes);
      !s.ok()) {
    response.Clear();
    return s;
  }
  return absl::OkStatus();
}

}  // namespace

grpc::ServerUnaryReactor* ServeCostToGo(const PlanDeps& deps,
                                        grpc::CallbackServerContext* context,
                                        const v1::CostToGoRequest* request,
                                        v1::CostToGoResponse* response) {
  std::shared_ptr<CostToGoCall> call =
      StartUnaryCall<CostToGoCall>(context, request, response);
  const absl::Status prepared = PrepareCostToGo(deps, *call);
  auto work = [inflation = &deps.inflation, cache = &deps.cache,
               max_message_bytes = deps.limits.max_message_bytes](
                  CostToGoCall& call, SearchScratch&) -> Verdict {
    absl::Status status = AnswerCostToGo(call, *inflation, *cache, max_message_bytes);
    return {status, status.ok() ? "OK" : "ERROR"};
  };
  auto job = std::make_unique<CallJob<CostToGoCall>>(
      call, std::move(work), &FinishCostToGo,
      JobFailureText{"out of memory while building the field", "field build failed"});
  return AdmitUnaryCall(deps.pool, std::move(call), prepared, std::move(job),
                        &FinishCostToGo);
}

}  // namespace pathd::server
