// Dubins and Reeds-Shepp curves through OMPL (docs/decisions.md, "What
// hybrid_astar takes from OMPL"): OMPL computes the shortest word and its
// segment lengths; pathd drives the segments itself so it knows exactly
// where each arc starts, ends and reverses.
#include "core/kinematics/curves.h"

#include <atomic>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <utility>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/synchronization/mutex.h"

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

// The lengths from rounded relative poses to the origin at unit radius,
// filled on first read. Entries are independent atomics: two threads may
// compute the same entry, and store the same value.
class CurveTable {
 public:
  CurveTable(bool reverse, int32_t bins)
      : reverse_(reverse),
        bins_(bins),
        side_(2 * kReach + 1),
        lengths_(static_cast<size_t>(side_) * (kReach + 1) * static_cast<size_t>(bins)) {
    for (auto& l : lengths_) l.store(kUnknown, std::memory_order_relaxed);
  }

  // The unit-radius length from (u, v, yaw) to the origin; |u|, |v| <=
  // kCurveTableRadii.
  double Length(double u, double v, double yaw) {
    // A mirror image across the x axis (v and yaw negated, left and right
    // swapped) has the same length, for Dubins and Reeds-Shepp alike.
    if (v < 0.0) {
      v = -v;
      yaw = -yaw;
    }
    const int iu = static_cast<int>(std::lround(u * kCurveTableSteps));
    const int iv = static_cast<int>(std::lround(v * kCurveTableSteps));
    const double bin = 2.0 * std::numbers::pi / bins_;
    const int ib = static_cast<int>(((std::lround(yaw / bin) % bins_) + bins_) % bins_);
    std::atomic<float>& entry =
        lengths_[(static_cast<size_t>(iv) * side_ + static_cast<size_t>(iu + kReach)) * bins_ +
                 static_cast<size_t>(ib)];
    float length = entry.load(std::memory_order_relaxed);
    if (length == kUnknown) {
      const Pose rounded{static_cast<double>(iu) / kCurveTableSteps,
                         static_cast<double>(iv) / kCurveTableSteps, ib * bin};
      length = static_cast<float>(ShortestCurveLength(rounded, Pose{}, 1.0, reverse_));
      entry.store(length, std::memory_order_relaxed);
    }
    return length;
  }

 private:
  static constexpr int kReach = static_cast<int>(kCurveTableRadii) * kCurveTableSteps;
  static constexpr float kUnknown = -1.0f;

  const bool reverse_;
  const int32_t bins_;
  const int side_;
  std::vector<std::atomic<float>> lengths_;
};

// The tables of each motion model and heading resolution asked for, made
// on first use and kept for the process. Thread-safe.
class CurveTables {
 public:
  CurveTable& Get(bool reverse, int32_t bins) ABSL_LOCKS_EXCLUDED(mu_) {
    absl::MutexLock lock(&mu_);
    std::unique_ptr<CurveTable>& table = tables_[{reverse, bins}];
    if (table == nullptr) table = std::make_unique<CurveTable>(reverse, bins);
    return *table;
  }

 private:
  absl::Mutex mu_;
  std::map<std::pair<bool, int32_t>, std::unique_ptr<CurveTable>> tables_
      ABSL_GUARDED_BY(mu_);
};

CurveTable& TableFor(bool reverse, int32_t bins) {
  static auto* const tables = new CurveTables();
  return tables->Get(reverse, bins);
}

}  // namespace

double TabledCurveLength(const Pose& from, const Pose& to, double radius, bool reverse,
                         int32_t heading_bins) {
  const double dx = from.x - to.x;
  const double dy = from.y - to.y;
  const double c = std::cos(to.yaw);
  const double s = std::sin(to.yaw);
  const double u = (c * dx + s * dy) / radius;
  const double v = (-s * dx + c * dy) / radius;
  if (std::fabs(u) > kCurveTableRadii || std::fabs(v) > kCurveTableRadii) {
    return ShortestCurveLength(from, to, radius, reverse);
  }
  // One table per thread would cost a map lookup anyway; the lock is held
  // for that lookup only.
  thread_local CurveTable* cached = nullptr;
  thread_local bool cached_reverse = false;
  thread_local int32_t cached_bins = 0;
  if (cached == nullptr || cached_reverse != reverse || cached_bins != heading_bins) {
    cached = &TableFor(reverse, heading_bins);
    cached_reverse = reverse;
    cached_bins = heading_bins;
  }
  return radius * cached->Length(u, v, NormalizeAngle(from.yaw - to.yaw));
}

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
