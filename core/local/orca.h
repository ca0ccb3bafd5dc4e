// Optimal reciprocal collision avoidance: van den Berg, Guy, Lin & Manocha,
// "Reciprocal n-body collision avoidance" (ISRR 2009, STAR 70, 2011), the
// reciprocal form of the velocity obstacles the lecture "Planning I" (the
// planning hierarchy: a global path, then a local layer) presents. Each
// neighbour within the time horizon contributes one half-plane of admissible
// velocities (each of two reacting robots takes half of the avoidance; an
// obstacle that does not react leaves all of it to us); static obstacles are
// line segments from the map's obstacle polygons (core/geometry/
// obstacle_polygons.h) with their own time horizon. The velocity closest to
// the preferred one inside every half-plane and the max-speed disc is the
// 2-D linear program, solved incrementally; when the half-planes of the
// neighbours cannot all hold, the 3-D linear program finds the velocity
// that violates them least (static obstacle lines stay hard).
//
// Pure functions; thread-safe. Work per call: O(neighbours considered +
// obstacle lines) expected for the programs (each line may restart the
// 1-D program over the previous ones: O(n^2) worst case), bounded by
// OrcaOptions::max_neighbours and max_obstacle_lines.
#ifndef PATHD_CORE_LOCAL_ORCA_H_
#define PATHD_CORE_LOCAL_ORCA_H_

#include <cstddef>
#include <cstdint>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/types/span.h"
#include "core/geometry/obstacle_polygons.h"
#include "core/local/local_types.h"
#include "core/map/grid.h"

