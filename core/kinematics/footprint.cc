#include "core/kinematics/footprint.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "core/map/cost_model.h"
#include "core/map/euclidean_distance.h"

namespace pathd {
namespace {

double Cross(CellPoint o, CellPoint a, CellPoint b) {
  return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
}

double Distance(CellPoint a, CellPoint b) { return std::hypot(a.x - b.x, a.y - b.y); }

double PointSegmentDistance(CellPoint p, CellPoint a, CellPoint b) {
  const double dx = b.x - a.x;
  const double dy = b.y - a.y;
  const double len2 = dx * dx + dy * dy;
  double t = len2 > 0.0 ? ((p.x - a.x) * dx + (p.y - a.y) * dy) / len2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  return Distance(p, CellPoint{a.x + t * dx, a.y + t * dy});
}

int Sign(double v) { return v > 0.0 ? 1 : (v < 0.0 ? -1 : 0); }

bool OnSegment(CellPoint p, CellPoint a, CellPoint b) {
  return std::min(a.x, b.x) <= p.x && p.x <= std::max(a.x, b.x) &&
         std::min(a.y, b.y) <= p.y && p.y <= std::max(a.y, b.y);
}

// Closed segments [a, b] and [c, d] share a point.
bool SegmentsIntersect(CellPoint a, CellPoint b, CellPoint c, CellPoint d) {
  const int d1 = Sign(Cross(c, d, a));
  const int d2 = Sign(Cross(c, d, b));
  const int d3 = Sign(Cross(a, b, c));
  const int d4 = Sign(Cross(a, b, d));
  if (d1 * d2 < 0 && d3 * d4 < 0) return true;
  return (d1 == 0 && OnSegment(a, c, d)) || (d2 == 0 && OnSegment(b, c, d)) ||
         (d3 == 0 && OnSegment(c, a, b)) || (d4 == 0 && OnSegment(d, a, b));
}

double SegmentDistance(CellPoint a, CellPoint b, CellPoint c, CellPoint d) {
  if (SegmentsIntersect(a, b, c, d)) return 0.0;
  return std::min({PointSegmentDistance(a, c, d), PointSegmentDistance(b, c, d),
                   PointSegmentDistance(c, a, b), PointSegmentDistance(d, a, b)});
}

// Even-odd rule; points on the outline may go either way (callers also test
// the outline's distance).
bool InsidePolygon(CellPoint p, const std::vector<CellPoint>& poly) {
  bool inside = false;
  for (size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const CellPoint& a = poly[i];
    const CellPoint& b = poly[j];
    if ((a.y > p.y) != (b.y > p.y) &&
        p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x) {
      inside = !inside;
    }
  }
  return inside;
}

double SignedArea(const std::vector<CellPoint>& poly) {
  double twice = 0.0;
  for (size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    twice += poly[j].x * poly[i].y - poly[i].x * poly[j].y;
  }
  return twice / 2.0;
}

struct Rect {
  double x0, y0, x1, y1;
  CellPoint corner(int k) const {
    return CellPoint{(k == 1 || k == 2) ? x1 : x0, k >= 2 ? y1 : y0};
  }
};

double RectPointDistance(const Rect& r, CellPoint p) {
  const double dx = std::max({r.x0 - p.x, 0.0, p.x - r.x1});
  const double dy = std::max({r.y0 - p.y, 0.0, p.y - r.y1});
  return std::hypot(dx, dy);
}

// Distance between a closed rectangle and a closed polygon (0 when they
// overlap or touch).
double RectPolygonDistance(const Rect& r, const std::vector<CellPoint>& poly) {
  for (const CellPoint& v : poly) {
    if (v.x >= r.x0 && v.x <= r.x1 && v.y >= r.y0 && v.y <= r.y1) return 0.0;
  }
  for (int k = 0; k < 4; ++k) {
    if (InsidePolygon(r.corner(k), poly)) return 0.0;
  }
  // Corners in the order 0 (x0,y0), 1 (x1,y0), 2 (x1,y1), 3 (x0,y1).
  const CellPoint c[4] = {{r.x0, r.y0}, {r.x1, r.y0}, {r.x1, r.y1}, {r.x0, r.y1}};
  double best = std::numeric_limits<double>::infinity();
  for (size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    for (int k = 0; k < 4; ++k) {
      best = std::min(best, SegmentDistance(poly[j], poly[i], c[k], c[(k + 1) % 4]));
      if (best == 0.0) return 0.0;
    }
  }
  return best;
}

std::vector<CellPoint> Rotated(const std::vector<CellPoint>& poly, double yaw) {
  const double c = std::cos(yaw);
  const double s = std::sin(yaw);
  std::vector<CellPoint> out;
  out.reserve(poly.size());
  for (const CellPoint& v : poly) out.push_back(CellPoint{c * v.x - s * v.y, s * v.x + c * v.y});
  return out;
}

}  // namespace

absl::StatusOr<Footprint> Footprint::Circle(double radius_cells) {
  if (!std::isfinite(radius_cells) || radius_cells <= 0.0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "footprint radius must be a positive finite number, got %g", radius_cells));
  }
  Footprint f;
  f.circle_radius_ = radius_cells;
  f.inscribed_radius_ = radius_cells;
  f.circumscribed_radius_ = radius_cells;
  return f;
}

