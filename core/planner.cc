// Stop condition, endpoint validation and path measurement shared by every
// planner.
#include "core/planner.h"

#include <cmath>
#include <cstdlib>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"

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
  }
  return "UNKNOWN";
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
  if (absl::Status s = ValidateEndpoint(grid, request.start, "start", request.cost);
      !s.ok()) {
    return s;
  }
  return ValidateEndpoint(grid, request.goal, "goal", request.cost);
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
