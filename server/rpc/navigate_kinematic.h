// The kinematic half of a Navigate session: a robot with a footprint and a
// turning radius (a session opened with hybrid_astar or state_lattice, or
// with kinematic options), replanned from its latest reported pose with a
// bounded number of expansions, its current path rechecked for the
// footprint's sweep when the map changes. NavigationSearch
// (navigate_search.h) keeps the map view (versions, the session's private
// cells) and calls this for the plans.
#ifndef PATHD_SERVER_RPC_NAVIGATE_KINEMATIC_H_
#define PATHD_SERVER_RPC_NAVIGATE_KINEMATIC_H_

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/kinematics/pose.h"
#include "core/map/grid.h"
#include "core/planning/plan_query.h"
#include "core/search/derived.h"
#include "core/search/planner.h"
#include "core/search/search_scratch.h"
#include "pathd/v1/planner_service.pb.h"

namespace pathd::server {

// What one replan plans on: the session's planning grid (the map version
// with the session's private cells, shaped) and, when that grid is a map
// version's own, the server's derived store for it (the obstacle distance
// field and the goal's obstacle heuristic shared with every query on that
// version); null: the session keeps those for its private grid itself.
struct KinematicView {
  std::shared_ptr<const Grid> grid;
  uint64_t version = 0;
  DerivedStore* shared_derived = nullptr;
  // The answer came from state the session kept (for PlanResponse).
  bool cache_hit = false;
  int64_t repaired_cells = 0;
};

// Not thread-safe: the session calls it under its plan_mu_ only.
class KinematicNavigation {
 public:
  // Expansions per replan when neither NavigateOpen.replan_max_expansions
  // nor options.max_expansions says.
  static constexpr int64_t kDefaultReplanExpansions = 20000;
  // How near the robot must be to a pose of the previous path for that path
  // to be kept when a replan runs out of budget.
  static constexpr double kKeepWithinCells = 1.0;
  static constexpr double kKeepWithinYaw = 0.35;

  // `query` passed CheckPlanQuery and names a kinematic planner (its
  // request.kinematic is the open message's robot and goal); `budget` > 0
  // is the expansion budget of each replan; `path_encoding` is how its
  // plans carry their path; `cancelled` must outlive this.
  KinematicNavigation(PlanQuery query, const Planner* planner, int64_t budget,
                      v1::PathEncoding path_encoding, const std::atomic<bool>* cancelled);
  ~KinematicNavigation();
  KinematicNavigation(const KinematicNavigation&) = delete;
  KinematicNavigation& operator=(const KinematicNavigation&) = delete;

  const Pose& robot() const { return robot_; }
  // The robot is now at `pose` (cell coordinates).
  void SetRobot(const Pose& pose) { robot_ = pose; }
  int64_t budget() const { return budget_; }
  bool has_path() const { return !path_.empty(); }

  // Whether the current path may touch an obstacle of `view.grid` anywhere
  // along its sweep (FirstBlockedPiece), or there is no current path.
  // Errors: the footprint checker could not be made for the grid.
  absl::StatusOr<bool> PathBlocked(const KinematicView& view);

  // Plans from the robot's pose to the goal on `view` within the budget and
  // fills `response` (plan, robot_pose, replan_max_expansions,
  // kept_previous_path). When the robot reported a pose of its current path
  // exactly and the rest of that path is still free and no dearer (PathCost
  // under the session's penalties) than the new plan, the rest is the answer
  // (FOUND, kept_previous_path): a robot following its path is not sent a
  // different one each message by a non-optimal search. When the budget runs out, the rest of the previous
  // path from its pose nearest the robot is kept if it is still free
  // (PathBlocked's test); a start or goal pose that collides is an answer
  // without a path (the reason says which), except with `opening`, where it
  // is INVALID_ARGUMENT naming open.start / open.goal. Other errors end the
  // session.
  absl::Status Replan(const KinematicView& view, bool opening, SearchScratch& scratch,
                      v1::NavigateResponse* response);

  // Bytes the session holds beyond the map: the private derived values and
  // the path. A replan's search state (bounded by the budget) lives only
  // while it runs, like a Plan call's.
  int64_t bytes() const;

 private:
  class PrivateStore;

  // The store for `view`: the server's, or the private one (reset when the
  // grid changes).
  DerivedStore* StoreFor(const KinematicView& view);
  // The rest of path_ from its pose nearest the robot, when within the keep
  // tolerances; empty otherwise.
  std::vector<PathPose> RestOfPath() const;
  // The rest of path_ from a pose the robot is exactly at (it reported a
  // pose of its path, as a robot following it does); empty otherwise.
  std::vector<PathPose> RestFromRobot() const;
  absl::StatusOr<bool> Blocked(const KinematicView& view, const std::vector<PathPose>& poses);

  PlanQuery query_;
  const Planner* planner_;
  const int64_t budget_;
  const v1::PathEncoding path_encoding_;
  const std::atomic<bool>* cancelled_;
  Pose robot_;
  std::vector<PathPose> path_;
  std::unique_ptr<PrivateStore> private_store_;
};

}  // namespace pathd::server

#endif  // PATHD_SERVER_RPC_NAVIGATE_KINEMATIC_H_
