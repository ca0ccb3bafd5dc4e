// Stop condition, endpoint validation and path measurement shared by every
// planner.
#include "core/planner.h"

#include <cmath>
#include <cstdlib>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "core/line_of_sight.h"

namespace pathd {

std::string_view PlanOutcomeName(PlanOutcome outcome) {
  switch (outcome) {
    case PlanOutcome::kFound:
      return "FOUND";
    case PlanOutcome::kNoPath:
      return "NO_PATH";
    case PlanOutcome::kExpansionLimit:
      return "EXPANSION_LIMIT";
    case PlanOutcome::kTimeout:
      return "TIMEOUT";
    case PlanOutcome::kCancelled:
      return "CANCELLED";
    case PlanOutcome::kLocalMinimum:
      return "LOCAL_MINIMUM";
  }
  return "UNKNOWN";
}

std::string_view GuaranteeName(const PlannerTraits& traits) {
  if (traits.real_time) return "real-time";
  if (traits.any_angle) return "any-angle";
  if (traits.fewest_moves) return "fewest moves";
  if (traits.optimal) return "optimal";
  if (traits.bounded) return "bounded";
  return "heuristic";
}

PlanOutcome StopCondition::CheckNow() const {
  if (cancelled_ != nullptr && cancelled_->load(std::memory_order_relaxed)) {
    return PlanOutcome::kCancelled;
  }
  if (deadline_ != absl::InfiniteFuture() && absl::Now() >= deadline_) {
    return PlanOutcome::kTimeout;
  }
  return PlanOutcome::kFound;
}

namespace {

absl::Status ValidateEndpoint(const Grid& grid, Cell c, std::string_view what,
                              const CostParams& cost) {
  if (!grid.InBounds(c)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("%s %s is outside the %d x %d map", what,
                        CellToString(c), grid.width(), grid.height()));
  }
  const uint8_t v = grid.cost(c);
  if (!Traversable(v, cost.unknown_is_free)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "%s %s is on a blocked cell (cost %d)", what, CellToString(c), v));
  }
  return absl::OkStatus();
}

}  // namespace

absl::Status ValidateEndpoints(const Grid& grid, const PlanRequest& request) {
  // Search records index cells with uint32 and reserve the largest value.
  if (grid.size() == 0 || grid.size() >= SearchScratch::kNoParent) {
    return absl::InvalidArgumentError(
        absl::StrFormat("map has %d cells; planners need 1..%d", grid.size(),
                        SearchScratch::kNoParent - 1));
  }
  if (!std::isfinite(request.cost.cost_weight) || request.cost.cost_weight < 0.0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "cost_weight %g must be finite and >= 0", request.cost.cost_weight));
  }
  if (request.cost.connectivity != Connectivity::kFour &&
      request.cost.connectivity != Connectivity::kEight) {
    return absl::InvalidArgumentError("connectivity must be 4 or 8");
  }
  if (!(request.heuristic_weight >= 1.0) || !std::isfinite(request.heuristic_weight)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "heuristic_weight %g must be finite and >= 1", request.heuristic_weight));
  }
  if (request.lookahead < 0) {
    return absl::InvalidArgumentError(
        absl::StrFormat("lookahead %d must be >= 0", request.lookahead));
  }
  const PotentialFieldParams& pf = request.potential;
  for (const auto& [name, value] : {
           std::pair<const char*, double>{"attractive_gain", pf.attractive_gain},
           {"switch_distance", pf.switch_distance},
           {"repulsive_gain", pf.repulsive_gain},
           {"influence_distance", pf.influence_distance},
           {"step_size", pf.step_size},
       }) {
    if (!std::isfinite(value) || value <= 0.0) {
      return absl::InvalidArgumentError(
          absl::StrFormat("potential field %s %g must be finite and > 0", name, value));
    }
  }
  if (pf.max_steps < 0) {
    return absl::InvalidArgumentError(
        absl::StrFormat("potential field max_steps %d must be >= 0", pf.max_steps));
  }
  if (absl::Status s = ValidateEndpoint(grid, request.start, "start", request.cost);
      !s.ok()) {
    return s;
  }
  return ValidateEndpoint(grid, request.goal, "goal", request.cost);
}

