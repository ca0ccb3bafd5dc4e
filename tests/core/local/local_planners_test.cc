// The local planners (core/local) against checks written apart from them:
// ORCA's programs against an exact enumeration of the optimum's candidate
// points and a brute-force grid of velocities, its half-planes against the
// motion they promise, whole fleets stepped with ORCA under a separation
// check; DWA's commands against the dynamic window and its accepted rollouts
// against the independent dense footprint checker (tests/testing/
// kinematic_checker); FIRAS on a trap and on an open map.
//
// PATHD_LOCAL_CASES=N scales the randomised cases (default 1000; the ASan run
// uses 100).
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "core/geometry/free_space.h"
#include "core/geometry/obstacle_polygons.h"
#include "core/kinematics/footprint.h"
#include "core/local/dwa.h"
#include "core/local/firas.h"
#include "core/local/local_types.h"
#include "core/local/orca.h"
#include "gtest/gtest.h"
#include "tests/testing/kinematic_checker.h"

namespace pathd {
namespace {

int Cases() {
  if (const char* env = std::getenv("PATHD_LOCAL_CASES")) {
    const int n = std::atoi(env);
    if (n > 0) return n;
  }
  return 1000;
}

double Cross(CellPoint a, CellPoint b) { return a.x * b.y - a.y * b.x; }
// Signed violation of a half-plane, computed here from the definition
// (left of the directed line is admissible).
double Violates(const OrcaLine& l, CellPoint v) {
  return Cross(l.direction, CellPoint{l.point.x - v.x, l.point.y - v.y});
}
double Dist(CellPoint a, CellPoint b) {
  return std::hypot(a.x - b.x, a.y - b.y);
}

// The exact optimum of min |v - pref| over the disc and the half-planes by
// enumeration: the optimum of a strictly convex objective over a convex
// region is pref itself, or the projection of pref onto one active
// constraint, or a vertex of two. Returns false when no candidate is
// feasible (then the region is empty, up to tolerance).
bool ExactClosest(const std::vector<OrcaLine>& lines, double radius,
                  CellPoint pref, CellPoint* best) {
  std::vector<CellPoint> cand;
  cand.push_back(pref);
  const double pn = std::hypot(pref.x, pref.y);
  if (pn > 0)
    cand.push_back(CellPoint{pref.x * radius / pn, pref.y * radius / pn});
  for (const OrcaLine& l : lines) {
    const double t = (pref.x - l.point.x) * l.direction.x +
                     (pref.y - l.point.y) * l.direction.y;
    cand.push_back(CellPoint{l.point.x + t * l.direction.x,
                             l.point.y + t * l.direction.y});
    // Line and circle.
    const double b = l.point.x * l.direction.x + l.point.y * l.direction.y;
    const double c =
        l.point.x * l.point.x + l.point.y * l.point.y - radius * radius;
    const double disc = b * b - c;
    if (disc >= 0) {
      for (double s : {-b - std::sqrt(disc), -b + std::sqrt(disc)}) {
        cand.push_back(CellPoint{l.point.x + s * l.direction.x,
                                 l.point.y + s * l.direction.y});
      }
    }
  }
  for (size_t i = 0; i < lines.size(); ++i) {
    for (size_t j = i + 1; j < lines.size(); ++j) {
      const double den = Cross(lines[i].direction, lines[j].direction);
      if (std::fabs(den) < 1e-12) continue;
      const CellPoint d{lines[j].point.x - lines[i].point.x,
                        lines[j].point.y - lines[i].point.y};
      const double t = Cross(d, lines[j].direction) / den;
      cand.push_back(CellPoint{lines[i].point.x + t * lines[i].direction.x,
                               lines[i].point.y + t * lines[i].direction.y});
    }
  }
  bool found = false;
  double best_d = std::numeric_limits<double>::infinity();
  for (const CellPoint& c : cand) {
    if (std::hypot(c.x, c.y) > radius + 1e-9) continue;
    bool ok = true;
    for (const OrcaLine& l : lines) ok = ok && Violates(l, c) <= 1e-9;
    if (ok && Dist(c, pref) < best_d) {
      best_d = Dist(c, pref);
      *best = c;
      found = true;
    }
  }
  return found;
}

OrcaLine RandomNeighbourLine(std::mt19937& rng, double* share_out) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  MovingObstacle o;
  o.position = CellPoint{4 * u(rng), 4 * u(rng)};
  o.velocity = CellPoint{u(rng), u(rng)};
  o.radius = 0.3 + 0.3 * (u(rng) + 1);
  o.reciprocal = u(rng) > 0;
  *share_out = o.reciprocal ? 0.5 : 1.0;
  return OrcaLineForNeighbour(CellPoint{0, 0}, CellPoint{u(rng), u(rng)}, 0.5,
                              o, 1.0 + (u(rng) + 1), 0.1, *share_out);
}

TEST(OrcaLinearProgram, FeasibleAnswersAreTheExactOptimum) {
  std::mt19937 rng(20);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int feasible = 0, infeasible = 0;
  for (int c = 0; c < Cases(); ++c) {
    const int n = 1 + static_cast<int>(rng() % 8);
    std::vector<OrcaLine> lines;
    double share;
    for (int i = 0; i < n; ++i)
      lines.push_back(RandomNeighbourLine(rng, &share));
    const double max_speed = 1.0 + (u(rng) + 1);
    const CellPoint pref{2 * u(rng), 2 * u(rng)};
    const OrcaSolution sol = SolveOrcaLines(lines, 0, max_speed, pref);
    CellPoint exact;
    const bool exact_found = ExactClosest(lines, max_speed, pref, &exact);
    SCOPED_TRACE(::testing::Message() << "case " << c << " lines " << n);
    if (sol.feasible) {
      ++feasible;
      EXPECT_LE(std::hypot(sol.velocity.x, sol.velocity.y), max_speed + 1e-9);
      for (const OrcaLine& l : lines)
        EXPECT_LE(Violates(l, sol.velocity), 1e-7);
      ASSERT_TRUE(exact_found);
      EXPECT_NEAR(Dist(sol.velocity, pref), Dist(exact, pref), 1e-6);
      EXPECT_LE(Dist(sol.velocity, exact), 1e-4);
    } else {
      ++infeasible;
      // Infeasible: no candidate clears every line by more than rounding.
      EXPECT_FALSE(exact_found && [&] {
        for (const OrcaLine& l : lines) {
          if (Violates(l, exact) > -1e-6) return false;
        }
        return true;
      }());
    }
  }
  EXPECT_GT(feasible, Cases() / 10);
  EXPECT_GT(infeasible, 0);
}

// Brute force on a grid of velocities: the feasible grid velocity nearest
// the preferred one is never nearer than the program's, and when the
// program is infeasible, no grid velocity has a smaller largest violation
// (hard lines kept).
TEST(OrcaLinearProgram, AgreesWithBruteForceGrid) {
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int cases = std::max(10, Cases() / 10);
  const double step = 0.01;
  int infeasible = 0;
  for (int c = 0; c < cases; ++c) {
    std::vector<OrcaLine> lines;
    // Hard lines: walls near the robot (velocity 0 satisfies them).
    const int hard = static_cast<int>(rng() % 3);
    for (int i = 0; i < hard; ++i) {
      const double a = std::numbers::pi * u(rng);
      const ObstacleSegment s{CellPoint{2 * std::cos(a) - std::sin(a),
                                        2 * std::sin(a) + std::cos(a)},
                              CellPoint{2 * std::cos(a) + std::sin(a),
                                        2 * std::sin(a) - std::cos(a)}};
      lines.push_back(OrcaLineForSegment(CellPoint{0, 0}, 0.5, s, 1.0, 0.1));
    }
    const int n = 1 + static_cast<int>(rng() % 10);
    double share;
    for (int i = 0; i < n; ++i)
      lines.push_back(RandomNeighbourLine(rng, &share));
    const double max_speed = 1.5;
    const CellPoint pref{2 * u(rng), 2 * u(rng)};
    const OrcaSolution sol =
        SolveOrcaLines(lines, static_cast<size_t>(hard), max_speed, pref);
    SCOPED_TRACE(::testing::Message() << "case " << c);
    double grid_best =
        std::numeric_limits<double>::infinity();  // distance, feasible
    double grid_minmax = std::numeric_limits<double>::infinity();
    for (double x = -max_speed; x <= max_speed; x += step) {
      for (double y = -max_speed; y <= max_speed; y += step) {
        const CellPoint v{x, y};
        if (std::hypot(x, y) > max_speed) continue;
        bool hard_ok = true;
        for (int i = 0; i < hard; ++i)
          hard_ok = hard_ok && Violates(lines[i], v) <= 0;
        if (!hard_ok) continue;
        double worst = -std::numeric_limits<double>::infinity();
        for (size_t i = static_cast<size_t>(hard); i < lines.size(); ++i) {
          worst = std::max(worst, Violates(lines[i], v));
        }
        grid_minmax = std::min(grid_minmax, worst);
        if (worst <= 0) grid_best = std::min(grid_best, Dist(v, pref));
      }
    }
    for (int i = 0; i < hard; ++i)
      EXPECT_LE(Violates(lines[i], sol.velocity), 1e-7);
    if (sol.feasible) {
      EXPECT_LE(Dist(sol.velocity, pref), grid_best + 1e-9);
    } else {
      ++infeasible;
      EXPECT_TRUE(std::isinf(grid_best))
          << "the grid found a feasible velocity";
      double worst = 0;
      for (size_t i = static_cast<size_t>(hard); i < lines.size(); ++i) {
        worst = std::max(worst, Violates(lines[i], sol.velocity));
      }
      EXPECT_LE(worst, grid_minmax + 1e-6);
    }
  }
  EXPECT_GT(infeasible, 0);
}

// The half-planes keep their promise: when each of two reacting robots picks
// any velocity in its own half-plane, they do not overlap within the
// horizon (the closest approach of the relative motion, computed here).
TEST(OrcaLines, ReciprocalHalfPlanesAvoidCollisionWithinHorizon) {
  std::mt19937 rng(22);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int c = 0; c < Cases(); ++c) {
    const CellPoint pa{0, 0}, pb{5 * u(rng), 5 * u(rng)};
    const double ra = 0.5, rb = 0.4, tau = 2.0;
    if (Dist(pa, pb) <= ra + rb + 0.01) continue;
    const CellPoint va{u(rng), u(rng)}, vb{u(rng), u(rng)};
    const OrcaLine la = OrcaLineForNeighbour(
        pa, va, ra, MovingObstacle{pb, vb, rb, true}, tau, 0.1, 0.5);
    const OrcaLine lb = OrcaLineForNeighbour(
        pb, vb, rb, MovingObstacle{pa, va, ra, true}, tau, 0.1, 0.5);
    for (int k = 0; k < 20; ++k) {
      CellPoint a{2 * u(rng), 2 * u(rng)}, b{2 * u(rng), 2 * u(rng)};
      if (Violates(la, a) > 0 || Violates(lb, b) > 0) continue;
      // Closest approach of pb - pa + t (b - a) over t in [0, tau].
      const CellPoint d{pb.x - pa.x, pb.y - pa.y}, w{b.x - a.x, b.y - a.y};
      const double ww = w.x * w.x + w.y * w.y;
      const double t =
          ww > 0 ? std::clamp(-(d.x * w.x + d.y * w.y) / ww, 0.0, tau) : 0.0;
      EXPECT_GE(std::hypot(d.x + t * w.x, d.y + t * w.y), ra + rb - 1e-9)
          << "case " << c << " sample " << k;
    }
  }
}

