#include "tests/testing/kinematic_checker.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <boost/geometry.hpp>
#include <boost/geometry/geometries/box.hpp>
#include <boost/geometry/geometries/point_xy.hpp>
#include <boost/geometry/geometries/polygon.hpp>

#include "absl/strings/str_format.h"
#include "core/map/cost_model.h"

namespace pathd::testing {
namespace {

namespace bg = boost::geometry;
using BPoint = bg::model::d2::point_xy<double>;
using BPolygon = bg::model::polygon<BPoint, /*ClockWise=*/false, /*Closed=*/true>;
using BBox = bg::model::box<BPoint>;

double Wrap(double a) {
  a = std::fmod(a, 2 * std::numbers::pi);
  if (a <= -std::numbers::pi) a += 2 * std::numbers::pi;
  if (a > std::numbers::pi) a -= 2 * std::numbers::pi;
  return a;
}

// Whether the robot at (x, y, yaw) overlaps or touches an obstacle cell or
// leaves the map; the offending cell in *where.
bool Hits(const Grid& grid, const KinematicCheck& check, double x, double y, double yaw,
          std::string* where) {
  const bool circle = check.footprint.empty();
  BPolygon poly;
  double x0, y0, x1, y1;
  if (circle) {
    const double r = check.circle_radius;
    x0 = x - r, y0 = y - r, x1 = x + r, y1 = y + r;
  } else {
    const double c = std::cos(yaw), s = std::sin(yaw);
    for (const CellPoint& v : check.footprint) {
      bg::append(poly.outer(), BPoint(x + c * v.x - s * v.y, y + s * v.x + c * v.y));
    }
    bg::correct(poly);
    const BBox box = bg::return_envelope<BBox>(poly);
    x0 = box.min_corner().x(), y0 = box.min_corner().y();
    x1 = box.max_corner().x(), y1 = box.max_corner().y();
  }
  if (x0 <= 0 || y0 <= 0 || x1 >= grid.width() || y1 >= grid.height()) {
    *where = "the map's edge";
    return true;
  }
  for (int32_t cy = static_cast<int32_t>(std::floor(y0)); cy <= static_cast<int32_t>(y1); ++cy) {
    for (int32_t cx = static_cast<int32_t>(std::floor(x0)); cx <= static_cast<int32_t>(x1); ++cx) {
      if (!grid.InBounds(cx, cy) || Traversable(grid.cost(cx, cy), check.unknown_is_free)) continue;
      const BBox cell(BPoint(cx, cy), BPoint(cx + 1, cy + 1));
      const bool hit = circle ? bg::distance(BPoint(x, y), cell) <= check.circle_radius
                              : bg::intersects(poly, cell);
      if (hit) {
        *where = absl::StrFormat("cell (%d, %d) of cost %d", cx, cy, grid.cost(cx, cy));
        return true;
      }
    }
  }
  return false;
}

std::string PoseString(const Pose& p) { return absl::StrFormat("(%.4f, %.4f, %.4f)", p.x, p.y, p.yaw); }

}  // namespace

std::string CheckKinematicPath(const Grid& grid, const std::vector<Pose>& poses,
                               const std::vector<bool>& reverse, const KinematicCheck& check) {
  if (poses.empty()) return "the path has no poses";
  if (!reverse.empty() && reverse.size() != poses.size()) {
    return absl::StrFormat("%d poses but %d direction flags", poses.size(), reverse.size());
  }
  if (check.check_ends) {
    const Pose& first = poses.front();
    if (std::hypot(first.x - check.start.x, first.y - check.start.y) > 1e-6 ||
        std::fabs(Wrap(first.yaw - check.start.yaw)) > 1e-6) {
      return absl::StrFormat("starts at %s, not at the start %s", PoseString(first),
                             PoseString(check.start));
    }
    const Pose& last = poses.back();
    const double off = std::hypot(last.x - check.goal.x, last.y - check.goal.y);
    const double turn = std::fabs(Wrap(last.yaw - check.goal.yaw));
    if (off > check.goal_tolerance + 1e-9 || turn > check.goal_yaw_tolerance + 1e-9) {
      return absl::StrFormat("ends at %s, %.6f cells and %.6f rad from the goal %s", PoseString(last),
                             off, turn, PoseString(check.goal));
    }
  }
  std::string where;
  if (Hits(grid, check, poses[0].x, poses[0].y, poses[0].yaw, &where)) {
    return absl::StrFormat("pose 0 %s touches %s", PoseString(poses[0]), where);
  }
  for (size_t i = 0; i + 1 < poses.size(); ++i) {
    const Pose& a = poses[i];
    const Pose& b = poses[i + 1];
    const double dx = b.x - a.x, dy = b.y - a.y;
    const double chord = std::hypot(dx, dy);
    const double turn = Wrap(b.yaw - a.yaw);
    const std::string motion =
        absl::StrFormat("motion %d %s -> %s", i, PoseString(a), PoseString(b));
    if (chord < 1e-9) {
      if (std::fabs(turn) > 1e-9 && !check.allow_turn_in_place) {
        return motion + " turns in place";
      }
    } else if (!check.allow_sideways) {
      const double mid = a.yaw + turn / 2;
      const double along = (dx * std::cos(mid) + dy * std::sin(mid)) / chord;
      const bool backwards = along < 0;
      const double drift = std::acos(std::min(1.0, std::fabs(along)));
      if (drift > check.max_drift) {
        return absl::StrFormat("%s moves %.4f rad off its heading", motion, drift);
      }
      if (backwards && !check.allow_reverse) return motion + " reverses";
      if (!reverse.empty() && reverse[i + 1] != backwards) {
        return absl::StrFormat("%s is marked %s but drives %s", motion,
                               reverse[i + 1] ? "reversing" : "forward",
                               backwards ? "backwards" : "forwards");
      }
      if (check.min_turning_radius > 0) {
        const double curvature = 2 * std::sin(std::fabs(turn) / 2) / chord;
        if (curvature > (1 + check.curvature_slack) / check.min_turning_radius) {
          return absl::StrFormat("%s curves with radius %.6f, below the minimum %.6f", motion,
                                 1 / curvature, check.min_turning_radius);
        }
      }
    }
    const int steps = std::max({1, static_cast<int>(std::ceil(chord / check.step_cells)),
                                static_cast<int>(std::ceil(std::fabs(turn) / check.step_yaw))});
    for (int k = 1; k <= steps; ++k) {
      const double t = static_cast<double>(k) / steps;
      const double x = a.x + t * dx, y = a.y + t * dy, yaw = a.yaw + t * turn;
      if (Hits(grid, check, x, y, yaw, &where)) {
        return absl::StrFormat("%s at (%.4f, %.4f, %.4f) touches %s", motion, x, y, yaw, where);
      }
    }
  }
  return "";
}

}  // namespace pathd::testing
