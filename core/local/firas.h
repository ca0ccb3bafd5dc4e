// A potential-field local method: attraction to the lookahead point on the
// global path plus Khatib's FIRAS repulsion (Khatib, "Real-time obstacle
// avoidance for manipulators and mobile robots", IJRR 5(1), 1986), as the
// lecture "Robot Navigation and collision avoidance" presents it:
// F_rep = beta (1/d - 1/d0) (q - q_r) / d^2 within the influence distance
// d0, where q_r is the nearest obstacle point and d the clearance; the
// attraction is -alpha (q - q_a), constant in magnitude beyond
// attraction_distance (the lecture "Planning I"'s conic-quadratic goal
// potential). The resulting force is the desired velocity. A baseline:
// potential fields stop in local minima, which this reports (status
// kLocalMinimum) when the forces nearly cancel or the robot has not moved
// along the path over a window of cycles.
//
// Pure function of its inputs and of the caller's per-robot ProgressWindow
// (core/local/local_types.h). Work per call: the cells within
// radius + influence of the robot, plus one term per moving obstacle.
#ifndef PATHD_CORE_LOCAL_FIRAS_H_
#define PATHD_CORE_LOCAL_FIRAS_H_

#include <cstdint>

#include "absl/status/statusor.h"
#include "absl/types/span.h"
#include "core/local/local_types.h"
#include "core/map/grid.h"

namespace pathd {

struct FirasOptions {
  double attraction = 1.0;           // alpha, 1/s
  double attraction_distance = 2.0;  // d*, cells
  double repulsion = 1.0;            // beta, cells^3/s
  double influence = 2.0;            // d0, cells of clearance
  double lookahead = 3.0;            // cells along the global path
  double goal_tolerance = 0.25;
  double turn_gain = 2.0;  // differential drive, 1/s per radian
  // Local minimum: the resulting force below this fraction of the
  // attraction alone, or (with a ProgressWindow) less than min_progress
  // cells of progress along the path over window_seconds.
  double min_force_ratio = 0.05;
  double window_seconds = 3.0;
  double min_progress = 0.5;
  bool unknown_is_free = false;
};

// INVALID_ARGUMENT naming the option.
absl::Status ValidateFirasOptions(const FirasOptions& options);

// One control cycle for a robot of `radius` cells. Status kLocalMinimum as
// above (the command is still the force's), kBlocked when the robot's disc
// already overlaps an obstacle cell or a moving obstacle (the command is
// zero), kGoalReached within goal_tolerance of the path's end. `progress`
// may be null (no stall detection). Errors: INVALID_ARGUMENT naming a bad
// option, limit, radius or period, or an empty path.
absl::StatusOr<LocalPlan> FirasStep(const Grid& grid, const RobotState& state,
                                    double radius, const VelocityLimits& limits,
                                    absl::Span<const MovingObstacle> obstacles,
                                    absl::Span<const CellPoint> path,
                                    double period, const FirasOptions& options,
                                    ProgressWindow* progress);

}  // namespace pathd

#endif  // PATHD_CORE_LOCAL_FIRAS_H_