// The static obstacle half-plane is sound: any velocity in it keeps the
// robot's disc off the segment for the whole horizon (distance from the
// moving centre to the segment, sampled every 1/200 of the horizon).
TEST(OrcaLines, SegmentHalfPlaneKeepsTheDiscOffTheSegment) {
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const auto segment_distance = [](CellPoint p, const ObstacleSegment& s) {
    const double dx = s.b.x - s.a.x, dy = s.b.y - s.a.y;
    const double len2 = dx * dx + dy * dy;
    const double t =
        len2 > 0 ? std::clamp(((p.x - s.a.x) * dx + (p.y - s.a.y) * dy) / len2,
                              0.0, 1.0)
                 : 0.0;
    return std::hypot(s.a.x + t * dx - p.x, s.a.y + t * dy - p.y);
  };
  int checked = 0;
  for (int c = 0; c < Cases(); ++c) {
    const ObstacleSegment seg{CellPoint{3 * u(rng), 3 * u(rng)},
                              CellPoint{3 * u(rng), 3 * u(rng)}};
    const CellPoint p{4 * u(rng), 4 * u(rng)};
    const double r = 0.5, tau = 1.0 + (u(rng) + 1);
    if (segment_distance(p, seg) <= r) continue;
    const OrcaLine line = OrcaLineForSegment(p, r, seg, tau, 0.1);
    for (int k = 0; k < 10; ++k) {
      const CellPoint v{3 * u(rng), 3 * u(rng)};
      if (Violates(line, v) > 0) continue;
      ++checked;
      for (int i = 0; i <= 200; ++i) {
        const double t = tau * i / 200;
        ASSERT_GE(
            segment_distance(CellPoint{p.x + v.x * t, p.y + v.y * t}, seg),
            r - 1e-9)
            << "case " << c << " t=" << t;
      }
    }
  }
  EXPECT_GT(checked, Cases());
}