absl::Status ValidateRequest(const Grid& grid, const PlanRequest& request,
                             std::string_view planner, const PlannerTraits& traits) {
  if (absl::Status s = ValidateEndpoints(grid, request); !s.ok()) return s;
  if (traits.needs_eight_connected &&
      request.cost.connectivity != Connectivity::kEight) {
    return absl::FailedPreconditionError(absl::StrFormat(
        "planner %s needs 8-connectivity; use astar for 4-connected search",
        planner));
  }
  if (traits.needs_uniform_cost && request.cost.cost_weight != 0.0) {
    // Traversable cells all cost the same only if they share one cost value.
    const std::vector<uint8_t>& cells = grid.cells();
    int first = -1;
    for (size_t i = 0; i < cells.size(); ++i) {
      if (!Traversable(cells[i], request.cost.unknown_is_free)) continue;
      // Unknown cells traversed as free cost like free cells.
      const int v = cells[i] == kUnknownCost ? kFreeCost : cells[i];
      if (first < 0) {
        first = v;
      } else if (v != first) {
        return absl::FailedPreconditionError(absl::StrFormat(
            "planner %s needs a map where every traversable cell costs the same, "
            "but cell %s has cost %d and others %d; use astar, or cost_weight 0 "
            "to ignore cell costs",
            planner, CellToString(grid.CellAt(i)), v, first));
      }
    }
  }
  return absl::OkStatus();
}

PathMeasure MeasureAnyAnglePath(const Grid& grid, const std::vector<Cell>& path,
                                const CostParams& cost) {
  PathMeasure m;
  if (path.empty()) return m;
  if (!grid.InBounds(path[0]) ||
      !Traversable(grid.cost(path[0]), cost.unknown_is_free)) {
    m.first_invalid = 0;
    return m;
  }
  for (size_t i = 1; i < path.size(); ++i) {
    if (!grid.InBounds(path[i]) || !LineOfSight(grid, path[i - 1], path[i], cost)) {
      m.first_invalid = i;
      return m;
    }
    m.length += SegmentLength(path[i - 1], path[i]);
    m.cost += SegmentCost(grid, path[i - 1], path[i], cost);
  }
  m.valid = true;
  return m;
}

PathMeasure MeasureResultPath(const Grid& grid, const PlanResult& result,
                              const CostParams& cost) {
  return result.any_angle ? MeasureAnyAnglePath(grid, result.path, cost)
                          : MeasurePath(grid, result.path, cost);
}

PathMeasure MeasurePath(const Grid& grid, const std::vector<Cell>& path,
                        const CostParams& cost) {
  PathMeasure m;
  if (path.empty()) return m;
  auto ok_cell = [&](Cell c) {
    return grid.InBounds(c) && Traversable(grid.cost(c), cost.unknown_is_free);
  };
  if (!ok_cell(path[0])) {
    m.first_invalid = 0;
    return m;
  }
  for (size_t i = 1; i < path.size(); ++i) {
    const Cell a = path[i - 1];
    const Cell b = path[i];
    const int dx = b.x - a.x;
    const int dy = b.y - a.y;
    const bool diagonal = dx != 0 && dy != 0;
    const bool adjacent = std::abs(dx) <= 1 && std::abs(dy) <= 1 && (dx || dy);
    bool legal = adjacent && ok_cell(b);
    if (legal && diagonal) {
      legal = cost.connectivity == Connectivity::kEight &&
              ok_cell(Cell{a.x + dx, a.y}) && ok_cell(Cell{a.x, a.y + dy});
    }
    if (!legal) {
      m.first_invalid = i;
      return m;
    }
    const double len = diagonal ? kSqrt2 : 1.0;
    m.length += len;
    m.cost += len * CellFactor(grid.cost(b), cost.cost_weight);
  }
  m.valid = true;
  return m;
}

}  // namespace pathd
