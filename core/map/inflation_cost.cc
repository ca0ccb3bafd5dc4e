// Nav2's inflation costs on the bounded exact distance transform, one cost
// per squared distance looked up from a table.
#include "core/map/inflation_cost.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "absl/strings/str_format.h"

namespace pathd {
namespace {

// Beyond this many squared distances the costs are computed per cell
// rather than tabled (a table of 2^20 bytes covers radii up to ~1000 cells
// past the robot radius).
constexpr int64_t kMaxTable = int64_t{1} << 20;

// The exponential part of Nav2's computeCost, for a distance beyond the
// inscribed radius.
uint8_t DecayCost(double distance, double inscribed, double scaling) {
  return static_cast<uint8_t>((kInscribedCost - 1) *
                              std::exp(-scaling * (distance - inscribed)));
}

}  // namespace

uint8_t InflationCost(double distance_cells, double inscribed_radius_cells,
                      double cost_scaling_per_cell) {
  if (distance_cells == 0.0) return kLethalCost;
  if (distance_cells <= inscribed_radius_cells) return kInscribedCost;
  return DecayCost(distance_cells, inscribed_radius_cells, cost_scaling_per_cell);
}

absl::Status CheckInflationCost(double robot_radius_cells, double inflation_radius_cells,
                                double cost_scaling_per_cell) {
  if (!std::isfinite(inflation_radius_cells) || inflation_radius_cells < 0.0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "inflation radius %g cells must be finite and >= 0", inflation_radius_cells));
  }
  if (inflation_radius_cells < robot_radius_cells) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "inflation radius %g cells is smaller than the robot radius %g cells; "
        "costs apply between the two",
        inflation_radius_cells, robot_radius_cells));
  }
  if (!std::isfinite(cost_scaling_per_cell) || cost_scaling_per_cell <= 0.0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "cost scaling %g per cell must be finite and > 0", cost_scaling_per_cell));
  }
  return absl::OkStatus();
}

double InflationCostReach(double robot_radius_cells, double inflation_radius_cells,
                          double cost_scaling_per_cell) {
  const double fades =
      robot_radius_cells +
      (std::log(static_cast<double>(kInscribedCost - 1)) + 1.0) / cost_scaling_per_cell;
  return std::min(inflation_radius_cells, fades);
}

absl::Status ApplyInflationCost(double robot_radius_cells, double inflation_radius_cells,
                                double cost_scaling_per_cell, bool unknown_is_free,
                                Grid* grid) {
  if (!std::isfinite(robot_radius_cells) || robot_radius_cells < 0.0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "robot radius %g cells must be finite and >= 0", robot_radius_cells));
  }
  if (absl::Status s = CheckInflationCost(robot_radius_cells, inflation_radius_cells,
                                          cost_scaling_per_cell);
      !s.ok()) {
    return s;
  }
  EuclideanDistanceField transform;
  ApplyInflationCost(robot_radius_cells, robot_radius_cells, inflation_radius_cells,
                     cost_scaling_per_cell, unknown_is_free, transform, CellRect::Of(*grid),
                     grid);
  return absl::OkStatus();
}

void ApplyInflationCost(double robot_radius_cells, double decay_radius_cells,
                        double inflation_radius_cells, double cost_scaling_per_cell,
                        bool unknown_is_free, EuclideanDistanceField& transform,
                        const CellRect& area, Grid* grid) {
  if (grid->size() == 0) return;
  // Squared distances in (inner, outer] get a cost: beyond the robot radius
  // (exactly: d2 <= inner is within it) and within the reach.
  const int64_t inner = SquaredRadiusBound(robot_radius_cells);
  const int64_t outer = SquaredRadiusBound(InflationCostReach(
      decay_radius_cells, inflation_radius_cells, cost_scaling_per_cell));
  if (outer <= inner) return;
  auto cost_at = [&](int64_t d2) {
    const double d = std::sqrt(static_cast<double>(d2));
    if (d <= decay_radius_cells) return static_cast<uint8_t>(kInscribedCost - 1);
    return DecayCost(d, decay_radius_cells, cost_scaling_per_cell);
  };
  std::vector<uint8_t> table;
  if (outer - inner <= kMaxTable) {
    table.resize(static_cast<size_t>(outer - inner));
    for (int64_t d2 = inner + 1; d2 <= outer; ++d2) {
      table[static_cast<size_t>(d2 - inner - 1)] = cost_at(d2);
    }
  }
  const size_t w = static_cast<size_t>(grid->width());
  uint8_t* cells = grid->mutable_cells().data();
  transform.ForEachRowIn(
      *grid, SourcesOfCost(kLethalCost), outer, area.y0, area.y1,
      [&](int32_t y, const int64_t* row) {
        uint8_t* out = cells + static_cast<size_t>(y) * w;
        for (int32_t x = area.x0; x <= area.x1; ++x) {
          const int64_t d2 = row[x];
          // kFar (no lethal cell within the reach) is above outer too.
          if (d2 <= inner || d2 > outer) continue;
          const uint8_t c = out[x];
          uint8_t own = c;
          if (c >= kInscribedCost) {
            if (c != kUnknownCost || !unknown_is_free) continue;
            own = kFreeCost;
          }
          const uint8_t cost =
              table.empty() ? cost_at(d2) : table[static_cast<size_t>(d2 - inner - 1)];
          if (cost > own) out[x] = cost;
        }
      });
}

}  // namespace pathd