// ObstacleSegmentsNear against every ring edge: each edge within range is
// returned (up to the cap), nearest first, and nothing farther.
TEST(OrcaStaticObstacles, SegmentsNearAreTheEdgesWithinRange) {
  std::mt19937 rng(24);
  Grid grid = *Grid::Create(40, 30);
  for (int i = 0; i < 120; ++i) {
    grid.set_cost(static_cast<int32_t>(rng() % 40),
                  static_cast<int32_t>(rng() % 30), kLethalCost);
  }
  const auto polygons = ObstaclePolygons::Build(FreeSpace(grid, false));
  const auto distance = [](CellPoint p, CellPoint a, CellPoint b) {
    const double dx = b.x - a.x, dy = b.y - a.y;
    const double len2 = dx * dx + dy * dy;
    const double t =
        std::clamp(((p.x - a.x) * dx + (p.y - a.y) * dy) / len2, 0.0, 1.0);
    return std::hypot(a.x + t * dx - p.x, a.y + t * dy - p.y);
  };
  for (int c = 0; c < 50; ++c) {
    const CellPoint centre{40.0 * (rng() % 1000) / 1000,
                           30.0 * (rng() % 1000) / 1000};
    const double range = 1.0 + (rng() % 50) / 10.0;
    int expected = 0;
    for (const BoundaryRing& ring : polygons->rings()) {
      for (size_t i = 0; i < ring.vertices.size(); ++i) {
        const GridCorner a = ring.vertices[i];
        const GridCorner b = ring.vertices[(i + 1) % ring.vertices.size()];
        expected += distance(centre, CellPoint{1.0 * a.x, 1.0 * a.y},
                             CellPoint{1.0 * b.x, 1.0 * b.y}) <= range;
      }
    }
    const std::vector<ObstacleSegment> all =
        ObstacleSegmentsNear(*polygons, centre, range, 100000);
    EXPECT_EQ(static_cast<int>(all.size()), expected) << "case " << c;
    double previous = 0;
    for (const ObstacleSegment& s : all) {
      const double d = distance(centre, s.a, s.b);
      EXPECT_LE(d, range);
      EXPECT_GE(d, previous);
      previous = d;
    }
    const std::vector<ObstacleSegment> capped =
        ObstacleSegmentsNear(*polygons, centre, range, 3);
    EXPECT_EQ(capped.size(), std::min<size_t>(3, all.size()));
  }
}

// The lookahead point, by an independent walk along the path: the point at
// arc length (nearest point's arc length + lookahead), clamped to the end.
TEST(LocalTypes, PathTargetIsTheLookaheadPoint) {
  const std::vector<CellPoint> path = {{0, 0}, {4, 0}, {4, 3}, {10, 3}};
  struct Case {
    CellPoint position;
    double lookahead;
    CellPoint expected;
    double remaining;
  } cases[] = {
      {{1, 1}, 2.0, {3, 0}, 12.0},   // nearest (1, 0)
      {{3, -1}, 2.0, {4, 1}, 10.0},  // nearest (3, 0): 1 to the corner
      {{5, 2}, 1.0, {6, 3}, 5.0},    // nearest (4, 2), (5, 3) tie: the later
      {{9, 4}, 5.0, {10, 3}, 1.0},   // clamped to the end
  };
  for (const Case& c : cases) {
    const PathTarget t = FindPathTarget(path, c.position, c.lookahead);
    EXPECT_NEAR(t.point.x, c.expected.x, 1e-9)
        << c.position.x << "," << c.position.y;
    EXPECT_NEAR(t.point.y, c.expected.y, 1e-9)
        << c.position.x << "," << c.position.y;
    EXPECT_NEAR(t.remaining, c.remaining, 1e-9)
        << c.position.x << "," << c.position.y;
  }
}

// The sight line from a robot beside a box to its lookahead point round
// the box's corner cuts the corner; VisibleTarget's point keeps the disc
// clear along the whole line (checked by sampling it against the box as a
// rectangle, apart from the segments the function reads), is on the path,
// and is the plain lookahead point wherever that one is in sight.
TEST(OrcaVisibleTarget, ShortensTheLookaheadUntilTheCornerIsClear) {
  // A box [10, 20] x [10, 14] cells; the path runs under it, then up its
  // left side: the robot at the bottom right corner heads left.
  const double x0 = 10, x1 = 20, y0 = 10, y1 = 14;
  const std::vector<ObstacleSegment> box = {{{x0, y0}, {x1, y0}},
                                            {{x1, y0}, {x1, y1}},
                                            {{x1, y1}, {x0, y1}},
                                            {{x0, y1}, {x0, y0}}};
  const auto box_distance = [&](double x, double y) {
    const double dx = std::max({x0 - x, 0.0, x - x1});
    const double dy = std::max({y0 - y, 0.0, y - y1});
    return std::hypot(dx, dy);
  };
  const double radius = 1.7;
  const std::vector<CellPoint> path = {
      {24, 8}, {8, 8}, {8, 20}, {8, 30}};
  std::mt19937 rng(5);
  int shortened = 0;
  for (int c = 0; c < 200; ++c) {
    // Robots on or near the lower leg, right of the box's corner and
    // clear of the box by at least the radius.
    const CellPoint at{8.5 + 15.0 * (rng() % 1000) / 1000.0,
                       7.3 + 1.4 * (rng() % 1000) / 1000.0};
    if (box_distance(at.x, at.y) < radius) continue;
    const double lookahead = 10.0;
    const PathTarget plain = FindPathTarget(path, at, lookahead);
    const PathTarget seen = VisibleTarget(path, at, radius, box, lookahead);
    const auto clearance = [&](CellPoint t) {
      double worst = 1e9;
      for (int i = 0; i <= 400; ++i) {
        const double f = i / 400.0;
        worst = std::min(worst, box_distance(at.x + f * (t.x - at.x),
                                             at.y + f * (t.y - at.y)));
      }
      return worst;
    };
    // Sampling may miss the exact minimum by a little.
    EXPECT_GE(clearance(seen.point), radius - 0.05) << "case " << c;
    // On the path: its distance to the nearest segment is zero.
    const PathTarget on = FindPathTarget(path, seen.point, 0.0);
    EXPECT_LT(on.distance_to_path, 1e-9) << "case " << c;
    if (clearance(plain.point) >= radius + 0.05) {
      EXPECT_NEAR(seen.point.x, plain.point.x, 1e-9) << "case " << c;
      EXPECT_NEAR(seen.point.y, plain.point.y, 1e-9) << "case " << c;
    } else if (clearance(plain.point) < radius - 0.05) {
      ++shortened;
      // Nearer along the path: more of it left after the point.
      EXPECT_GT(on.remaining, FindPathTarget(path, plain.point, 0.0).remaining)
          << "case " << c;
    }
  }
  // The cases did include corners cut.
  EXPECT_GT(shortened, 20);
}

