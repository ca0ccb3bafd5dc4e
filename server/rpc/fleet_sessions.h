// Fleet sessions: Navigate sessions whose robots are planned together. The
// robots of the fleet sessions of one group on one map share a conflict-free
// timed plan from core/fleet/mapf.h, and each robot is released along its
// timed path by core/fleet/execution.h: it may drive on only past cells that
// every robot planned through them earlier has passed, and at most
// kReleaseHorizon steps ahead, so robots that run late or stop never meet,
// whatever their speeds.
//
// A group is planned again when a robot joins, when a robot reports a cell
// off its released stretch, and when a map change blocks a cell of a
// remaining path. Before that plan the group is frozen: no release grows,
// and the plan waits until every robot has reported reaching the end of the
// stretch it was released for, so the new plan starts from where the robots
// stand. A blocked cell cuts the release of a robot released past it back
// to the cell before it (the one case where a release shrinks). A robot
// that leaves (its session ends) stops holding others back.
//
// Thread-safe. Lock order: the registry's mu_, then a group's mu, then
// whatever a member's push callback takes (the session's stream lock); no
// caller may hold a lock a push callback takes.
#ifndef PATHD_SERVER_RPC_FLEET_SESSIONS_H_
#define PATHD_SERVER_RPC_FLEET_SESSIONS_H_

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <utility>

#include "absl/base/thread_annotations.h"
#include "absl/status/status.h"
#include "absl/synchronization/mutex.h"
#include "absl/time/time.h"
#include "core/fleet/mapf.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/planning/plan_query.h"
#include "pathd/v1/planner_service.pb.h"
#include "server/inflation_cache.h"
#include "server/map_store.h"
#include "server/worker_pool.h"

namespace pathd::server {

class FleetGroups {
 public:
  // Queues a message to the member's client: a push, or the answer to its
  // own message. Called with the group's lock held: it must only queue. The
  // group queues a member's answers itself, under that lock, so a push made
  // after an answer never reaches the client before it (a client keeps the
  // newest state it received).
  using Push = std::function<void(v1::NavigateResponse)>;

  struct Join {
    uint64_t session_id = 0;
    std::shared_ptr<const MapSnapshot> snapshot;
    std::string group;
    Cell start;
    Cell goal;
    // The robot's planning grid is the snapshot's shaped by this (its
    // radius); connectivity and unknown_is_free come from `cost`.
    GridShape shape;
    CostParams cost;
    // Unset in the request: the group's (or the default for a new group).
    std::optional<FleetSolver> solver;
    std::optional<absl::Duration> time_limit;
    Push push;
  };

  // Registers a map listener on `store` (construct before serving). All
  // three must outlive this object.
  FleetGroups(MapStore& store, InflationCache& inflation, WorkerPool& pool);
  FleetGroups(const FleetGroups&) = delete;
  FleetGroups& operator=(const FleetGroups&) = delete;

  // Adds a robot to its group (created on first use), and fills and queues
  // `answer` (its fleet part and plan; the caller set its seq). The group is
  // planned again once every robot has finished the moves it was released for
  // (at once when they have). INVALID_ARGUMENT when the start is where another
  // robot of the group stands or may drive now, the goal is another robot's
  // goal, or the solver or time limit differ from the group's; errors of the
  // shaping.
  absl::Status Add(Join join, v1::NavigateResponse* answer)
      ABSL_LOCKS_EXCLUDED(mu_);

  // The robot of session `id` stands in `cell`; fills and queues `answer`
  // (the caller set its seq and event). Other
  // robots whose release grew are pushed. A cell off the robot's released
  // stretch plans the group again from where the robots stand.
  absl::Status Report(uint64_t id, Cell cell, v1::NavigateResponse* answer)
      ABSL_LOCKS_EXCLUDED(mu_);

  // Fills and queues `answer` with the session's current fleet state
  // (observations); false (nothing queued) when the session is in no group.
  bool Describe(uint64_t id, v1::NavigateResponse* answer)
      ABSL_LOCKS_EXCLUDED(mu_);

  // The session ended: its robot leaves its group.
  void Remove(uint64_t id) ABSL_LOCKS_EXCLUDED(mu_);

  // Groups and robots, for tests and metrics.
  int groups() const ABSL_LOCKS_EXCLUDED(mu_);

  // How far past its progress a robot is released at most (steps of its
  // timed path): what a frozen group waits for a robot to finish.
  static constexpr int64_t kReleaseHorizon = 4;
  // Default and largest time limit of one joint plan.
  static constexpr absl::Duration kDefaultTimeLimit = absl::Seconds(2);
  static constexpr absl::Duration kMaxTimeLimit = absl::Seconds(60);

  // One group's state (fleet_sessions.cc).
  struct Group;

 private:
  // Add's checks and joining under the group's lock; OK without joining
  // when the group was closed meanwhile.
  absl::Status AddLocked(Join& join, const std::string& group_name,
                         Group& group, v1::NavigateResponse* answer);
  void OnMapChanged(std::string_view name,
                    const std::shared_ptr<const MapSnapshot>& snapshot)
      ABSL_LOCKS_EXCLUDED(mu_);

  MapStore& store_;
  InflationCache& inflation_;
  WorkerPool& pool_;
  mutable absl::Mutex mu_;
  // (map, group) -> group, and session -> its group.
  std::map<std::pair<std::string, std::string>, std::shared_ptr<Group>> groups_
      ABSL_GUARDED_BY(mu_);
  std::map<uint64_t, std::shared_ptr<Group>> by_session_ ABSL_GUARDED_BY(mu_);
};

}  // namespace pathd::server

#endif  // PATHD_SERVER_RPC_FLEET_SESSIONS_H_
