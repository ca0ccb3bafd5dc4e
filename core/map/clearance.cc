// Clearance costs on the bounded exact distance transform, and a path's
// clearance by ring search.
#include "core/map/clearance.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "absl/strings/str_format.h"
#include "core/map/cost_model.h"
#include "core/map/euclidean_distance.h"

namespace pathd {
namespace {

// Everything the robot centre may not occupy, and the map's outside.
DistanceSources ObstacleSources(bool unknown_is_free) {
  DistanceSources sources;
  for (int c = 0; c < 256; ++c) {
    sources.by_cost[c] = !Traversable(static_cast<uint8_t>(c), unknown_is_free);
  }
  sources.border = true;
  return sources;
}

// The exact distance (cells) from cell `c`'s centre to the nearest obstacle
// centre when it is below `bound`; otherwise a lower bound of it that is at
// least `bound`.
double NearestObstacle(const Grid& grid, Cell c, bool unknown_is_free, double bound) {
  // A path through an obstacle (a partial or foreign path) touches it.
  if (!grid.InBounds(c) || !Traversable(grid.cost(c), unknown_is_free)) return 0.0;
  // The outside ring: straight across to the nearest border.
  const int32_t to_border =
      std::min({c.x + 1, c.y + 1, grid.width() - c.x, grid.height() - c.y});
  int64_t best2 = static_cast<int64_t>(to_border) * to_border;
  // A ring at Chebyshev distance r holds no centre nearer than r.
  for (int32_t r = 1; static_cast<int64_t>(r) * r < best2; ++r) {
    if (r >= bound) return std::min(std::sqrt(static_cast<double>(best2)), static_cast<double>(r));
    auto visit = [&](int32_t x, int32_t y) {
      if (x < 0 || y < 0 || x >= grid.width() || y >= grid.height()) return;
      if (Traversable(grid.cost(Cell{x, y}), unknown_is_free)) return;
      const int64_t dx = x - c.x;
      const int64_t dy = y - c.y;
      best2 = std::min(best2, dx * dx + dy * dy);
    };
    for (int32_t i = -r; i <= r; ++i) {
      visit(c.x + i, c.y - r);
      visit(c.x + i, c.y + r);
    }
    for (int32_t i = -r + 1; i <= r - 1; ++i) {
      visit(c.x - r, c.y + i);
      visit(c.x + r, c.y + i);
    }
  }
  return std::sqrt(static_cast<double>(best2));
}

// The cells the path passes through, consecutive ones 8-adjacent: each
// segment sampled every quarter cell (a grid path's steps are single moves,
// an any-angle or simplified path's segments long).
std::vector<Cell> CellsPassed(absl::Span<const Cell> path) {
  std::vector<Cell> cells;
  if (path.empty()) return cells;
  cells.push_back(path.front());
  for (size_t i = 1; i < path.size(); ++i) {
    const Cell a = path[i - 1];
    const Cell b = path[i];
    const double dx = b.x - a.x;
    const double dy = b.y - a.y;
    const int samples = static_cast<int>(std::ceil(4.0 * std::max(std::abs(dx), std::abs(dy))));
    for (int k = 1; k <= samples; ++k) {
      const double t = static_cast<double>(k) / samples;
      const Cell at{static_cast<int32_t>(std::lround(a.x + t * dx)),
                    static_cast<int32_t>(std::lround(a.y + t * dy))};
      if (!(at == cells.back())) cells.push_back(at);
    }
  }
  return cells;
}

}  // namespace

uint8_t ClearanceCost(double distance, double min_clearance_cells) {
  if (!(distance < min_clearance_cells)) return 0;
  const double cost = std::ceil(static_cast<double>(kMaxTraversableCost) *
                                (min_clearance_cells - std::max(distance, 0.0)) /
                                min_clearance_cells);
  return static_cast<uint8_t>(
      std::clamp(cost, 1.0, static_cast<double>(kMaxTraversableCost)));
}

absl::Status ApplyClearanceCost(double min_clearance_cells, bool unknown_is_free,
                                Grid* grid) {
  if (!std::isfinite(min_clearance_cells) || min_clearance_cells <= 0.0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "minimum clearance %g cells must be finite and > 0", min_clearance_cells));
  }
  EuclideanDistanceField transform;
  ApplyClearanceCost(min_clearance_cells, unknown_is_free, transform, CellRect::Of(*grid),
                     grid);
  return absl::OkStatus();
}

void ApplyClearanceCost(double min_clearance_cells, bool unknown_is_free,
                        EuclideanDistanceField& transform, const CellRect& area,
                        Grid* grid) {
  if (grid->size() == 0) return;
  // Squared distances up to ceil(m^2) are all the ramp needs.
  const double m2 = std::ceil(min_clearance_cells * min_clearance_cells);
  const int64_t bound = static_cast<int64_t>(
      std::min(m2, static_cast<double>(std::numeric_limits<int32_t>::max())));
  const size_t w = static_cast<size_t>(grid->width());
  uint8_t* cells = grid->mutable_cells().data();
  transform.ForEachRowIn(
      *grid, ObstacleSources(unknown_is_free), bound, area.y0, area.y1,
      [&](int32_t y, const int64_t* row) {
        uint8_t* out = cells + static_cast<size_t>(y) * w;
        for (int32_t x = area.x0; x <= area.x1; ++x) {
          if (row[x] == EuclideanDistanceField::kFar) continue;
          const uint8_t c = out[x];
          if (!Traversable(c, unknown_is_free)) continue;
          const uint8_t penalty =
              ClearanceCost(std::sqrt(static_cast<double>(row[x])), min_clearance_cells);
          // An unknown cell traversed as free costs what a free cell does.
          const uint8_t own = c == kUnknownCost ? 0 : c;
          if (penalty > own) out[x] = penalty;
        }
      });
}

double PathClearance(const Grid& grid, absl::Span<const Cell> path,
                     bool unknown_is_free) {
  const std::vector<Cell> cells = CellsPassed(path);
  double smallest = std::numeric_limits<double>::infinity();
  // Clearance is 1-Lipschitz in the centre's position: after measuring d at
  // a cell, the next cells within (d - smallest) of walking cannot go lower.
  double skip_until = -1.0;
  double walked = 0.0;
  for (size_t i = 0; i < cells.size(); ++i) {
    if (i > 0) {
      walked += std::hypot(cells[i].x - cells[i - 1].x, cells[i].y - cells[i - 1].y);
    }
    if (walked < skip_until) continue;
    const double d = NearestObstacle(grid, cells[i], unknown_is_free, smallest);
    smallest = std::min(smallest, d);
    skip_until = walked + (d - smallest);
  }
  return smallest;
}

}  // namespace pathd
