// The independent kinematic checker catches what it is there to catch, so a
// planner test that passes it means something.
#include "tests/testing/kinematic_checker.h"

#include <cmath>
#include <numbers>
#include <vector>

#include "gtest/gtest.h"

namespace pathd::testing {
namespace {

constexpr double kPi = std::numbers::pi;

// A left turn of `angle` on a circle of `radius` from (x, y) facing +x,
// sampled every `step` radians.
std::vector<Pose> Arc(double x, double y, double radius, double angle, double step) {
  std::vector<Pose> poses;
  for (double t = 0; t <= angle + 1e-12; t += step) {
    poses.push_back(Pose{x + radius * std::sin(t), y + radius * (1 - std::cos(t)), t});
  }
  return poses;
}

KinematicCheck Rectangle() {
  KinematicCheck c;
  c.footprint = {{1.0, 0.5}, {-1.0, 0.5}, {-1.0, -0.5}, {1.0, -0.5}};
  c.check_ends = false;
  return c;
}

TEST(KinematicCheckerTest, PassesAFreeArcAtTheTurningRadius) {
  const Grid grid = *Grid::Create(30, 30);
  KinematicCheck c = Rectangle();
  c.min_turning_radius = 8.0;
  EXPECT_EQ(CheckKinematicPath(grid, Arc(5, 5, 8.0, kPi / 2, 0.05), {}, c), "");
  c.min_turning_radius = 8.5;
  EXPECT_NE(CheckKinematicPath(grid, Arc(5, 5, 8.0, kPi / 2, 0.05), {}, c).find("below the minimum"),
            std::string::npos);
}

TEST(KinematicCheckerTest, FindsTheCornerBetweenSamples) {
  Grid grid = *Grid::Create(30, 30);
  grid.set_cost(15, 6, kLethalCost);
  KinematicCheck c = Rectangle();
  // Poses 10 cells apart: only the dense walk sees the rectangle's corner
  // clip cell (15, 6) (the footprint's top edge is at y = 6.05).
  const std::vector<Pose> poses = {{10, 5.55, 0}, {20, 5.55, 0}};
  EXPECT_NE(CheckKinematicPath(grid, poses, {}, c).find("cell (15, 6)"), std::string::npos);
  const std::vector<Pose> lower = {{10, 5.45, 0}, {20, 5.45, 0}};
  EXPECT_EQ(CheckKinematicPath(grid, lower, {}, c), "");
  // Touching counts.
  const std::vector<Pose> touching = {{10, 5.5, 0}, {20, 5.5, 0}};
  EXPECT_NE(CheckKinematicPath(grid, touching, {}, c), "");
}

TEST(KinematicCheckerTest, RotationSweepsTheCorners) {
  Grid grid = *Grid::Create(30, 30);
  grid.set_cost(10, 11, kLethalCost);
  KinematicCheck c = Rectangle();
  c.footprint = {{0.9, 0.5}, {-0.9, 0.5}, {-0.9, -0.5}, {0.9, -0.5}};
  c.allow_turn_in_place = true;
  // Turning in place at (10, 10): the robot is clear of cell (10, 11) at
  // both ends (top at y = 10.5, then 10.9), but the corner (0.9, 0.5)
  // sweeps a circle of radius 1.03 that crosses y = 11 mid-turn.
  EXPECT_EQ(CheckKinematicPath(grid, {{10, 10, 0}}, {}, c), "");
  EXPECT_EQ(CheckKinematicPath(grid, {{10, 10, kPi / 2}}, {}, c), "");
  const std::vector<Pose> turn = {{10, 10, 0}, {10, 10, kPi / 2}};
  EXPECT_NE(CheckKinematicPath(grid, turn, {}, c).find("cell (10, 11)"), std::string::npos);
  c.allow_turn_in_place = false;
  EXPECT_NE(CheckKinematicPath(grid, turn, {}, c).find("turns in place"), std::string::npos);
}

TEST(KinematicCheckerTest, DirectionsEndsAndEdges) {
  const Grid grid = *Grid::Create(30, 30);
  KinematicCheck c = Rectangle();
  const std::vector<Pose> back = {{10, 10, 0}, {8, 10, 0}};
  EXPECT_EQ(CheckKinematicPath(grid, back, {}, c), "");
  EXPECT_EQ(CheckKinematicPath(grid, back, {false, true}, c), "");
  EXPECT_NE(CheckKinematicPath(grid, back, {false, false}, c).find("marked forward"),
            std::string::npos);
  c.allow_reverse = false;
  EXPECT_NE(CheckKinematicPath(grid, back, {}, c).find("reverses"), std::string::npos);
  const std::vector<Pose> sideways = {{10, 10, 0}, {10, 12, 0}};
  EXPECT_NE(CheckKinematicPath(grid, sideways, {}, c).find("off its heading"), std::string::npos);
  c.allow_sideways = true;
  EXPECT_EQ(CheckKinematicPath(grid, sideways, {}, c), "");
  const std::vector<Pose> edge = {{10, 0.5, 0}, {12, 0.5, 0}};
  EXPECT_EQ(CheckKinematicPath(grid, {{10, 0.51, 0}, {12, 0.51, 0}}, {}, c), "");
  EXPECT_NE(CheckKinematicPath(grid, edge, {}, c).find("edge"), std::string::npos);
  c.check_ends = true;
  c.start = Pose{10, 10, 0};
  c.goal = Pose{12, 10, kPi};
  c.allow_sideways = false;
  c.allow_reverse = true;
  const std::vector<Pose> path = {{10, 10, 0}, {12, 10, 0}};
  EXPECT_NE(CheckKinematicPath(grid, path, {}, c).find("from the goal"), std::string::npos);
  c.goal_yaw_tolerance = kPi;
  EXPECT_EQ(CheckKinematicPath(grid, path, {}, c), "");
  c.start = Pose{10, 10.1, 0};
  EXPECT_NE(CheckKinematicPath(grid, path, {}, c).find("not at the start"), std::string::npos);
}

TEST(KinematicCheckerTest, CircleRobot) {
  Grid grid = *Grid::Create(30, 30);
  grid.set_cost(15, 12, kLethalCost);
  KinematicCheck c;
  c.circle_radius = 1.5;
  c.check_ends = false;
  // The circle's top is 1.5 above y = 10.4: 11.9 < 12 passes, 10.6 + 1.5 hits.
  EXPECT_EQ(CheckKinematicPath(grid, {{10, 10.4, 0}, {20, 10.4, 0}}, {}, c), "");
  EXPECT_NE(CheckKinematicPath(grid, {{10, 10.6, 0}, {20, 10.6, 0}}, {}, c), "");
}

}  // namespace
}  // namespace pathd::testing
