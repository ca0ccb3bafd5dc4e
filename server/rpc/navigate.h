// Navigate sessions: one D* Lite search per bidirectional stream, kept
// between the robot's messages and repaired when it moves, when its sensors
// report changed cells, and when anyone else changes the shared map, in which
// case the session pushes the new path unasked.
#ifndef PATHD_SERVER_RPC_NAVIGATE_H_
#define PATHD_SERVER_RPC_NAVIGATE_H_

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <string_view>
#include <thread>

#include "absl/base/thread_annotations.h"
#include "absl/status/status.h"
#include "absl/synchronization/mutex.h"
#include "absl/time/time.h"
#include "pathd/v1/planner_service.grpc.pb.h"
#include "server/derived_cache.h"
#include "server/inflation_cache.h"
#include "server/map_store.h"
#include "server/memory_budget.h"
#include "server/rpc/fleet_sessions.h"
#include "server/rpc/navigate_control.h"
#include "server/rpc/robot_registry.h"
#include "server/worker_pool.h"

namespace pathd::server {

class NavigationSession;

// Thread-safe registry and factory of sessions. Planning for a session runs
// on the worker pool; messages of one session are handled one at a time in
// arrival order (the next message is read only once the previous one has
// been answered), and pushes are serialised with them.
class NavigationSessions {
 public:
  struct Options {
    // A session without a client message for this long ends with
    // DEADLINE_EXCEEDED (--session_idle_timeout).
    absl::Duration idle_timeout = absl::Minutes(10);
    // Open sessions at most; further Navigate calls get RESOURCE_EXHAUSTED
    // (--max_sessions).
    size_t max_sessions = 1024;
    // Expansion cap per session search; 0 = none (--max_expansions).
    int64_t max_expansions = 0;
    // Where each session reserves its search state's bytes when it opens
    // (about kSessionBytesPerCell per map cell); null = no byte limit. Must
    // outlive this object.
    MemoryBudget* budget = nullptr;
    // The server's derived values per map version (kinematic sessions take
    // the obstacle heuristic of a version from it); null: each session
    // builds its own. Must outlive this object.
    DerivedCache* derived = nullptr;
  };
  // What an open session's D* Lite state costs per map cell, reserved before
  // it is built (the reservation then follows the real size). Kinematic
  // sessions reserve the same: a private view of the map (session_only
  // observations) holds a grid copy, its obstacle distance field and the
  // goal's obstacle heuristic, 9 bytes per cell.
  static constexpr int64_t kSessionBytesPerCell = 16;

  // `store`, `pool` and `inflation` must outlive this object. Registers a
  // map listener on `store` (so construct before serving) and starts the
  // thread that ends idle sessions.
  NavigationSessions(MapStore& store, WorkerPool& pool, InflationCache& inflation,
                     Options options);
  // Stops the idle reaper. Every session must have ended (the gRPC server
  // shut down and the pool joined) before this runs.
  ~NavigationSessions();
  NavigationSessions(const NavigationSessions&) = delete;
  NavigationSessions& operator=(const NavigationSessions&) = delete;

  // The reactor for one Navigate call (gRPC deletes it when done).
  // `shared_observations`: what an observation that would update the shared
  // map (session_only = false) gets instead; OK = allowed, else the session
  // ends with it (e.g. PERMISSION_DENIED for a read-only token).
  grpc::ServerBidiReactor<v1::NavigateRequest, v1::NavigateResponse>* Start(
      grpc::CallbackServerContext* context,
      absl::Status shared_observations = absl::OkStatus());

  // Refuses new sessions and ends every open one with UNAVAILABLE (after the
  // message it is handling, if any), so a draining server need not wait for
  // robots to hang up.
  void Shutdown();

  // Appends the open sessions of `map` (every map when empty) to `out`, in
  // id order, each with the last answer or push it sent.
  void List(std::string_view map, v1::ListSessionsResponse& out) const
      ABSL_LOCKS_EXCLUDED(mu_);

  // Open sessions and the bytes of their D* Lite state.
  int64_t count() const;
  int64_t bytes() const;

  // Control sessions' robots per map, and their control cycles' latencies
  // (from the state's arrival to its answer being queued), for the metrics.
  const RobotRegistry& robots() const { return robots_; }
  const CycleHistogram& control_cycles() const { return control_cycles_; }

 private:
  friend class NavigationSession;

  // MapStore listener: schedules a repair-and-maybe-push on every session of
  // the map (or ends them with NOT_FOUND when it was deleted).
  void OnMapChanged(std::string_view name,
                    const std::shared_ptr<const MapSnapshot>& snapshot);
  // Registers a new session; RESOURCE_EXHAUSTED beyond max_sessions.
  absl::Status Add(NavigationSession* session) ABSL_LOCKS_EXCLUDED(mu_);
  void Remove(NavigationSession* session) ABSL_LOCKS_EXCLUDED(mu_);
  void ReapIdle();

  MapStore& store_;
  WorkerPool& pool_;
  InflationCache& inflation_;
  const Options options_;
  RobotRegistry robots_;
  CycleHistogram control_cycles_;
  // Fleet sessions' groups (registers its own map listener).
  FleetGroups fleets_;

  mutable absl::Mutex mu_;
  uint64_t next_id_ ABSL_GUARDED_BY(mu_) = 1;
  std::map<uint64_t, NavigationSession*> sessions_ ABSL_GUARDED_BY(mu_);
  bool stopping_ ABSL_GUARDED_BY(mu_) = false;
  std::thread reaper_;
};

}  // namespace pathd::server

#endif  // PATHD_SERVER_RPC_NAVIGATE_H_
