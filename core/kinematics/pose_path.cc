#include "core/kinematics/pose_path.h"

#include <cmath>
#include <cstdlib>
#include <limits>

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

namespace {

// Appends the cells from a's cell (already the last cell of `out`) to b's
// cell along the segment a-b, each sharing an edge with the one before
// (Amanatides & Woo's voxel walk; at an exact corner, the side cell that is
// traversable is taken first).
void WalkSegment(const Grid& grid, CellPoint a, CellPoint b, bool unknown_is_free,
                 std::vector<Cell>& out) {
  const Cell from{static_cast<int32_t>(std::floor(a.x)), static_cast<int32_t>(std::floor(a.y))};
  const Cell to{static_cast<int32_t>(std::floor(b.x)), static_cast<int32_t>(std::floor(b.y))};
  const int32_t sx = to.x > from.x ? 1 : -1;
  const int32_t sy = to.y > from.y ? 1 : -1;
  const double dx = b.x - a.x;
  const double dy = b.y - a.y;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  // Parameter t in [0, 1] along a-b at which the next vertical (horizontal)
  // cell boundary is crossed, and the step of t between boundaries.
  double next_x = dx == 0.0 ? kInf : ((sx > 0 ? from.x + 1 : from.x) - a.x) / dx;
  double next_y = dy == 0.0 ? kInf : ((sy > 0 ? from.y + 1 : from.y) - a.y) / dy;
  const double step_x = dx == 0.0 ? kInf : std::fabs(1.0 / dx);
  const double step_y = dy == 0.0 ? kInf : std::fabs(1.0 / dy);
  const auto traversable = [&](Cell c) {
    return grid.InBounds(c) && Traversable(grid.cost(c), unknown_is_free);
  };
  Cell c = from;
  while (!(c == to)) {
    bool step_in_x;
    if (c.x == to.x) {
      step_in_x = false;
    } else if (c.y == to.y) {
      step_in_x = true;
    } else if (next_x != next_y) {
      step_in_x = next_x < next_y;
    } else {
      step_in_x = traversable(Cell{c.x + sx, c.y}) || !traversable(Cell{c.x, c.y + sy});
    }
    if (step_in_x) {
      c.x += sx;
      next_x += step_x;
    } else {
      c.y += sy;
      next_y += step_y;
    }
    out.push_back(c);
  }
}

}  // namespace

std::vector<Cell> PathCells(const Grid& grid, const std::vector<PathPose>& poses,
                            bool unknown_is_free) {
  std::vector<Cell> cells;
  if (poses.empty()) return cells;
  cells.push_back(poses[0].pose.cell());
  for (size_t i = 1; i < poses.size(); ++i) {
    WalkSegment(grid, poses[i - 1].pose.point(), poses[i].pose.point(), unknown_is_free,
                cells);
  }
  return cells;
}

}  // namespace pathd
