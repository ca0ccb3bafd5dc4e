// Drawing maps and plans as RGB images and as text.
#include "client/pathctl/render.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "client/pathctl/text.h"

namespace pathd::pathctl {
namespace {

// Calls visit(x, y) for every point of Bresenham's line from (x0, y0) to
// (x1, y1), both ends included.
template <typename Visit>
void ForEachLinePoint(int64_t x0, int64_t y0, int64_t x1, int64_t y1,
                      Visit visit) {
  const int64_t dx = std::abs(x1 - x0);
  const int64_t dy = -std::abs(y1 - y0);
  const int64_t sx = x0 < x1 ? 1 : -1;
  const int64_t sy = y0 < y1 ? 1 : -1;
  int64_t error = dx + dy;
  while (true) {
    visit(x0, y0);
    if (x0 == x1 && y0 == y1) return;
    const int64_t e2 = 2 * error;
    if (e2 >= dy) {
      error += dy;
      x0 += sx;
    }
    if (e2 <= dx) {
      error += dx;
      y0 += sy;
    }
  }
}

Rgb Blend(Rgb a, Rgb b) {
  return Rgb{static_cast<uint8_t>((a.r + b.r + 1) / 2),
             static_cast<uint8_t>((a.g + b.g + 1) / 2),
             static_cast<uint8_t>((a.b + b.b + 1) / 2)};
}

// The row a grid row is drawn at, top first.
int32_t DrawnRow(const Grid& grid, int32_t y, bool y_up) {
  return y_up ? grid.height() - 1 - y : y;
}

// An RGB canvas with clipped writes.
class Canvas {
 public:
  Canvas(int32_t width, int32_t height) {
    image_.width = width;
    image_.height = height;
    image_.channels = 3;
    image_.pixels.resize(static_cast<size_t>(width) *
                         static_cast<size_t>(height) * 3);
  }

  void Set(int64_t x, int64_t y, Rgb c) {
    if (x < 0 || y < 0 || x >= image_.width || y >= image_.height) return;
    const size_t i =
        (static_cast<size_t>(y) * static_cast<size_t>(image_.width) +
         static_cast<size_t>(x)) *
        3;
    image_.pixels[i] = c.r;
    image_.pixels[i + 1] = c.g;
    image_.pixels[i + 2] = c.b;
  }

  void FillRect(int64_t x0, int64_t y0, int64_t size, Rgb c) {
    for (int64_t y = y0; y < y0 + size; ++y) {
      for (int64_t x = x0; x < x0 + size; ++x) Set(x, y, c);
    }
  }

  // A disc of `radius` pixels around the continuous point (cx, cy); a pixel
  // belongs to it when its centre does.
  void FillDisc(double cx, double cy, double radius, Rgb c) {
    const int64_t x_min = static_cast<int64_t>(std::floor(cx - radius));
    const int64_t x_max = static_cast<int64_t>(std::ceil(cx + radius));
    const int64_t y_min = static_cast<int64_t>(std::floor(cy - radius));
    const int64_t y_max = static_cast<int64_t>(std::ceil(cy + radius));
    for (int64_t y = y_min; y <= y_max; ++y) {
      for (int64_t x = x_min; x <= x_max; ++x) {
        const double ddx = x + 0.5 - cx;
        const double ddy = y + 0.5 - cy;
        if (ddx * ddx + ddy * ddy <= radius * radius) Set(x, y, c);
      }
    }
  }

  Image Take() { return std::move(image_); }

