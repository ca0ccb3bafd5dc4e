// Obstacle inflation on the exact distance transform thresholded at the
// radius (EuclideanDistanceField::ForEachRowWithin).
#include "core/map/inflation.h"

#include <cmath>
#include <cstdint>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "core/map/clearance.h"
#include "core/map/euclidean_distance.h"
#include "core/status_macros.h"

namespace pathd {
namespace {

// The largest integer n with n <= r^2 in exact arithmetic, so that an integer
// squared distance d2 is within the radius exactly when d2 <= n. floor(r * r)
// alone can be off by one when the product rounds across an integer; fma
// gives the sign of r * r - n exactly. Radii beyond any grid's diagonal are
// clamped (2^40 > 2 * (kMaxGridDimension + 1)^2).
int64_t SquaredRadiusBound(double r) {
  constexpr double kBeyondAnyGrid = 1099511627776.0;  // 2^40
  const double r2 = r * r;
  if (r2 >= kBeyondAnyGrid) return static_cast<int64_t>(kBeyondAnyGrid);
  double n = std::floor(r2);
  if (std::fma(r, r, -n) < 0.0) n -= 1.0;
  if (std::fma(r, r, -(n + 1.0)) >= 0.0) n += 1.0;
  return static_cast<int64_t>(n);
}

}  // namespace

absl::StatusOr<Grid> InflateObstacles(const Grid& grid, double radius_cells) {
  if (!std::isfinite(radius_cells) || radius_cells < 0.0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "robot radius %g cells must be finite and >= 0", radius_cells));
  }
  Grid inflated = grid;
  const int64_t bound = SquaredRadiusBound(radius_cells);
  // Below radius 1 only the lethal cells themselves are within reach.
  if (bound == 0 || grid.size() == 0) return inflated;

  // One transform per call: its O(cells) buffers cost less than a lock or a
  // thread-local cache would, and the server caches the inflated grid anyway.
  EuclideanDistanceField transform;
  const size_t w = static_cast<size_t>(grid.width());
  const uint8_t* in = grid.cells().data();
  uint8_t* out = inflated.mutable_cells().data();
  transform.ForEachRowWithin(
      grid, SourcesOfCost(kLethalCost), bound,
      [&](int32_t y, const uint8_t* within) {
        const size_t begin = static_cast<size_t>(y) * w;
        for (size_t x = 0; x < w; ++x) {
          const uint8_t c = in[begin + x];
          // Branch-free so the loop vectorises.
          out[begin + x] = (within[x] & (c < kLethalCost)) ? kInscribedCost : c;
        }
      });
  return inflated;
}

absl::StatusOr<Grid> ShapeGrid(const Grid& grid, const GridShape& shape) {
  PATHD_ASSIGN_OR_RETURN(Grid shaped, InflateObstacles(grid, shape.robot_radius_cells));
  if (shape.min_clearance_cells > 0.0) {
    PATHD_RETURN_IF_ERROR(ApplyClearanceCost(shape.min_clearance_cells,
                                             shape.unknown_is_free, &shaped));
  }
  return shaped;
}

}  // namespace pathd
