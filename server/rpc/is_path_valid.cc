// IsPathValid: DecodePlanQuery for the options, the poses as cells, and the
// verdict (blocked poses, illegal steps, cost and length of a valid path).
#include "server/rpc/is_path_valid.h"

#include <algorithm>
#include <cmath>
#include <numbers>
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
  // options.footprint: the exact poses (headings facing the next pose when
  // a position has none) checked against it instead of the grid moves.
  std::shared_ptr<const FootprintChecker> footprint;
  std::vector<std::optional<Pose>> poses;
};

void FinishPathCheck(PathCheckCall& call, const absl::Status& status,
                     std::string_view outcome) {
  LogRequest("IsPathValid", call.request->map(),
             absl::StrFormat("poses=%d outcome=%s", call.request->path_size(),
                             outcome),
             status, call.received);
  call.reactor->Finish(ToGrpcStatus(status));
}

// call.poses from the request: exact positions; a position without a
// heading faces the next pose (the last, as the one before it). nullopt for
// a world point off the map (call.cells says so).
void PoseHeadings(PathCheckCall& call) {
  const v1::IsPathValidRequest& request = *call.request;
  const Grid& grid = *call.snapshot->grid;
  const int n = request.path_size();
  std::vector<std::optional<PositionPose>> exact(n);
  for (int i = 0; i < n; ++i) {
    if (!call.cells[i].has_value()) continue;
    absl::StatusOr<PositionPose> pose = PoseFromPosition(request.path(i), grid, "pose");
    if (pose.ok()) {
      exact[i] = *pose;
    } else {
      // A cell off the map: its centre, so the footprint check reports it.
      exact[i] = PositionPose{Pose::AtCellCenter(*call.cells[i]), false};
    }
  }
  call.poses.resize(n);
  for (int i = 0; i < n; ++i) {
    if (!exact[i].has_value()) continue;
    Pose pose = exact[i]->pose;
    if (!exact[i]->has_yaw) {
      const int a = i + 1 < n ? i : i - 1;
      if (a >= 0 && exact[a].has_value() && exact[a + 1].has_value()) {
        const Pose& from = exact[a]->pose;
        const Pose& to = exact[a + 1]->pose;
        if (from.x != to.x || from.y != to.y) pose.yaw = std::atan2(to.y - from.y, to.x - from.x);
      }
    }
    call.poses[i] = pose;
  }
}

// The footprint verdict: each pose, then each straight step between two
// poses sampled at most a quarter cell (and 2 degrees) apart; length is the
// sum of the steps.
void CheckFootprintOn(const Grid& grid, const PathCheckCall& call) {
  v1::IsPathValidResponse& response = *call.response;
  response.set_map_version(call.snapshot->version);
  response.set_robot_radius_cells(call.robot_radius_cells);
  response.set_footprint_checked(true);
  const bool unknown_is_free = call.cost.unknown_is_free;
  std::string reason;
  const auto note = [&reason](std::string text) {
    if (reason.empty()) reason = std::move(text);
  };
  double length = 0.0;
  for (size_t i = 0; i < call.poses.size(); ++i) {
    const int index = static_cast<int>(i);
    const std::optional<Pose>& pose = call.poses[i];
    if (!pose.has_value()) {
      response.add_invalid_indices(index);
      note(absl::StrFormat("pose %d: the world point is outside the map", index));
      continue;
    }
    if (call.footprint->CollidesExactly(grid, *pose, unknown_is_free)) {
      response.add_invalid_indices(index);
      note(absl::StrFormat(
          "pose %d (%.3f, %.3f) facing %.3f rad: the footprint touches a blocked cell "
          "or leaves the map",
          index, pose->x, pose->y, pose->yaw));
    }
    if (i == 0 || !call.poses[i - 1].has_value()) continue;
    const Pose& from = *call.poses[i - 1];
    const double dx = pose->x - from.x, dy = pose->y - from.y;
    const double turn = NormalizeAngle(pose->yaw - from.yaw);
    const double step = std::hypot(dx, dy);
    length += step;
    const int samples = static_cast<int>(std::max(
        {1.0, std::ceil(step / 0.25), std::ceil(std::fabs(turn) / (std::numbers::pi / 90))}));
    for (int k = 1; k < samples; ++k) {
      const double t = static_cast<double>(k) / samples;
      const Pose between{from.x + t * dx, from.y + t * dy, from.yaw + t * turn};
      if (call.footprint->CollidesExactly(grid, between, unknown_is_free)) {
        response.add_invalid_steps(index);
        note(absl::StrFormat(
            "step %d -> %d: the footprint touches a blocked cell near (%.3f, %.3f) facing "
            "%.3f rad",
            index - 1, index, between.x, between.y, between.yaw));
        break;
      }
    }
  }
  response.set_valid(reason.empty());
  response.set_reason(reason);
  if (response.valid()) {
    response.set_length(length);
    response.set_length_m(length * grid.resolution());
  }
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
  PATHD_ASSIGN_OR_RETURN(const std::optional<Footprint> footprint,
                         FootprintFromOptions(request.options(), grid));
  if (footprint.has_value()) {
    // The footprint is checked exactly, not through its inscribed radius.
    PATHD_ASSIGN_OR_RETURN(call.robot_radius_cells, RobotRadiusCells(request.options(), grid));
    PATHD_ASSIGN_OR_RETURN(call.footprint, SharedFootprintChecker(*footprint, {.headings = 72}));
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
  if (call.footprint != nullptr) PoseHeadings(call);
  return absl::OkStatus();
}

// Checks call.cells on `grid` (the snapshot, inflated when a robot radius was
// given) and fills the verdict into call.response; with a footprint,
// CheckFootprintOn.
void CheckPathOn(const Grid& grid, const PathCheckCall& call) {
  if (call.footprint != nullptr) return CheckFootprintOn(grid, call);
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
  response.set_length_m(measure.length * grid.resolution());
}

}  // namespace

grpc::ServerUnaryReactor* ServeIsPathValid(const PlanDeps& deps,
                                           grpc::CallbackServerContext* context,
                                           const v1::IsPathValidRequest* request,
                                           v1::IsPathValidResponse* response) {
  std::shared_ptr<PathCheckCall> call =
      StartUnaryCall<PathCheckCall>(context, request, response);
  const absl::Status prepared = PreparePathCheck(deps, *call);
  if (prepared.ok() && call->robot_radius_cells <= 0.0 && call->footprint == nullptr) {
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
        call.robot_radius_cells > 0.0
            ? inflation->Get(*call.snapshot, call.robot_radius_cells)
            : absl::StatusOr<std::shared_ptr<const Grid>>(call.snapshot->grid);
    if (!inflated.ok()) return {inflated.status(), "ERROR"};
    CheckPathOn(**inflated, call);
    return {absl::OkStatus(), call.response->valid() ? "VALID" : "INVALID"};
  };
  auto job = std::make_unique<CallJob<PathCheckCall>>(
      call, std::move(work), &FinishPathCheck,
      JobFailureText{"out of memory while inflating the map", "path check failed"});
  return AdmitUnaryCall(deps.pool, std::move(call), prepared, std::move(job),
                        &FinishPathCheck, JobLength::kUsuallyShort);
}

}  // namespace pathd::server
