// Control sets of a state lattice: the motion primitives a lattice planner
// (core/planners/kinematic/state_lattice.h) chains, one list per start
// heading, every primitive ending on a lattice point (a whole number of cells
// from where it starts) at one of the lattice's headings. Here: the value
// types, the control-set file format (ROS 2 Nav2's lattice primitive JSON,
// which pathd reads and writes, with two optional fields of its own), the
// sets shipped with pathd (data/lattices/, compiled in), and the
// process-wide cache that hands a query its set by name, by file or by
// motion model. How sets are made: core/kinematics/lattice_generator.h.
// docs/planners.md, "Control sets", documents the format.
#ifndef PATHD_CORE_KINEMATICS_LATTICE_H_
#define PATHD_CORE_KINEMATICS_LATTICE_H_

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "core/kinematics/pose.h"
#include "core/kinematics/vehicle.h"

namespace pathd {

// The robot a control set was made for, by Nav2's names for it.
enum class LatticeRobot {
  // "diff": straight moves and arcs both ways, turns in place by one
  // heading.
  kDifferential,
  // "ackermann": straight moves and arcs no tighter than the turning radius,
  // forward only or both ways; no turning in place.
  kAckermann,
  // "omni": a differential set plus moves sideways and diagonally, with and
  // without a change of heading.
  kOmnidirectional,
};

// "diff", "ackermann", "omni".
std::string_view LatticeRobotName(LatticeRobot robot);
// The inverse of LatticeRobotName; INVALID_ARGUMENT listing the names.
absl::StatusOr<LatticeRobot> ParseLatticeRobot(std::string_view name);

// Largest distance, cells, between consecutive poses of a primitive, and
// largest heading change, radians: dense enough to be returned as a path
// (PlanResult::poses) as they are.
inline constexpr double kLatticePoseSpacing = 0.5;
inline constexpr double kLatticeYawSpacing = 0.1;

// One motion primitive, in cells, relative to the lattice point it starts
// from. A value type.
struct LatticePrimitive {
  int32_t start_heading = 0;
  int32_t end_heading = 0;
  // Where it ends, cells from where it starts.
  int32_t dx = 0;
  int32_t dy = 0;
  // Distance the robot's reference point travels, cells (0 for a turn in
  // place), and how much of it is on an arc.
  double length = 0.0;
  double arc_length = 0.0;
  // The arc's radius, cells; 0 when the primitive has no arc (straight
  // moves, sideways moves, turns in place).
  double radius = 0.0;
  // The heading increases along the motion (Nav2's left_turn).
  bool left_turn = false;
  // Driven backwards: every pose is reached moving against its heading.
  bool reverse = false;
  // Length 0: the robot turns where it stands.
  bool turn_in_place = false;
  // The motion, start to end inclusive: poses[0] = (0, 0, start angle), the
  // last (dx, dy, end angle); between consecutive poses the robot moves
  // linearly in position and heading; consecutive poses are at most
  // kLatticePoseSpacing apart and differ by at most kLatticeYawSpacing in
  // heading. The heading of a pose is the robot's, not the direction of
  // travel (they differ when reversing or moving sideways).
  std::vector<Pose> poses;

  // The heading changes along the motion (an arc, a turn in place, or a
  // sideways move that turns).
  bool turns() const { return start_heading != end_heading; }
};

// A lattice's headings and the primitives from each of them. Immutable once
// made; shared between queries as shared_ptr<const ControlSet>.
struct ControlSet {
  // The shipped name, the file it was read from, or a description of the
  // generator's parameters: what messages call it.
  std::string name;
  LatticeRobot robot = LatticeRobot::kAckermann;
  // The grid resolution, metres per cell, and the minimum turning radius,
  // metres, it was made for. Only turning_radius / resolution (cells)
  // matters to a planner: a set is the same at every scale.
  double resolution_m = 1.0;
  double turning_radius_m = 1.0;
  // The generator's parameters, kept in the file; 0 when unknown.
  int32_t stopping_threshold = 0;
  double length_tolerance = 0.0;
  // Heading i is heading_angles[i], radians in [0, 2pi), increasing.
  std::vector<double> heading_angles;
  // Sorted by start heading; first_of_heading[h] .. first_of_heading[h+1]
  // are the primitives from heading h.
  std::vector<LatticePrimitive> primitives;
  std::vector<size_t> first_of_heading;

