// The robots of control sessions, per map: each control session publishes its
// robot's latest state here, and each control cycle reads the others near its
// robot as moving neighbours (docs/service.md, "Control sessions"). A robot
// that sent nothing for its session's stale_after is a static obstacle; after
// forget_after it is gone; a session that ends removes its robot at once.
#ifndef PATHD_SERVER_RPC_ROBOT_REGISTRY_H_
#define PATHD_SERVER_RPC_ROBOT_REGISTRY_H_

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/synchronization/mutex.h"
#include "core/local/local_types.h"
#include "core/map/grid.h"

namespace pathd::server {

// The server's steady clock: receipt times never jump with the wall clock.
using SteadyTime = std::chrono::steady_clock::time_point;

// One robot's latest state, cell coordinates of its map.
struct RobotReport {
  CellPoint position;
  CellPoint velocity;  // cells/s, grid frame
  double radius = 0.0;  // cells
  SteadyTime received;
  // Its own session's thresholds (ControlOptions.stale_after, forget_after).
  std::chrono::duration<double> stale_after{1.0};
  std::chrono::duration<double> forget_after{10.0};
  // RobotState.stamp, and whether it is on the clock the map's robots
  // share (ControlOptions.shared_clock).
  double stamp = 0.0;
  bool shared_clock = false;
};

// Thread-safe. Robots are kept per map in a vector under one mutex: a cycle
// scans the map's robots once (200 robots: a few microseconds, measured by
// tests/bench/control_bench), which is cheaper than keeping a spatial hash
// up to date at every state message.
class RobotRegistry {
 public:
  // Stores `report` as robot `id`'s state on `map` (replacing the previous),
  // and drops the map's forgotten robots.
  void Publish(const std::string& map, uint64_t id, const RobotReport& report)
      ABSL_LOCKS_EXCLUDED(mu_);
  // Drops robot `id` (its session ended).
  void Remove(const std::string& map, uint64_t id) ABSL_LOCKS_EXCLUDED(mu_);

  // The robots of `map` other than `self` whose disc comes within `range`
  // cells of `center` (centre distance less their radius), as moving
  // obstacles at `now`: a fresh robot (state younger than its stale_after)
  // at its reported position moved on by its velocity for the state's age,
  // reciprocal; a stale one (younger than forget_after) where it last was,
  // still and not reciprocal. Forgotten robots are skipped.
  // `clock`: the asking robot's stamp when it is on the shared clock; then a
  // fresh robot on the shared clock too is moved on by the difference of
  // the stamps instead (which may be negative: it reported from later).
  std::vector<MovingObstacle> Near(const std::string& map, uint64_t self,
                                   CellPoint center, double range, SteadyTime now,
                                   std::optional<double> clock = std::nullopt) const
      ABSL_LOCKS_EXCLUDED(mu_);

  // Robots not yet forgotten at `now`, per map (maps without any are left
  // out), for the metrics.
  std::map<std::string, int64_t> Counts(SteadyTime now) const
      ABSL_LOCKS_EXCLUDED(mu_);

 private:
  struct Robot {
    uint64_t id = 0;
    RobotReport report;
  };

  mutable absl::Mutex mu_;
  std::map<std::string, std::vector<Robot>, std::less<>> maps_ ABSL_GUARDED_BY(mu_);
};

}  // namespace pathd::server

#endif  // PATHD_SERVER_RPC_ROBOT_REGISTRY_H_
