// Dubins and Reeds-Shepp curves through OMPL (docs/decisions.md, "What
// hybrid_astar takes from OMPL"): OMPL computes the shortest word and its
// segment lengths; pathd drives the segments itself so it knows exactly
// where each arc starts, ends and reverses.
#include "core/kinematics/curves.h"

#include <cmath>

#include <ompl/base/spaces/DubinsStateSpace.h>
#include <ompl/base/spaces/ReedsSheppStateSpace.h>

namespace pathd {
namespace {

namespace ob = ompl::base;

// OMPL's spaces at unit radius: a curve for radius r is the unit curve
// between the poses scaled by 1/r, its lengths scaled by r. Built once,
// never destroyed (so no static destruction order to worry about); their
// curve functions are const and keep no state, so threads share them.
const ob::ReedsSheppStateSpace& ReedsShepp() {
  static const auto* const kSpace = new ob::ReedsSheppStateSpace(1.0);
  return *kSpace;
}
const ob::DubinsStateSpace& Dubins() {
  static const auto* const kSpace = new ob::DubinsStateSpace(1.0);
  return *kSpace;
}

// Two SE(2) states of a space for one call, freed on scope exit.
class StatePair {
 public:
  StatePair(const ob::StateSpace& space, const Pose& from, const Pose& to, double radius)
      : space_(space), from_(space.allocState()), to_(space.allocState()) {
    Set(from_, from, radius);
    Set(to_, to, radius);
  }
  ~StatePair() {
    space_.freeState(from_);
    space_.freeState(to_);
  }
  StatePair(const StatePair&) = delete;
  StatePair& operator=(const StatePair&) = delete;

  const ob::State* from() const { return from_; }
  const ob::State* to() const { return to_; }

 private:
  static void Set(ob::State* state, const Pose& pose, double radius) {
    auto* se2 = state->as<ob::SE2StateSpace::StateType>();
    se2->setXY(pose.x / radius, pose.y / radius);
    se2->setYaw(pose.yaw);
  }

  const ob::StateSpace& space_;
  ob::State* from_;
  ob::State* to_;
};

Steer FromReedsShepp(ob::ReedsSheppStateSpace::ReedsSheppPathSegmentType type) {
  switch (type) {
    case ob::ReedsSheppStateSpace::RS_LEFT:
      return Steer::kLeft;
    case ob::ReedsSheppStateSpace::RS_RIGHT:
      return Steer::kRight;
    default:
      return Steer::kStraight;
  }
}

Steer FromDubins(ob::DubinsStateSpace::DubinsPathSegmentType type) {
  switch (type) {
    case ob::DubinsStateSpace::DUBINS_LEFT:
      return Steer::kLeft;
    case ob::DubinsStateSpace::DUBINS_RIGHT:
      return Steer::kRight;
    default:
      return Steer::kStraight;
  }
}

}  // namespace

Pose Drive(const Pose& pose, Steer steer, double radius, double length) {
  const double c = std::cos(pose.yaw);
  const double s = std::sin(pose.yaw);
  if (steer == Steer::kStraight) {
    return Pose{pose.x + length * c, pose.y + length * s, pose.yaw};
  }
  // Left: the centre of the circle is `radius` to the robot's left, and the
  // heading turns by length / radius; right mirrors both.
  const double side = steer == Steer::kLeft ? 1.0 : -1.0;
  const double turn = side * length / radius;
  const double yaw = pose.yaw + turn;
  return Pose{pose.x + side * radius * (std::sin(yaw) - s),
              pose.y - side * radius * (std::cos(yaw) - c), NormalizeAngle(yaw)};
}

Curve ShortestCurve(const Pose& from, const Pose& to, double radius, bool reverse) {
  Curve curve;
  if (reverse) {
    const StatePair states(ReedsShepp(), from, to, radius);
    const ob::ReedsSheppStateSpace::ReedsSheppPath path =
        ReedsShepp().reedsShepp(states.from(), states.to());
    for (int i = 0; i < 5; ++i) {
      if (path.type_[i] == ob::ReedsSheppStateSpace::RS_NOP || path.length_[i] == 0.0) {
        continue;
      }
      curve.segments[curve.count++] =
          CurveSegment{FromReedsShepp(path.type_[i]), path.length_[i] * radius};
      curve.length += std::fabs(path.length_[i]) * radius;
    }
    return curve;
  }
  const StatePair states(Dubins(), from, to, radius);
  const ob::DubinsStateSpace::DubinsPath path = Dubins().dubins(states.from(), states.to());
  for (int i = 0; i < 3; ++i) {
    if (path.length_[i] == 0.0) continue;
    curve.segments[curve.count++] =
        CurveSegment{FromDubins(path.type_[i]), path.length_[i] * radius};
    curve.length += path.length_[i] * radius;
  }
  return curve;
}

double ShortestCurveLength(const Pose& from, const Pose& to, double radius, bool reverse) {
  if (reverse) {
    const StatePair states(ReedsShepp(), from, to, radius);
    return ReedsShepp().reedsShepp(states.from(), states.to()).length() * radius;
  }
  const StatePair states(Dubins(), from, to, radius);
  return Dubins().dubins(states.from(), states.to()).length() * radius;
}

}  // namespace pathd