absl::StatusOr<Footprint> Footprint::Polygon(std::vector<CellPoint> vertices) {
  const size_t n = vertices.size();
  if (n < 3 || n > kMaxVertices) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "footprint polygon must have 3 to %d vertices, got %d", kMaxVertices, n));
  }
  for (size_t i = 0; i < n; ++i) {
    if (!std::isfinite(vertices[i].x) || !std::isfinite(vertices[i].y)) {
      return absl::InvalidArgumentError(
          absl::StrFormat("footprint vertex %d is not a finite point", i));
    }
    for (size_t j = 0; j < i; ++j) {
      if (vertices[i].x == vertices[j].x && vertices[i].y == vertices[j].y) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "footprint vertices %d and %d are the same point (%g, %g)", j, i,
            vertices[i].x, vertices[i].y));
      }
    }
  }
  // Edge i joins vertex i and i + 1. Edges that share no vertex must not
  // meet; adjacent edges must not fold back onto each other.
  for (size_t i = 0; i < n; ++i) {
    const CellPoint a = vertices[i];
    const CellPoint b = vertices[(i + 1) % n];
    for (size_t j = i + 1; j < n; ++j) {
      const CellPoint c = vertices[j];
      const CellPoint d = vertices[(j + 1) % n];
      const bool adjacent = j == i + 1 || (i == 0 && j == n - 1);
      if (adjacent) {
        // The shared vertex is b (j == i + 1) or a (wrap-around); the other
        // edge folds back when it runs along this one.
        const CellPoint shared = j == i + 1 ? b : a;
        const CellPoint mine = j == i + 1 ? a : b;
        const CellPoint other = j == i + 1 ? d : c;
        if (Cross(shared, mine, other) == 0.0 &&
            (mine.x - shared.x) * (other.x - shared.x) +
                    (mine.y - shared.y) * (other.y - shared.y) > 0.0) {
          return absl::InvalidArgumentError(absl::StrFormat(
              "footprint edges %d and %d overlap (the outline folds back)", i, j));
        }
        continue;
      }
      if (SegmentsIntersect(a, b, c, d)) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "footprint edges %d and %d cross: the polygon must not intersect itself", i, j));
      }
    }
  }
  const double area = SignedArea(vertices);
  if (!(std::fabs(area) > 1e-12)) {
    return absl::InvalidArgumentError("footprint polygon has zero area");
  }
  if (area < 0.0) std::reverse(vertices.begin(), vertices.end());
  Footprint f;
  f.vertices_ = std::move(vertices);
  const CellPoint origin{0.0, 0.0};
  for (const CellPoint& v : f.vertices_) {
    f.circumscribed_radius_ = std::max(f.circumscribed_radius_, Distance(origin, v));
  }
  if (InsidePolygon(origin, f.vertices_)) {
    double nearest = std::numeric_limits<double>::infinity();
    for (size_t i = 0, j = n - 1; i < n; j = i++) {
      nearest = std::min(nearest, PointSegmentDistance(origin, f.vertices_[j], f.vertices_[i]));
    }
    f.inscribed_radius_ = nearest;
  }
  return f;
}

