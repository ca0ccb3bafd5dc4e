// MotionChecker (core/kinematics/motion_check.h) against the independent
// checker: a motion it calls free is free when sampled every 0.02 cells
// with the exact footprint.
#include "core/kinematics/motion_check.h"

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "core/kinematics/curves.h"
#include "core/kinematics/vehicle.h"
#include "gtest/gtest.h"
#include "tests/testing/kinematic_checker.h"
#include "tests/testing/test_grids.h"

namespace pathd {
namespace {

constexpr double kPi = std::numbers::pi;

testing::KinematicCheck Exact(const Footprint& f) {
  testing::KinematicCheck c;
  if (f.is_circle()) {
    c.circle_radius = f.circle_radius();
  } else {
    c.footprint = f.vertices();
  }
  c.check_ends = false;
  c.allow_sideways = true;
  return c;
}

TEST(MotionChecker, FreeMotionsAreFreeWhenSampledDensely) {
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const std::vector<Footprint> footprints = {
      Footprint::Circle(0.7).value(),
      Footprint::Polygon({{-0.5, -0.4}, {1.6, -0.4}, {1.6, 0.4}, {-0.5, 0.4}}).value(),
      Footprint::Polygon({{1.2, 0.0}, {-0.4, 0.9}, {-0.7, -0.3}, {0.2, -0.8}}).value(),
  };
  int free = 0, blocked = 0;
  for (int trial = 0; trial < 600; ++trial) {
    Grid grid = Grid::Create(20, 20).value();
    for (int b = 0; b < 8; ++b) {
      const int x0 = static_cast<int>(rng() % 20), y0 = static_cast<int>(rng() % 20);
      for (int y = y0; y < std::min(20, y0 + 3); ++y) {
        for (int x = x0; x < std::min(20, x0 + 3); ++x) grid.set_cost(x, y, kLethalCost);
      }
    }
    const Footprint& footprint = footprints[trial % footprints.size()];
    const auto checker = SharedFootprintChecker(footprint).value();
    const std::vector<float> distance = ObstacleDistanceField(grid, false);
    const MotionChecker motion =
        MotionChecker::Create(checker, grid, false, distance.data()).value();
    const Pose start{20 * u(rng), 20 * u(rng), 2 * kPi * u(rng) - kPi};
    if (!motion.PoseFree(start)) continue;
    const Steer steer = static_cast<Steer>(static_cast<int>(rng() % 3) - 1);
    const double length = 6.0 * u(rng) - 3.0;
    const double radius = 0.5 + 4.5 * u(rng);
    const double turn = steer == Steer::kStraight ? 0.0 : std::fabs(length) / radius;
    const auto at = [&](double t) { return Drive(start, steer, radius, length * t); };
    if (!motion.MotionFree(at, std::fabs(length) + motion.reach() * turn, 0.0, MotionEnd::kExact,
                           MotionEnd::kSample)) {
      ++blocked;
      continue;
    }
    ++free;
    std::vector<Pose> dense;
    const int n = static_cast<int>(std::ceil(std::fabs(length) / 0.02)) + 1;
    for (int i = 0; i <= n; ++i) dense.push_back(at(static_cast<double>(i) / n));
    EXPECT_EQ(testing::CheckKinematicPath(grid, dense, {}, Exact(footprint)), "")
        << "trial " << trial;
  }
  EXPECT_GT(free, 100);
  EXPECT_GT(blocked, 50);
}

// A start closer to an obstacle than the margin: driving away is proven
// free with the finer samples, driving into it is not.
TEST(MotionChecker, ExactEndsCloserThanTheMargin) {
  const Grid grid = MakeGrid({"..........", "..........", "..........", "....#.....",
                              "..........", "..........", ".........."});
  const auto checker = SharedFootprintChecker(Footprint::Circle(0.5).value(), {.subcells = 8})
                           .value();
  const std::vector<float> distance = ObstacleDistanceField(grid, false);
  const MotionChecker motion = MotionChecker::Create(checker, grid, false, distance.data()).value();
  // 0.19 cells from the obstacle cell's left side: free for the query's
  // masks (which cover the disc anywhere in its eighth of a cell, so 0.125
  // cells more), not with the margin on top.
  const Pose start{3.31, 3.5, 0.0};
  ASSERT_TRUE(motion.PoseFree(start));
  ASSERT_FALSE(motion.PoseFreeWithMargin(start));
  const auto away = [&](double t) { return Drive(start, Steer::kStraight, 1, -2.0 * t); };
  const auto into = [&](double t) { return Drive(start, Steer::kStraight, 1, 2.0 * t); };
  EXPECT_TRUE(motion.MotionFree(away, 2.0, 0.0, MotionEnd::kExact, MotionEnd::kSample));
  EXPECT_FALSE(motion.MotionFree(into, 2.0, 0.0, MotionEnd::kExact, MotionEnd::kSample));
  // Without the exact-end rule the start's own margin test fails.
  EXPECT_FALSE(motion.MotionFree(away, 2.0, 0.0, MotionEnd::kSample, MotionEnd::kSample));
}

// FirstBlockedPiece, the recheck of a kept Navigate path: a path it calls
// free passes the independent checker (footprint sampled every 0.02 cells
// along each chord), and a cell blocked under the path is found in the
// piece that reaches it.
TEST(FirstBlockedPiece, FreeVerdictsHoldWhenSampledDensely) {
  std::mt19937 rng(47);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Footprint footprint =
      Footprint::Polygon({{-0.6, -0.4}, {0.9, -0.4}, {0.9, 0.4}, {-0.6, 0.4}}).value();
  const auto checker = SharedFootprintChecker(footprint).value();
  testing::KinematicCheck exact = Exact(footprint);
  exact.step_cells = 0.02;
  int free = 0, blocked = 0;
  for (int trial = 0; trial < 200; ++trial) {
    Grid grid = Grid::Create(24, 24).value();
    for (int b = 0; b < 6; ++b) {
      const int x0 = static_cast<int>(rng() % 24), y0 = static_cast<int>(rng() % 24);
      for (int y = y0; y < std::min(24, y0 + 2); ++y) {
        for (int x = x0; x < std::min(24, x0 + 2); ++x) grid.set_cost(x, y, kLethalCost);
      }
    }
    const std::vector<float> distance = ObstacleDistanceField(grid, false);
    const MotionChecker motion =
        MotionChecker::Create(checker, grid, false, distance.data()).value();
    // Poses 0.4 cells apart along an arc of radius 3 to 10 cells.
    const double radius = (3.0 + 7.0 * u(rng)) * (rng() % 2 == 0 ? 1.0 : -1.0);
    Pose p{4.0 + 16.0 * u(rng), 4.0 + 16.0 * u(rng), 2 * kPi * u(rng) - kPi};
    std::vector<PathPose> path = {{p, false}};
    std::vector<Pose> poses = {p};
    for (int i = 0; i < 20; ++i) {
      const double turn = 0.4 / radius;
      p = Pose{p.x + 0.4 * std::cos(p.yaw + turn / 2), p.y + 0.4 * std::sin(p.yaw + turn / 2),
               NormalizeAngle(p.yaw + turn)};
      path.push_back({p, false});
      poses.push_back(p);
    }
    const int64_t piece = FirstBlockedPiece(motion, path);
    if (piece < 0) {
      ++free;
      EXPECT_EQ(testing::CheckKinematicPath(grid, poses, {}, exact), "") << "trial " << trial;
    } else {
      ++blocked;
      EXPECT_LT(piece, static_cast<int64_t>(path.size()) - 1);
    }
  }
  EXPECT_GT(free, 20);
  EXPECT_GT(blocked, 20);
}

TEST(FirstBlockedPiece, FindsTheCellBlockedUnderTheTenthPose) {
  Grid grid = Grid::Create(30, 10).value();
  const auto checker =
      SharedFootprintChecker(Footprint::Polygon({{-0.5, -0.3}, {0.5, -0.3}, {0.5, 0.3},
                                                 {-0.5, 0.3}})
                                 .value())
          .value();
  std::vector<PathPose> path;
  for (int i = 0; i <= 40; ++i) path.push_back({Pose{3.0 + 0.5 * i, 5.0, 0.0}, false});
  {
    const std::vector<float> distance = ObstacleDistanceField(grid, false);
    const MotionChecker motion =
        MotionChecker::Create(checker, grid, false, distance.data()).value();
    EXPECT_EQ(FirstBlockedPiece(motion, path), -1);
    EXPECT_EQ(FirstBlockedPiece(motion, {}), -1);
  }
  // Pose 10 is at x = 8; the robot's front (+0.5) reaches cell 8 from pose 9
  // on (x = 7.5), with the margin a little before.
  grid.set_cost(8, 5, kLethalCost);
  const std::vector<float> distance = ObstacleDistanceField(grid, false);
  const MotionChecker motion =
      MotionChecker::Create(checker, grid, false, distance.data()).value();
  const int64_t piece = FirstBlockedPiece(motion, path);
  EXPECT_GE(piece, 7);
  EXPECT_LE(piece, 8);
  // One pose on the blocked cell.
  EXPECT_EQ(FirstBlockedPiece(motion, {{Pose{8.5, 5.5, 0.0}, false}}), 0);
  // The rest of the path beyond the cell is free.
  EXPECT_EQ(FirstBlockedPiece(motion, std::vector<PathPose>(path.begin() + 14, path.end())), -1);
}

}  // namespace
}  // namespace pathd