// Where constant (v, vy, w) takes `p` after t seconds, in closed form.
Pose ExactMotion(const Pose& p, double v, double vy, double w, double t) {
  if (std::fabs(w) < 1e-12) {
    const double c = std::cos(p.yaw), s = std::sin(p.yaw);
    return Pose{p.x + (v * c - vy * s) * t, p.y + (v * s + vy * c) * t, p.yaw};
  }
  const double a = p.yaw, b = p.yaw + w * t;
  // Integral of the rotated body velocity over the arc.
  const double x =
      (v * (std::sin(b) - std::sin(a)) + vy * (std::cos(b) - std::cos(a))) / w;
  const double y =
      (-v * (std::cos(b) - std::cos(a)) + vy * (std::sin(b) - std::sin(a))) / w;
  return Pose{p.x + x, p.y + y, NormalizeAngle(b)};
}

struct SimRobot {
  CellPoint position;
  CellPoint velocity;
  std::vector<CellPoint> path;
  double radius = 0.5;
  double yaw = 0.0;
  double w = 0.0;
  bool arrived = false;
};

// Steps every robot with ORCA from the same snapshot (no acceleration limit;
// holonomic or differential drive, each period moved exactly; keep_right
// >= 0 replaces the option's default), checking
// separation after every step and, when `grid` is given, that no robot overlaps
// a blocked cell. Returns the time the last robot arrived (infinity when one
// did not within max_time).
double RunFleet(std::vector<SimRobot>& robots, const Grid* grid,
                double max_time, bool holonomic = true,
                double keep_right = -1) {
  const double dt = 0.1;
  OrcaOptions options;
  options.max_neighbours = robots.size();
  options.respect_acceleration = false;
  VelocityLimits limits;
  limits.holonomic = holonomic;
  limits.min_v = holonomic ? -1.0 : 0.0;
  limits.max_v = 1.0;
  limits.max_vy = holonomic ? 1.0 : 0.0;
  limits.max_w = 2.0;
  if (keep_right >= 0) options.keep_right = keep_right;
  std::shared_ptr<const ObstaclePolygons> polygons;
  if (grid != nullptr)
    polygons = ObstaclePolygons::Build(FreeSpace(*grid, false));
  double t = 0.0;
  for (; t < max_time; t += dt) {
    std::vector<LocalPlan> next(robots.size());
    bool all = true;
    for (size_t i = 0; i < robots.size(); ++i) {
      std::vector<MovingObstacle> others;
      for (size_t j = 0; j < robots.size(); ++j) {
        if (j != i) {
          others.push_back(MovingObstacle{
              robots[j].position, robots[j].velocity, robots[j].radius, true});
        }
      }
      std::vector<ObstacleSegment> segments;
      if (polygons) {
        segments =
            ObstacleSegmentsNear(*polygons, robots[i].position,
                                 options.obstacle_range + robots[i].radius,
                                 options.max_obstacle_lines);
      }
      // The grid-frame velocity in the body frame.
      const double c = std::cos(robots[i].yaw), sn = std::sin(robots[i].yaw);
      const CellPoint u = robots[i].velocity;
      RobotState state{
          Pose{robots[i].position.x, robots[i].position.y, robots[i].yaw},
          u.x * c + u.y * sn, -u.x * sn + u.y * c, robots[i].w};
      absl::StatusOr<LocalPlan> plan =
          OrcaStep(state, robots[i].radius, limits, others, segments,
                   robots[i].path, dt, options);
      EXPECT_TRUE(plan.ok()) << plan.status();
      if (!plan.ok()) return std::numeric_limits<double>::infinity();
      robots[i].arrived = plan->status == LocalStatus::kGoalReached;
      all = all && robots[i].arrived;
      next[i] = *plan;
    }
    if (all) return t;
    for (size_t i = 0; i < robots.size(); ++i) {
      const Pose moved = ExactMotion(
          Pose{robots[i].position.x, robots[i].position.y, robots[i].yaw},
          next[i].v, next[i].vy, next[i].w, dt);
      robots[i].position = moved.point();
      robots[i].yaw = moved.yaw;
      robots[i].w = next[i].w;
      const double c = std::cos(moved.yaw), sn = std::sin(moved.yaw);
      robots[i].velocity = CellPoint{next[i].v * c - next[i].vy * sn,
                                     next[i].v * sn + next[i].vy * c};
    }
    for (size_t i = 0; i < robots.size(); ++i) {
      for (size_t j = i + 1; j < robots.size(); ++j) {
        const double d = Dist(robots[i].position, robots[j].position);
        if (d < robots[i].radius + robots[j].radius - 1e-6) {
          ADD_FAILURE() << "robots " << i << " and " << j << " at distance "
                        << d << " at t=" << t;
          return std::numeric_limits<double>::infinity();
        }
      }
      if (grid != nullptr) {
        // No blocked cell's square (nor the map's outside) within the radius.
        const CellPoint p = robots[i].position;
        const double r = robots[i].radius;
        if (p.x < r - 1e-6 || p.y < r - 1e-6 ||
            p.x > grid->width() - r + 1e-6 || p.y > grid->height() - r + 1e-6) {
          ADD_FAILURE() << "robot " << i << " leaves the map at t=" << t;
          return std::numeric_limits<double>::infinity();
        }
        for (int32_t y = 0; y < grid->height(); ++y) {
          for (int32_t x = 0; x < grid->width(); ++x) {
            if (grid->cost(x, y) < kInscribedCost) continue;
            const double dx = std::max({x - p.x, 0.0, p.x - (x + 1)});
            const double dy = std::max({y - p.y, 0.0, p.y - (y + 1)});
            if (std::hypot(dx, dy) < r - 1e-6) {
              ADD_FAILURE() << "robot " << i << " enters blocked cell (" << x
                            << ", " << y << ") at t=" << t;
              return std::numeric_limits<double>::infinity();
            }
          }
        }
      }
    }
  }
  return std::numeric_limits<double>::infinity();
}