 private:
  Image image_;
};

}  // namespace

Rgb CostColour(uint8_t cost) {
  if (cost == kFreeCost) return kFreeColour;
  if (cost <= kMaxTraversableCost) {
    // 1 -> 230 (clearly not free) .. 252 -> 80 (clearly not lethal).
    const int level = 230 - (cost - 1) * 150 / (kMaxTraversableCost - 1);
    const auto v = static_cast<uint8_t>(level);
    return Rgb{v, v, v};
  }
  if (cost == kInscribedCost) return kInscribedColour;
  if (cost == kLethalCost) return kLethalColour;
  return kUnknownColour;
}

Rgb FleetColour(size_t robot) {
  // Twelve of Sasha Trubetskoy's "20 simple distinct colours" (no white,
  // black, greys or pastels, which vanish on the map's greys).
  static constexpr Rgb kPalette[] = {
      {230, 25, 75},  {60, 180, 75},  {0, 130, 200}, {245, 130, 48},
      {145, 30, 180}, {70, 200, 220}, {240, 50, 230}, {170, 110, 40},
      {128, 0, 0},    {0, 128, 128},  {128, 128, 0}, {0, 0, 128}};
  return kPalette[robot % std::size(kPalette)];
}

int DefaultScale(int32_t width, int32_t height) {
  const int32_t side = std::max(width, height);
  if (side <= 0) return 1;
  return std::clamp(kTargetImageSide / side, 1, 16);
}

namespace {

// How strongly a cost blocks, for DownsampleGrid: higher wins a block.
int BlockRank(uint8_t cost) {
  switch (cost) {
    case kLethalCost:
      return 1000;
    case kInscribedCost:
      return 999;
    case kUnknownCost:
      return 998;
    default:
      return cost;  // weighted by cost, free (0) last
  }
}

}  // namespace

Grid DownsampleGrid(const Grid& grid, int k) {
  const int32_t width = (grid.width() + k - 1) / k;
  const int32_t height = (grid.height() + k - 1) / k;
  Grid small = *Grid::Create(width, height);
  std::vector<uint8_t>& out = small.mutable_cells();
  // Row by row, so the source is read in order: each source row folds into
  // its output row.
  for (int32_t y = 0; y < grid.height(); ++y) {
    uint8_t* dst = out.data() + small.Index(0, y / k);
    const uint8_t* src = grid.cells().data() + grid.Index(0, y);
    for (int32_t x = 0; x < grid.width(); ++x) {
      uint8_t& cell = dst[x / k];
      if (BlockRank(src[x]) > BlockRank(cell)) cell = src[x];
    }
  }
  small.set_resolution(grid.resolution() * k);
  small.set_origin(grid.origin());
  small.set_honour_origin_yaw(grid.honour_origin_yaw());
  return small;
}

PlanOverlay DownsampleOverlay(const PlanOverlay& overlay, int k) {
  const auto cell = [k](const Cell& c) { return Cell{c.x / k, c.y / k}; };
  const auto point = [k](const CellPoint& p) { return CellPoint{p.x / k, p.y / k}; };
  const auto cells = [&](const std::vector<Cell>& in) {
    std::vector<Cell> out;
    out.reserve(in.size());
    for (const Cell& c : in) {
      // Consecutive cells of one block draw nothing new.
      if (out.empty() || !(out.back() == cell(c))) out.push_back(cell(c));
    }
    return out;
  };
  const auto points = [&](const std::vector<CellPoint>& in) {
    std::vector<CellPoint> out;
    out.reserve(in.size());
    for (const CellPoint& p : in) out.push_back(point(p));
    return out;
  };
  PlanOverlay small;
  small.path = cells(overlay.path);
  small.polyline = points(overlay.polyline);
  small.expanded = cells(overlay.expanded);
  for (const auto& s : overlay.structure_segments) {
    small.structure_segments.push_back({point(s[0]), point(s[1])});
  }
  small.structure_points = points(overlay.structure_points);
  for (const auto& outline : overlay.outlines) small.outlines.push_back(points(outline));
  if (overlay.start.has_value()) small.start = cell(*overlay.start);
  if (overlay.goal.has_value()) small.goal = cell(*overlay.goal);
  for (const auto& path : overlay.fleet_paths) small.fleet_paths.push_back(cells(path));
  for (const SimTrail& trail : overlay.trails) {
    small.trails.push_back(
        SimTrail{points(trail.points), trail.radius / k, point(trail.goal)});
  }
  return small;
}

absl::StatusOr<Image> RenderImage(const Grid& grid, const PlanOverlay& overlay,
                                  const RenderOptions& options) {
  if (options.scale == 0 &&
      std::max(grid.width(), grid.height()) > kMaxImageSide) {
    const int k = (std::max(grid.width(), grid.height()) + kMaxImageSide - 1) /
                  kMaxImageSide;
    return RenderImage(DownsampleGrid(grid, k), DownsampleOverlay(overlay, k),
                       options);
  }
  if (options.scale < 0 || options.scale > kMaxScale) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "--scale must be 1..%d pixels per cell (0: automatic), not %d",
        kMaxScale, options.scale));
  }
  const int scale = options.scale == 0
                        ? DefaultScale(grid.width(), grid.height())
                        : options.scale;
  const int64_t width = int64_t{grid.width()} * scale;
  const int64_t height = int64_t{grid.height()} * scale;
  if (width * height > kMaxImagePixels) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "a %dx%d map at %d pixels per cell is a %dx%d picture, above the "
        "limit of %d pixels%s",
        grid.width(), grid.height(), scale, width, height, kMaxImagePixels,
        scale > 1 ? "; use a smaller --scale"
                  : "; leave out --scale to draw it downsampled"));
  }
  Canvas canvas(static_cast<int32_t>(width), static_cast<int32_t>(height));
  std::vector<bool> expanded(grid.size(), false);
  for (const Cell& c : overlay.expanded) {
    if (grid.InBounds(c)) expanded[grid.Index(c)] = true;
  }
  for (int32_t y = 0; y < grid.height(); ++y) {
    const int64_t top = int64_t{DrawnRow(grid, y, options.y_up)} * scale;
    for (int32_t x = 0; x < grid.width(); ++x) {
      const Rgb base = CostColour(grid.cost(x, y));
      canvas.FillRect(
          int64_t{x} * scale, top, scale,
          expanded[grid.Index(x, y)] ? Blend(base, kExpandedTint) : base);
    }
  }

  // Pixel coordinates of a cell's centre.
  const auto centre_x = [&](const Cell& c) {
    return int64_t{c.x} * scale + scale / 2;
  };
  const auto centre_y = [&](const Cell& c) {
    return int64_t{DrawnRow(grid, c.y, options.y_up)} * scale + scale / 2;
  };
  // A third of a cell wide, at least 3 pixels from 3 pixels per cell on, so
  // the path stands out yet the costs beside it remain visible.
  const int64_t half_width = scale < 3 ? 0 : std::max(1, scale / 6);
  const auto stamp = [&](int64_t x, int64_t y) {
    canvas.FillRect(x - half_width, y - half_width, 2 * half_width + 1,
                    kPathColour);
  };
  // Pixel coordinates of a point in cell coordinates, clamped to the
  // picture (points on the map's far edges map to its last pixel).
  const auto point_x = [&](const CellPoint& p) {
    return std::clamp<int64_t>(std::llround(p.x * scale), 0, width - 1);
  };
  const auto point_y = [&](const CellPoint& p) {
    const double row = options.y_up ? grid.height() - p.y : p.y;
    return std::clamp<int64_t>(std::llround(row * scale), 0, height - 1);
  };
  for (const std::array<CellPoint, 2>& s : overlay.structure_segments) {
    ForEachLinePoint(point_x(s[0]), point_y(s[0]), point_x(s[1]), point_y(s[1]),
                     [&](int64_t x, int64_t y) { canvas.FillRect(x, y, 1, kStructureColour); });
  }
  const int64_t dot = std::max(1, scale / 4);
  for (const CellPoint& p : overlay.structure_points) {
    canvas.FillRect(point_x(p) - dot / 2, point_y(p) - dot / 2, dot, kStructureColour);
  }
  for (const std::vector<CellPoint>& outline : overlay.outlines) {
    for (size_t i = 0; i < outline.size(); ++i) {
      const CellPoint& a = outline[i];
      const CellPoint& b = outline[(i + 1) % outline.size()];
      ForEachLinePoint(point_x(a), point_y(a), point_x(b), point_y(b),
                       [&](int64_t x, int64_t y) { canvas.FillRect(x, y, 1, kFootprintColour); });
    }
  }
  if (!overlay.polyline.empty()) {
    for (size_t i = 0; i < overlay.polyline.size(); ++i) {
      const CellPoint& a = overlay.polyline[i];
      const CellPoint& b = i + 1 < overlay.polyline.size() ? overlay.polyline[i + 1] : a;
      ForEachLinePoint(point_x(a), point_y(a), point_x(b), point_y(b), stamp);
    }
  } else {
    for (size_t i = 0; i < overlay.path.size(); ++i) {
      const Cell& a = overlay.path[i];
      const Cell& b = i + 1 < overlay.path.size() ? overlay.path[i + 1] : a;
      if (!grid.InBounds(a) || !grid.InBounds(b)) continue;
      ForEachLinePoint(centre_x(a), centre_y(a), centre_x(b), centre_y(b), stamp);
    }
  }

  // Markers stay visible at one pixel per cell: a few pixels across at least.
  const double radius = std::max(3.5, 0.45 * scale);
  const auto marker = [&](const std::optional<Cell>& cell, Rgb colour) {
    if (!cell.has_value() || !grid.InBounds(*cell)) return;
    const double cx = (cell->x + 0.5) * scale;
    const double cy = (DrawnRow(grid, cell->y, options.y_up) + 0.5) * scale;
    canvas.FillDisc(cx, cy, radius + 1.0, kMarkerOutlineColour);
    canvas.FillDisc(cx, cy, radius, colour);
  };
  marker(overlay.start, kStartColour);
  marker(overlay.goal, kGoalColour);
  // Every path first, then every start and goal, so no path hides one.
  for (size_t i = 0; i < overlay.fleet_paths.size(); ++i) {
    const std::vector<Cell>& path = overlay.fleet_paths[i];
    const Rgb colour = FleetColour(i);
    for (size_t t = 0; t + 1 < path.size(); ++t) {
      if (!grid.InBounds(path[t]) || !grid.InBounds(path[t + 1])) continue;
      ForEachLinePoint(centre_x(path[t]), centre_y(path[t]), centre_x(path[t + 1]),
                       centre_y(path[t + 1]), [&](int64_t x, int64_t y) {
                         canvas.FillRect(x - half_width, y - half_width, 2 * half_width + 1,
                                         colour);
                       });
    }
  }
  for (size_t i = 0; i < overlay.fleet_paths.size(); ++i) {
    const std::vector<Cell>& path = overlay.fleet_paths[i];
    if (path.empty()) continue;
    marker(path.front(), FleetColour(i));
    // The goal: a ring (the colour around a white centre).
    marker(path.back(), FleetColour(i));
    if (grid.InBounds(path.back())) {
      canvas.FillDisc((path.back().x + 0.5) * scale,
                      (DrawnRow(grid, path.back().y, options.y_up) + 0.5) * scale,
                      radius * 0.5, kFreeColour);
    }
  }
  // Simulated trails: thin lines, so that robots passing each other stay
  // apart in the picture; then every start, outline and goal.
  const int64_t trail_half = scale < 6 ? 0 : 1;
  for (size_t i = 0; i < overlay.trails.size(); ++i) {
    const std::vector<CellPoint>& points = overlay.trails[i].points;
    const Rgb colour = FleetColour(i);
    for (size_t k = 0; k + 1 < points.size(); ++k) {
      ForEachLinePoint(point_x(points[k]), point_y(points[k]), point_x(points[k + 1]),
                       point_y(points[k + 1]), [&](int64_t x, int64_t y) {
                         canvas.FillRect(x - trail_half, y - trail_half, 2 * trail_half + 1,
                                         colour);
                       });
    }
  }
  for (size_t i = 0; i < overlay.trails.size(); ++i) {
    const SimTrail& trail = overlay.trails[i];
    if (trail.points.empty()) continue;
    const Rgb colour = FleetColour(i);
    const auto px = [&](const CellPoint& p) { return p.x * scale; };
    const auto py = [&](const CellPoint& p) {
      return (options.y_up ? grid.height() - p.y : p.y) * scale;
    };
    const CellPoint& start = trail.points.front();
    canvas.FillDisc(px(start), py(start), radius * 0.6 + 1.0, kMarkerOutlineColour);
    canvas.FillDisc(px(start), py(start), radius * 0.6, colour);
    canvas.FillDisc(px(trail.goal), py(trail.goal), radius * 0.6 + 1.0, colour);
    canvas.FillDisc(px(trail.goal), py(trail.goal), radius * 0.3, kFreeColour);
    // The robot's disc where it ended, as a polygon of 32 sides.
    const CellPoint& end = trail.points.back();
    constexpr int kSides = 32;
    for (int k = 0; k < kSides; ++k) {
      const double a0 = 2.0 * M_PI * k / kSides, a1 = 2.0 * M_PI * (k + 1) / kSides;
      const CellPoint p0{end.x + trail.radius * std::cos(a0), end.y + trail.radius * std::sin(a0)};
      const CellPoint p1{end.x + trail.radius * std::cos(a1), end.y + trail.radius * std::sin(a1)};
      ForEachLinePoint(point_x(p0), point_y(p0), point_x(p1), point_y(p1),
                       [&](int64_t x, int64_t y) { canvas.FillRect(x, y, 1, colour); });
    }
  }
  return canvas.Take();
}