namespace pathd {

// A half-plane of velocities: those on the left of the directed line through
// `point` along the unit vector `direction` (det(direction, v - point) >= 0).
struct OrcaLine {
  CellPoint point;
  CellPoint direction;
};

// How far velocity `v` is on the wrong side of `line` (> 0 violates), in
// cells/s.
double OrcaViolation(const OrcaLine& line, CellPoint v);

// The ORCA half-plane of a robot at `position` with velocity `velocity` and
// `radius` against `other` within time horizon `horizon` s (> 0). `share` is
// the part of the avoidance this robot takes: 0.5 against a robot that
// reacts too, 1 against one that does not (OrcaStep also takes all of it
// behind a robot ahead that goes its way: the follower keeps the gap).
// When the two already overlap, the half-plane pushes them apart within
// `period` (the control period, s).
OrcaLine OrcaLineForNeighbour(CellPoint position, CellPoint velocity,
                              double radius, const MovingObstacle& other,
                              double horizon, double period, double share);

// A static obstacle: a segment of an obstacle's boundary, cell coordinates.
struct ObstacleSegment {
  CellPoint a;
  CellPoint b;
};

// The segments of `polygons`' rings within `range` cells of `center`, nearest
// first, at most `max_segments` of them. O(ring vertices); rings whose
// bounding box is farther than `range` are skipped whole.
std::vector<ObstacleSegment> ObstacleSegmentsNear(
    const ObstaclePolygons& polygons, CellPoint center, double range,
    size_t max_segments);

// The half-plane that keeps a disc of `radius` at `position` out of the
// segment for `horizon` s: with q the segment's point nearest `position`
// at distance d and n the unit vector from q to `position`, n . v >=
// -(d - radius) / horizon. The segment lies in the half-space behind q, so
// any velocity in it keeps the disc off the segment for the horizon: sound,
// and more cautious than the paper's truncated cone around the segment (a
// robot may still slide along a wall at full speed). When the disc already
// touches the segment, n . v >= (radius - d) / period pushes it out.
OrcaLine OrcaLineForSegment(CellPoint position, double radius,
                            const ObstacleSegment& segment, double horizon,
                            double period);

// Where a robot of `radius` (cells) at `position` should head on `path`:
// FindPathTarget's lookahead point, or the first of shorter ones (7/8, 3/4,
// ... 1/8 of `lookahead`) that it sees past `segments` with the clearance
// it has (the sight line keeps `radius` from every segment, or as much as
// the robot keeps now when it is closer). A point round a corner would pull
// the robot into the corner. The shortest when none is clear.
// Precondition: path not empty.
PathTarget VisibleTarget(absl::Span<const CellPoint> path, CellPoint position,
                         double radius,
                         absl::Span<const ObstacleSegment> segments,
                         double lookahead);

// The answer of the linear programs.
struct OrcaSolution {
  CellPoint velocity;
  // True when every line holds (within 1e-9); false when the 3-D program
  // answered (velocity then minimises the largest violation of the lines
  // from index `hard_lines` on, keeping lines 0..hard_lines-1).
  bool feasible = true;
  double max_violation = 0.0;  // over all lines, cells/s
};

// The velocity inside the disc of `max_speed` (>= 0) that satisfies every
// line and is closest to `preferred`; when there is none, the one that
// satisfies lines [0, hard_lines) and minimises the largest violation of
// the rest. Lines 0..hard_lines-1 are static obstacles and assumed jointly
// feasible (velocity 0 satisfies them when the robot touches nothing).
// Precondition: directions are unit vectors.
OrcaSolution SolveOrcaLines(absl::Span<const OrcaLine> lines, size_t hard_lines,
                            double max_speed, CellPoint preferred);

struct OrcaOptions {
  // Seconds ahead neighbours and static obstacles are avoided for.
  double time_horizon = 2.0;
  double obstacle_time_horizon = 1.0;
  // Neighbours farther than this (centre to centre, cells) are ignored, and
  // at most max_neighbours of the nearest are taken.
  double neighbour_range = 10.0;
  size_t max_neighbours = 16;
  // Obstacle segments within this many cells of the robot's boundary, at most
  // max_obstacle_lines of the nearest.
  double obstacle_range = 4.0;
  size_t max_obstacle_lines = 32;
  // Added to the robot's radius in every constraint, cells: room for the
  // discretisation of time and of the map.
  double safety_margin = 0.05;
  // The preferred velocity aims at the point this far along the global path
  // (cells) at max speed, slowing to stop at the goal.
  double lookahead = 3.0;
  // The goal counts as reached within this distance, cells.
  double goal_tolerance = 0.25;
  // The preferred velocity is turned this many radians clockwise while a
  // neighbour is within neighbour_range: the "keep right" convention that
  // breaks the symmetric equilibria in which reciprocal robots otherwise
  // stop face to face for ever (robots swapping across a circle, or two
  // head-on in a corridor). 0 turns it off. Crowds of differential-drive
  // robots, which cannot sidestep, need more (0.5); in corridors that much
  // steers robots into the wall on their right (docs/decisions.md).
  double keep_right = 0.15;
  // Differential drive: turn rate per radian of heading error, 1/s.
  double turn_gain = 2.0;
  // Limit the new velocity to what the accelerations reach in one period.
  // Changes the answer away from the program's when the limits bind (then
  // ORCA's collision-free guarantee no longer holds; docs/decisions.md).
  bool respect_acceleration = true;
  // Stall detection, with a ProgressWindow: less than min_progress cells of
  // progress along the path over window_seconds is reported as
  // kLocalMinimum.
  double window_seconds = 3.0;
  double min_progress = 0.5;
  // Sub-steps of the predicted trajectory over one time_horizon.
  int32_t trajectory_steps = 10;
};

// INVALID_ARGUMENT naming the option.
absl::Status ValidateOrcaOptions(const OrcaOptions& options);

// One control cycle of ORCA for a robot of `radius` cells: the preferred
// velocity toward the lookahead point on `path` (cell coordinates; not
// empty), the half-planes of the neighbours and of `segments` (static
// obstacle segments, e.g. ObstacleSegmentsNear), the program, and for a
// differential-drive robot the (v, w) that follows the answer
// (FollowVelocityDiffDrive), its forward speed cut so that the velocity
// along the current heading stays inside every half-plane. Status
// kBlocked when the program was infeasible (the least-violating velocity is
// still commanded), kGoalReached within goal_tolerance of the path's end,
// kLocalMinimum when `progress` (optional, the caller's per robot) sees a
// stall.
// The robot's current grid-frame velocity is taken from `state` (v, vy in
// the body frame). Errors: INVALID_ARGUMENT naming a bad option, limit,
// radius, or an empty path.
absl::StatusOr<LocalPlan> OrcaStep(const RobotState& state, double radius,
                                   const VelocityLimits& limits,
                                   absl::Span<const MovingObstacle> neighbours,
                                   absl::Span<const ObstacleSegment> segments,
                                   absl::Span<const CellPoint> path,
                                   double period, const OrcaOptions& options,
                                   ProgressWindow* progress = nullptr);

}  // namespace pathd

#endif  // PATHD_CORE_LOCAL_ORCA_H_