Footprint Footprint::Scaled(double factor) const {
  Footprint f = *this;
  f.circle_radius_ *= factor;
  for (CellPoint& v : f.vertices_) {
    v.x *= factor;
    v.y *= factor;
  }
  f.inscribed_radius_ *= factor;
  f.circumscribed_radius_ *= factor;
  return f;
}

std::vector<CellPoint> Footprint::At(const Pose& pose) const {
  std::vector<CellPoint> out = Rotated(vertices_, pose.yaw);
  for (CellPoint& v : out) {
    v.x += pose.x;
    v.y += pose.y;
  }
  return out;
}

std::string Footprint::DebugString() const {
  if (is_circle()) return absl::StrFormat("circle r=%g", circle_radius_);
  std::string out = "polygon [";
  for (size_t i = 0; i < vertices_.size(); ++i) {
    absl::StrAppend(&out, i == 0 ? "" : ",",
                    absl::StrFormat("[%g,%g]", vertices_[i].x, vertices_[i].y));
  }
  return out + "]";
}

std::vector<float> ObstacleDistanceField(const Grid& grid, bool unknown_is_free) {
  DistanceSources sources;
  sources.by_cost[kInscribedCost] = true;
  sources.by_cost[kLethalCost] = true;
  sources.by_cost[kUnknownCost] = !unknown_is_free;
  sources.border = true;
  EuclideanDistanceField field;
  const std::vector<int64_t>& squared = field.Compute(grid, sources);
  std::vector<float> out(squared.size());
  for (size_t i = 0; i < squared.size(); ++i) {
    out[i] = static_cast<float>(std::sqrt(static_cast<double>(squared[i])));
  }
  return out;
}

absl::StatusOr<FootprintChecker> FootprintChecker::Create(
    const Footprint& footprint, const FootprintCheckerOptions& options) {
  if (options.headings < 1 || options.headings > 3600) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "footprint heading bins must be in 1..3600, got %d", options.headings));
  }
  if (options.subcells < 1 || options.subcells > 8) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "footprint subcells must be in 1..8, got %d", options.subcells));
  }
  if (!std::isfinite(options.margin_cells) || options.margin_cells < 0.0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "footprint margin must be a non-negative finite number, got %g",
        options.margin_cells));
  }
  FootprintChecker checker(footprint, options);
  checker.BuildMasks();
  return checker;
}