class OrcaCircleSwap : public ::testing::TestWithParam<int> {};

TEST_P(OrcaCircleSwap, RobotsSwapWithoutContactAndArrive) {
  const int n = GetParam();
  const double ring = 4.0 + 0.4 * n;
  std::vector<SimRobot> robots(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    const double a = 2 * std::numbers::pi * i / n;
    robots[i].position = CellPoint{ring * std::cos(a), ring * std::sin(a)};
    robots[i].yaw = NormalizeAngle(1.7 * i);  // any heading: holonomic
    robots[i].path = {robots[i].position,
                      CellPoint{-robots[i].position.x, -robots[i].position.y}};
  }
  const double bound = 3 * (2 * ring) / 1.0 + 20.0;
  const double arrival = RunFleet(robots, nullptr, bound);
  EXPECT_LT(arrival, bound);
  EXPECT_GT(arrival, 2 * ring - 1.0);
  for (int i = 0; i < n; ++i)
    EXPECT_TRUE(robots[i].arrived)
        << "robot " << i << " at " << robots[i].position.x << ","
        << robots[i].position.y << " v " << robots[i].velocity.x << ","
        << robots[i].velocity.y;
}

// Differential drive through the "turn toward it" mapping with the forward
// speed kept inside the half-planes along the heading: separation is
// checked against the true radii. Such robots cannot sidestep, so they need
// a stronger keep-right (0.5 rad) to get round each other; 32 of them jam
// in a ring (a deadlock, docs/decisions.md) but still never touch.
std::vector<SimRobot> DiffDriveCircle(int n) {
  const double ring = 4.0 + 0.4 * n;
  std::vector<SimRobot> robots(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    const double a = 2 * std::numbers::pi * i / n;
    robots[i].position = CellPoint{ring * std::cos(a), ring * std::sin(a)};
    robots[i].yaw = NormalizeAngle(a + std::numbers::pi);
    robots[i].path = {robots[i].position,
                      CellPoint{-robots[i].position.x, -robots[i].position.y}};
  }
  return robots;
}

class OrcaCircleSwapDiffDrive : public ::testing::TestWithParam<int> {};

TEST_P(OrcaCircleSwapDiffDrive, RobotsSwapWithoutContactAndArrive) {
  std::vector<SimRobot> robots = DiffDriveCircle(GetParam());
  const double bound = 3 * 2 * (4.0 + 0.4 * GetParam()) + 20.0;
  const double arrival =
      RunFleet(robots, nullptr, bound, /*holonomic=*/false, 0.5);
  EXPECT_LT(arrival, bound);
  // Not faster than straight across at full speed.
  EXPECT_GT(arrival, 2 * (4.0 + 0.4 * GetParam()) - 1.0);
}

INSTANTIATE_TEST_SUITE_P(Fleets, OrcaCircleSwapDiffDrive,
                         ::testing::Values(8, 16));

TEST(OrcaCircleSwapDiffDrive, ThirtyTwoJamButNeverTouch) {
  std::vector<SimRobot> robots = DiffDriveCircle(32);
  // RunFleet fails the test on any contact.
  RunFleet(robots, nullptr, 60.0, /*holonomic=*/false, 0.5);
}

INSTANTIATE_TEST_SUITE_P(Fleets, OrcaCircleSwap, ::testing::Values(8, 16, 32));

Grid MakeGrid(const std::vector<std::string>& rows) {
  // rows[0] is the top row (largest y), as drawn.
  const int32_t h = static_cast<int32_t>(rows.size());
  const int32_t w = static_cast<int32_t>(rows[0].size());
  Grid g = *Grid::Create(w, h);
  for (int32_t r = 0; r < h; ++r) {
    for (int32_t x = 0; x < w; ++x) {
      if (rows[r][x] == '#') g.set_cost(x, h - 1 - r, kLethalCost);
    }
  }
  return g;
}

TEST(OrcaStaticObstacles, CorridorTrafficStaysOffBlockedCells) {
  const Grid grid = MakeGrid({
      "........................",
      "........................",
      "........########........",
      "........########........",
      "........................",
      "........................",
      "........................",
      "........########........",
      "........########........",
  });
  std::vector<SimRobot> robots(3);
  robots[0].position = CellPoint{1.5, 3.5};
  robots[0].path = {robots[0].position, CellPoint{22.5, 3.5}};
  robots[1].position = CellPoint{22.5, 4.5};
  robots[1].path = {robots[1].position, CellPoint{1.5, 4.5}};
  // Its straight path runs into the lower block: ORCA must stop at the wall
  // (it does not arrive; the global planner is the one to go around).
  robots[2].position = CellPoint{1.5, 1.0};
  robots[2].path = {robots[2].position, CellPoint{22.5, 1.0}};
  for (SimRobot& r : robots) r.radius = 0.4;
  RunFleet(robots, &grid, 60.0);
  EXPECT_FALSE(robots[2].arrived);
  EXPECT_GT(robots[2].position.x, 5.0) << "it should approach the wall";
}

TEST(OrcaStaticObstacles, CorridorTrafficArrives) {
  const Grid grid = MakeGrid({
      "........................",
      "........########........",
      "........########........",
      "........................",
      "........................",
      "........................",
      "........########........",
      "........########........",
  });
  // The corridor is y in [2, 5]: two robots each way, on their right.
  std::vector<SimRobot> robots(4);
  robots[0].position = CellPoint{1.5, 2.6};
  robots[0].path = {robots[0].position, CellPoint{22.5, 2.6}};
  robots[1].position = CellPoint{22.5, 4.4};
  robots[1].path = {robots[1].position, CellPoint{1.5, 4.4}};
  robots[2].position = CellPoint{3.5, 2.6};
  robots[2].path = {robots[2].position, CellPoint{20.5, 2.6}};
  robots[3].position = CellPoint{20.5, 4.4};
  robots[3].path = {robots[3].position, CellPoint{3.5, 4.4}};
  for (SimRobot& r : robots) r.radius = 0.4;
  EXPECT_LT(RunFleet(robots, &grid, 120.0), 120.0);
}

