// Obstacle inflation on the exact distance transform thresholded at the
// radius (EuclideanDistanceField::ForEachRowWithin); the shaping pipeline,
// in full or over padded windows around a version's changed cells.
#include "core/map/inflation.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "core/map/clearance.h"
#include "core/map/euclidean_distance.h"
#include "core/map/inflation_cost.h"
#include "core/status_macros.h"

namespace pathd {
namespace {

// Marks the cells of `area` within the radius of a lethal cell inscribed, in
// place (the transform's column pass reads the whole grid before any row is
// written). Precondition: radius finite and >= 0.
void InflateInPlace(double radius_cells, EuclideanDistanceField& transform,
                    const CellRect& area, Grid* grid) {
  const int64_t bound = SquaredRadiusBound(radius_cells);
  // Below radius 1 only the lethal cells themselves are within reach.
  if (bound == 0 || grid->size() == 0) return;
  const size_t w = static_cast<size_t>(grid->width());
  uint8_t* cells = grid->mutable_cells().data();
  transform.ForEachRowWithinIn(
      *grid, SourcesOfCost(kLethalCost), bound, area.y0, area.y1,
      [&](int32_t y, const uint8_t* within) {
        uint8_t* row = cells + static_cast<size_t>(y) * w;
        for (int32_t x = area.x0; x <= area.x1; ++x) {
          const uint8_t c = row[x];
          // Branch-free so the loop vectorises.
          row[x] = (within[x] & (c < kLethalCost)) ? kInscribedCost : c;
        }
      });
}

// ShapeGrid's steps on `grid` in place, sharing one transform, for the cells
// of `area` (exact there; other cells are left partly shaped). The clearance
// of an area cell reads whether cells closer than the clearance are blocked,
// so the radius's inflation covers the area grown by it; the inflation
// costs block nothing and cover the area only. Precondition:
// CheckGridShape(shape) is OK.
void ShapeInPlace(const GridShape& shape, EuclideanDistanceField& transform,
                  const CellRect& area, Grid* grid) {
  CellRect blocked = area;
  if (shape.min_clearance_cells > 0.0) {
    const auto grow = static_cast<int32_t>(std::ceil(shape.min_clearance_cells));
    blocked = CellRect{std::max(area.x0 - grow, 0), std::max(area.y0 - grow, 0),
                       std::min(area.x1 + grow, grid->width() - 1),
                       std::min(area.y1 + grow, grid->height() - 1)};
  }
  InflateInPlace(shape.robot_radius_cells, transform, blocked, grid);
  if (shape.has_inflation_cost()) {
    ApplyInflationCost(shape.robot_radius_cells, shape.decay_radius_cells(),
                       shape.inflation_radius_cells, shape.cost_scaling_per_cell,
                       shape.unknown_is_free, transform, area, grid);
  }
  if (shape.min_clearance_cells > 0.0) {
    ApplyClearanceCost(shape.min_clearance_cells, shape.unknown_is_free, transform, area,
                       grid);
  }
}

// Cells of `b` grown by `pad` on every side (not clipped: for comparing).
int64_t PaddedArea(const CellRect& b, int32_t pad) {
  return (int64_t{b.x1} - b.x0 + 1 + 2 * int64_t{pad}) *
         (int64_t{b.y1} - b.y0 + 1 + 2 * int64_t{pad});
}

CellRect Clip(CellRect b, int32_t pad, const Grid& grid) {
  return CellRect{std::max(b.x0 - pad, 0), std::max(b.y0 - pad, 0),
                  std::min(b.x1 + pad, grid.width() - 1),
                  std::min(b.y1 + pad, grid.height() - 1)};
}

int64_t Area(const CellRect& b) {
  return (int64_t{b.x1} - b.x0 + 1) * (int64_t{b.y1} - b.y0 + 1);
}

// Merging is only for speed (every window is exact on its own, and
// overlapping windows write the same bytes), so it gives up on many boxes
// rather than spend O(boxes^2) on them.
constexpr size_t kMaxBoxesToMerge = 2048;
constexpr int kMaxMergePasses = 4;

// Merges two boxes into their bounding box where shaping that once costs no
// more than shaping both (their padded windows overlap enough).
void MergeBoxes(int32_t pad, std::vector<CellRect>* boxes) {
  if (boxes->size() > kMaxBoxesToMerge) return;
  std::vector<CellRect>& b = *boxes;
  std::sort(b.begin(), b.end(),
            [](const CellRect& l, const CellRect& r) { return l.x0 < r.x0; });
  std::vector<bool> gone(b.size(), false);
  for (int pass = 0; pass < kMaxMergePasses; ++pass) {
    bool merged = false;
    for (size_t i = 0; i < b.size(); ++i) {
      if (gone[i]) continue;
      for (size_t j = i + 1; j < b.size(); ++j) {
        // Sorted by x0 (a merge keeps box i's): the rest start too far right
        // for their padded windows to meet box i's.
        if (int64_t{b[j].x0} > int64_t{b[i].x1} + 2 * int64_t{pad} + 1) break;
        if (gone[j]) continue;
        const CellRect both{b[i].x0, std::min(b[i].y0, b[j].y0),
                            std::max(b[i].x1, b[j].x1), std::max(b[i].y1, b[j].y1)};
        if (PaddedArea(both, pad) <= PaddedArea(b[i], pad) + PaddedArea(b[j], pad)) {
          b[i] = both;
          gone[j] = true;
          merged = true;
        }
      }
    }
    if (!merged) break;
  }
  size_t kept = 0;
  for (size_t i = 0; i < b.size(); ++i) {
    if (!gone[i]) b[kept++] = b[i];
  }
  b.resize(kept);
}

}  // namespace

absl::StatusOr<Grid> InflateObstacles(const Grid& grid, double radius_cells) {
  if (!std::isfinite(radius_cells) || radius_cells < 0.0) {
    return absl::InvalidArgumentError(
        absl::StrFormat("robot radius %g cells must be finite and >= 0", radius_cells));
  }
  Grid inflated = grid;
  // One transform per call: its O(cells) buffers cost less than a lock or a
  // thread-local cache would, and the server caches the inflated grid anyway.
  EuclideanDistanceField transform;
  InflateInPlace(radius_cells, transform, CellRect::Of(inflated), &inflated);
  return inflated;
}

absl::Status CheckGridShape(const GridShape& shape) {
  if (!std::isfinite(shape.robot_radius_cells) || shape.robot_radius_cells < 0.0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "robot radius %g cells must be finite and >= 0", shape.robot_radius_cells));
  }
  if (!std::isfinite(shape.cost_inscribed_cells) || shape.cost_inscribed_cells < 0.0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "inscribed radius %g cells must be finite and >= 0", shape.cost_inscribed_cells));
  }
  if (shape.has_inflation_cost()) {
    PATHD_RETURN_IF_ERROR(CheckInflationCost(shape.decay_radius_cells(),
                                             shape.inflation_radius_cells,
                                             shape.cost_scaling_per_cell));
  }
  if (shape.min_clearance_cells > 0.0 && !std::isfinite(shape.min_clearance_cells)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "minimum clearance %g cells must be finite and > 0", shape.min_clearance_cells));
  }
  return absl::OkStatus();
}

