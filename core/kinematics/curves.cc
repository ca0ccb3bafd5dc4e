// Dubins and Reeds-Shepp curves (docs/decisions.md, "Hybrid A* and the path
// smoother"): OMPL computes the shortest Reeds-Shepp word and its segment
// lengths; the Dubins words are OMPL's formulas (Shkel & Lumelsky) written
// out here, because Debian's OMPL asserts on its own rounding in them and
// aborts the process; pathd drives the segments itself so it knows exactly
// where each arc starts, ends and reverses.
#include "core/kinematics/curves.h"

#include <array>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <optional>
#include <utility>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/synchronization/mutex.h"

#include <ompl/base/spaces/ReedsSheppStateSpace.h>

namespace pathd {
namespace {

namespace ob = ompl::base;

// OMPL's space at unit radius: a curve for radius r is the unit curve
// between the poses scaled by 1/r, its lengths scaled by r. Built once,
// never destroyed (so no static destruction order to worry about); its
// curve function is const and keeps no state, so threads share it.
const ob::ReedsSheppStateSpace& ReedsShepp() {
  static const auto* const kSpace = new ob::ReedsSheppStateSpace(1.0);
  return *kSpace;
}

// Dubins's six words at unit radius, from the start's frame rotated onto
// the line to the goal: distance d, headings alpha and beta relative to it
// (Shkel & Lumelsky, "Classification of the Dubins set", 2001, as OMPL's
// DubinsStateSpace computes them, without its asserts).
struct DubinsWord {
  std::array<Steer, 3> steer;
  std::array<double, 3> length;
  double total() const { return length[0] + length[1] + length[2]; }
};

double Mod2Pi(double a) {
  constexpr double kTwoPi = 2.0 * std::numbers::pi;
  double v = std::fmod(a, kTwoPi);
  if (v < 0.0) v += kTwoPi;
  // Within rounding of a whole turn is no turn.
  if (v > kTwoPi - 1e-12) v = 0.0;
  return v;
}

DubinsWord ShortestDubins(double d, double alpha, double beta) {
  constexpr Steer L = Steer::kLeft, S = Steer::kStraight, R = Steer::kRight;
  const double ca = std::cos(alpha), sa = std::sin(alpha);
  const double cb = std::cos(beta), sb = std::sin(beta);
  const double cab = std::cos(alpha - beta);
  std::optional<DubinsWord> best;
  const auto offer = [&best](const DubinsWord& w) {
    if (!best || w.total() < best->total()) best = w;
  };
  // LSL and RSR always exist: their squared straight lengths are
  // (d + sa - sb)^2 + (cb - ca)^2 and its mirror (clamped against
  // rounding below zero).
  {
    const double tmp = std::max(0.0, 2.0 + d * d - 2.0 * cab + 2.0 * d * (sa - sb));
    const double theta = std::atan2(cb - ca, d + sa - sb);
    offer({{L, S, L}, {Mod2Pi(-alpha + theta), std::sqrt(tmp), Mod2Pi(beta - theta)}});
  }
  {
    const double tmp = std::max(0.0, 2.0 + d * d - 2.0 * cab + 2.0 * d * (sb - sa));
    const double theta = std::atan2(ca - cb, d - sa + sb);
    offer({{R, S, R}, {Mod2Pi(alpha - theta), std::sqrt(tmp), Mod2Pi(-beta + theta)}});
  }
  // LSR
  if (const double tmp = -2.0 + d * d + 2.0 * cab + 2.0 * d * (sa + sb); tmp >= 0.0) {
    const double p = std::sqrt(tmp);
    const double theta = std::atan2(-ca - cb, d + sa + sb) - std::atan2(-2.0, p);
    offer({{L, S, R}, {Mod2Pi(-alpha + theta), p, Mod2Pi(-Mod2Pi(beta) + theta)}});
  }
  // RSL
  if (const double tmp = d * d - 2.0 + 2.0 * cab - 2.0 * d * (sa + sb); tmp >= 0.0) {
    const double p = std::sqrt(tmp);
    const double theta = std::atan2(ca + cb, d - sa - sb) - std::atan2(2.0, p);
    offer({{R, S, L}, {Mod2Pi(alpha - theta), p, Mod2Pi(beta - theta)}});
  }
  // RLR
  if (const double tmp = 0.125 * (6.0 - d * d + 2.0 * cab + 2.0 * d * (sa - sb));
      std::fabs(tmp) <= 1.0) {
    const double p = 2.0 * std::numbers::pi - std::acos(tmp);
    const double theta = std::atan2(ca - cb, d - sa + sb);
    const double t = Mod2Pi(alpha - theta + 0.5 * p);
    offer({{R, L, R}, {t, p, Mod2Pi(alpha - beta - t + p)}});
  }
  // LRL
  if (const double tmp = 0.125 * (6.0 - d * d + 2.0 * cab + 2.0 * d * (sb - sa));
      std::fabs(tmp) <= 1.0) {
    const double p = 2.0 * std::numbers::pi - std::acos(tmp);
    const double theta = std::atan2(-ca + cb, d + sa - sb);
    const double t = Mod2Pi(-alpha + theta + 0.5 * p);
    offer({{L, R, L}, {t, p, Mod2Pi(beta - alpha - t + p)}});
  }
  return *best;
}

// The shortest Dubins word from `from` to `to` at unit radius (poses
// already scaled).
DubinsWord DubinsBetween(const Pose& from, const Pose& to) {
  const double dx = to.x - from.x;
  const double dy = to.y - from.y;
  const double d = std::sqrt(dx * dx + dy * dy);
  const double th = d > 0.0 ? std::atan2(dy, dx) : 0.0;
  const double alpha = Mod2Pi(from.yaw - th);
  const double beta = Mod2Pi(to.yaw - th);
  // The same pose: no motion.
  if (d < 1e-10 && std::fabs(NormalizeAngle(alpha - beta)) < 1e-10) {
    return DubinsWord{{Steer::kStraight, Steer::kStraight, Steer::kStraight}, {0.0, 0.0, 0.0}};
  }
  return ShortestDubins(d, alpha, beta);
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
  const DubinsWord word = DubinsBetween(Pose{from.x / radius, from.y / radius, from.yaw},
                                        Pose{to.x / radius, to.y / radius, to.yaw});
  for (int i = 0; i < 3; ++i) {
    if (word.length[i] == 0.0) continue;
    curve.segments[curve.count++] = CurveSegment{word.steer[i], word.length[i] * radius};
    curve.length += word.length[i] * radius;
  }
  return curve;
}

double ShortestCurveLength(const Pose& from, const Pose& to, double radius, bool reverse) {
  if (reverse) {
    const StatePair states(ReedsShepp(), from, to, radius);
    return ReedsShepp().reedsShepp(states.from(), states.to()).length() * radius;
  }
  return DubinsBetween(Pose{from.x / radius, from.y / radius, from.yaw},
                       Pose{to.x / radius, to.y / radius, to.yaw})
             .total() *
         radius;
}

}  // namespace pathd