// --- DWA ---

Footprint Rectangle() {
  return *Footprint::Polygon({CellPoint{0.6, 0.4}, CellPoint{-0.6, 0.4},
                              CellPoint{-0.6, -0.4}, CellPoint{0.6, -0.4}});
}

testing::KinematicCheck DenseCheck(const Footprint& f, bool holonomic) {
  testing::KinematicCheck check;
  check.footprint = f.vertices();
  check.step_cells = 0.02;
  check.allow_reverse = true;
  check.allow_turn_in_place = true;
  check.allow_sideways = holonomic;
  check.check_ends = false;
  check.max_drift = 1e-6;
  return check;
}

TEST(Dwa, CommandsInTheWindowAndAcceptedRolloutsAreCollisionFree) {
  std::mt19937 rng(30);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Footprint footprint = Rectangle();
  FootprintCheckerOptions copt;
  copt.margin_cells = 0.1;
  const FootprintChecker checker = *FootprintChecker::Create(footprint, copt);
  const int cases = std::max(5, Cases() / 25);
  int accepted = 0, rejected = 0;
  for (int c = 0; c < cases; ++c) {
    Grid grid = *Grid::Create(20, 20);
    for (int32_t y = 0; y < 20; ++y) {
      for (int32_t x = 0; x < 20; ++x) {
        if (u(rng) < 0.06) grid.set_cost(x, y, kLethalCost);
      }
    }
    const std::vector<float> distance = ObstacleDistanceField(grid, false);
    Pose start;
    do {
      start =
          Pose{2 + 16 * u(rng), 2 + 16 * u(rng), 2 * std::numbers::pi * u(rng)};
    } while (checker.Collides(grid, start, false, distance.data()));
    const bool holonomic = c % 3 == 0;
    VelocityLimits limits;
    limits.holonomic = holonomic;
    limits.min_v = -0.3;
    limits.max_v = 1.5;
    limits.max_vy = holonomic ? 0.8 : 0.0;
    limits.max_w = 1.2;
    limits.acc_v = 1.0;
    limits.acc_vy = 1.0;
    limits.acc_w = 2.0;
    RobotState state{start,
                     limits.min_v + (limits.max_v - limits.min_v) * u(rng),
                     holonomic ? (2 * u(rng) - 1) * limits.max_vy : 0.0,
                     (2 * u(rng) - 1) * limits.max_w};
    const std::vector<CellPoint> path = {
        start.point(), CellPoint{1 + 18 * u(rng), 1 + 18 * u(rng)}};
    DwaOptions options;
    options.v_samples = 5;
    options.w_samples = 7;
    options.vy_samples = 3;
    const double period = 0.2;
    std::vector<DwaRollout> rollouts;
    absl::StatusOr<LocalPlan> plan =
        DwaStep(DwaMap{&grid, &checker, c % 2 == 0 ? distance.data() : nullptr},
                state, limits, {}, path, period, options, &rollouts);
    ASSERT_TRUE(plan.ok()) << plan.status();
    SCOPED_TRACE(::testing::Message() << "case " << c);
    // The window, from its definition.
    const double eps = 1e-9;
    EXPECT_GE(plan->v,
              std::max(limits.min_v, state.v - limits.acc_v * period) - eps);
    EXPECT_LE(plan->v,
              std::min(limits.max_v, state.v + limits.acc_v * period) + eps);
    EXPECT_GE(plan->w,
              std::max(-limits.max_w, state.w - limits.acc_w * period) - eps);
    EXPECT_LE(plan->w,
              std::min(limits.max_w, state.w + limits.acc_w * period) + eps);
    if (holonomic) {
      EXPECT_GE(
          plan->vy,
          std::max(-limits.max_vy, state.vy - limits.acc_vy * period) - eps);
      EXPECT_LE(
          plan->vy,
          std::min(limits.max_vy, state.vy + limits.acc_vy * period) + eps);
    } else {
      EXPECT_EQ(plan->vy, 0.0);
    }
    bool command_among_accepted = plan->status != LocalStatus::kOk;
    for (const DwaRollout& r : rollouts) {
      if (!r.admissible) {
        ++rejected;
        continue;
      }
      ++accepted;
      command_among_accepted =
          command_among_accepted ||
          (r.v == plan->v && r.vy == plan->vy && r.w == plan->w);
      EXPECT_EQ(CheckKinematicPath(grid, r.poses, {},
                                   DenseCheck(footprint, holonomic)),
                "")
          << "rollout v=" << r.v << " vy=" << r.vy << " w=" << r.w;
      // The rollout is the motion of its velocity over the horizon.
      const Pose exact =
          ExactMotion(state.pose, r.v, r.vy, r.w, options.horizon);
      EXPECT_NEAR(r.poses.back().x, exact.x, 1e-2);
      EXPECT_NEAR(r.poses.back().y, exact.y, 1e-2);
      EXPECT_NEAR(AngleBetween(r.poses.back().yaw, exact.yaw), 0.0, 1e-6);
    }
    EXPECT_TRUE(command_among_accepted);
  }
  EXPECT_GT(accepted, 0);
  EXPECT_GT(rejected, 0);
}