absl::StatusOr<std::string> RenderText(const Grid& grid,
                                       const PlanOverlay& overlay,
                                       const RenderOptions& options) {
  if (grid.width() > kMaxTextWidth || grid.height() > kMaxTextHeight) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "--ascii draws maps up to %dx%d cells; this one is %dx%d: write a PNG "
        "with -o FILE.png instead",
        kMaxTextWidth, kMaxTextHeight, grid.width(), grid.height()));
  }
  std::vector<char> glyphs(grid.size());
  for (size_t i = 0; i < grid.size(); ++i)
    glyphs[i] = CellGlyph(grid.cells()[i]);
  const auto put = [&](const Cell& c, char glyph) {
    if (grid.InBounds(c)) glyphs[grid.Index(c)] = glyph;
  };
  for (const Cell& c : overlay.expanded) put(c, kExpandedGlyph);
  for (size_t i = 0; i < overlay.path.size(); ++i) {
    const Cell& a = overlay.path[i];
    const Cell& b = i + 1 < overlay.path.size() ? overlay.path[i + 1] : a;
    if (!grid.InBounds(a) || !grid.InBounds(b)) continue;
    ForEachLinePoint(a.x, a.y, b.x, b.y, [&](int64_t x, int64_t y) {
      put(Cell{static_cast<int32_t>(x), static_cast<int32_t>(y)}, kPathGlyph);
    });
  }
  if (overlay.start.has_value()) put(*overlay.start, kStartGlyph);
  if (overlay.goal.has_value()) put(*overlay.goal, kGoalGlyph);
  // Every path first, then every start and goal, so no path hides one.
  for (size_t i = 0; i < overlay.fleet_paths.size(); ++i) {
    for (const Cell& c : overlay.fleet_paths[i]) put(c, static_cast<char>('a' + i % 26));
  }
  for (size_t i = 0; i < overlay.fleet_paths.size(); ++i) {
    const std::vector<Cell>& path = overlay.fleet_paths[i];
    if (path.empty()) continue;
    put(path.front(), static_cast<char>('A' + i % 26));
    put(path.back(), static_cast<char>('A' + i % 26));
  }

  std::string text;
  text.reserve(static_cast<size_t>(grid.width() + 1) * grid.height());
  for (int32_t row = 0; row < grid.height(); ++row) {
    const int32_t y = DrawnRow(grid, row, options.y_up);
    text.append(&glyphs[grid.Index(0, y)], static_cast<size_t>(grid.width()));
    text.push_back('\n');
  }
  return text;
}

}  // namespace pathd::pathctl
