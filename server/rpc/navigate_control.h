// The control half of a Navigate session (docs/service.md, "Control
// sessions"): NavigateOpen.control decoded into core's units (cells, cells/s,
// seconds), and one control cycle per RobotState: the robot's state, the
// other robots on the map (robot_registry.h) and the reported obstacles, the
// map's static obstacles for the local planner (per map version, from the
// server's derived cache), the latest global path -> DwaStep, OrcaStep or
// FirasStep (core/local) -> a VelocityCommand in metres.
//
// Bounded work: a cycle never plans globally. It follows the newest global
// path the session's D* Lite published (SetPath), whatever replan is running
// meanwhile on the worker pool.
#ifndef PATHD_SERVER_RPC_NAVIGATE_CONTROL_H_
#define PATHD_SERVER_RPC_NAVIGATE_CONTROL_H_

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/synchronization/mutex.h"
#include "core/geometry/obstacle_polygons.h"
#include "core/kinematics/footprint.h"
#include "core/local/dwa.h"
#include "core/local/firas.h"
#include "core/local/local_types.h"
#include "core/local/orca.h"
#include "core/map/grid.h"
#include "pathd/v1/planner_service.pb.h"
#include "server/derived_cache.h"
#include "server/map_store.h"
#include "server/rpc/robot_registry.h"

namespace pathd::server {

enum class LocalPlannerKind { kDwa, kOrca, kFiras };

// A control session's settings in core's units.
struct ControlConfig {
  LocalPlannerKind planner = LocalPlannerKind::kOrca;
  VelocityLimits limits;  // cells/s, cells/s^2, rad/s, rad/s^2
  double period = 0.1;    // s
  double stale_after = 1.0;  // s
  double forget_after = 10.0;  // s
  bool shared_clock = false;  // ControlOptions.shared_clock
  DwaOptions dwa;
  OrcaOptions orca;
  FirasOptions firas;
  // The robot as a disc, cells: options.robot_radius, else the footprint's
  // circumscribed radius.
  double radius = 0.0;
  // What DWA checks rollouts with: options.footprint, else the disc (set
  // by DecodeControlOptions).
  std::optional<Footprint> footprint;
  // Detours (local_options "detour_range"): a stalled robot asks for a
  // global path around the slow robots and obstacles whose discs come
  // within this many cells of its own; 0 turns detours off.
  double detour_range = 0.0;
};

// A stalled robot's request for a global path around what stands in its
// way (docs/service.md, "Detours"): the robot and the discs to plan around
// (in place of the last ones; none keeps them), cells in the grid frame;
// or, with `lift`, the word that the last ones are gone.
struct DetourRequest {
  struct Disc {
    CellPoint centre;
    double radius = 0.0;
  };
  CellPoint robot;
  double robot_radius = 0.0;
  std::vector<Disc> blockers;
  // The clearance the local planner keeps from the map (radius and safety
  // margin) and the detour range, cells: when the robot stalled within
  // clearance + 1.5 of the map, the cells near the next ahead + 2 clearance
  // of its path whose centres are closer than `clearance` to a blocked
  // cell's area are gaps the grid's centre-to-centre inflation lets
  // through but the robot's disc does not. 0: none looked for (a lift).
  double clearance = 0.0;
  double ahead = 0.0;
  bool lift = false;
};

// NavigateOpen.control (with the open's robot: `options` and `grid` for the
// resolution) in core's units, defaults filled in. INVALID_ARGUMENT naming
// "open.control.<field>" or "open.control.local_options[\"<name>\"]" (an
// unknown name, or a bad value), or "open.options.robot_radius" when the
// robot has no size.
absl::StatusOr<ControlConfig> DecodeControlOptions(const v1::ControlOptions& control,
                                                   const v1::PlanOptions& options,
                                                   const Grid& grid);

// The global path a control session follows: one D* Lite answer.
struct GlobalPath {
  // Increases with every path published; the control answer carries `plan`
  // when it is newer than the last one carried.
  uint64_t generation = 0;
  uint64_t map_version = 0;
  // Cell centres, start to goal; empty when there is no path.
  std::vector<CellPoint> points;
  v1::PlanResponse plan;
};

// Control-cycle latencies (seconds) in fixed buckets, for the metrics.
// Thread-safe.
class CycleHistogram {
 public:
  static constexpr std::array<double, 12> kBounds = {
      0.0001, 0.00025, 0.0005, 0.001, 0.0025, 0.005,
      0.01,   0.025,   0.05,   0.1,   0.25,   1.0};
  struct Snapshot {
    std::array<int64_t, kBounds.size() + 1> counts{};  // last: +Inf
    double sum = 0.0;
    int64_t count = 0;
  };
  void Observe(double seconds) ABSL_LOCKS_EXCLUDED(mu_);
  Snapshot Read() const ABSL_LOCKS_EXCLUDED(mu_);

