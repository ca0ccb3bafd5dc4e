// Plans through ordered intermediate goals (via points, Nav2's "through
// poses"): one search per leg start -> via[0] -> ... -> goal with the same
// planner, grid and options, the legs' paths joined at their shared cells.
#ifndef PATHD_CORE_POSTPROCESS_PLAN_THROUGH_H_
#define PATHD_CORE_POSTPROCESS_PLAN_THROUGH_H_

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/search/planner.h"
#include "core/search/search_scratch.h"

namespace pathd {

// Most via points one plan may name: each is a full search, so this bounds a
// request's work at 257 searches.
inline constexpr int kMaxViaPoints = 256;

struct ThroughOptions {
  // When a leg ends without a path, return the legs before it (the path to
  // the last reached goal) instead of no path at all.
  bool allow_partial = false;
  // Simplify each leg's path (core/postprocess/path_simplify.h) before joining: a
  // shortcut over the whole path could skip a via point.
  bool simplify = false;
};

struct ThroughResult {
  // The joined plan. outcome is kFound when every leg was, else the failed
  // leg's outcome (and its stall_point). path runs from the start through
  // every reached goal, one cell per junction; empty when a leg failed
  // without allow_partial or when the first leg failed. cost, length,
  // expansions, episodes and planning_time are sums over the legs run
  // (cost and length over the legs in `path`); trajectory joins the legs'
  // trajectories, polyline the legs' polylines and poses the legs' poses
  // (a junction pose once when both legs have it).
  PlanResult plan;
  // Index into (via..., goal) of the last goal `path` reaches: via.size()
  // when found, -1 when not even the first was reached.
  int32_t reached_goal_index = -1;
  // For each reached goal, the index in plan.path where its leg ends.
  std::vector<int32_t> leg_end_indices;
  // The leg that ended without a path (leg i ends at goal i), -1 when none.
  int32_t failed_leg = -1;
};

// INVALID_ARGUMENT naming "via" when `count` is more than kMaxViaPoints, so a
// caller can refuse before sizing anything by the count.
absl::Status CheckViaCount(size_t count);

// INVALID_ARGUMENT naming "via" when there are more than kMaxViaPoints, or
// "via[i]" when a point is off the grid or on a cell the robot centre may not
// occupy under `cost`.
absl::Status ValidateVia(const Grid& grid, const std::vector<Cell>& via,
                         const CostParams& cost);

// "leg 2 (via[1] -> goal)": how messages name leg `leg` of a plan through
// `via_count` via points.
std::string LegName(int32_t leg, int32_t via_count);

// Plans request.start -> via... -> request.goal with `planner`, each leg a
// copy of `request` with its own endpoints (so every leg shares the cost
// options, heuristic weight, look-ahead and expansion recorder). `stop`'s
// deadline and cancel flag apply to the whole plan and its expansion budget
// is shared: each leg gets what the legs before it left. Errors: ValidateVia,
// INVALID_ARGUMENT naming "want_cost_to_go" when via is not empty (a field
// belongs to one goal), and any leg's own error. A leg ending without a path
// is an OK result (see ThroughResult).
absl::StatusOr<ThroughResult> PlanThrough(
    const Planner& planner, const Grid& grid, const PlanRequest& request,
    const std::vector<Cell>& via, const StopCondition& stop,
    SearchScratch& scratch, const ThroughOptions& options);

}  // namespace pathd

#endif  // PATHD_CORE_POSTPROCESS_PLAN_THROUGH_H_
