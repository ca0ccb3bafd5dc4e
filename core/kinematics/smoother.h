// Smoothing a path of poses for a robot with a footprint and a turning
// radius, after Nav2's "simple smoother" (nav2_smoother::SimpleSmoother,
// also the first stage of Smac's smoother): gradient descent of each pose's
// position on a data term (stay near the original) and a smoothness term
// (towards the middle of its neighbours), with the cusps, start and goal
// held fixed and the headings recomputed along the result. The refinement
// step of Faigl's lecture "Path Planning" (B4M36UIR Lecture 03, "Path
// Refinement") shortens a path the same way, by testing a candidate against
// the obstacles and keeping the original where it fails.
//
// Unlike Nav2 the result is verified, not only its poses: every piece that
// changed is tested over its whole sweep (core/kinematics/motion_check.h)
// and against the curvature bound; a piece that fails pins the original pose
// at it and the stretches on either side are smoothed again, so the worst
// case is the original path. The result is therefore never less valid than
// the input.
#ifndef PATHD_CORE_KINEMATICS_SMOOTHER_H_
#define PATHD_CORE_KINEMATICS_SMOOTHER_H_

#include <cstdint>
#include <vector>

#include "absl/status/statusor.h"
#include "core/kinematics/footprint.h"
#include "core/kinematics/motion_check.h"
#include "core/kinematics/pose.h"
#include "core/map/grid.h"

namespace pathd {

struct SmootherOptions {
  // Nav2 SimpleSmoother's defaults.
  double w_data = 0.2;
  double w_smooth = 0.3;
  // Stop when a sweep moves the poses by less than this in total, cells.
  double tolerance = 1e-10;
  int32_t max_iterations = 1000;
  // > 0: between cusps, every changed piece curves at most 1 /
  // min_turning_radius, its curvature being that of the circle through both
  // poses, 2 sin(|heading change| / 2) / chord. 0: no bound.
  double min_turning_radius = 0.0;
  // The most a changed piece's direction may differ from its heading
  // halfway along (or its opposite, reversing), radians: a piece of an arc
  // differs by nothing, headings taken along smoothed positions by a
  // little, more is sliding sideways. Just under the independent checker's
  // 0.05 (tests/testing/kinematic_checker.h).
  double max_drift = 0.045;
  // A stretch whose smoothing failed this many times (each failure pins one
  // more original pose) keeps its original poses.
  int32_t max_pins = 32;
};

// The smoothed path. Preconditions: `poses` is valid for `checker`'s robot
// (the motions between consecutive poses, position and heading linear
// between them, are free; within the curvature bound between cusps when
// options.min_turning_radius > 0) and consecutive poses are at most half a
// cell apart; PathPose::reverse marks the motion into each pose. The first
// and last pose and every cusp (where reverse changes) are kept exactly;
// poses keep their reverse flags; the result has as many poses as the input.
std::vector<PathPose> SmoothPath(const std::vector<PathPose>& poses, const MotionChecker& checker,
                                 const SmootherOptions& options);

// Poses along a polyline in cell coordinates (a grid planner's cell centres,
// a geometric planner's polyline): at most `spacing` apart along each
// segment, forward, each with the heading of the segment it ends (the first
// with the first segment's), so the heading turns over the first piece after
// each bend (and the curvature bound does not hold there). Consecutive
// duplicate points are dropped; a single point gives one pose, heading 0.
std::vector<PathPose> PosesAlongPolyline(const std::vector<CellPoint>& points,
                                         double spacing = 0.5);

// A planner's polyline smoothed for a robot: PosesAlongPolyline, then
// SmoothPath with `footprint` on `grid` (no curvature bound unless
// options.min_turning_radius > 0, which the bends of a polyline break
// anyway: smoothing rounds them where the footprint fits). For the planners
// that return cells or polylines; the polyline must be free for the
// footprint at its segments' headings (a grid path on a map inflated by the
// robot's radius is, for a circular robot). INVALID_ARGUMENT from the
// checker's options when it cannot grow the footprint.
absl::StatusOr<std::vector<PathPose>> SmoothPolyline(
    const Grid& grid, const std::vector<CellPoint>& points,
    std::shared_ptr<const FootprintChecker> footprint, bool unknown_is_free,
    const SmootherOptions& options = {});

}  // namespace pathd

#endif  // PATHD_CORE_KINEMATICS_SMOOTHER_H_