void FootprintChecker::BuildMasks() {
  const int32_t n = options_.headings;
  const int32_t s = options_.subcells;
  const double bin = 2.0 * std::numbers::pi / n;
  const double radius = footprint_.circumscribed_radius();
  // A point at distance <= radius from the origin moves at most the chord of
  // half a bin when the heading moves within its bin.
  const double turn_margin =
      footprint_.is_circle() ? 0.0 : 2.0 * radius * std::sin(std::min(bin / 4.0, std::numbers::pi / 2));
  const double margin = options_.margin_cells + turn_margin;
  const int32_t reach = static_cast<int32_t>(std::ceil(radius + margin)) + 2;
  masks_.assign(static_cast<size_t>(n) * s * s, Mask{});
  const double sqrt2_half = std::numbers::sqrt2 / 2.0;
  free_beyond_ = radius + options_.margin_cells + 2.0 * sqrt2_half;
  hit_within_ = footprint_.inscribed_radius() - sqrt2_half;
  for (int32_t h = 0; h < n; ++h) {
    const std::vector<CellPoint> poly = Rotated(footprint_.vertices(), h * bin);
    for (int32_t sy = 0; sy < s; ++sy) {
      for (int32_t sx = 0; sx < s; ++sx) {
        Mask& mask = masks_[(static_cast<size_t>(h) * s + sy) * s + sx];
        mask.min_dx = mask.min_dy = reach;
        mask.max_dx = mask.max_dy = -reach;
        size_t cells = 0;
        for (int32_t dy = -reach; dy <= reach; ++dy) {
          int32_t run_begin = 0;
          bool in_run = false;
          for (int32_t dx = -reach; dx <= reach + 1; ++dx) {
            bool covered = false;
            if (dx <= reach) {
              // The cell (dx, dy) relative to the pose's cell, seen from a
              // pose anywhere in subcell (sx, sy): the cell minus the set of
              // positions, a rectangle 1 + 1/s on a side.
              const Rect r{dx - (sx + 1.0) / s, dy - (sy + 1.0) / s, dx + 1.0 - sx * 1.0 / s,
                           dy + 1.0 - sy * 1.0 / s};
              const double d = footprint_.is_circle()
                                   ? RectPointDistance(r, CellPoint{0.0, 0.0}) -
                                         footprint_.circle_radius()
                                   : RectPolygonDistance(r, poly);
              covered = d <= margin;
            }
            if (covered && !in_run) {
              run_begin = dx;
              in_run = true;
            } else if (!covered && in_run) {
              mask.runs.push_back(Run{dy, run_begin, dx});
              cells += static_cast<size_t>(dx - run_begin);
              mask.min_dx = std::min(mask.min_dx, run_begin);
              mask.max_dx = std::max(mask.max_dx, dx - 1);
              mask.min_dy = std::min(mask.min_dy, dy);
              mask.max_dy = std::max(mask.max_dy, dy);
              in_run = false;
            }
          }
        }
        max_mask_cells_ = std::max(max_mask_cells_, cells);
      }
    }
  }
}

int32_t FootprintChecker::HeadingIndex(double yaw) const {
  const int32_t n = options_.headings;
  const double bin = 2.0 * std::numbers::pi / n;
  const int64_t k = std::llround(NormalizeAngle(yaw) / bin);
  return static_cast<int32_t>(((k % n) + n) % n);
}

double FootprintChecker::HeadingAngle(int32_t index) const {
  return NormalizeAngle(index * 2.0 * std::numbers::pi / options_.headings);
}

const FootprintChecker::Mask& FootprintChecker::MaskOf(const Pose& pose) const {
  const int32_t s = options_.subcells;
  const auto sub = [s](double v) {
    const int32_t k = static_cast<int32_t>((v - std::floor(v)) * s);
    return std::clamp(k, 0, s - 1);
  };
  return masks_[(static_cast<size_t>(HeadingIndex(pose.yaw)) * s + sub(pose.y)) * s +
                sub(pose.x)];
}

bool FootprintChecker::Collides(const Grid& grid, const Pose& pose, bool unknown_is_free,
                                const float* distance) const {
  if (!std::isfinite(pose.x) || !std::isfinite(pose.y) || !std::isfinite(pose.yaw)) return true;
  const Cell c = pose.cell();
  if (distance != nullptr && grid.InBounds(c)) {
    const double d = distance[grid.Index(c)];
    if (d > free_beyond_) return false;
    if (d < hit_within_) return true;
  }
  const Mask& mask = MaskOf(pose);
  if (c.x + mask.min_dx < 0 || c.y + mask.min_dy < 0 || c.x + mask.max_dx >= grid.width() ||
      c.y + mask.max_dy >= grid.height()) {
    return true;
  }
  const uint8_t* cells = grid.cells().data();
  for (const Run& run : mask.runs) {
    const uint8_t* row = cells + grid.Index(c.x, c.y + run.dy);
    for (int32_t dx = run.dx_begin; dx < run.dx_end; ++dx) {
      if (!Traversable(row[dx], unknown_is_free)) return true;
    }
  }
  return false;
}

