// Felzenszwalb & Huttenlocher's separable exact Euclidean distance transform
// (Theory of Computing 8, 2012), specialised to binary sources: the column
// pass is two linear scans, the row pass the lower envelope of parabolas.
#include "core/map/euclidean_distance.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

namespace pathd {
namespace {

// Column distance of a cell with no source in its column. Its square (2^60)
// exceeds every bound Prepare() returns, so such cells never enter a row's
// envelope.
constexpr int32_t kNoneInColumn = int32_t{1} << 30;

// Bounds below (this radius + 1)^2 use WindowRow. The envelope costs about
// the same whatever the bound (2-3.5 ms on a 512 x 512 map); the window's
// 2r + 1 vectorised passes cost less up to about this radius.
constexpr int32_t kMaxWindowRadius = 16;
// A squared column distance WindowRow treats as "none": beyond every window
// bound, and adding a squared offset (<= kMaxWindowRadius^2) cannot overflow.
constexpr int32_t kOutsideWindow = int32_t{1} << 30;

// floor(sqrt(v)) exactly, or -1 for negative v.
int64_t FloorSqrt(int64_t v) {
  if (v < 0) return -1;
  auto root = static_cast<int64_t>(std::sqrt(static_cast<double>(v)));
  while (root * root > v) --root;
  while ((root + 1) * (root + 1) <= v) ++root;
  return root;
}

}  // namespace

int64_t SquaredRadiusBound(double r) {
  // floor(r * r) alone can be off by one when the product rounds across an
  // integer; fma gives the sign of r * r - n exactly. 2^40 > 2 *
  // (kMaxGridDimension + 1)^2.
  constexpr double kBeyondAnyGrid = 1099511627776.0;  // 2^40
  const double r2 = r * r;
  if (r2 >= kBeyondAnyGrid) return static_cast<int64_t>(kBeyondAnyGrid);
  double n = std::floor(r2);
  if (std::fma(r, r, -n) < 0.0) n -= 1.0;
  if (std::fma(r, r, -(n + 1.0)) >= 0.0) n += 1.0;
  return static_cast<int64_t>(n);
}

DistanceSources SourcesOfCost(uint8_t cost) {
  DistanceSources sources;
  sources.by_cost[cost] = true;
  return sources;
}

int64_t EuclideanDistanceField::Prepare(const Grid& grid,
                                   const DistanceSources& sources,
                                   int64_t max_squared) {
  const int32_t w = grid.width();
  const int32_t h = grid.height();
  const size_t n = grid.size();
  if (column_.size() < n) column_.resize(n);
  const size_t envelope = static_cast<size_t>(w) + 2;  // + the border pair
  if (apex_.size() < envelope) {
    apex_.resize(envelope);
    apex_height_.resize(envelope);
    start_num_.resize(envelope);
    start_den_.resize(envelope);
  }
  if (row_.size() < static_cast<size_t>(w)) row_.resize(w);

  const uint8_t* cells = grid.cells().data();
  // All ones for non-sources, zero for sources: the downward pass masks with
  // it instead of branching, which mispredicts on cluttered maps.
  std::array<int32_t, 256> keep;
  for (int c = 0; c < 256; ++c) keep[c] = sources.by_cost[c] ? 0 : -1;
  int32_t* col = column_.data();
  // Downwards: distance to the nearest source at or above. The value "one row
  // above the grid" is 0 when the border is a source.
  const int32_t above = sources.border ? 0 : kNoneInColumn;
  for (int32_t x = 0; x < w; ++x) {
    col[x] = std::min(above + 1, kNoneInColumn) & keep[cells[x]];
  }
  for (size_t i = static_cast<size_t>(w); i < n; ++i) {
    col[i] = std::min(col[i - w] + 1, kNoneInColumn) & keep[cells[i]];
  }
  // Upwards: the nearest source at or below, if nearer.
  const size_t last_row = static_cast<size_t>(h - 1) * static_cast<size_t>(w);
  if (sources.border) {
    for (size_t i = last_row; i < n; ++i) col[i] = std::min(col[i], 1);
  }
  for (size_t i = last_row; i-- > 0;) {
    col[i] = std::min(col[i], col[i + w] + 1);
  }

  // No squared distance on this grid exceeds the diagonal from a cell to the
  // far corner of the border ring; capping the bound there keeps every
  // product in LowerEnvelopeRow far inside int64.
  const int64_t diagonal =
      (int64_t{w} + 1) * (int64_t{w} + 1) + (int64_t{h} + 1) * (int64_t{h} + 1);
  const int64_t bound = std::min(max_squared, diagonal);
  const int64_t radius = FloorSqrt(bound);
  window_ = radius <= kMaxWindowRadius ? static_cast<int32_t>(radius) : -1;
  if (window_ >= 0) {
    const size_t padded = static_cast<size_t>(w) + 2 * kMaxWindowRadius;
    if (padded_.size() < padded) padded_.resize(padded);
    if (window_min_.size() < static_cast<size_t>(w)) window_min_.resize(w);
  }
  return bound;
}

void EuclideanDistanceField::DistanceRow(int32_t y, int32_t width, bool border,
                                    int64_t bound) {
  if (window_ >= 0) {
    WindowRow(y, width, border, bound);
  } else {
    LowerEnvelopeRow(y, width, border, bound);
  }
}

void EuclideanDistanceField::WindowRow(int32_t y, int32_t width, bool border,
                                  int64_t bound) {
  // Within the bound only columns x' with |x - x'| <= r can be nearest, so
  // row[x] = min over offsets o in [-r, r] of o^2 + g(x + o)^2, computed one
  // offset at a time across the whole row so the compiler vectorises it.
  const int32_t r = window_;
  const int32_t* col = column_.data() + static_cast<size_t>(y) * width;
  int32_t* padded = padded_.data();  // padded[r + x] holds column x
  std::fill(padded, padded + r, kOutsideWindow);
  std::fill(padded + r + width, padded + 2 * r + width, kOutsideWindow);
  if (border && r >= 1) {
    padded[r - 1] = 0;      // x = -1
    padded[r + width] = 0;  // x = width
  }
  for (int32_t x = 0; x < width; ++x) {
    const int32_t g = col[x];
    padded[r + x] = g <= r ? g * g : kOutsideWindow;
  }
  int32_t* best = window_min_.data();
  std::fill(best, best + width, kOutsideWindow);
  for (int32_t o = -r; o <= r; ++o) {
    const int32_t* shifted = padded + r + o;
    const int32_t o2 = o * o;
    for (int32_t x = 0; x < width; ++x) {
      best[x] = std::min(best[x], shifted[x] + o2);
    }
  }
  int64_t* row = row_.data();
  for (int32_t x = 0; x < width; ++x) {
    row[x] = best[x] <= bound ? best[x] : kFar;
  }
}

void EuclideanDistanceField::LowerEnvelopeRow(int32_t y, int32_t width, bool border,
                                         int64_t bound) {
  const int32_t* col = column_.data() + static_cast<size_t>(y) * width;
  int32_t* apex = apex_.data();
  int64_t* height = apex_height_.data();
  int64_t* start_num = start_num_.data();
  int64_t* start_den = start_den_.data();

  // Parabola p: (x - apex)^2 + height. A new parabola q meets the top one v at
  // s = ((h_q + q^2) - (h_v + v^2)) / (2 (q - v)); v is hidden when s is not
  // right of where v's interval starts. Comparing the fractions by cross
  // multiplication keeps it exact: numerators stay below ~2^35 and
  // denominators below 2^18.
  int top = -1;
  auto push = [&](int32_t q, int64_t h_q) {
    const int64_t offset_q = h_q + int64_t{q} * q;
    while (top >= 0) {
      const int64_t num =
          offset_q - (height[top] + int64_t{apex[top]} * apex[top]);
      const int64_t den = 2 * (int64_t{q} - apex[top]);
      if (top > 0 && num * start_den[top] <= start_num[top] * den) {
        --top;
        continue;
      }
      ++top;
      apex[top] = q;
      height[top] = h_q;
      start_num[top] = num;
      start_den[top] = den;
      return;
    }
    top = 0;
    apex[0] = q;
    height[0] = h_q;
  };
  if (border) push(-1, 0);
  for (int32_t x = 0; x < width; ++x) {
    const int64_t g = col[x];
    const int64_t h_x = g * g;
    // Also drops columns without a source (kNoneInColumn^2 > bound).
    if (h_x <= bound) push(x, h_x);
  }
  if (border) push(width, 0);

  int64_t* row = row_.data();
  if (top < 0) {
    std::fill(row, row + width, kFar);
    return;
  }
  int k = 0;
  for (int32_t x = 0; x < width; ++x) {
    while (k < top && start_num[k + 1] < int64_t{x} * start_den[k + 1]) ++k;
    const int64_t dx = int64_t{x} - apex[k];
    const int64_t d = dx * dx + height[k];
    // A value above the bound may come from a parabola standing in for a
    // dropped nearer one, so it is not exact: report only "beyond".
    row[x] = d <= bound ? d : kFar;
  }
}

void EuclideanDistanceField::PrepareChords(int64_t bound) {
  // The exact integer square root of the bound, so no chord is off by one.
  const int64_t root = FloorSqrt(bound);
  chord_limit_ = static_cast<int32_t>(root + 1);
  half_width_.resize(static_cast<size_t>(chord_limit_) + 1);
  int64_t h = root;
  for (int64_t g = 0; g <= root; ++g) {
    while (g * g + h * h > bound) --h;
    half_width_[g] = static_cast<int32_t>(h);
  }
  half_width_[chord_limit_] = -1;
  if (within_.size() < row_.size()) within_.resize(row_.size());
}

void EuclideanDistanceField::ChordRow(int32_t y, int32_t width, bool border) {
  const int32_t* col = column_.data() + static_cast<size_t>(y) * width;
  const int32_t* half_width = half_width_.data();
  const int32_t limit = chord_limit_;
  uint8_t* within = within_.data();
  // Column x' covers [x' - w(x'), x' + w(x')] with w its half width (-1:
  // nothing). Left to right, `reach` is the furthest right end of the chords
  // seen so far; right to left, the furthest left end. A border source at
  // x = -1 or width sits on this row's own level (column distance 0).
  int32_t reach = border ? -1 + half_width[0] : -1;
  for (int32_t x = 0; x < width; ++x) {
    reach = std::max(reach, x + half_width[std::min(col[x], limit)]);
    within[x] = reach >= x;
  }
  reach = border ? width - half_width[0] : width;
  for (int32_t x = width - 1; x >= 0; --x) {
    reach = std::min(reach, x - half_width[std::min(col[x], limit)]);
    within[x] |= reach <= x;
  }
}

const std::vector<int64_t>& EuclideanDistanceField::Compute(
    const Grid& grid, const DistanceSources& sources, int64_t max_squared) {
  result_.resize(grid.size());
  const size_t w = static_cast<size_t>(grid.width());
  ForEachRow(grid, sources, max_squared, [&](int32_t y, const int64_t* row) {
    std::copy(row, row + w, result_.begin() + static_cast<size_t>(y) * w);
  });
  return result_;
}

std::vector<double> SquaredDistanceToNearest(const Grid& grid,
                                             const DistanceSources& sources) {
  EuclideanDistanceField transform;
  const std::vector<int64_t>& squared = transform.Compute(grid, sources);
  std::vector<double> out(squared.size());
  for (size_t i = 0; i < squared.size(); ++i) {
    out[i] = squared[i] == EuclideanDistanceField::kFar
                 ? std::numeric_limits<double>::infinity()
                 : static_cast<double>(squared[i]);
  }
  return out;
}

}  // namespace pathd
