// Collision tests of motions, not only of poses. A FootprintChecker answers
// for one pose; a robot driving from one pose to the next sweeps everything
// in between. MotionChecker samples a motion densely enough, and tests the
// samples with a footprint grown by a margin large enough, that free
// verdicts at the samples prove the whole sweep free: every point of the
// footprint moves at most (distance driven + reach * heading change) over the
// motion, so at most kMotionMargin between a sample and the poses on either
// side of it up to the next sample (FootprintCheckerOptions::margin_cells).
#ifndef PATHD_CORE_KINEMATICS_MOTION_CHECK_H_
#define PATHD_CORE_KINEMATICS_MOTION_CHECK_H_

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "absl/status/statusor.h"
#include "core/kinematics/footprint.h"
#include "core/kinematics/pose.h"
#include "core/map/grid.h"

namespace pathd {

// The margin, cells, of the footprint tested at the samples of a motion.
// Smaller keeps narrow passages open (the default point-like robot of
// DefaultKinematicQuery, 0.05 cells with 4 subcells, keeps one-cell
// corridors at 1/8); larger needs fewer samples.
inline constexpr double kMotionMargin = 0.125;

// How far, cells, the poses a planner returns may lie from the motion it
// checked: the sagitta of a returned piece of an arc (the chord between two
// returned poses against the arc), kept below this by MaxPieceLength.
inline constexpr double kMotionDeviation = kMotionMargin / 16.0;

// The longest piece between returned poses on an arc of radius `radius`
// (straight motions: `radius` infinite): at most half a cell, and short
// enough that the chord strays at most kMotionDeviation from the arc.
inline double MaxPieceLength(double radius) {
  return std::min(0.5, std::sqrt(8.0 * kMotionDeviation * radius));
}

// How a motion's end pose is tested.
enum class MotionEnd {
  // Already proven with the margin (a search state reached by a checked
  // motion): not tested again.
  kProven,
  // Tested like every other sample.
  kSample,
  // An exact start or goal pose the caller tested with the query's checker.
  // When it fails the margin (the robot starts or ends closer than the
  // margin to an obstacle), the half sample step next to it is tested with
  // finer samples and a quarter of the margin; when it fails that too, the
  // poses of the motion less than that quarter margin (in how far the
  // footprint moved) from it rest on the exact pose test alone.
  kExact,
};

// The query's checker, a grid and two grown copies of the footprint. Holds
// pointers to the grid and distance field it was created with (they must
// outlive it). Immutable; thread-safe.
class MotionChecker {
 public:
  // `footprint` is the query's checker; the grown checkers share its heading
  // bins and subcells and come from SharedFootprintChecker. `distance`, when
  // not null, is ObstacleDistanceField(grid, unknown_is_free).
  static absl::StatusOr<MotionChecker> Create(std::shared_ptr<const FootprintChecker> footprint,
                                              const Grid& grid, bool unknown_is_free,
                                              const float* distance);

  const FootprintChecker& footprint() const { return *exact_; }
  // How far from the robot's reference point its (grown) outline reaches,
  // cells: the lever arm of a heading change.
  double reach() const { return reach_; }

  // The pose itself, with the query's checker.
  bool PoseFree(const Pose& pose) const {
    return !exact_->Collides(*grid_, pose, unknown_is_free_, distance_);
  }
  // The pose with the margin (what a search state needs).
  bool PoseFreeWithMargin(const Pose& pose) const {
    return !coarse_->Collides(*grid_, pose, unknown_is_free_, distance_);
  }

  // The number of sample steps a motion needs (samples at t = i / n, i =
  // 0..n).
  static int SampleCount(double sweep, double deviation) {
    const double cover = kMotionMargin - deviation;
    return std::max(1, static_cast<int>(std::ceil(sweep / (2.0 * cover))));
  }

  // Whether the motion pose_at(t), t in [0, 1], is free: `sweep` bounds how
  // far any point of the footprint moves over it (distance + reach() x
  // heading change), `deviation` (<= kMotionDeviation) how far the poses a
  // caller reports may stray from it. Precondition: sweep >= 0.
  // MotionFree calls pose_at at t = i / SampleCount(sweep, deviation), i =
  // 0..n (callers may precompute those poses), and at other t only next to
  // a kExact end that fails the margin.
  template <typename PoseAt>
  bool MotionFree(const PoseAt& pose_at, double sweep, double deviation, MotionEnd from,
                  MotionEnd to) const {
    const int n = SampleCount(sweep, deviation);
    for (int i = 0; i <= n; ++i) {
      const MotionEnd end = i == 0 ? from : (i == n ? to : MotionEnd::kSample);
      if (end == MotionEnd::kProven) continue;
      const double t = static_cast<double>(i) / n;
      if (PoseFreeWithMargin(pose_at(t))) continue;
      if (end != MotionEnd::kExact) return false;
      // The exact end failed the margin: cover the half step next to it.
      const double half = 0.5 / n;
      const double fine_cover = kMotionMargin / 4.0 - deviation;
      const int m =
          std::max(1, static_cast<int>(std::ceil(sweep * half / (2.0 * fine_cover))));
      // Sample j of m covers its neighbourhood; sample 0 is the end itself,
      // whose own neighbourhood is left to the exact test when it fails.
      for (int j = 0; j <= m; ++j) {
        const double u = half * j / m;
        const Pose p = pose_at(i == 0 ? u : 1.0 - u);
        if (!fine_->Collides(*grid_, p, unknown_is_free_, distance_)) continue;
        if (j == 0) continue;
        return false;
      }
    }
    return true;
  }

 private:
  MotionChecker() = default;

  std::shared_ptr<const FootprintChecker> exact_;
  std::shared_ptr<const FootprintChecker> coarse_;
  std::shared_ptr<const FootprintChecker> fine_;
  const Grid* grid_ = nullptr;
  bool unknown_is_free_ = false;
  const float* distance_ = nullptr;
  double reach_ = 0.0;
};

// Rechecks a path a planner returned earlier against `checker`'s grid (a
// newer map version): the index i of the first piece poses[i] -> poses[i+1]
// whose sweep may touch an obstacle (the chord between the two poses, heading
// turned evenly, tested as a motion whose reported poses may stray
// kMotionDeviation from it, as a returned arc's chord does), or of the pose
// itself for a one-pose path; -1 when the whole path is free. The first and
// last poses are tested exactly (MotionEnd::kExact), the rest with the margin.
// Conservative: a path a planner proved free on a map can fail the recheck on
// the same map only near obstacles closer than the margin.
int64_t FirstBlockedPiece(const MotionChecker& checker, const std::vector<PathPose>& poses);

}  // namespace pathd

#endif  // PATHD_CORE_KINEMATICS_MOTION_CHECK_H_