TEST(Dwa, FollowsAPathAroundAnObstacleToTheGoal) {
  const Grid grid = MakeGrid({
      "..............................",
      "..............................",
      "..............................",
      "..........######..............",
      "..........######..............",
      "..........######..............",
      "..........######..............",
      "..........######..............",
      "..........######..............",
      "..............................",
      "..............................",
      "..............................",
  });
  const Footprint footprint = Rectangle();
  FootprintCheckerOptions copt;
  copt.margin_cells = 0.1;
  const FootprintChecker checker = *FootprintChecker::Create(footprint, copt);
  const std::vector<float> distance = ObstacleDistanceField(grid, false);
  // The global path passes under the block.
  const std::vector<CellPoint> path = {
      {3.5, 6.0}, {8.0, 1.5}, {18.0, 1.5}, {26.5, 6.0}};
  VelocityLimits limits;
  limits.min_v = 0.0;
  limits.max_v = 2.0;
  limits.max_w = 1.5;
  limits.acc_v = 2.0;
  limits.acc_w = 3.0;
  RobotState state{Pose{3.5, 6.0, 0.0}, 0.0, 0.0, 0.0};
  DwaOptions options;
  const double period = 0.1;
  bool arrived = false;
  for (int cycle = 0; cycle < 600 && !arrived; ++cycle) {
    absl::StatusOr<LocalPlan> plan =
        DwaStep(DwaMap{&grid, &checker, distance.data()}, state, limits, {},
                path, period, options);
    ASSERT_TRUE(plan.ok()) << plan.status();
    ASSERT_NE(plan->status, LocalStatus::kBlocked) << plan->reason;
    if (plan->status == LocalStatus::kGoalReached) {
      arrived = true;
      break;
    }
    // Execute one period, exactly, and check the motion densely.
    std::vector<Pose> moved;
    for (int k = 0; k <= 10; ++k) {
      moved.push_back(
          ExactMotion(state.pose, plan->v, plan->vy, plan->w, period * k / 10));
    }
    ASSERT_EQ(CheckKinematicPath(grid, moved, {}, DenseCheck(footprint, false)),
              "")
        << "cycle " << cycle;
    state = RobotState{moved.back(), plan->v, 0.0, plan->w};
  }
  EXPECT_TRUE(arrived) << "ended at " << state.pose.x << ", " << state.pose.y;
}

TEST(Dwa, TooFastTowardAWallIsBlocked) {
  const Grid grid = MakeGrid({
      "..........",
      "......#...",
      "......#...",
      "......#...",
      "......#...",
      "..........",
  });
  const FootprintChecker checker = *FootprintChecker::Create(Rectangle());
  VelocityLimits limits;
  limits.max_v = 2.0;
  limits.acc_v = 0.1;  // cannot stop within the horizon
  limits.max_w = 0.2;
  limits.acc_w = 0.1;
  const RobotState state{Pose{4.5, 3.0, 0.0}, 2.0, 0.0, 0.0};
  const std::vector<CellPoint> path = {{4.5, 3.0}, {9.5, 3.0}};
  absl::StatusOr<LocalPlan> plan =
      DwaStep(DwaMap{&grid, &checker, nullptr}, state, limits, {}, path, 0.1,
              DwaOptions{});
  ASSERT_TRUE(plan.ok()) << plan.status();
  EXPECT_EQ(plan->status, LocalStatus::kBlocked);
  EXPECT_NE(plan->reason.find("with the map"), std::string::npos)
      << plan->reason;
  EXPECT_LT(plan->v, 2.0);  // braking

  // Standing on the wall: blocked, and the reason says why.
  const RobotState on_wall{Pose{6.2, 3.0, 0.0}, 0.0, 0.0, 0.0};
  plan = DwaStep(DwaMap{&grid, &checker, nullptr}, on_wall, limits, {}, path,
                 0.1, DwaOptions{});
  ASSERT_TRUE(plan.ok()) << plan.status();
  EXPECT_EQ(plan->status, LocalStatus::kBlocked);
  EXPECT_NE(plan->reason.find("current pose"), std::string::npos)
      << plan->reason;
}

// Two DWA robots head-on treat each other as obstacles moving at constant
// velocity and stall nose to nose (docs/performance.md); the stall must be
// reported, never silent: every robot that does not arrive ends with
// kLocalMinimum (or kBlocked), and they never touch.
TEST(Dwa, AHeadOnStallIsReported) {
  const Grid grid = *Grid::Create(30, 10);
  const FootprintChecker checker =
      *FootprintChecker::Create(*Footprint::Circle(0.5));
  const std::vector<float> distance = ObstacleDistanceField(grid, false);
  VelocityLimits limits;
  limits.max_v = 1.0;
  limits.max_w = 2.0;
  limits.acc_v = 2.0;
  limits.acc_w = 4.0;
  RobotState robots[2] = {{Pose{5.0, 5.0, 0.0}, 0, 0, 0},
                          {Pose{25.0, 5.0, std::numbers::pi}, 0, 0, 0}};
  const std::vector<CellPoint> paths[2] = {{{5.0, 5.0}, {25.0, 5.0}},
                                           {{25.0, 5.0}, {5.0, 5.0}}};
  ProgressWindow progress[2];
  LocalStatus last[2] = {LocalStatus::kOk, LocalStatus::kOk};
  const double period = 0.1;
  for (int cycle = 0; cycle < 400; ++cycle) {
    LocalPlan plans[2];
    for (int i = 0; i < 2; ++i) {
      const RobotState& other = robots[1 - i];
      const MovingObstacle o{other.pose.point(),
                             CellPoint{other.v * std::cos(other.pose.yaw),
                                       other.v * std::sin(other.pose.yaw)},
                             0.5, false};
      absl::StatusOr<LocalPlan> plan = DwaStep(
          DwaMap{&grid, &checker, distance.data()}, robots[i], limits, {&o, 1},
          paths[i], period, DwaOptions{}, nullptr, &progress[i]);
      ASSERT_TRUE(plan.ok()) << plan.status();
      plans[i] = *plan;
      last[i] = plan->status;
    }
    if (last[0] == LocalStatus::kGoalReached &&
        last[1] == LocalStatus::kGoalReached) {
      break;
    }
    for (int i = 0; i < 2; ++i) {
      robots[i] = RobotState{
          ExactMotion(robots[i].pose, plans[i].v, 0, plans[i].w, period),
          plans[i].v, 0, plans[i].w};
    }
    ASSERT_GE(std::hypot(robots[0].pose.x - robots[1].pose.x,
                         robots[0].pose.y - robots[1].pose.y),
              1.0)
        << "cycle " << cycle;
  }
  for (int i = 0; i < 2; ++i) {
    EXPECT_NE(last[i], LocalStatus::kOk) << "robot " << i;
  }
}

