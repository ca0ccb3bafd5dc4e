// Shortest paths of a car between two poses when nothing is in the way:
// Dubins curves (forward only; Dubins 1957) and Reeds-Shepp curves (forward
// and reverse; Reeds & Shepp 1990), at a given turning radius. Reeds-Shepp
// curves come from OMPL's ReedsSheppStateSpace (a private dependency of
// pathd::core: no OMPL type appears here); Dubins curves are OMPL's
// DubinsStateSpace formulas written out in curves.cc, because Debian's OMPL
// build asserts on its own rounding in them (about once in 10^5-10^6 random
// pose pairs 40 radii apart, more often farther) and the assert aborts the
// process. This file turns them into pathd's steering segments and drives
// them.
#ifndef PATHD_CORE_KINEMATICS_CURVES_H_
#define PATHD_CORE_KINEMATICS_CURVES_H_

#include <array>
#include <cstdint>

#include "core/kinematics/pose.h"

namespace pathd {

// Which way the wheels point during a motion.
enum class Steer : int8_t { kRight = -1, kStraight = 0, kLeft = 1 };

// The pose reached from `pose` after driving `length` cells (negative:
// backwards) with the wheels at `steer`, on a circle of `radius` cells when
// turning. Forward left turns raise the heading, as does reversing with the
// wheels turned right. The heading is normalised. Precondition: radius > 0.
Pose Drive(const Pose& pose, Steer steer, double radius, double length);

// One segment of a curve: a steering and a signed length (cells; negative:
// reverse).
struct CurveSegment {
  Steer steer = Steer::kStraight;
  double length = 0.0;
};

// A shortest curve: up to five segments (three for Dubins), in order.
struct Curve {
  std::array<CurveSegment, 5> segments;
  int32_t count = 0;
  // Sum of the segments' absolute lengths, cells.
  double length = 0.0;
};

// The shortest curve from `from` to `to` for a car with turning radius
// `radius` cells (> 0): Reeds-Shepp when `reverse` is true, else Dubins.
// Driving its segments from `from` ends at `to` up to rounding (~1e-9 of the
// distance). Thread-safe.
Curve ShortestCurve(const Pose& from, const Pose& to, double radius, bool reverse);

// ShortestCurve(...).length, the non-holonomic distance without obstacles.
// Thread-safe; a Reeds-Shepp length costs about 5-10 us (OMPL tries all 48
// word families), a Dubins length well under 1 us.
double ShortestCurveLength(const Pose& from, const Pose& to, double radius, bool reverse);

// Within kCurveTableRadii turning radii of `to`: ShortestCurveLength read
// from a process-wide table, Nav2's "distance heuristic lookup table" in
// the goal's frame, shared by every query (lengths scale with the radius, so
// one table in units of the radius serves all radii): the relative pose is
// rounded to 1/kCurveTableSteps radius in position and to one of
// `heading_bins` bins in heading, and the table holds the exact length from
// the rounded pose, computed on first use (thread-safe; 2.4 MB per motion
// model for 72 bins). The rounding moves the pose by at most 0.09 radius,
// so the value is within about that of the exact length (and a heading bin
// of turning). Farther: ShortestCurveLength itself.
// Precondition: radius > 0, heading_bins in 1..3600.
inline constexpr double kCurveTableRadii = 8.0;
inline constexpr int kCurveTableSteps = 8;
double TabledCurveLength(const Pose& from, const Pose& to, double radius, bool reverse,
                         int32_t heading_bins);

}  // namespace pathd

#endif  // PATHD_CORE_KINEMATICS_CURVES_H_
