#include "core/kinematics/vehicle.h"

#include <cmath>
#include <list>
#include <numbers>
#include <utility>

#include "absl/base/thread_annotations.h"
#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "absl/synchronization/mutex.h"

namespace pathd {
namespace {

constexpr std::pair<MotionModel, std::string_view> kModelNames[] = {
    {MotionModel::kDubins, "dubins"},
    {MotionModel::kReedsShepp, "reeds_shepp"},
    {MotionModel::kDifferential, "differential"},
    {MotionModel::kOmnidirectional, "omnidirectional"},
};

bool SameShape(const Footprint& a, const Footprint& b) {
  if (a.circle_radius() != b.circle_radius() || a.vertices().size() != b.vertices().size()) {
    return false;
  }
  for (size_t i = 0; i < a.vertices().size(); ++i) {
    if (a.vertices()[i].x != b.vertices()[i].x || a.vertices()[i].y != b.vertices()[i].y) {
      return false;
    }
  }
  return true;
}

bool SameOptions(const FootprintCheckerOptions& a, const FootprintCheckerOptions& b) {
  return a.headings == b.headings && a.subcells == b.subcells && a.margin_cells == b.margin_cells;
}

// The most recently used checkers, newest first.
class CheckerCache {
 public:
  static constexpr size_t kCapacity = 16;

  absl::StatusOr<std::shared_ptr<const FootprintChecker>> Get(
      const Footprint& footprint, const FootprintCheckerOptions& options)
      ABSL_LOCKS_EXCLUDED(mu_) {
    {
      absl::MutexLock lock(&mu_);
      for (auto it = entries_.begin(); it != entries_.end(); ++it) {
        if (SameShape((*it)->footprint(), footprint) && SameOptions((*it)->options(), options)) {
          entries_.splice(entries_.begin(), entries_, it);
          return entries_.front();
        }
      }
    }
    // Built outside the lock; two queries racing on a new footprint both
    // build it, which costs time but never correctness.
    absl::StatusOr<FootprintChecker> built = FootprintChecker::Create(footprint, options);
    if (!built.ok()) return built.status();
    auto shared = std::make_shared<const FootprintChecker>(*std::move(built));
    absl::MutexLock lock(&mu_);
    entries_.push_front(shared);
    if (entries_.size() > kCapacity) entries_.pop_back();
    return shared;
  }

 private:
  absl::Mutex mu_;
  std::list<std::shared_ptr<const FootprintChecker>> entries_ ABSL_GUARDED_BY(mu_);
};

}  // namespace

std::string_view MotionModelName(MotionModel model) {
  for (const auto& [m, name] : kModelNames) {
    if (m == model) return name;
  }
  return "unknown";
}

absl::StatusOr<MotionModel> ParseMotionModel(std::string_view name) {
  std::string names;
  for (const auto& [m, n] : kModelNames) {
    if (n == name) return m;
    absl::StrAppend(&names, names.empty() ? "" : ", ", std::string(n));
  }
  return absl::InvalidArgumentError(
      absl::StrCat("unknown motion model \"", std::string(name), "\"; expected one of ", names));
}

bool AllowsReverse(MotionModel model) { return model != MotionModel::kDubins; }

KinematicQuery DefaultKinematicQuery(Cell start, Cell goal) {
  KinematicQuery q;
  q.start = Pose::AtCellCenter(start);
  q.goal = Pose::AtCellCenter(goal);
  if (!(start == goal)) q.start.yaw = std::atan2(goal.y - start.y, goal.x - start.x);
  // A circle of 0.05 cells is valid, so this cannot fail.
  q.footprint = *SharedFootprintChecker(*Footprint::Circle(0.05), {.subcells = 4});
  q.motion = MotionModel::kReedsShepp;
  q.min_turning_radius_cells = 1.0;
  q.goal_tolerance_yaw = std::numbers::pi;
  return q;
}

absl::StatusOr<std::shared_ptr<const FootprintChecker>> SharedFootprintChecker(
    const Footprint& footprint, const FootprintCheckerOptions& options) {
  static CheckerCache* cache = new CheckerCache();
  return cache->Get(footprint, options);
}

}  // namespace pathd