TEST(Dwa, AMovingObstacleHeadOnRejectsTheStraightRollouts) {
  const Grid grid = *Grid::Create(30, 10);
  const FootprintChecker checker = *FootprintChecker::Create(Rectangle());
  VelocityLimits limits;
  limits.max_v = 1.0;
  limits.max_w = 1.0;
  const RobotState state{Pose{5.0, 5.0, 0.0}, 1.0, 0.0, 0.0};
  const std::vector<CellPoint> path = {{5.0, 5.0}, {25.0, 5.0}};
  const MovingObstacle person{CellPoint{12.0, 5.0}, CellPoint{-1.0, 0.0}, 0.5,
                              false};
  std::vector<DwaRollout> rollouts;
  DwaOptions options;
  options.horizon = 3.0;
  absl::StatusOr<LocalPlan> plan =
      DwaStep(DwaMap{&grid, &checker, nullptr}, state, limits, {&person, 1},
              path, 0.1, options, &rollouts);
  ASSERT_TRUE(plan.ok()) << plan.status();
  EXPECT_EQ(plan->status, LocalStatus::kOk) << plan->reason;
  int by_obstacle = 0;
  for (const DwaRollout& r : rollouts)
    by_obstacle += r.rejected == "moving obstacle";
  EXPECT_GT(by_obstacle, 0);
  // The command's predicted trajectory keeps clear of the predicted person.
  const double h = options.horizon / (plan->trajectory.size() - 1);
  for (size_t i = 0; i < plan->trajectory.size(); ++i) {
    const double px = 12.0 - h * i;
    EXPECT_GE(
        std::hypot(plan->trajectory[i].x - px, plan->trajectory[i].y - 5.0),
        0.5 + checker.footprint().circumscribed_radius() - 1e-9);
  }
}

// --- FIRAS ---

// Drives a differential-drive robot with FIRAS (exact motion per period);
// returns the first status other than kOk, and checks the robot's disc
// never overlaps a blocked cell.
LocalStatus DriveFiras(const Grid& grid, Pose start,
                       const std::vector<CellPoint>& path, int cycles,
                       Pose* end) {
  VelocityLimits limits;
  limits.max_v = 1.0;
  limits.max_w = 1.5;
  limits.acc_v = 2.0;
  limits.acc_w = 4.0;
  const double radius = 0.4, period = 0.1;
  RobotState state{start, 0, 0, 0};
  ProgressWindow memory;
  for (int cycle = 0; cycle < cycles; ++cycle) {
    absl::StatusOr<LocalPlan> plan = FirasStep(
        grid, state, radius, limits, {}, path, period, FirasOptions{}, &memory);
    EXPECT_TRUE(plan.ok()) << plan.status();
    if (!plan.ok()) return LocalStatus::kBlocked;
    if (plan->status != LocalStatus::kOk) {
      *end = state.pose;
      std::cerr << "cycle " << cycle << " at " << end->x << "," << end->y
                << ": " << plan->reason << "\n";
      return plan->status;
    }
    state = RobotState{ExactMotion(state.pose, plan->v, 0, plan->w, period),
                       plan->v, 0, plan->w};
    for (int32_t y = 0; y < grid.height(); ++y) {
      for (int32_t x = 0; x < grid.width(); ++x) {
        if (grid.cost(x, y) < kInscribedCost) continue;
        const double dx =
            std::max({x - state.pose.x, 0.0, state.pose.x - (x + 1)});
        const double dy =
            std::max({y - state.pose.y, 0.0, state.pose.y - (y + 1)});
        EXPECT_GE(std::hypot(dx, dy), radius)
            << "cycle " << cycle << " cell " << x << "," << y;
      }
    }
  }
  *end = state.pose;
  return LocalStatus::kOk;
}

TEST(Firas, AUShapedTrapIsALocalMinimum) {
  const Grid grid = MakeGrid({
      "..............................",
      "..............................",
      "..............................",
      "............#######...........",
      "..................#...........",
      "..................#...........",
      "..................#...........",
      "..................#...........",
      "..................#...........",
      "..................#...........",
      "............#######...........",
      "..............................",
      "..............................",
      "..............................",
  });
  // The naive global path runs straight through the cup's back wall.
  const std::vector<CellPoint> path = {{4.5, 7.0}, {27.5, 7.0}};
  Pose end;
  EXPECT_EQ(DriveFiras(grid, Pose{4.5, 7.0, 0.0}, path, 600, &end),
            LocalStatus::kLocalMinimum);
  EXPECT_GT(end.x, 12.0) << "it should be inside the cup";
  EXPECT_LT(end.x, 18.0);
}

TEST(Firas, OpenMapReachesTheGoal) {
  const Grid grid = MakeGrid({
      "..............................",
      "..............................",
      "..............................",
      "..............#...............",
      "..............#...............",
      "..............................",
      "..............................",
      "..............................",
      "..............................",
      "..............................",
  });
  // The path passes just under the small block, which pushes the robot aside
  // (a block straight across the path would be a local minimum too).
  const std::vector<CellPoint> path = {{2.5, 4.5}, {27.5, 4.5}};
  Pose end;
  EXPECT_EQ(DriveFiras(grid, Pose{2.5, 4.5, 0.0}, path, 600, &end),
            LocalStatus::kGoalReached);
}

TEST(Firas, BadInputNamesTheField) {
  const Grid grid = *Grid::Create(5, 5);
  FirasOptions options;
  options.influence = -1;
  const std::vector<CellPoint> path = {{1, 1}};
  absl::StatusOr<LocalPlan> plan =
      FirasStep(grid, RobotState{}, 0.4, VelocityLimits{}, {}, path, 0.1,
                options, nullptr);
  ASSERT_FALSE(plan.ok());
  EXPECT_NE(plan.status().message().find("influence"), std::string::npos);
}

TEST(OrcaStep, BadInputNamesTheField) {
  RobotState state;
  VelocityLimits limits;
  OrcaOptions options;
  const std::vector<CellPoint> path = {CellPoint{1, 1}};
  options.time_horizon = 0;
  EXPECT_NE(OrcaStep(state, 0.5, limits, {}, {}, path, 0.1, options)
                .status()
                .message()
                .find("time_horizon"),
            std::string::npos);
  options = OrcaOptions{};
  limits.acc_v = -1;
  EXPECT_NE(OrcaStep(state, 0.5, limits, {}, {}, path, 0.1, options)
                .status()
                .message()
                .find("acc_v"),
            std::string::npos);
  limits = VelocityLimits{};
  EXPECT_FALSE(OrcaStep(state, 0.5, limits, {}, {}, {}, 0.1, options).ok());
  EXPECT_FALSE(OrcaStep(state, -1, limits, {}, {}, path, 0.1, options).ok());
}

}  // namespace
}  // namespace pathd
