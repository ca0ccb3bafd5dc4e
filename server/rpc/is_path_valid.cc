// IsPathValid: DecodePlanQuery for the options, the poses as cells, and the
// verdict (blocked poses, illegal steps, cost and length of a valid path).
#include "server/rpc/is_path_valid.h"

#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "absl/strings/str_format.h"
#include "core/search/path_measure.h"
#include "core/status_macros.h"
#include "server/convert.h"
#include "server/request_log.h"
#include "server/rpc/unary_call.h"

namespace pathd::server {
namespace {

// Everything one IsPathValid call needs; shared like PlanCall when it runs on
// the pool.
struct PathCheckCall : UnaryCall<v1::IsPathValidRequest, v1::IsPathValidResponse> {
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
// request and is checked in 60-90 ms on the gRPC thread (docs/service.md).
absl::Status PreparePathCheck(const PlanDeps& deps, PathCheckCall& call) {
  const v1::IsPathValidRequest& request = *call.request;
  PATHD_ASSIGN_OR_RETURN(DecodedQuery decoded,
                         DecodePlanQuery(WireQueryOf(request), deps.store, QueryLimits{}));
  call.snapshot = std::move(decoded.snapshot);
  call.cost = decoded.query.request.cost;
  call.robot_radius_cells = decoded.query.robot_radius_cells;
  const Grid& grid = *call.snapshot->grid;
  const int64_t max_path_points = deps.limits.max_path_points;
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

}  // namespace

grpc::ServerUnaryReactor* ServeIsPathValid(const PlanDeps& deps,
                                           grpc::CallbackServerContext* context,
                                           const v1::IsPathValidRequest* request,
                                           v1::IsPathValidResponse* response) {
  std::shared_ptr<PathCheckCall> call =
      StartUnaryCall<PathCheckCall>(context, request, response);
  const absl::Status prepared = PreparePathCheck(deps, *call);
  if (prepared.ok() && call->robot_radius_cells <= 0.0) {
    // O(path): answered here rather than queued behind plans.
    CheckPathOn(*call->snapshot->grid, *call);
    FinishPathCheck(*call, absl::OkStatus(), response->valid() ? "VALID" : "INVALID");
    return call->reactor;
  }
  // Inflating a map version for the first time is O(map), too much for a
  // gRPC thread.
  auto work = [inflation = &deps.inflation](PathCheckCall& call,
                                            SearchScratch&) -> Verdict {
    absl::StatusOr<std::shared_ptr<const Grid>> inflated =
        inflation->Get(*call.snapshot, call.robot_radius_cells);
    if (!inflated.ok()) return {inflated.status(), "ERROR"};
    CheckPathOn(**inflated, call);
    return {absl::OkStatus(), call.response->valid() ? "VALID" : "INVALID"};
  };
  auto job = std::make_unique<CallJob<PathCheckCall>>(
      call, std::move(work), &FinishPathCheck,
      JobFailureText{"out of memory while inflating the map", "path check failed"});
  return AdmitUnaryCall(deps.pool, std::move(call), prepared, std::move(job),
                        &FinishPathCheck);
}

}  // namespace pathd::server
