// proto <-> core translation.
#include "server/convert.h"

#include <cmath>
#include <utility>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"

namespace pathd::server {
namespace {

// Formats a double so NaN and infinities read as such in messages.
std::string Num(double v) { return absl::StrFormat("%g", v); }

}  // namespace

absl::StatusOr<Cell> CellFromPosition(const v1::Position& position,
                                      const Grid& grid, std::string_view what) {
  switch (position.kind_case()) {
    case v1::Position::kCell:
      return FromProto(position.cell());
    case v1::Position::kWorld: {
      const WorldPoint p{position.world().x(), position.world().y()};
      if (!std::isfinite(p.x) || !std::isfinite(p.y)) {
        return absl::InvalidArgumentError(
            absl::StrFormat("%s world point (%s, %s) is not finite", what,
                            Num(p.x), Num(p.y)));
      }
      absl::StatusOr<Cell> cell = grid.WorldToCell(p);
      if (!cell.ok()) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "%s world point (%s, %s) is outside the map: %s", what, Num(p.x),
            Num(p.y), cell.status().message()));
      }
      return *cell;
    }
    case v1::Position::KIND_NOT_SET:
      break;
  }
  return absl::InvalidArgumentError(
      absl::StrFormat("%s is not set (give a cell or a world point)", what));
}

absl::StatusOr<CostParams> CostParamsFromOptions(const v1::PlanOptions& options) {
  CostParams params;
  switch (options.connectivity()) {
    case v1::CONNECTIVITY_UNSPECIFIED:
    case v1::CONNECTIVITY_EIGHT:
      params.connectivity = Connectivity::kEight;
      break;
    case v1::CONNECTIVITY_FOUR:
      params.connectivity = Connectivity::kFour;
      break;
    default:
      return absl::InvalidArgumentError(absl::StrFormat(
          "options.connectivity: unknown connectivity %d",
          static_cast<int>(options.connectivity())));
  }
  if (options.has_cost_weight()) {
    const double w = options.cost_weight();
    if (!std::isfinite(w) || w < 0.0) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "options.cost_weight %s must be finite and >= 0", Num(w)));
    }
    params.cost_weight = w;
  } else {
    params.cost_weight = 1.0;
  }
  params.unknown_is_free = options.unknown_is_free();
  return params;
}

absl::StatusOr<int64_t> EffectiveMaxExpansions(const v1::PlanOptions& options,
                                               int64_t server_limit) {
  const int64_t requested = options.max_expansions();
  if (requested < 0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "options.max_expansions %d must be >= 0", requested));
  }
  if (server_limit <= 0) return requested;
  if (requested == 0) return server_limit;
  return std::min(requested, server_limit);
}

absl::StatusOr<std::string_view> PlannerName(int planner) {
  switch (planner) {
    case v1::PLANNER_UNSPECIFIED:
    case v1::PLANNER_ASTAR:
      return "astar";
    case v1::PLANNER_DIJKSTRA:
      return "dijkstra";
    case v1::PLANNER_BFS:
      return "bfs";
    default:
      return absl::InvalidArgumentError(
          absl::StrFormat("unknown planner %d", planner));
  }
}

v1::PlanOutcome ToProto(PlanOutcome outcome) {
  switch (outcome) {
    case PlanOutcome::kFound:
      return v1::PLAN_OUTCOME_FOUND;
    case PlanOutcome::kNoPath:
      return v1::PLAN_OUTCOME_NO_PATH;
    case PlanOutcome::kExpansionLimit:
      return v1::PLAN_OUTCOME_EXPANSION_LIMIT;
    case PlanOutcome::kTimeout:
      return v1::PLAN_OUTCOME_TIMEOUT;
    case PlanOutcome::kCancelled:
      return v1::PLAN_OUTCOME_CANCELLED;
  }
  return v1::PLAN_OUTCOME_UNSPECIFIED;
}

