// The path smoother (core/kinematics/smoother.h): smoothed paths stay valid
// for the independent checker (footprint, curvature, direction, ends), keep
// their cusps and ends, are smoother than the input, and keep the original
// poses where smoothing them would collide.
#include "core/kinematics/smoother.h"

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "core/kinematics/footprint.h"
#include "core/kinematics/motion_check.h"
#include "core/kinematics/pose_path.h"
#include "core/kinematics/vehicle.h"
#include "core/planners/kinematic/hybrid_astar.h"
#include "gtest/gtest.h"
#include "tests/testing/kinematic_checker.h"
#include "tests/testing/test_grids.h"

namespace pathd {
namespace {

constexpr double kPi = std::numbers::pi;

testing::KinematicCheck CheckFor(const Footprint& f, const std::vector<PathPose>& path,
                                 double min_turning_radius) {
  testing::KinematicCheck c;
  if (f.is_circle()) {
    c.circle_radius = f.circle_radius();
  } else {
    c.footprint = f.vertices();
  }
  c.min_turning_radius = min_turning_radius;
  c.start = path.front().pose;
  c.goal = path.back().pose;
  return c;
}

std::string Check(const Grid& grid, const std::vector<PathPose>& path,
                  const testing::KinematicCheck& check) {
  std::vector<Pose> poses;
  std::vector<bool> reverse;
  for (const PathPose& p : path) {
    poses.push_back(p.pose);
    reverse.push_back(p.reverse);
  }
  return testing::CheckKinematicPath(grid, poses, reverse, check);
}

// Sum of squared heading changes between consecutive pieces' directions of
// travel: what smoothing lowers.
double Roughness(const std::vector<PathPose>& path) {
  double sum = 0.0;
  for (size_t i = 2; i < path.size(); ++i) {
    const Pose& a = path[i - 2].pose;
    const Pose& b = path[i - 1].pose;
    const Pose& c = path[i].pose;
    if (path[i].reverse != path[i - 1].reverse) continue;
    const double turn = NormalizeAngle(std::atan2(c.y - b.y, c.x - b.x) -
                                       std::atan2(b.y - a.y, b.x - a.x));
    sum += turn * turn;
  }
  return sum;
}

// Hybrid A* paths (unsmoothed) between random poses on cluttered maps,
// smoothed: every one stays valid, with the same ends, cusps and size.
TEST(SmoothPath, HybridPathsStayValidAndGetSmoother) {
  std::mt19937 rng(12);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const std::vector<Footprint> footprints = {
      Footprint::Circle(0.8).value(),
      Footprint::Polygon({{-0.8, -0.6}, {2.0, -0.6}, {2.0, 0.6}, {-0.8, 0.6}}).value(),
  };
  int smoothed = 0, changed = 0;
  double before = 0.0, after = 0.0;
  for (int trial = 0; trial < 120; ++trial) {
    Grid grid = Grid::Create(40, 30).value();
    for (int b = 0; b < 10; ++b) {
      const int x0 = static_cast<int>(rng() % 40), y0 = static_cast<int>(rng() % 30);
      for (int y = y0; y < std::min(30, y0 + 4); ++y) {
        for (int x = x0; x < std::min(40, x0 + 4); ++x) grid.set_cost(x, y, kLethalCost);
      }
    }
    const Footprint& footprint = footprints[trial % 2];
    KinematicQuery q;
    q.footprint = SharedFootprintChecker(footprint).value();
    q.motion = trial % 3 == 0 ? MotionModel::kDubins : MotionModel::kReedsShepp;
    q.min_turning_radius_cells = 2.0 + 3.0 * u(rng);
    q.smooth = false;
    q.start = Pose{40 * u(rng), 30 * u(rng), 2 * kPi * u(rng)};
    q.goal = Pose{40 * u(rng), 30 * u(rng), 2 * kPi * u(rng)};
    if (q.footprint->Collides(grid, q.start, false) || q.footprint->Collides(grid, q.goal, false)) {
      continue;
    }
    PlanRequest request = PlanRequest::Between(q.start.cell(), q.goal.cell());
    request.kinematic = std::make_shared<KinematicQuery>(q);
    auto r = PlanHybridAStar(grid, request, StopCondition(absl::InfiniteFuture(), nullptr, 20000));
    ASSERT_TRUE(r.ok()) << r.status();
    if (!r->found() || r->poses.size() < 3) continue;
    const std::vector<float> distance = ObstacleDistanceField(grid, false);
    const MotionChecker motion =
        MotionChecker::Create(q.footprint, grid, false, distance.data()).value();
    SmootherOptions options;
    options.min_turning_radius = q.min_turning_radius_cells;
    const std::vector<PathPose> out = SmoothPath(r->poses, motion, options);
    ++smoothed;
    ASSERT_EQ(out.size(), r->poses.size());
    EXPECT_EQ(Check(grid, out, CheckFor(footprint, r->poses, q.min_turning_radius_cells)), "")
        << "trial " << trial;
    bool moved = false;
    for (size_t i = 0; i < out.size(); ++i) {
      EXPECT_EQ(out[i].reverse, r->poses[i].reverse);
      const bool end = i == 0 || i + 1 == out.size();
      const bool cusp = i > 1 && i + 1 < out.size() && out[i + 1].reverse != out[i].reverse;
      if (end || cusp) {
        EXPECT_EQ(out[i].pose.x, r->poses[i].pose.x) << "trial " << trial << " pose " << i;
        EXPECT_EQ(out[i].pose.y, r->poses[i].pose.y) << "trial " << trial << " pose " << i;
        EXPECT_EQ(out[i].pose.yaw, r->poses[i].pose.yaw) << "trial " << trial << " pose " << i;
      }
      moved = moved || out[i].pose.x != r->poses[i].pose.x || out[i].pose.y != r->poses[i].pose.y;
    }
    changed += moved;
    before += Roughness(r->poses);
    after += Roughness(out);
  }
  std::printf("%d paths smoothed, %d changed; roughness %.3f -> %.3f\n", smoothed, changed,
              before, after);
  EXPECT_GT(smoothed, 30);
  EXPECT_GT(changed, smoothed / 2);
  EXPECT_LT(after, before);
}

// An 8-connected grid path's corners, rounded for a disc that fits; the
// smoothed polyline stays free and is smoother.
TEST(SmoothPolyline, RoundsAGridPath) {
  const Grid grid = Grid::Create(20, 20).value();
  std::vector<CellPoint> cells;
  for (int i = 0; i < 8; ++i) cells.push_back({2.5 + i, 2.5});
  for (int i = 1; i < 8; ++i) cells.push_back({9.5 + i, 2.5 + i});
  for (int i = 1; i < 6; ++i) cells.push_back({16.5, 9.5 + i});
  const Footprint disc = Footprint::Circle(0.6).value();
  const auto out = SmoothPolyline(grid, cells, SharedFootprintChecker(disc).value(), false);
  ASSERT_TRUE(out.ok()) << out.status();
  const std::vector<PathPose> in = PosesAlongPolyline(cells);
  ASSERT_EQ(out->size(), in.size());
  // A disc's heading does not matter; the polyline's poses slide sideways
  // at the bends anyway.
  testing::KinematicCheck check = CheckFor(disc, in, 0.0);
  check.allow_sideways = true;
  EXPECT_EQ(Check(grid, *out, check), "");
  std::printf("roughness %.3f -> %.3f\n", Roughness(in), Roughness(*out));
  EXPECT_LT(Roughness(*out), 0.5 * Roughness(in));
}

// Around the corner of a block, close to it: the plain gradient descent
// (Nav2's simple smoother without its collision test) cuts the corner into
// the block; SmoothPath keeps original poses there and stays free.
TEST(SmoothPolyline, KeepsTheOriginalWhereSmoothingWouldCollide) {
  std::vector<std::string> rows(12, std::string(12, '.'));
  for (int y = 0; y < 8; ++y) {
    for (int x = 0; x < 8; ++x) rows[y][x] = '#';
  }
  const Grid grid = MakeGrid(rows);
  // Along the block's top side and down its right side, 0.2 cells clear.
  const std::vector<CellPoint> points = {{1.5, 8.5}, {8.5, 8.5}, {8.5, 1.5}};
  const Footprint disc = Footprint::Circle(0.3).value();
  const std::vector<PathPose> in = PosesAlongPolyline(points);
  std::vector<PathPose> naive = in;
  for (int it = 0; it < 1000; ++it) {
    for (size_t i = 1; i + 1 < naive.size(); ++i) {
      for (double Pose::*c : {&Pose::x, &Pose::y}) {
        double& v = naive[i].pose.*c;
        v += 0.2 * (in[i].pose.*c - v) +
             0.3 * (naive[i - 1].pose.*c + naive[i + 1].pose.*c - 2 * v);
      }
    }
  }
  testing::KinematicCheck check = CheckFor(disc, in, 0.0);
  check.allow_sideways = true;
  EXPECT_NE(Check(grid, naive, check), "");
  const auto out = SmoothPolyline(grid, points,
                                  SharedFootprintChecker(disc, {.subcells = 8}).value(), false);
  ASSERT_TRUE(out.ok()) << out.status();
  EXPECT_EQ(Check(grid, *out, check), "");
  EXPECT_EQ(Check(grid, in, check), "");
}

}  // namespace
}  // namespace pathd
