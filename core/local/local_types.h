// The values the local planners (core/local: dwa, orca, firas) share: the
// robot's state and limits, the moving obstacles around it, and the answer of
// one control cycle. Units are core's: positions in cell coordinates,
// velocities in cells/s, angles in radians, times in seconds; the server
// converts metres at its edge.
#ifndef PATHD_CORE_LOCAL_LOCAL_TYPES_H_
#define PATHD_CORE_LOCAL_LOCAL_TYPES_H_

#include <cstdint>
#include <deque>
#include <initializer_list>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/types/span.h"
#include "core/kinematics/pose.h"
#include "core/map/grid.h"

namespace pathd {

// The robot now: pose, and its velocity in the body frame (v forward, vy to
// the left, w counter-clockwise). vy is 0 for a differential-drive robot.
struct RobotState {
  Pose pose;
  double v = 0.0;
  double vy = 0.0;
  double w = 0.0;
};

// What the robot can do. Differential drive (holonomic false) commands (v, w);
// an omnidirectional robot (holonomic true) commands (v, vy, w).
struct VelocityLimits {
  double min_v = 0.0;  // may be negative: the robot may reverse
  double max_v = 1.0;
  double max_vy = 0.0;  // |vy|, holonomic robots only
  double max_w = 1.0;   // |w|
  double acc_v = 1.0;   // |dv/dt|
  double acc_vy = 1.0;  // |dvy/dt|
  double acc_w = 2.0;   // |dw/dt|
  bool holonomic = false;
};

// INVALID_ARGUMENT naming the field when a limit is not finite, a maximum or
// acceleration is negative, or min_v > max_v.
absl::Status ValidateVelocityLimits(const VelocityLimits& limits);

// One named option of a local planner, for CheckOptionValues.
struct OptionValue {
  const char* name;
  double value;
};
// OK when every value is finite and positive (zero_ok: finite and >= 0);
// else INVALID_ARGUMENT "<owner> options: <name> must be positive and
// finite (got <value>)" (">= 0 and finite") for the first that is not.
absl::Status CheckOptionValues(const char* owner,
                               std::initializer_list<OptionValue> values,
                               bool zero_ok);

// Something that moves near the robot: another robot or a non-robot
// obstacle (a person, a forklift), as a disc moving at constant velocity.
struct MovingObstacle {
  CellPoint position;
  CellPoint velocity;  // cells/s, grid frame
  double radius = 0.0;
  // True when it runs the same avoidance (ORCA takes half the avoidance
  // then); false for obstacles that do not react.
  bool reciprocal = false;
};

enum class LocalStatus {
  kOk,
  // No sampled or solved velocity is admissible: every one collides (DWA),
  // or the constraints cannot all hold (ORCA's fallback answer is given).
  kBlocked,
  // Potential-field methods: the forces balance, or the robot has not moved
  // away from where it was over the detection window.
  kLocalMinimum,
  kGoalReached,
};

const char* LocalStatusName(LocalStatus status);

// The answer of one control cycle.
struct LocalPlan {
  // The command, body frame.
  double v = 0.0;
  double vy = 0.0;
  double w = 0.0;
  // The predicted poses under the command, one per sub-step, starting at the
  // current pose.
  std::vector<Pose> trajectory;
  LocalStatus status = LocalStatus::kOk;
  // Why, in words (empty for kOk).
  std::string reason;
  // Work done: velocity samples rolled out (DWA), half-planes built (ORCA),
  // force terms summed (FIRAS).
  int64_t samples = 0;
  int64_t constraints = 0;
  // Progress along the path over the stall window (cells), as ReportStall
  // measured it; nullopt before the window is full or when nothing
  // measured it.
  std::optional<double> progress;
};

// The pose reached from `pose` after `seconds` at the constant body-frame
// velocity (v, vy, w), integrated in `steps` equal sub-steps with the
// heading at each sub-step's midpoint (exact for vy = 0 up to the chord).
Pose IntegrateVelocity(const Pose& pose, double v, double vy, double w,
                       double seconds, int32_t steps);

// Where the robot should head on the global path: the point `lookahead`
// cells along the path beyond the path point nearest `position`, clamped to
// the path's end. O(path points). Precondition: path not empty.
struct PathTarget {
  CellPoint point;             // the lookahead point
  size_t nearest_segment = 0;  // index of the nearest segment's first point
  double distance_to_path = 0.0;
  double remaining = 0.0;  // along the path from the nearest point to the end
  double distance_to_goal = 0.0;  // straight line to the path's last point
};
PathTarget FindPathTarget(absl::Span<const CellPoint> path, CellPoint position,
                          double lookahead);

// Differential drive: the (v, w) that follows a desired grid-frame velocity
// `desired` from heading `yaw`: turn toward it at gain/s (clamped to max_w),
// and drive at |desired| scaled by the cosine of the heading error (0 when
// the error exceeds 90 degrees, so the robot turns in place first), clamped
// to [max(min_v, 0), max_v]. The robot then moves along its heading, not
// exactly along `desired` (OrcaStep then cuts the forward speed to stay in
// its half-planes; docs/decisions.md).
void FollowVelocityDiffDrive(CellPoint desired, double yaw, double turn_gain,
                             const VelocityLimits& limits, double* v,
                             double* w);

// A robot's progress along its global path over its recent cycles, kept by
// the caller per robot and passed to each cycle: the planners report a
// robot whose remaining path length has shrunk by less than min_progress
// cells over window_seconds (standing still nose to nose, oscillating,
// circling) as kLocalMinimum, so that a stall is never silent. Not
// thread-safe; one per robot. Holds at most 10000 cycles.
struct ProgressWindow {
  std::deque<double> remaining;  // one per cycle, oldest first
};

// Records this cycle's remaining path length and returns the progress over
// the window (cells; negative when the robot lost ground) once it holds
// window_seconds of cycles; nullopt before. A new path (remaining grew by
// more than a cell) starts the window again.
std::optional<double> RecordProgress(ProgressWindow& window, double remaining,
                                     double period, double window_seconds);

// When `window` is not null: records target.remaining, and when the plan's
// status is kOk and the progress over a full window is below
// `min_progress`, makes it kLocalMinimum with a reason naming the
// progress. The planners call it last; callers need not.
void ReportStall(ProgressWindow* window, const PathTarget& target,
                 double period, double window_seconds, double min_progress,
                 LocalPlan* plan);

// Limits `target` to what is reachable from `current` within `period` at
// `acceleration` and to [lo, hi].
double ClampToWindow(double target, double current, double acceleration,
                     double period, double lo, double hi);

}  // namespace pathd

#endif  // PATHD_CORE_LOCAL_LOCAL_TYPES_H_
