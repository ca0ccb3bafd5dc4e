// The dynamic window approach: Fox, Burgard & Thrun, "The dynamic window
// approach to collision avoidance", IEEE Robotics & Automation Magazine 4(1),
// 1997, as the lecture "Planning I" presents it for the local layer of the
// planning hierarchy. Velocities (v, w) -- (v, vy, w) for an omnidirectional
// robot -- are sampled in the window the accelerations reach within one
// control period; each is held for a horizon and rolled out (unicycle
// integration at a fixed sub-step); rollouts whose footprint touches the
// costmap (lethal, inscribed and, unless allowed, unknown cells, through
// core/kinematics/footprint.h's FootprintChecker) or comes within a moving
// obstacle's radius at its predicted (constant-velocity) position are
// rejected; the rest are scored by weighted critics after Nav2's DWB
// (path distance, distance to the lookahead point, heading to it, obstacle
// clearance, forward speed, twirling), and the cheapest is commanded.
//
// Pure function; thread-safe. Work per call: v_samples x w_samples (x
// vy_samples) rollouts of at most max_sub_steps footprint checks each.
#ifndef PATHD_CORE_LOCAL_DWA_H_
#define PATHD_CORE_LOCAL_DWA_H_

#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/types/span.h"
#include "core/kinematics/footprint.h"
#include "core/local/local_types.h"
#include "core/map/grid.h"

namespace pathd {

struct DwaOptions {
  // Samples across the window per axis (>= 1; 1 samples the window's middle).
  int32_t v_samples = 11;
  int32_t w_samples = 21;
  int32_t vy_samples = 5;  // holonomic robots only
  // Seconds each sample is held in its rollout, and the longest sub-step.
  // The sub-step shrinks so that no point of the footprint moves more than
  // twice the checker's margin_cells between checked poses (then the motion
  // between them is covered too), down to horizon / max_sub_steps.
  double horizon = 1.5;
  double sub_step = 0.1;
  int32_t max_sub_steps = 100;
  // Critic weights (costs; the lowest weighted sum wins). Each critic is
  // scaled to about [0, 1].
  double path_distance_weight = 1.0;  // rollout end to the global path
  double goal_distance_weight = 1.0;  // rollout end to the lookahead point
  double heading_weight = 0.3;  // final heading against the lookahead direction
  double obstacle_weight = 0.5;   // clearance below clearance_limit (map
                                  // or predicted moving obstacles)
  double speed_weight = 0.3;      // slower than max_v
  double twirling_weight = 0.05;  // |w| / max_w
  // The lookahead point this far along the global path, cells.
  double lookahead = 3.0;
  // Clearance (cells, footprint's circumscribed disc to the nearest obstacle
  // cell centre or predicted moving obstacle disc) beyond which the
  // obstacle critic is 0.
  double clearance_limit = 3.0;
  double goal_tolerance = 0.25;
  // Stall detection, with a ProgressWindow: less than min_progress cells of
  // progress along the path over window_seconds is reported as
  // kLocalMinimum.
  double window_seconds = 3.0;
  double min_progress = 0.5;
  bool unknown_is_free = false;
};

// INVALID_ARGUMENT naming the option.
absl::Status ValidateDwaOptions(const DwaOptions& options);

// The velocities reachable from `state` within `period` under `limits`
// (each axis [lo, hi]). When the current velocity is outside the limits by
// more than one period can change, that axis is the one reachable value
// nearest the limits.
struct DynamicWindow {
  double v_lo = 0, v_hi = 0;
  double vy_lo = 0, vy_hi = 0;
  double w_lo = 0, w_hi = 0;
};
DynamicWindow ComputeDynamicWindow(const RobotState& state,
                                   const VelocityLimits& limits, double period);

// The map as DWA reads it. `distance` (optional) is ObstacleDistanceField of
// `grid` with the same unknown rule: it speeds up the checker and feeds the
// obstacle critic (without it, the critic reads the highest cost under the
// footprint). Pointers do not own and must outlive the call.
struct DwaMap {
  const Grid* grid = nullptr;
  const FootprintChecker* checker = nullptr;
  const float* distance = nullptr;
};

// One rolled-out sample, for callers that draw or check them.
struct DwaRollout {
  double v = 0, vy = 0, w = 0;
  std::vector<Pose> poses;  // from the current pose, one per sub-step
  bool admissible = false;
  std::string rejected;  // "map" or "moving obstacle" when not admissible
  double score = 0;      // the weighted critics (admissible only)
};

// One control cycle. Status kBlocked (the command then brakes as hard as the
// window allows) when every rollout is rejected, kGoalReached within
// goal_tolerance of the path's end (also braking), kLocalMinimum when
// `progress` (optional, the caller's per robot) sees a stall. `rollouts`,
// when not null, receives every sample. Errors: INVALID_ARGUMENT naming a bad
// option, limit or period, a missing grid or checker, or an empty path.
// Precondition: map.distance, when set, has one entry per cell of the grid.
absl::StatusOr<LocalPlan> DwaStep(const DwaMap& map, const RobotState& state,
                                  const VelocityLimits& limits,
                                  absl::Span<const MovingObstacle> obstacles,
                                  absl::Span<const CellPoint> path,
                                  double period, const DwaOptions& options,
                                  std::vector<DwaRollout>* rollouts = nullptr,
                                  ProgressWindow* progress = nullptr);

}  // namespace pathd

#endif  // PATHD_CORE_LOCAL_DWA_H_
