// Measuring and pricing paths of poses (core/kinematics/pose_path.h).
#include "core/kinematics/pose_path.h"

#include <cmath>
#include <numbers>
#include <vector>

#include "core/kinematics/curves.h"
#include "gtest/gtest.h"
#include "tests/testing/test_grids.h"

namespace pathd {
namespace {

constexpr double kPi = std::numbers::pi;

std::vector<PathPose> Driven(Pose from, Steer steer, double radius, double length, int pieces) {
  std::vector<PathPose> poses = {PathPose{from, length < 0}};
  for (int j = 1; j <= pieces; ++j) {
    poses.push_back(PathPose{Drive(from, steer, radius, length * j / pieces), length < 0});
  }
  return poses;
}

TEST(PieceLength, ExactOnArcsAndSegments) {
  const Pose from{3.0, 4.0, 0.7};
  for (const Steer steer : {Steer::kLeft, Steer::kRight, Steer::kStraight}) {
    for (const double length : {2.0, -2.0}) {
      const std::vector<PathPose> poses = Driven(from, steer, 1.5, length, 7);
      EXPECT_NEAR(PathLength(poses), 2.0, 1e-12);
    }
  }
}

TEST(PathCost, NavSmacPenalties) {
  const Grid grid = MakeGrid({"........", "........", "99999999", "........"});
  MotionPenalties p;
  p.cost_penalty = 2.0;
  p.non_straight = 1.2;
  p.reverse = 2.0;
  // Straight on free cells: the length.
  EXPECT_NEAR(PathCost(grid, Driven(Pose{0.5, 0.5, 0.0}, Steer::kStraight, 1, 4, 8), p), 4.0,
              1e-12);
  // On cells of cost 252: (1 + 2 * 252 / 252) = 3 times.
  EXPECT_NEAR(PathCost(grid, Driven(Pose{0.5, 2.5, 0.0}, Steer::kStraight, 1, 4, 8), p), 12.0,
              1e-12);
  // Reversing: twice.
  EXPECT_NEAR(PathCost(grid, Driven(Pose{5.5, 0.5, 0.0}, Steer::kStraight, 1, -4, 8), p), 8.0,
              1e-12);
  // Turning: 1.2 times; turning in reverse 2.4 times.
  EXPECT_NEAR(PathCost(grid, Driven(Pose{2.5, 0.2, 0.0}, Steer::kLeft, 3, 1.0, 2), p), 1.2,
              1e-12);
  EXPECT_NEAR(PathCost(grid, Driven(Pose{2.5, 0.2, 0.0}, Steer::kRight, 3, -1.0, 2), p), 2.4,
              1e-12);
  // A turn after a straight adds change * change_length once.
  p.change = 0.5;
  p.change_length = 2.0;
  std::vector<PathPose> poses = Driven(Pose{0.5, 0.5, 0.0}, Steer::kStraight, 1, 1.0, 2);
  const std::vector<PathPose> turn = Driven(poses.back().pose, Steer::kLeft, 4, 1.0, 2);
  poses.insert(poses.end(), turn.begin() + 1, turn.end());
  EXPECT_NEAR(PathCost(grid, poses, p), 1.0 + 1.2 + 0.5 * 2.0, 1e-12);
}

TEST(KindOf, SteeringInTheWheelsSense) {
  const Pose a{0, 0, 0};
  EXPECT_EQ(KindOf(a, Drive(a, Steer::kLeft, 1, 0.3), false).steer, 1);
  EXPECT_EQ(KindOf(a, Drive(a, Steer::kLeft, 1, -0.3), true).steer, 1);
  EXPECT_EQ(KindOf(a, Drive(a, Steer::kRight, 1, -0.3), true).steer, -1);
  EXPECT_EQ(KindOf(a, Drive(a, Steer::kStraight, 1, 0.3), false).steer, 0);
}

TEST(PathCells, ThePosesCellsOnce) {
  const std::vector<PathPose> poses = {PathPose{Pose{0.5, 0.5, 0}}, PathPose{Pose{0.9, 0.6, 0}},
                                       PathPose{Pose{1.2, 1.1, 0}}, PathPose{Pose{1.6, 1.4, 0}},
                                       PathPose{Pose{2.1, 1.4, 0}}};
  EXPECT_EQ(PathCells(poses), (std::vector<Cell>{{0, 0}, {1, 1}, {2, 1}}));
  EXPECT_TRUE(PathCells({}).empty());
}

}  // namespace
}  // namespace pathd
