// Endpoint and option validation, endpoint faults as status payloads, the
// nearest traversable cell, goal tolerance and robot-radius endpoint checks.
#include "core/search/endpoints.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>
#include <utility>

#include "absl/status/status.h"
#include "absl/strings/cord.h"
#include "absl/strings/str_format.h"

namespace pathd {

namespace {

// Payload key of EndpointFault; the value is the enumerator's number.
constexpr char kEndpointFaultUrl[] = "type.pathd.dev/pathd.EndpointFault";

}  // namespace

absl::Status ValidateEndpoint(const Grid& grid, Cell c, std::string_view what,
                              const CostParams& cost) {
  absl::Status fault_status;
  bool outside = false;
  if (!grid.InBounds(c)) {
    outside = true;
    fault_status = absl::InvalidArgumentError(
        absl::StrFormat("%s %s is outside the %d x %d map", what, CellToString(c),
                        grid.width(), grid.height()));
  } else if (const uint8_t v = grid.cost(c); !Traversable(v, cost.unknown_is_free)) {
    fault_status = absl::InvalidArgumentError(absl::StrFormat(
        "%s %s is on a blocked cell (cost %d)", what, CellToString(c), v));
  } else {
    return absl::OkStatus();
  }
  if (const std::optional<EndpointFault> fault = EndpointFaultFor(what, outside)) {
    return WithEndpointFault(std::move(fault_status), *fault);
  }
  return fault_status;
}

absl::Status WithEndpointFault(absl::Status status, EndpointFault fault) {
  status.SetPayload(kEndpointFaultUrl,
                    absl::Cord(std::to_string(static_cast<int>(fault))));
  return status;
}

std::optional<EndpointFault> EndpointFaultOf(const absl::Status& status) {
  const auto payload = status.GetPayload(kEndpointFaultUrl);
  if (!payload.has_value()) return std::nullopt;
  for (const EndpointFault fault :
       {EndpointFault::kStartOutsideMap, EndpointFault::kGoalOutsideMap,
        EndpointFault::kStartBlocked, EndpointFault::kGoalBlocked}) {
    if (*payload == std::to_string(static_cast<int>(fault))) return fault;
  }
  return std::nullopt;
}

std::optional<EndpointFault> EndpointFaultFor(std::string_view what, bool outside) {
  if (what == "start") {
    return outside ? EndpointFault::kStartOutsideMap : EndpointFault::kStartBlocked;
  }
  if (what == "goal") {
    return outside ? EndpointFault::kGoalOutsideMap : EndpointFault::kGoalBlocked;
  }
  return std::nullopt;
}

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

std::optional<NearestCell> NearestAllowedCell(const Grid& grid, Cell target,
                                              double max_distance,
                                              const std::function<bool(Cell)>& allowed) {
  if (!(max_distance >= 0.0)) return std::nullopt;
  const double max_d2 = max_distance * max_distance;
  // Rings past the grid's far side hold no cell.
  const int64_t far = std::max<int64_t>(
      std::max<int64_t>(std::abs(int64_t{target.x}), std::abs(int64_t{target.x} - grid.width())),
      std::max<int64_t>(std::abs(int64_t{target.y}), std::abs(int64_t{target.y} - grid.height())));
  const int64_t max_ring =
      std::min<int64_t>(static_cast<int64_t>(std::floor(max_distance)), far);
  std::optional<NearestCell> best;
  int64_t best_d2 = 0;
  int64_t tested = 0;
  const auto consider = [&](int64_t x, int64_t y) {
    if (x < 0 || y < 0 || x >= grid.width() || y >= grid.height()) return;
    const int64_t dx = x - target.x;
    const int64_t dy = y - target.y;
    const int64_t d2 = dx * dx + dy * dy;
    if (static_cast<double>(d2) > max_d2) return;
    const Cell c{static_cast<int32_t>(x), static_cast<int32_t>(y)};
    // Only a candidate that would win needs the (possibly costly) test.
    if (best.has_value() &&
        (d2 > best_d2 || (d2 == best_d2 && (c.y > best->cell.y ||
                                            (c.y == best->cell.y && c.x > best->cell.x))))) {
      return;
    }
    ++tested;
    if (!allowed(c)) return;
    best = NearestCell{c, std::sqrt(static_cast<double>(d2)), 0};
    best_d2 = d2;
  };
  for (int64_t r = 0; r <= max_ring; ++r) {
    // Every cell of ring r is at least r from the target.
    if (best.has_value() && best_d2 < r * r) break;
    if (r == 0) {
      consider(target.x, target.y);
      continue;
    }
    for (int64_t x = int64_t{target.x} - r; x <= int64_t{target.x} + r; ++x) {
      consider(x, int64_t{target.y} - r);
      consider(x, int64_t{target.y} + r);
    }
    for (int64_t y = int64_t{target.y} - r + 1; y <= int64_t{target.y} + r - 1; ++y) {
      consider(int64_t{target.x} - r, y);
      consider(int64_t{target.x} + r, y);
    }
  }
  if (best.has_value()) best->tested = tested;
  return best;
}

std::optional<Cell> NearestTraversableCell(const Grid& grid, Cell target,
                                           double max_distance,
                                           const CostParams& cost) {
  const std::optional<NearestCell> nearest =
      NearestAllowedCell(grid, target, max_distance, [&](Cell c) {
        return Traversable(grid.cost(c), cost.unknown_is_free);
      });
  if (!nearest.has_value()) return std::nullopt;
  return nearest->cell;
}

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

absl::Status CheckRadiusEndpoints(
    const Grid& stored, const Grid& inflated, double radius_cells,
    std::initializer_list<std::pair<Cell, std::string_view>> endpoints) {
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

}  // namespace pathd
