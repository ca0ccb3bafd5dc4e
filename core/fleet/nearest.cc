// Nearest allowed cell by growing rings.
#include "core/fleet/nearest.h"

#include <algorithm>
#include <cmath>

#include "core/kinematics/pose.h"

namespace pathd {

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

std::function<bool(Cell)> FootprintFits(const Grid& grid, const FootprintChecker& checker,
                                        double yaw, bool unknown_is_free) {
  return [&grid, &checker, yaw, unknown_is_free](Cell c) {
    return !checker.CollidesExactly(grid, Pose{c.x + 0.5, c.y + 0.5, yaw}, unknown_is_free);
  };
}

}  // namespace pathd