absl::StatusOr<Grid> ShapeGrid(const Grid& grid, const GridShape& shape) {
  PATHD_RETURN_IF_ERROR(CheckGridShape(shape));
  Grid shaped = grid;
  EuclideanDistanceField transform;
  ShapeInPlace(shape, transform, CellRect::Of(shaped), &shaped);
  return shaped;
}

double ShapeReach(const GridShape& shape) {
  const double r = shape.robot_radius_cells;
  double reach = r;
  if (shape.has_inflation_cost()) {
    reach = std::max(reach, InflationCostReach(shape.decay_radius_cells(),
                                               shape.inflation_radius_cells,
                                               shape.cost_scaling_per_cell));
  }
  // A cell the radius blocks or frees moves the clearance of cells up to the
  // clearance beyond it.
  if (shape.min_clearance_cells > 0.0)
    reach = std::max(reach, r + shape.min_clearance_cells);
  return reach;
}

absl::StatusOr<ShapedGridAdvance> AdvanceShapedGrid(const Grid& previous_shaped,
                                                    const Grid& stored,
                                                    absl::Span<const Cell> changed_cells,
                                                    const GridShape& shape) {
  PATHD_RETURN_IF_ERROR(CheckGridShape(shape));
  const int64_t cells = static_cast<int64_t>(stored.size());
  auto in_full = [&]() -> absl::StatusOr<ShapedGridAdvance> {
    PATHD_ASSIGN_OR_RETURN(Grid grid, ShapeGrid(stored, shape));
    return ShapedGridAdvance{std::move(grid), false, cells};
  };
  if (previous_shaped.width() != stored.width() ||
      previous_shaped.height() != stored.height()) {
    return in_full();
  }
  // Ceilings of distances, so the boxes hold every cell within them.
  const double reach = ShapeReach(shape);
  if (reach >= static_cast<double>(kMaxGridDimension)) return in_full();
  const auto pad = static_cast<int32_t>(std::ceil(reach));
  const auto near =
      static_cast<int32_t>(std::ceil(std::max(shape.min_clearance_cells, 0.0)));

  // One box per changed cell (a row's run of neighbours shares one): a cell
  // that became or stopped being lethal moves every cell within the reach;
  // any other moves its own cost and, through the clearance, the cells
  // within the clearance of it. The previous shaped grid is lethal exactly
  // where the previous stored grid was (no step makes or unmakes 254).
  std::vector<CellRect> boxes;
  const uint8_t* before = previous_shaped.cells().data();
  const uint8_t* after = stored.cells().data();
  for (const Cell& c : changed_cells) {
    if (!stored.InBounds(c)) return in_full();
    const size_t i = stored.Index(c);
    const bool lethal_moved = (before[i] == kLethalCost) != (after[i] == kLethalCost);
    const int32_t h = lethal_moved ? pad : near;
    if (!boxes.empty()) {
      CellRect& last = boxes.back();
      if (last.y0 == c.y - h && last.y1 == c.y + h && last.x1 == c.x - 1 + h) {
        last.x1 = c.x + h;
        continue;
      }
    }
    boxes.push_back(CellRect{c.x - h, c.y - h, c.x + h, c.y + h});
  }
  MergeBoxes(pad, &boxes);
  int64_t window_cells = 0;
  for (CellRect& b : boxes) {
    b = Clip(b, 0, stored);
    window_cells += Area(Clip(b, pad, stored));
  }
  if (window_cells > cells / 2) return in_full();

  ShapedGridAdvance advance{previous_shaped, true, window_cells};
  Grid& out = advance.grid;
  out.set_resolution(stored.resolution());
  out.set_origin(stored.origin());
  EuclideanDistanceField transform;
  std::vector<uint8_t> buffer;
  const size_t w = static_cast<size_t>(stored.width());
  for (const CellRect& b : boxes) {
    // The box padded by the reach, shaped as a grid of its own: every source
    // a box cell's shaping reads lies inside it, and its edges (which the
    // clearance counts as the map's outside) are further from every box cell
    // than the clearance, unless they are the map's own.
    const CellRect p = Clip(b, pad, stored);
    const int32_t pw = p.x1 - p.x0 + 1;
    const int32_t ph = p.y1 - p.y0 + 1;
    buffer.resize(static_cast<size_t>(pw) * static_cast<size_t>(ph));
    for (int32_t y = p.y0; y <= p.y1; ++y) {
      std::copy_n(
          after + stored.Index(p.x0, y), pw,
          buffer.begin() + static_cast<size_t>(y - p.y0) * static_cast<size_t>(pw));
    }
    PATHD_ASSIGN_OR_RETURN(Grid window, Grid::FromCells(pw, ph, std::move(buffer)));
    // Only the box's own cells are wanted, and only their rows are
    // transformed.
    ShapeInPlace(shape, transform,
                 CellRect{b.x0 - p.x0, b.y0 - p.y0, b.x1 - p.x0, b.y1 - p.y0}, &window);
    const size_t bw = static_cast<size_t>(b.x1 - b.x0 + 1);
    uint8_t* dst = out.mutable_cells().data();
    for (int32_t y = b.y0; y <= b.y1; ++y) {
      std::copy_n(window.cells().data() + window.Index(b.x0 - p.x0, y - p.y0), bw,
                  dst + static_cast<size_t>(y) * w + static_cast<size_t>(b.x0));
    }
    buffer = std::move(window.mutable_cells());
  }
  return advance;
}

}  // namespace pathd
