// Poses of a robot with a heading, in the grid's continuous cell coordinates
// (core/map/grid.h CellPoint: cell (x, y) covers [x, x+1) x [y, y+1)), and the
// angle arithmetic every kinematic part shares. Core works in cells and
// radians; the server converts metres and world frames at its edge.
#ifndef PATHD_CORE_KINEMATICS_POSE_H_
#define PATHD_CORE_KINEMATICS_POSE_H_

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/map/grid.h"

namespace pathd {

// A pose: position in cell coordinates and heading in radians,
// counter-clockwise from the grid's +x axis (towards +y). The grid frame of a
// ROS map is the map frame translated to its origin (and rotated by the
// origin yaw only when the server is asked to honour it).
struct Pose {
  double x = 0.0;
  double y = 0.0;
  double yaw = 0.0;

  CellPoint point() const { return CellPoint{x, y}; }
  // The cell containing the position (may be off the grid; positions beyond
  // +/-1e9 cells are clamped there). Precondition: x and y are not NaN.
  Cell cell() const {
    const auto index = [](double v) {
      return static_cast<int32_t>(std::floor(std::clamp(v, -1e9, 1e9)));
    };
    return Cell{index(x), index(y)};
  }
  // The pose at a cell's centre.
  static Pose AtCellCenter(Cell c, double yaw = 0.0) {
    return Pose{c.x + 0.5, c.y + 0.5, yaw};
  }
};

// One pose of a path with the direction the robot drives into it: false
// forward, true reversing. A path's first pose has the direction of the first
// motion.
struct PathPose {
  Pose pose;
  bool reverse = false;
};

// The angle in (-pi, pi].
inline double NormalizeAngle(double a) {
  constexpr double kTwoPi = 2.0 * std::numbers::pi;
  a = std::fmod(a, kTwoPi);
  if (a <= -std::numbers::pi) a += kTwoPi;
  if (a > std::numbers::pi) a -= kTwoPi;
  return a;
}

// |a - b| as the smaller angle between the two headings, in [0, pi].
inline double AngleBetween(double a, double b) {
  return std::fabs(NormalizeAngle(a - b));
}

}  // namespace pathd

#endif  // PATHD_CORE_KINEMATICS_POSE_H_
