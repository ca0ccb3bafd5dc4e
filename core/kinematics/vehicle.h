// What a kinematic planner needs beyond a grid query: exact start and goal
// poses, the robot's footprint, its motion model and turning radius, the
// penalties that shape its paths, and the goal tolerance in position and
// heading. In cells and radians like the rest of core; the server converts
// the request's metres (PlanRequest::kinematic, core/search/plan_types.h).
#ifndef PATHD_CORE_KINEMATICS_VEHICLE_H_
#define PATHD_CORE_KINEMATICS_VEHICLE_H_

#include <cstdint>
#include <memory>
#include <string>

#include "absl/status/statusor.h"
#include "core/kinematics/footprint.h"
#include "core/kinematics/pose.h"

namespace pathd {

// How the robot may move between poses.
enum class MotionModel {
  // Forward only, curvature at most 1 / min_turning_radius (Dubins 1957).
  kDubins,
  // Forward and reverse, same curvature bound (Reeds & Shepp 1990).
  kReedsShepp,
  // Turns in place and drives straight, both directions (differential drive).
  kDifferential,
  // Moves in any direction while turning (holonomic base).
  kOmnidirectional,
};

// "dubins", "reeds_shepp", "differential", "omnidirectional".
std::string_view MotionModelName(MotionModel model);
// The inverse of MotionModelName; INVALID_ARGUMENT listing the names.
absl::StatusOr<MotionModel> ParseMotionModel(std::string_view name);
// Whether the model lets the robot reverse.
bool AllowsReverse(MotionModel model);

// One kinematic planning query. Penalties follow Nav2's Smac planners, whose
// defaults they take: a motion's cost is its length times (1 + the cost
// penalty's share of the cells' cost) times non_straight_penalty when it
// turns and reverse_penalty when it reverses, plus change_penalty at each
// change of direction.
struct KinematicQuery {
  Pose start;
  Pose goal;
  // The robot's outline, cells (body frame).
  std::shared_ptr<const FootprintChecker> footprint;
  MotionModel motion = MotionModel::kReedsShepp;
  // Smallest turning radius of the robot's centre, cells (> 0 for Dubins and
  // Reeds-Shepp).
  double min_turning_radius_cells = 0.0;
  double reverse_penalty = 2.0;
  double change_penalty = 0.0;
  double non_straight_penalty = 1.2;
  double cost_penalty = 2.0;
  // The path ends within this distance (cells) of the goal position and this
  // angle (radians) of its heading.
  double goal_tolerance_cells = 0.0;
  double goal_tolerance_yaw = 0.0;
  // state_lattice: the control set's name or file (empty: the default for the
  // motion model).
  std::string lattice;
  // Smooth the path (core/kinematics/smoother.h) before returning it.
  bool smooth = true;
};

// The query a kinematic planner answers for a request that carries none (a
// grid query naming a kinematic planner): a point-like robot (a disc of 0.05
// cells, checked with 4 subcells so one-cell corridors stay open),
// Reeds-Shepp with a one-cell turning radius, starting at the start cell's
// centre facing the goal, ending at the goal cell's centre with any heading.
KinematicQuery DefaultKinematicQuery(Cell start, Cell goal);

// A footprint's checker with the given options, shared by every query that
// asks for the same footprint and options: building the masks costs
// milliseconds, so a process-wide cache of the most recent ones (thread-safe)
// keeps it out of every query.
absl::StatusOr<std::shared_ptr<const FootprintChecker>> SharedFootprintChecker(
    const Footprint& footprint, const FootprintCheckerOptions& options = {});

}  // namespace pathd

#endif  // PATHD_CORE_KINEMATICS_VEHICLE_H_
