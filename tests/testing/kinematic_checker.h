// An independent checker of kinematic paths, written apart from the planners
// and from core/kinematics' footprint masks: it walks a path of poses densely
// (every step_cells and step_yaw of each motion between consecutive poses,
// position and heading interpolated linearly: callers set step_cells to
// 1 cm in cells, 0.01 / resolution) and tests the footprint
// polygon at every sample against every obstacle cell's square with
// Boost.Geometry, then checks curvature, direction and the end poses.
#ifndef PATHD_TESTS_TESTING_KINEMATIC_CHECKER_H_
#define PATHD_TESTS_TESTING_KINEMATIC_CHECKER_H_

#include <string>
#include <vector>

#include "core/kinematics/pose.h"
#include "core/map/grid.h"

namespace pathd::testing {

struct KinematicCheck {
  // The robot's outline in its body frame, cells: a polygon (any
  // orientation), or empty with circle_radius > 0.
  std::vector<CellPoint> footprint;
  double circle_radius = 0.0;
  bool unknown_is_free = false;
  // Sampling of each motion between consecutive poses, cells and radians.
  double step_cells = 0.2;
  double step_yaw = 3.14159265358979323846 / 180.0;
  // > 0: between cusps, the curvature of the circular arc through two
  // consecutive poses, 2 sin(|heading change| / 2) / chord, is at most
  // 1 / min_turning_radius (+ curvature_slack of it, for floating point).
  double min_turning_radius = 0.0;
  double curvature_slack = 1e-6;
  // False: every motion must go the way the robot faces.
  bool allow_reverse = true;
  // Turning in place (zero distance, changed heading) is allowed.
  bool allow_turn_in_place = false;
  // Moving sideways (omnidirectional robots): the motion's direction is not
  // checked against the heading, nor is the curvature.
  bool allow_sideways = false;
  // The most a motion's direction may differ from the heading halfway
  // along it (forward) or its opposite (reversing), radians: consecutive
  // poses on a circular arc differ by 0.
  double max_drift = 0.05;
  // The first pose must be `start` (within 1e-6) and the last within these
  // tolerances of `goal` (position, cells; heading, radians).
  bool check_ends = true;
  Pose start;
  Pose goal;
  double goal_tolerance = 1e-6;
  double goal_yaw_tolerance = 1e-6;
};

// The first problem found along `poses` (which of the motions, what), or an
// empty string when the path passes. `reverse[i]` says pose i was reached
// driving backwards (the planner's claim, checked against the motion); empty:
// not checked.
std::string CheckKinematicPath(const Grid& grid, const std::vector<Pose>& poses,
                               const std::vector<bool>& reverse, const KinematicCheck& check);

}  // namespace pathd::testing

#endif  // PATHD_TESTS_TESTING_KINEMATIC_CHECKER_H_
