#include "core/kinematics/pose_path.h"

#include <cmath>

#include "core/map/cost_model.h"

namespace pathd {

double PieceLength(const Pose& a, const Pose& b) {
  const double chord = std::sqrt((b.x - a.x) * (b.x - a.x) + (b.y - a.y) * (b.y - a.y));
  const double half = std::fabs(NormalizeAngle(b.yaw - a.yaw)) / 2.0;
  // sin(h) / h is 1 - h^2/6 + ...; below 1e-4 the ratio is 1 to double
  // precision.
  if (half < 1e-4) return chord;
  return chord * half / std::sin(half);
}

double PathLength(const std::vector<PathPose>& poses) {
  double length = 0.0;
  for (size_t i = 1; i < poses.size(); ++i) {
    length += PieceLength(poses[i - 1].pose, poses[i].pose);
  }
  return length;
}

MotionPenalties PenaltiesOf(const KinematicQuery& query, double change_length) {
  MotionPenalties p;
  p.cost_penalty = query.cost_penalty;
  p.non_straight = query.non_straight_penalty;
  p.reverse = query.reverse_penalty;
  p.change = query.change_penalty;
  p.change_length = change_length;
  return p;
}

PieceKind KindOf(const Pose& a, const Pose& b, bool reverse) {
  const double turn = NormalizeAngle(b.yaw - a.yaw);
  PieceKind kind;
  kind.reverse = reverse;
  if (std::fabs(turn) > kStraightPieceYaw) {
    // Reversing with the wheels to the left turns the heading clockwise.
    kind.steer = static_cast<int8_t>((turn > 0.0) != reverse ? 1 : -1);
  }
  return kind;
}

double PieceCost(double length, uint8_t cell_cost, const PieceKind& kind,
                 const PieceKind* previous, const MotionPenalties& penalties) {
  const double factor = CellFactor(cell_cost, penalties.cost_penalty);
  double cost = length * factor;
  if (kind.steer != 0) cost *= penalties.non_straight;
  if (kind.reverse) cost *= penalties.reverse;
  if (kind.steer != 0 && previous != nullptr && !(*previous == kind)) {
    cost += penalties.change * penalties.change_length * factor;
  }
  return cost;
}

double PathCost(const Grid& grid, const std::vector<PathPose>& poses,
                const MotionPenalties& penalties) {
  double cost = 0.0;
  PieceKind previous;
  for (size_t i = 1; i < poses.size(); ++i) {
    const Pose& a = poses[i - 1].pose;
    const Pose& b = poses[i].pose;
    const PieceKind kind = KindOf(a, b, poses[i].reverse);
    const Cell c = b.cell();
    const uint8_t cell_cost = grid.InBounds(c) ? grid.cost(c) : kFreeCost;
    cost += PieceCost(PieceLength(a, b), cell_cost, kind, i > 1 ? &previous : nullptr,
                      penalties);
    previous = kind;
  }
  return cost;
}

std::vector<Cell> PathCells(const std::vector<PathPose>& poses) {
  std::vector<Cell> cells;
  for (const PathPose& p : poses) {
    const Cell c = p.pose.cell();
    if (cells.empty() || !(cells.back() == c)) cells.push_back(c);
  }
  return cells;
}

}  // namespace pathd
