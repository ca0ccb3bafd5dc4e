// The kinematic half of a Navigate session (navigate_kinematic.h).
#include "server/rpc/navigate_kinematic.h"

#include <cmath>
#include <limits>
#include <map>
#include <utility>

#include "absl/strings/match.h"
#include "absl/strings/str_format.h"
#include "absl/time/time.h"
#include "core/kinematics/motion_check.h"
#include "core/kinematics/obstacle_heuristic.h"
#include "core/kinematics/pose_path.h"
#include "core/kinematics/vehicle.h"
#include "core/search/stop_condition.h"
#include "core/status_macros.h"
#include "server/convert.h"

namespace pathd::server {

// The derived values of a grid only this session plans on (the map with its
// private cells): one grid at a time, dropped when the grid changes. The
// session's own thread only.
class KinematicNavigation::PrivateStore final : public DerivedStore {
 public:
  explicit PrivateStore(std::shared_ptr<const Grid> grid) : grid_(std::move(grid)) {}

  const std::shared_ptr<const Grid>& grid() const { return grid_; }
  int64_t bytes() const { return bytes_; }

  std::shared_ptr<const void> Get(const std::string& key, const DerivedRecipe& recipe,
                                  DerivedStop& stop) override {
    auto it = values_.find(key);
    if (it != values_.end()) return it->second;
    std::shared_ptr<const void> value = recipe.build(*grid_, stop);
    if (value == nullptr) return nullptr;
    bytes_ += static_cast<int64_t>(recipe.bytes(value.get()));
    values_.emplace(key, value);
    return value;
  }

 private:
  const std::shared_ptr<const Grid> grid_;
  std::map<std::string, std::shared_ptr<const void>> values_;
  int64_t bytes_ = 0;
};

KinematicNavigation::KinematicNavigation(PlanQuery query, const Planner* planner,
                                         int64_t budget, v1::PathEncoding path_encoding,
                                         const std::atomic<bool>* cancelled)
    : query_(std::move(query)),
      planner_(planner),
      budget_(budget),
      path_encoding_(path_encoding),
      cancelled_(cancelled),
      robot_(query_.request.kinematic->start) {}

KinematicNavigation::~KinematicNavigation() = default;

DerivedStore* KinematicNavigation::StoreFor(const KinematicView& view) {
  if (view.shared_derived != nullptr) {
    private_store_.reset();
    return view.shared_derived;
  }
  if (private_store_ == nullptr || private_store_->grid() != view.grid) {
    private_store_ = std::make_unique<PrivateStore>(view.grid);
  }
  return private_store_.get();
}

absl::StatusOr<bool> KinematicNavigation::Blocked(const KinematicView& view,
                                                  const std::vector<PathPose>& poses) {
  if (poses.empty()) return true;
  const bool unknown_is_free = query_.request.cost.unknown_is_free;
  const std::shared_ptr<const std::vector<float>> distance =
      GetObstacleDistance(StoreFor(view), *view.grid, unknown_is_free);
  PATHD_ASSIGN_OR_RETURN(
      const MotionChecker checker,
      MotionChecker::Create(query_.request.kinematic->footprint, *view.grid, unknown_is_free,
                            distance->data()));
  return FirstBlockedPiece(checker, poses) >= 0;
}

absl::StatusOr<bool> KinematicNavigation::PathBlocked(const KinematicView& view) {
  return Blocked(view, path_);
}

std::vector<PathPose> KinematicNavigation::RestOfPath() const {
  size_t best = path_.size();
  double best_distance = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < path_.size(); ++i) {
    const Pose& p = path_[i].pose;
    const double d = std::hypot(p.x - robot_.x, p.y - robot_.y);
    if (d < best_distance && d <= kKeepWithinCells &&
        AngleBetween(p.yaw, robot_.yaw) <= kKeepWithinYaw) {
      best = i;
      best_distance = d;
    }
  }
  if (best == path_.size()) return {};
  return std::vector<PathPose>(path_.begin() + static_cast<std::ptrdiff_t>(best), path_.end());
}

std::vector<PathPose> KinematicNavigation::RestFromRobot() const {
  constexpr double kSame = 1e-9;
  for (size_t i = 0; i < path_.size(); ++i) {
    const Pose& p = path_[i].pose;
    if (std::fabs(p.x - robot_.x) <= kSame && std::fabs(p.y - robot_.y) <= kSame &&
        AngleBetween(p.yaw, robot_.yaw) <= kSame) {
      return std::vector<PathPose>(path_.begin() + static_cast<std::ptrdiff_t>(i), path_.end());
    }
  }
  return {};
}

