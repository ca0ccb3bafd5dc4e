// Measuring a path of poses (PlanResult::poses): the length of each piece
// between consecutive poses, its price under Nav2 Smac's penalties, and the
// cells of the poses. The kinematic planners price their
// motions with these same functions, so a result's cost is exactly what
// PathCost() says of its poses.
#ifndef PATHD_CORE_KINEMATICS_POSE_PATH_H_
#define PATHD_CORE_KINEMATICS_POSE_PATH_H_

#include <cstdint>
#include <vector>

#include "core/kinematics/pose.h"
#include "core/kinematics/vehicle.h"
#include "core/map/grid.h"

namespace pathd {

// A piece turns when its heading changes by more than this (radians); a
// straight motion's poses share one heading exactly.
inline constexpr double kStraightPieceYaw = 1e-9;

// The length of the piece from `a` to `b`: the arc of the circle through both
// positions tangent to the chord's mean heading change, chord x (dyaw / 2) /
// sin(dyaw / 2). Exact when the piece is a straight segment or an arc of one
// circle (what the planners emit: Drive() samples), the usual second-order
// estimate otherwise.
double PieceLength(const Pose& a, const Pose& b);

// Sum of PieceLength over consecutive poses.
double PathLength(const std::vector<PathPose>& poses);

// Nav2 Smac Hybrid-A*'s traversal cost (NodeHybrid::getTraversalCost), as a
// price of path pieces. A piece of length L ending in a cell of cost c costs
//   L * (1 + cost_penalty * c / 252)
//     * (non_straight_penalty when it turns)
//     * (reverse_penalty when it reverses)
// and a turning piece whose previous piece drove differently (other steering
// or direction) adds change_penalty * change_length * (1 + cost_penalty * c
// / 252): Nav2 multiplies a whole turning primitive by (non_straight +
// change) when the primitive differs from its parent's, which is that
// addition when change_length is one turning primitive's length.
struct MotionPenalties {
  double cost_penalty = 2.0;
  double non_straight = 1.2;
  double reverse = 2.0;
  double change = 0.0;
  double change_length = 0.0;
};

// The query's penalties; change_length: the length of the planner's turning
// primitive (0 for callers without primitives).
MotionPenalties PenaltiesOf(const KinematicQuery& query, double change_length = 0.0);

// How a piece drives, for the change penalty: steering (-1 right, 0
// straight, 1 left, in the wheels' sense, so reversing with the wheels left
// lowers the heading) and direction.
struct PieceKind {
  int8_t steer = 0;
  bool reverse = false;
  friend bool operator==(const PieceKind&, const PieceKind&) = default;
};

// The kind of the piece from `a` to `b` driven in direction `reverse`.
PieceKind KindOf(const Pose& a, const Pose& b, bool reverse);

// The price of one piece (see MotionPenalties); `previous` is the kind of the
// piece before it (nullptr for a path's first piece: no change penalty).
double PieceCost(double length, uint8_t cell_cost, const PieceKind& kind,
                 const PieceKind* previous, const MotionPenalties& penalties);

// The price of a whole path: PieceCost of each piece, with c the cost of the
// cell of the piece's end pose (off-map or blocked cells count as free:
// callers check collisions separately).
double PathCost(const Grid& grid, const std::vector<PathPose>& poses,
                const MotionPenalties& penalties);

// The cells of the poses, start to end, consecutive duplicates removed
// (PlanResult::path of a kinematic plan). Consecutive cells are neighbours
// (edge or corner) when the poses are at most a cell apart.
std::vector<Cell> PathCells(const std::vector<PathPose>& poses);

}  // namespace pathd

#endif  // PATHD_CORE_KINEMATICS_POSE_PATH_H_
