// The generator of near-minimal control sets for a state lattice (Pivtoraiko
// & Kelly, "Generating near minimal spanning control sets for constrained
// motion planning in discrete state spaces", IROS 2005), with the heading
// discretisation and trajectory shape of ROS 2 Nav2's lattice primitive
// generator (nav2_smac_planner/lattice_primitives), so its sets read like
// Nav2's and its files load in Nav2.
//
// Headings: for 8m headings, the directions from the centre of a
// (2m+1) x (2m+1) square of cells to the 8m cells on its border (16: 0,
// 26.6, 45, 63.4, 90, ... degrees), so a straight move along any heading ends
// on a lattice point. Trajectories: from heading a at the origin to heading b
// at a lattice point, a straight line, an arc, a straight line, the arc as
// large as the two heading lines allow (Nav2's trajectory generator) and no
// tighter than the turning radius; straight moves when a == b.
//
// Minimality (Pivtoraiko & Kelly): candidate primitives are taken in order of
// length, ring by ring of end points around the origin; a candidate is kept
// only when no chain of primitives already kept reaches its end state within
// (1 + length_tolerance) times its length, and the rings stop growing after
// stopping_threshold rings that added nothing. A last pass drops any kept
// primitive that the others compose within the same tolerance. The dihedral
// symmetry of the square lattice (quarter turns and mirror images) maps every
// primitive to up to seven others, which are kept or dropped with it, so only
// start headings between 0 and 45 degrees are searched.
#ifndef PATHD_CORE_KINEMATICS_LATTICE_GENERATOR_H_
#define PATHD_CORE_KINEMATICS_LATTICE_GENERATOR_H_

#include <cstdint>
#include <vector>

#include "absl/status/statusor.h"
#include "core/kinematics/lattice.h"

namespace pathd {

struct LatticeGeneratorOptions {
  LatticeRobot robot = LatticeRobot::kAckermann;
  // Ackermann only: add every arc and straight move driven backwards.
  // Differential and omnidirectional sets always have them.
  bool reverse = false;
  // Metres per cell and the minimum turning radius, metres: the set depends
  // only on their ratio (the radius in cells), they are kept in the file.
  double resolution_m = 0.05;
  double turning_radius_m = 0.5;
  // A multiple of 8, 8..64.
  int32_t headings = 16;
  // A candidate within (1 + length_tolerance) x its length of a chain of
  // kept primitives is dropped.
  double length_tolerance = 0.1;
  // Rings of end points without a new primitive before the search stops
  // (Nav2's stopping_threshold).
  int32_t stopping_threshold = 5;
};

// The headings' angles, radians in [0, 2pi), increasing (see the file
// comment), and the integer direction of each: the border cell it points at.
// Precondition: headings is a multiple of 8 and > 0.
std::vector<double> LatticeHeadingAngles(int32_t headings);
std::vector<Cell> LatticeHeadingDirections(int32_t headings);

// The control set for `options`. INVALID_ARGUMENT naming the option when the
// resolution or radius is not positive and finite, the radius is below half
// a cell or above 64 cells, the heading count is not a multiple of 8 in
// 8..64, the tolerance is not in [0, 1] or the threshold not in 1..50.
// Deterministic: the same options give the same set.
//
// Every set spans the lattice: from each heading, chains of its primitives
// reach every heading. The primitives that move, other than sideways ones,
// turn no tighter than the turning radius; differential and omnidirectional
// sets add a turn in place to each neighbouring heading; omnidirectional
// sets add moves along each lattice direction other than the heading,
// keeping the heading or turning to a neighbouring one, kept or dropped by
// the same rule.
absl::StatusOr<ControlSet> GenerateControlSet(const LatticeGeneratorOptions& options);

}  // namespace pathd

#endif  // PATHD_CORE_KINEMATICS_LATTICE_GENERATOR_H_