absl::Status KinematicNavigation::Replan(const KinematicView& view, bool opening,
                                         SearchScratch& scratch,
                                         v1::NavigateResponse* response) {
  auto kinematic = std::make_shared<KinematicQuery>(*query_.request.kinematic);
  kinematic->start = robot_;
  PlanQuery query = query_;
  query.request.start = robot_.cell();
  query.request.kinematic = kinematic;
  query.request.derived = StoreFor(view);
  query.max_expansions = budget_;
  const StopCondition stop(absl::InfiniteFuture(), cancelled_, budget_);
  absl::StatusOr<PlanResult> result = planner_->Plan(*view.grid, query.request, stop, scratch);
  query.request.derived = nullptr;

  PlanAnswer answer;
  answer.goal = query.request.goal;
  answer.source = PlanSource{view.grid, view.version, view.cache_hit, view.repaired_cells};
  std::string reason;
  bool kept = false;
  if (!result.ok()) {
    if (result.status().code() != absl::StatusCode::kInvalidArgument) return result.status();
    const std::string message(result.status().message());
    if (opening) {
      // The planner's endpoint messages ("start pose ... collides", "goal
      // ...") name the open message's field; others (an option the planner
      // refuses) name theirs already.
      for (const char* field : {"start", "goal"}) {
        if (absl::StartsWith(message, field)) {
          return absl::InvalidArgumentError(absl::StrFormat("open.%s: %s", field, message));
        }
      }
      return result.status();
    }
    // The robot reported a pose in collision, or the map now blocks the
    // goal: an answer without a path, as a grid session's blocked cell is.
    answer.result.outcome = PlanOutcome::kNoPath;
    reason = message;
    path_.clear();
  } else if (result->found()) {
    answer.result = *std::move(result);
    std::vector<PathPose> rest = RestFromRobot();
    if (rest.size() >= 2) {
      const MotionPenalties penalties = PenaltiesOf(*kinematic);
      const double rest_cost = PathCost(*view.grid, rest, penalties);
      // Ties (the same straight path, priced by sums in another order) go
      // to the path the robot is on.
      const double replan_cost = PathCost(*view.grid, answer.result.poses, penalties);
      if (rest_cost <= replan_cost * (1.0 + 1e-9) + 1e-9) {
        PATHD_ASSIGN_OR_RETURN(const bool blocked, Blocked(view, rest));
        if (!blocked) {
          answer.result.poses = rest;
          answer.result.path = PathCells(rest);
          answer.result.length = PathLength(rest);
          answer.result.cost = rest_cost;
          kept = true;
        }
      }
    }
    path_ = answer.result.poses;
  } else if (result->outcome == PlanOutcome::kExpansionLimit) {
    // Out of budget: keep what is left of the previous path when the robot
    // is on it and its sweep is still free on this map.
    std::vector<PathPose> rest = RestOfPath();
    answer.result = *std::move(result);
    PATHD_ASSIGN_OR_RETURN(const bool blocked, Blocked(view, rest));
    if (!blocked) {
      answer.result.poses = rest;
      answer.result.path = PathCells(rest);
      answer.result.length = PathLength(rest);
      answer.result.cost = PathCost(*view.grid, rest, PenaltiesOf(*kinematic));
      path_ = std::move(rest);
      kept = true;
    } else {
      path_.clear();
    }
  } else {
    answer.result = *std::move(result);
    path_.clear();
  }
  SetSingleLeg(&answer);
  v1::PlanResponse* plan = response->mutable_plan();
  BuildPlanResponse(query, answer, /*expansion_limit_source=*/"", path_encoding_, plan);
  if (!reason.empty()) plan->set_reason(reason);
  if (answer.result.outcome == PlanOutcome::kExpansionLimit) {
    plan->set_reason(absl::StrFormat(
        "%s (NavigateOpen.replan_max_expansions %d); %s", plan->reason(), budget_,
        kept ? "kept the rest of the previous path, still collision-free for the footprint"
             : "no previous path to keep (none, the robot is off it, or it is blocked)"));
  }
  response->set_kept_previous_path(kept);
  response->set_replan_max_expansions(budget_);
  const Pose& from = kept ? path_.front().pose : robot_;
  v1::CellPose* robot = response->mutable_robot_pose();
  robot->set_x(from.x);
  robot->set_y(from.y);
  robot->set_yaw(from.yaw);
  return absl::OkStatus();
}

int64_t KinematicNavigation::bytes() const {
  return (private_store_ != nullptr ? private_store_->bytes() : 0) +
         static_cast<int64_t>(path_.capacity() * sizeof(PathPose));
}

}  // namespace pathd::server