 private:
  mutable absl::Mutex mu_;
  Snapshot data_ ABSL_GUARDED_BY(mu_);
};

// One session's control state. Thread-safe: the session's state messages
// call Cycle one at a time, while its replans call SetPath from the worker
// pool.
class ControlSession {
 public:
  struct Deps {
    MapStore& store;
    // Per-version static obstacles come from here; null: the session builds
    // its own per version.
    DerivedCache* derived;
    RobotRegistry& robots;
  };
  // `map` is the session's map, `robot_id` its session id.
  ControlSession(Deps deps, ControlConfig config, std::string map, uint64_t robot_id);
  // The stream half removes the robot from the registry when the session
  // finishes (the registry may be gone by the time this is destroyed).
  ControlSession(const ControlSession&) = delete;
  ControlSession& operator=(const ControlSession&) = delete;

  const ControlConfig& config() const { return config_; }

  // Publishes a new global path (its generation is set here).
  void SetPath(GlobalPath path) ABSL_LOCKS_EXCLUDED(path_mu_);

  // Answers one RobotState into `response` (event CONTROL, the command, and
  // the plan when the path is new to the client). `robot_cell` receives the
  // robot's cell. `detour` (optional) receives a request when the robot has
  // stalled over the local planner's window (at most one per window), or
  // when the last one's blockers may be lifted. INVALID_ARGUMENT naming a bad state
  // field (the session ends, as for any bad message).
  absl::Status Cycle(const v1::RobotState& state, v1::NavigateResponse* response,
                     Cell* robot_cell, std::optional<DetourRequest>* detour = nullptr)
      ABSL_LOCKS_EXCLUDED(mu_, path_mu_);

  // Bytes the session keeps besides its D* Lite state: the path, its plan,
  // the progress window.
  int64_t bytes() const ABSL_LOCKS_EXCLUDED(mu_, path_mu_);

 private:
  // The map version's static obstacles, built or taken from the cache when
  // the version changed.
  absl::Status RefreshStatics() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_);

  // A detour request when `plan` says the robot stalled and no request went
  // out within the stall window (its blockers: the slow `obstacles` near
  // it); or one lifting the last blockers once the robot is clear of where
  // it stalled and none of `obstacles` stands in their discs any more.
  std::optional<DetourRequest> DetourFor(const RobotState& robot, const LocalPlan& plan,
                                         const std::vector<MovingObstacle>& obstacles)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_);

  const Deps deps_;
  const ControlConfig config_;
  const std::string map_;
  const uint64_t robot_id_;
  // DWA's checker of config_.footprint (null for the other planners).
  std::shared_ptr<const FootprintChecker> checker_;

  mutable absl::Mutex path_mu_;
  std::shared_ptr<const GlobalPath> path_ ABSL_GUARDED_BY(path_mu_);
  uint64_t next_generation_ ABSL_GUARDED_BY(path_mu_) = 1;

  mutable absl::Mutex mu_;
  ProgressWindow progress_ ABSL_GUARDED_BY(mu_);
  // Cycles since the last detour request (or since the session began).
  int64_t cycles_since_detour_ ABSL_GUARDED_BY(mu_) = 0;
  // The blockers of the last detour, where the robot stood then, and how
  // far from there it must be before they may be lifted (cells).
  std::vector<DetourRequest::Disc> blockers_ ABSL_GUARDED_BY(mu_);
  CellPoint detour_origin_ ABSL_GUARDED_BY(mu_);
  double detour_clear_ ABSL_GUARDED_BY(mu_) = 0.0;
  double last_yaw_ ABSL_GUARDED_BY(mu_) = 0.0;
  uint64_t sent_generation_ ABSL_GUARDED_BY(mu_) = 0;
  // The points of the path last carried to the client.
  std::vector<CellPoint> carried_ ABSL_GUARDED_BY(mu_);
  // The newest map version seen and its static obstacles.
  std::shared_ptr<const MapSnapshot> snapshot_ ABSL_GUARDED_BY(mu_);
  std::shared_ptr<const ObstaclePolygons> polygons_ ABSL_GUARDED_BY(mu_);
  std::shared_ptr<const std::vector<float>> distance_ ABSL_GUARDED_BY(mu_);
};

}  // namespace pathd::server

#endif  // PATHD_SERVER_RPC_NAVIGATE_CONTROL_H_