void FillPlanResponse(const PlanResult& result, const PlanRequest& request,
                      const Grid& grid, int64_t max_expansions,
                      v1::PlanResponse* response) {
  response->set_found(result.found());
  response->set_outcome(ToProto(result.outcome));
  *response->mutable_start() = ToProto(request.start);
  *response->mutable_goal() = ToProto(request.goal);
  response->set_expansions(result.expansions);
  response->set_planning_time_us(absl::ToInt64Microseconds(result.planning_time));
  switch (result.outcome) {
    case PlanOutcome::kFound:
      break;
    case PlanOutcome::kNoPath:
      response->set_reason(absl::StrFormat("no path from %s to %s",
                                           CellToString(request.start),
                                           CellToString(request.goal)));
      break;
    case PlanOutcome::kExpansionLimit:
      response->set_reason(absl::StrFormat(
          "expansion limit of %d reached before the goal", max_expansions));
      break;
    case PlanOutcome::kTimeout:
      response->set_reason(absl::StrFormat(
          "deadline passed after %d expansions", result.expansions));
      break;
    case PlanOutcome::kCancelled:
      response->set_reason("cancelled");
      break;
  }
  if (!result.found()) return;
  response->set_cost(result.cost);
  response->set_length(result.length);
  response->mutable_path()->Reserve(static_cast<int>(result.path.size()));
  response->mutable_world_path()->Reserve(static_cast<int>(result.path.size()));
  for (const Cell& c : result.path) {
    *response->add_path() = ToProto(c);
    const WorldPoint p = grid.CellCenter(c);
    v1::WorldPoint* w = response->add_world_path();
    w->set_x(p.x);
    w->set_y(p.y);
  }
}

void FillMapInfo(const MapSnapshot& snapshot, v1::MapInfo* info) {
  const Grid& grid = *snapshot.grid;
  info->set_name(snapshot.name);
  info->set_width(grid.width());
  info->set_height(grid.height());
  info->set_resolution(grid.resolution());
  v1::Origin* origin = info->mutable_origin();
  origin->set_x(grid.origin().x);
  origin->set_y(grid.origin().y);
  origin->set_yaw(grid.origin().yaw);
  info->set_version(snapshot.version);
  info->set_free_cells(grid.CountFree());
  info->set_blocked_cells(grid.CountBlocked());
}

absl::StatusOr<std::vector<MapChange>> MapChangesFromProto(
    const google::protobuf::RepeatedPtrField<v1::CellChange>& changes) {
  std::vector<MapChange> out;
  out.reserve(static_cast<size_t>(changes.size()));
  for (int i = 0; i < changes.size(); ++i) {
    const v1::CellChange& c = changes.Get(i);
    switch (c.target_case()) {
      case v1::CellChange::kCell:
        out.push_back(MapChange::ForCell(c.cell().x(), c.cell().y(), c.cost()));
        break;
      case v1::CellChange::kRect:
        out.push_back(MapChange::ForRect(c.rect().x_min(), c.rect().y_min(),
                                         c.rect().x_max(), c.rect().y_max(),
                                         c.cost()));
        break;
      case v1::CellChange::TARGET_NOT_SET:
        return absl::InvalidArgumentError(
            absl::StrFormat("change %d: neither cell nor rect is set", i));
    }
  }
  return out;
}

absl::StatusOr<double> ResolutionFromProto(double resolution) {
  if (resolution == 0.0) return 1.0;
  if (!std::isfinite(resolution) || resolution < 0.0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "resolution %s must be finite and > 0", Num(resolution)));
  }
  return resolution;
}

absl::StatusOr<GridOrigin> OriginFromProto(const v1::Origin& origin) {
  const std::pair<const char*, double> parts[] = {
      {"origin.x", origin.x()}, {"origin.y", origin.y()}, {"origin.yaw", origin.yaw()}};
  for (const auto& [field, value] : parts) {
    if (!std::isfinite(value)) {
      return absl::InvalidArgumentError(
          absl::StrFormat("%s %s must be finite", field, Num(value)));
    }
  }
  return GridOrigin{origin.x(), origin.y(), origin.yaw()};
}

absl::StatusOr<Grid> GridFromRawCells(const v1::RawCells& raw, const MapStore& store) {
  if (raw.width() <= 0 || raw.height() <= 0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "raw: width %d and height %d must be positive", raw.width(), raw.height()));
  }
  if (absl::Status s = store.CheckSize(raw.width(), raw.height()); !s.ok()) return s;
  const int64_t expected = int64_t{raw.width()} * int64_t{raw.height()};
  if (static_cast<int64_t>(raw.cells().size()) != expected) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "raw: width %d x height %d needs %d cells, got %d", raw.width(),
        raw.height(), expected, raw.cells().size()));
  }
  std::vector<uint8_t> cells(raw.cells().begin(), raw.cells().end());
  absl::StatusOr<Grid> grid = Grid::FromCells(raw.width(), raw.height(), std::move(cells));
  if (!grid.ok()) {
    return absl::InvalidArgumentError(
        absl::StrFormat("raw: %s", grid.status().message()));
  }
  return grid;
}

}  // namespace pathd::server
