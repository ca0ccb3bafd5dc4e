// FootprintChecker against an exact test written apart from it: Boost.Geometry
// polygons and boxes (the footprint placed at the pose vs every obstacle
// cell's square and the map's outline).
#include "core/kinematics/footprint.h"

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include <boost/geometry.hpp>
#include <boost/geometry/geometries/box.hpp>
#include <boost/geometry/geometries/point_xy.hpp>
#include <boost/geometry/geometries/polygon.hpp>

#include "core/map/cost_model.h"
#include "gtest/gtest.h"

namespace pathd {
namespace {

namespace bg = boost::geometry;
using BPoint = bg::model::d2::point_xy<double>;
using BPolygon = bg::model::polygon<BPoint, /*ClockWise=*/false, /*Closed=*/true>;
using BBox = bg::model::box<BPoint>;

constexpr double kPi = std::numbers::pi;

// The footprint at (x, y, yaw) as a Boost polygon; circles as 64-gons
// circumscribing the circle (so "free" verdicts stay exact-safe).
BPolygon Placed(const Footprint& f, double x, double y, double yaw) {
  BPolygon poly;
  if (f.is_circle()) {
    const int n = 64;
    const double r = f.circle_radius() / std::cos(kPi / n);
    for (int i = 0; i < n; ++i) {
      const double a = 2 * kPi * i / n;
      bg::append(poly.outer(), BPoint(x + r * std::cos(a), y + r * std::sin(a)));
    }
  } else {
    for (const CellPoint& v : f.vertices()) {
      bg::append(poly.outer(), BPoint(x + std::cos(yaw) * v.x - std::sin(yaw) * v.y,
                                      y + std::sin(yaw) * v.x + std::cos(yaw) * v.y));
    }
  }
  bg::correct(poly);
  return poly;
}

// Smallest distance from the placed footprint to an obstacle cell or the
// outside of the map; 0 when it overlaps or touches one.
double ExactClearance(const Grid& grid, const BPolygon& poly, bool unknown_is_free);

// The same for the footprint at (x, y, yaw); circles measured exactly.
double ExactClearance(const Grid& grid, const Footprint& f, double x, double y, double yaw,
                      bool unknown_is_free) {
  if (!f.is_circle()) return ExactClearance(grid, Placed(f, x, y, yaw), unknown_is_free);
  const double r = f.circle_radius();
  double best = std::min({x, y, grid.width() - x, grid.height() - y}) - r;
  for (int32_t cy = 0; cy < grid.height(); ++cy) {
    for (int32_t cx = 0; cx < grid.width(); ++cx) {
      if (Traversable(grid.cost(cx, cy), unknown_is_free)) continue;
      best = std::min(best, bg::distance(BPoint(x, y), BBox(BPoint(cx, cy), BPoint(cx + 1, cy + 1))) - r);
    }
  }
  return std::max(best, 0.0);
}

double ExactClearance(const Grid& grid, const BPolygon& poly, bool unknown_is_free) {
  const BBox bounds = bg::return_envelope<BBox>(poly);
  double best = std::min({bounds.min_corner().x(), bounds.min_corner().y(),
                          grid.width() - bounds.max_corner().x(),
                          grid.height() - bounds.max_corner().y()});
  if (best <= 0.0) return 0.0;
  for (int32_t y = 0; y < grid.height(); ++y) {
    for (int32_t x = 0; x < grid.width(); ++x) {
      if (Traversable(grid.cost(x, y), unknown_is_free)) continue;
      const BBox cell(BPoint(x, y), BPoint(x + 1, y + 1));
      if (bg::intersects(poly, cell)) return 0.0;
      best = std::min(best, bg::distance(poly, cell));
    }
  }
  return best;
}

Grid RandomGrid(std::mt19937& rng, int32_t w, int32_t h, double density) {
  Grid g = *Grid::Create(w, h);
  std::uniform_real_distribution<double> u(0, 1);
  for (int32_t y = 0; y < h; ++y) {
    for (int32_t x = 0; x < w; ++x) {
      const double r = u(rng);
      if (r < density) g.set_cost(x, y, kLethalCost);
      else if (r < density * 1.2) g.set_cost(x, y, kUnknownCost);
      else if (r < density * 1.4) g.set_cost(x, y, kInscribedCost);
    }
  }
  return g;
}

Footprint RandomFootprint(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  if (u(rng) < 0.25) return *Footprint::Circle(0.3 + 3.0 * u(rng));
  // A star-shaped polygon about a point near the origin: simple by
  // construction, often not convex, sometimes not containing the origin.
  const int n = 3 + static_cast<int>(u(rng) * 7);
  const double cx = (u(rng) - 0.5) * 2.0;
  const double cy = (u(rng) - 0.5) * 2.0;
  std::vector<CellPoint> v;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * kPi * (i + 0.8 * u(rng)) / n;
    const double r = 0.5 + 3.5 * u(rng);
    v.push_back(CellPoint{cx + r * std::cos(a), cy + r * std::sin(a)});
  }
  absl::StatusOr<Footprint> f = Footprint::Polygon(v);
  EXPECT_TRUE(f.ok()) << f.status();
  return *f;
}

TEST(FootprintTest, RectangleRadii) {
  const Footprint f =
      *Footprint::Polygon({{0.3, 0.2}, {0.3, -0.2}, {-0.3, -0.2}, {-0.3, 0.2}});
  EXPECT_NEAR(f.inscribed_radius(), 0.2, 1e-12);
  EXPECT_NEAR(f.circumscribed_radius(), std::hypot(0.3, 0.2), 1e-12);
  // Given clockwise, kept counter-clockwise: positive signed area.
  double twice_area = 0;
  for (size_t i = 0, j = f.vertices().size() - 1; i < f.vertices().size(); j = i++) {
    twice_area += f.vertices()[j].x * f.vertices()[i].y - f.vertices()[i].x * f.vertices()[j].y;
  }
  EXPECT_NEAR(twice_area, 2 * 0.6 * 0.4, 1e-12);
  const Footprint scaled = f.Scaled(20.0);
  EXPECT_NEAR(scaled.inscribed_radius(), 4.0, 1e-9);
  EXPECT_NEAR(scaled.circumscribed_radius(), 20 * std::hypot(0.3, 0.2), 1e-9);
  EXPECT_NEAR(std::fabs(scaled.vertices()[0].x), 6.0, 1e-9);
  // The origin outside the outline: no inscribed disc.
  const Footprint off = *Footprint::Polygon({{1, 1}, {2, 1}, {2, 2}});
  EXPECT_EQ(off.inscribed_radius(), 0.0);
}

TEST(FootprintTest, RejectsBadPolygonsNamingTheProblem) {
  auto error = [](std::vector<CellPoint> v) {
    absl::StatusOr<Footprint> f = Footprint::Polygon(std::move(v));
    EXPECT_FALSE(f.ok());
    return std::string(f.status().message());
  };
  EXPECT_NE(error({{0, 0}, {1, 0}}).find("3 to"), std::string::npos);
  EXPECT_NE(error({{0, 0}, {1, 0}, {1, 1}, {0, 0}}).find("same point"), std::string::npos);
  EXPECT_NE(error({{0, 0}, {1, 1}, {1, 0}, {0, 1}}).find("cross"), std::string::npos);
  EXPECT_NE(error({{0, 0}, {1, 0}, {2, 0}}).find("overlap"), std::string::npos);
  EXPECT_NE(error({{0, 0}, {1, 0}, {std::nan(""), 1}}).find("vertex 2"), std::string::npos);
  EXPECT_FALSE(Footprint::Circle(0.0).ok());
  EXPECT_FALSE(Footprint::Circle(-1.0).ok());
  EXPECT_FALSE(FootprintChecker::Create(*Footprint::Circle(1.0), {.headings = 0}).ok());
  EXPECT_FALSE(FootprintChecker::Create(*Footprint::Circle(1.0), {.subcells = 9}).ok());
  EXPECT_FALSE(FootprintChecker::Create(*Footprint::Circle(1.0), {.margin_cells = -1}).ok());
}

TEST(FootprintTest, HeadingBinsWrapAround) {
  const FootprintChecker c = *FootprintChecker::Create(*Footprint::Circle(1.0), {.headings = 72});
  EXPECT_EQ(c.HeadingIndex(0.0), 0);
  EXPECT_EQ(c.HeadingIndex(-0.01), 0);
  EXPECT_EQ(c.HeadingIndex(2 * kPi - 0.01), 0);
  EXPECT_EQ(c.HeadingIndex(kPi / 2), 18);
  EXPECT_EQ(c.HeadingIndex(-kPi / 2), 54);
  EXPECT_EQ(c.HeadingIndex(kPi), 36);
  EXPECT_NEAR(c.HeadingAngle(18), kPi / 2, 1e-12);
}

// Free verdicts are free for the exact footprint anywhere in the pose's
// subcell and heading bin, grown by the margin; collision verdicts from the
// inscribed shortcut are real collisions; and the masks are tight: a pose
// whose footprint keeps more than the documented slack from every obstacle
// is free.
TEST(FootprintTest, AgreesWithExactGeometry) {
  std::mt19937 rng(20261202);
  std::uniform_real_distribution<double> u(0, 1);
  int free_verdicts = 0, collision_verdicts = 0, tight_checks = 0;
  for (int round = 0; round < 60; ++round) {
    const Grid grid = RandomGrid(rng, 24 + static_cast<int>(u(rng) * 10),
                                 24 + static_cast<int>(u(rng) * 10), 0.02 + 0.08 * u(rng));
    const bool unknown_is_free = u(rng) < 0.3;
    const Footprint footprint = RandomFootprint(rng);
    const FootprintCheckerOptions options{.headings = 1 + static_cast<int32_t>(u(rng) * 96),
                                          .subcells = 1 + static_cast<int32_t>(u(rng) * 4),
                                          .margin_cells = u(rng) < 0.5 ? 0.0 : u(rng)};
    const FootprintChecker checker = *FootprintChecker::Create(footprint, options);
    const std::vector<float> distance = ObstacleDistanceField(grid, unknown_is_free);
    const double bin = 2 * kPi / options.headings;
    const double turn = footprint.is_circle()
                            ? 0.0
                            : 2 * footprint.circumscribed_radius() * std::sin(std::min(bin / 4, kPi / 2));
    for (int k = 0; k < 40; ++k) {
      const Pose pose{u(rng) * grid.width(), u(rng) * grid.height(), (u(rng) - 0.5) * 4 * kPi};
      const bool plain = checker.Collides(grid, pose, unknown_is_free);
      const bool fast = checker.Collides(grid, pose, unknown_is_free, distance.data());
      for (const bool verdict : {plain, fast}) {
        if (verdict) continue;
        ++free_verdicts;
        // Anywhere in the subcell, any heading of the bin.
        const double s = options.subcells;
        const Cell c = pose.cell();
        const double sx = std::floor((pose.x - c.x) * s) / s + c.x;
        const double sy = std::floor((pose.y - c.y) * s) / s + c.y;
        const double heading = checker.HeadingAngle(checker.HeadingIndex(pose.yaw));
        for (int t = 0; t < 6; ++t) {
          const double x = sx + u(rng) / s;
          const double y = sy + u(rng) / s;
          const double yaw = heading + (u(rng) - 0.5) * bin;
          const double clearance = ExactClearance(grid, footprint, x, y, yaw, unknown_is_free);
          ASSERT_GT(clearance, options.margin_cells - 1e-9)
              << footprint.DebugString() << " at (" << x << ", " << y << ", " << yaw
              << ") was called free";
        }
      }
      if (fast && !plain) ADD_FAILURE() << "the shortcut found a collision the mask did not";
      // The exact test agrees with the exact geometry at the pose itself.
      const double here = ExactClearance(grid, footprint, pose.x, pose.y, pose.yaw, unknown_is_free);
      if (here == 0.0 || std::fabs(here - options.margin_cells) > 1e-6) {
        EXPECT_EQ(checker.CollidesExactly(grid, pose, unknown_is_free), here <= options.margin_cells)
            << footprint.DebugString() << " at (" << pose.x << ", " << pose.y << ", " << pose.yaw
            << "): clearance " << here;
      }
      if (!plain) EXPECT_FALSE(checker.CollidesExactly(grid, pose, unknown_is_free));
      if (plain) ++collision_verdicts;
      // Tightness at the pose itself.
      const double slack = options.margin_cells + turn + std::numbers::sqrt2 / options.subcells + 1e-6;
      if (ExactClearance(grid, footprint, pose.x, pose.y, pose.yaw, unknown_is_free) > slack) {
        ++tight_checks;
        EXPECT_FALSE(plain) << footprint.DebugString() << " at (" << pose.x << ", " << pose.y
                            << ", " << pose.yaw << ") keeps " << slack << " clear";
      }
    }
  }
  EXPECT_GT(free_verdicts, 250);
  EXPECT_GT(collision_verdicts, 250);
  EXPECT_GT(tight_checks, 100);
}

TEST(FootprintTest, OffTheMapCollides) {
  const Grid grid = *Grid::Create(10, 10);
  const FootprintChecker c = *FootprintChecker::Create(*Footprint::Circle(1.0));
  EXPECT_FALSE(c.Collides(grid, Pose{5, 5, 0}, false));
  EXPECT_TRUE(c.Collides(grid, Pose{0.5, 5, 0}, false));
  EXPECT_TRUE(c.Collides(grid, Pose{-3, 5, 0}, false));
  EXPECT_TRUE(c.Collides(grid, Pose{std::nan(""), 5, 0}, false));
  EXPECT_EQ(c.MaxCost(grid, Pose{0.5, 5, 0}), kUnknownCost);
}

}  // namespace
}  // namespace pathd
