// PlanThrough: legs planned one after another on one grid, joined.
#include "core/postprocess/plan_through.h"

#include <memory>
#include <numbers>
#include <utility>

#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "core/postprocess/path_simplify.h"
#include "core/status_macros.h"

namespace pathd {

absl::Status CheckViaCount(size_t count) {
  if (count > static_cast<size_t>(kMaxViaPoints)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("via has %d points; a plan may pass through at most %d",
                        count, kMaxViaPoints));
  }
  return absl::OkStatus();
}

absl::Status ValidateVia(const Grid& grid, const std::vector<Cell>& via,
                         const CostParams& cost) {
  PATHD_RETURN_IF_ERROR(CheckViaCount(via.size()));
  for (size_t i = 0; i < via.size(); ++i) {
    const Cell c = via[i];
    if (!grid.InBounds(c)) {
      return absl::InvalidArgumentError(
          absl::StrFormat("via[%d] %s is outside the %d x %d map", i,
                          CellToString(c), grid.width(), grid.height()));
    }
    if (const uint8_t v = grid.cost(c); !Traversable(v, cost.unknown_is_free)) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "via[%d] %s is on a blocked cell (cost %d)", i, CellToString(c), v));
    }
  }
  return absl::OkStatus();
}

std::string LegName(int32_t leg, int32_t via_count) {
  const auto point = [via_count](int32_t i) {
    return i == via_count ? std::string("goal") : absl::StrFormat("via[%d]", i);
  };
  return absl::StrFormat("leg %d (%s -> %s)", leg,
                         leg == 0 ? std::string("start") : point(leg - 1),
                         point(leg));
}

namespace {

// A kinematic leg's query: the first starts at the request's start pose,
// every later one at the pose where the previous leg ended (so the robot
// drives on without turning on the spot); a via leg ends at the via cell's
// centre with any heading, the last at the request's goal pose.
std::shared_ptr<const KinematicQuery> KinematicLeg(const KinematicQuery& query,
                                                   const PlanResult& so_far,
                                                   const std::vector<Cell>& goals,
                                                   size_t leg) {
  auto leg_query = std::make_shared<KinematicQuery>(query);
  if (!so_far.poses.empty()) leg_query->start = so_far.poses.back().pose;
  if (leg + 1 < goals.size()) {
    leg_query->goal = Pose::AtCellCenter(goals[leg]);
    leg_query->goal_tolerance_yaw = std::numbers::pi;
  }
  return leg_query;
}

}  // namespace

absl::StatusOr<ThroughResult> PlanThrough(
    const Planner& planner, const Grid& grid, const PlanRequest& request,
    const std::vector<Cell>& via, const StopCondition& stop,
    SearchScratch& scratch, const ThroughOptions& options) {
  PATHD_RETURN_IF_ERROR(ValidateVia(grid, via, request.cost));
  if (request.want_cost_to_go && !via.empty()) {
    return absl::InvalidArgumentError(
        "want_cost_to_go: a cost-to-go field belongs to one goal, and a plan "
        "through via points has several");
  }
  std::vector<Cell> goals = via;
  goals.push_back(request.goal);

  ThroughResult through;
  PlanResult& plan = through.plan;
  plan.outcome = PlanOutcome::kFound;
  const int64_t budget = stop.max_expansions();
  for (size_t leg = 0; leg < goals.size(); ++leg) {
    PlanRequest leg_request = request;
    leg_request.start = plan.path.empty() ? request.start : plan.path.back();
    leg_request.goal = goals[leg];
    if (request.kinematic != nullptr) {
      leg_request.kinematic = KinematicLeg(*request.kinematic, plan, goals, leg);
    }
    PlanResult result;
    if (budget > 0 && plan.expansions >= budget) {
      // An exhausted budget would read as "no budget" (0) to the next leg.
      result.outcome = PlanOutcome::kExpansionLimit;
    } else {
      const StopCondition leg_stop =
          budget > 0 ? stop.WithMaxExpansions(budget - plan.expansions) : stop;
      absl::StatusOr<PlanResult> planned =
          planner.Plan(grid, leg_request, leg_stop, scratch);
      if (!planned.ok()) {
        // Name the leg when there are several: "goal pose ... collides"
        // may be about a via point.
        if (goals.size() == 1) return planned.status();
        const std::string name =
            LegName(static_cast<int32_t>(leg), static_cast<int32_t>(via.size()));
        return absl::Status(planned.status().code(),
                            absl::StrFormat("%s: %s", name, planned.status().message()));
      }
      result = *std::move(planned);
    }
    plan.expansions += result.expansions;
    plan.episodes += result.episodes;
    plan.planning_time += result.planning_time;
    plan.trajectory.insert(plan.trajectory.end(), result.trajectory.begin(),
                           result.trajectory.end());
    if (!result.found()) {
      plan.outcome = result.outcome;
      plan.stall_point = result.stall_point;
      plan.stopped_while = result.stopped_while;
      through.failed_leg = static_cast<int32_t>(leg);
      break;
    }
    if (options.simplify) SimplifyPath(grid, request.cost, &result);
    const size_t skip_point = plan.polyline.empty() ? 0 : 1;
    plan.polyline.insert(plan.polyline.end(),
                         result.polyline.begin() + (result.polyline.empty() ? 0 : skip_point),
                         result.polyline.end());
    // Kinematic legs: the poses of each, the junction once when the legs
    // meet in the same pose (a grid request's default query starts the next
    // leg at the cell's centre facing its goal, so the junction may turn).
    const bool same_pose = !plan.poses.empty() && !result.poses.empty() &&
                           plan.poses.back().pose.x == result.poses.front().pose.x &&
                           plan.poses.back().pose.y == result.poses.front().pose.y &&
                           plan.poses.back().pose.yaw == result.poses.front().pose.yaw;
    plan.poses.insert(plan.poses.end(), result.poses.begin() + (same_pose ? 1 : 0),
                      result.poses.end());
    plan.any_angle = plan.any_angle || result.any_angle;
    plan.cost += result.cost;
    plan.length += result.length;
    // The leg starts where the previous one ended: keep that cell once.
    const size_t skip = plan.path.empty() ? 0 : 1;
    plan.path.insert(plan.path.end(), result.path.begin() + skip,
                     result.path.end());
    through.leg_end_indices.push_back(
        static_cast<int32_t>(plan.path.size() - 1));
    through.reached_goal_index = static_cast<int32_t>(leg);
  }
  if (!plan.found() && !options.allow_partial) {
    plan.path.clear();
    plan.polyline.clear();
    plan.poses.clear();
    plan.cost = 0.0;
    plan.length = 0.0;
    plan.any_angle = false;
    through.leg_end_indices.clear();
    through.reached_goal_index = -1;
  }
  return through;
}

}  // namespace pathd