  int32_t headings() const { return static_cast<int32_t>(heading_angles.size()); }
  double turning_radius_cells() const { return turning_radius_m / resolution_m; }
  // The tightest arc among the primitives, cells (+infinity when none).
  double tightest_radius_cells() const;
  bool has_reverse() const;
  bool has_turn_in_place() const;
  // The heading whose angle is within `tolerance` radians of `yaw`, or -1.
  int32_t HeadingOf(double yaw, double tolerance = 1e-6) const;
  // The heading nearest `yaw`.
  int32_t NearestHeading(double yaw) const;
  // Sorts the primitives by start heading and fills first_of_heading.
  void Index();
};

// The control-set file (JSON; docs/planners.md, "Control sets"): Nav2's
// lattice_primitives output with lengths in metres,
//   {"version": 1.0, "lattice_metadata": {"motion_model": "ackermann",
//    "turning_radius": 0.5, "grid_resolution": 0.05, "stopping_threshold": 5,
//    "num_of_headings": 16, "heading_angles": [...],
//    "number_of_trajectories": N},
//    "primitives": [{"trajectory_id": 0, "start_angle_index": 0,
//      "end_angle_index": 1, "left_turn": true, "trajectory_radius": 0.63,
//      "trajectory_length": 0.37, "arc_length": 0.29,
//      "straight_length": 0.07, "poses": [[x, y, yaw], ...]}, ...]}
// plus pathd's optional "reverse": true on a primitive driven backwards and
// "length_tolerance" in the metadata. Written with every field, deterministic
// (no date), two-space indented.
std::string WriteControlSet(const ControlSet& set);

// Parses a control-set file's text. `source` names it in errors:
// INVALID_ARGUMENT "<source>:<line>: <field>: <problem>" for text that is not
// JSON, a missing or mistyped field, a heading index out of range, a
// primitive whose poses do not start at the origin with its start heading,
// do not end on a lattice point (a whole number of cells, within 1e-3 cell)
// with its end heading, or jump (poses more than 1.5 cells apart).
// Poses farther apart than kLatticePoseSpacing / kLatticeYawSpacing are
// interpolated linearly (Nav2's files space them a cell apart); a first pose
// other than the start (Nav2 leaves it out) is preceded by the start.
absl::StatusOr<ControlSet> ParseControlSet(std::string_view text, std::string_view source);

// Reads and parses a file: NOT_FOUND naming the path when it cannot be read,
// else ParseControlSet's errors.
absl::StatusOr<ControlSet> ReadControlSetFile(const std::string& path);

// The names of the sets pathd ships (data/lattices/<name>.json, compiled
// in), sorted.
std::vector<std::string> ShippedControlSetNames();

// The set called `name_or_path`: a shipped name, else a file path (anything
// with a '/' or ending in .json). Parsed once per process and kept
// (thread-safe); a file is read again when its modification time changes.
// INVALID_ARGUMENT listing the shipped names when it is neither.
absl::StatusOr<std::shared_ptr<const ControlSet>> LoadControlSet(std::string_view name_or_path);

// The set a query plans with: query.lattice when set (LoadControlSet); else
// the default for its motion model (kDubins: ackermann forward only;
// kReedsShepp: ackermann both ways; kDifferential: diff; kOmnidirectional:
// omni; 16 headings) at the query's turning radius (kDifferential and
// kOmnidirectional without one: kDefaultArcRadiusCells): the shipped set of
// that robot and radius in cells when there is one, else one generated now
// and kept for the process (thread-safe; a generation takes milliseconds to
// a few seconds, growing with the radius). INVALID_ARGUMENT when the
// radius is not usable (not finite, or below 0.5 or above 64 cells for a
// generated set).
absl::StatusOr<std::shared_ptr<const ControlSet>> ControlSetForQuery(const KinematicQuery& query);

// The arc radius of the default differential and omnidirectional sets,
// cells, when the query has no turning radius.
inline constexpr double kDefaultArcRadiusCells = 2.0;

}  // namespace pathd

#endif  // PATHD_CORE_KINEMATICS_LATTICE_H_