bool FootprintChecker::CollidesExactly(const Grid& grid, const Pose& pose,
                                       bool unknown_is_free) const {
  if (!std::isfinite(pose.x) || !std::isfinite(pose.y) || !std::isfinite(pose.yaw)) return true;
  const double margin = options_.margin_cells;
  const double reach = footprint_.circumscribed_radius() + margin;
  const std::vector<CellPoint> poly = footprint_.At(pose);
  // The footprint's extent, grown by the margin: anything reaching the
  // map's outline leaves the map.
  double x0 = pose.x - reach, x1 = pose.x + reach, y0 = pose.y - reach, y1 = pose.y + reach;
  if (!poly.empty()) {
    x0 = y0 = std::numeric_limits<double>::infinity();
    x1 = y1 = -x0;
    for (const CellPoint& v : poly) {
      x0 = std::min(x0, v.x), x1 = std::max(x1, v.x);
      y0 = std::min(y0, v.y), y1 = std::max(y1, v.y);
    }
    x0 -= margin, x1 += margin, y0 -= margin, y1 += margin;
  }
  if (x0 <= 0.0 || y0 <= 0.0 || x1 >= grid.width() || y1 >= grid.height()) return true;
  for (int32_t cy = static_cast<int32_t>(std::floor(y0)); cy <= static_cast<int32_t>(y1); ++cy) {
    for (int32_t cx = static_cast<int32_t>(std::floor(x0)); cx <= static_cast<int32_t>(x1);
         ++cx) {
      if (Traversable(grid.cost(cx, cy), unknown_is_free)) continue;
      const Rect cell{static_cast<double>(cx), static_cast<double>(cy), cx + 1.0, cy + 1.0};
      const double d = footprint_.is_circle()
                           ? RectPointDistance(cell, pose.point()) - footprint_.circle_radius()
                           : RectPolygonDistance(cell, poly);
      if (d <= margin) return true;
    }
  }
  return false;
}

uint8_t FootprintChecker::MaxCost(const Grid& grid, const Pose& pose) const {
  if (!std::isfinite(pose.x) || !std::isfinite(pose.y) || !std::isfinite(pose.yaw)) {
    return kUnknownCost;
  }
  const Cell c = pose.cell();
  const Mask& mask = MaskOf(pose);
  if (c.x + mask.min_dx < 0 ||
      c.y + mask.min_dy < 0 || c.x + mask.max_dx >= grid.width() ||
      c.y + mask.max_dy >= grid.height()) {
    return kUnknownCost;
  }
  uint8_t highest = 0;
  const uint8_t* cells = grid.cells().data();
  for (const Run& run : mask.runs) {
    const uint8_t* row = cells + grid.Index(c.x, c.y + run.dy);
    for (int32_t dx = run.dx_begin; dx < run.dx_end; ++dx) highest = std::max(highest, row[dx]);
  }
  return highest;
}

std::vector<Cell> FootprintChecker::CoveredCells(const Pose& pose) const {
  const Cell c = pose.cell();
  std::vector<Cell> out;
  for (const Run& run : MaskOf(pose).runs) {
    for (int32_t dx = run.dx_begin; dx < run.dx_end; ++dx) {
      out.push_back(Cell{c.x + dx, c.y + run.dy});
    }
  }
  return out;
}

size_t FootprintChecker::bytes() const {
  size_t total = sizeof(*this) + masks_.capacity() * sizeof(Mask);
  for (const Mask& m : masks_) total += m.runs.capacity() * sizeof(Run);
  return total;
}

}  // namespace pathd
