// The planning half of a Navigate session: a D* Lite search on the newest
// version of the session's map with the session's private cells laid over it,
// repaired from the cells that changed between versions, or for a robot with
// a footprint and kinematics the kinematic replanning of
// navigate_kinematic.h on the same view of the map; and the session's
// reservation in the memory budget. The stream half (reads, writes,
// lifetime) is NavigationSession in navigate.cc.
#ifndef PATHD_SERVER_RPC_NAVIGATE_SEARCH_H_
#define PATHD_SERVER_RPC_NAVIGATE_SEARCH_H_

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/incremental/incremental_search.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "pathd/v1/planner_service.pb.h"
#include "core/search/search_scratch.h"
#include "server/convert.h"
#include "server/derived_cache.h"
#include "server/inflation_cache.h"
#include "server/map_store.h"
#include "server/memory_budget.h"
#include "server/rpc/fleet_sessions.h"
#include "server/rpc/navigate_control.h"
#include "server/rpc/navigate_kinematic.h"
#include "server/rpc/robot_registry.h"

namespace pathd::server {

// Not thread-safe: the session calls it under its plan_mu_ only.
class NavigationSearch {
 public:
  struct Deps {
    MapStore& store;
    InflationCache& inflation;
    // Where the search state's bytes are reserved; null = no byte limit.
    MemoryBudget* budget;
    // The server's expansion cap (--max_expansions); 0 = none.
    int64_t max_expansions;
    // The server's derived values per map version (kinematic sessions read
    // the obstacle heuristic there); null: each session builds its own.
    DerivedCache* derived = nullptr;
    // Control sessions: where robots meet (null: control sessions refused),
    // and this session's robot id there.
    RobotRegistry* robots = nullptr;
    uint64_t session_id = 0;
    // Fleet sessions: the server's groups (null: fleet sessions refused),
    // and how this session's stream queues a push (with no lock of the
    // caller's held).
    FleetGroups* fleets = nullptr;
    FleetGroups::Push push;
  };

  // `caller`: whose share of the budget the session counts against.
  // `shared_observations`: what an observation of the shared map gets (OK or
  // the caller's PERMISSION_DENIED). `cancelled` stops a running plan and
  // `bytes` receives the state's size after each plan; both must outlive
  // this object. `on_open` gets the map's name once the session is open.
  NavigationSearch(Deps deps, std::string caller,
                   absl::Status shared_observations,
                   const std::atomic<bool>* cancelled,
                   std::atomic<int64_t>* bytes,
                   std::function<void(const std::string&)> on_open);

  bool is_open() const { return search_ != nullptr || kinematic_ != nullptr || fleet_; }

  // True once after Handle when the answer was already queued to the stream
  // (fleet sessions: their group queues answers in order with its pushes);
  // the stream half must then not queue it again.
  bool TakeAnswerQueued() { return std::exchange(answer_queued_, false); }

  // Answers one client message (open, pose or observe) into `response`, with
  // the new plan. An error ends the session. `scratch` is the worker's.
  absl::Status Handle(const v1::NavigateRequest& message, SearchScratch& scratch,
                      v1::NavigateResponse* response);
  // Moves to the map's newest version; when there was one, fills `response`
  // with the new plan and sets `changed` when it is worth pushing: the path
  // differs from the last one sent (D* Lite), or the change hit the
  // kinematic path's swept footprint (or there was no path) and this is the
  // replan. Requires is_open().
  absl::Status Push(SearchScratch& scratch, v1::NavigateResponse* response, bool* changed);

  // Control sessions: the control state (null for other sessions), shared
  // with the stream half, which runs the control cycles without plan_mu_.
  const std::shared_ptr<ControlSession>& control() const { return control_; }
  // Control sessions: moves to the map's newest version and to the robot's
  // cell `robot` (unless it is blocked on the planning grid, where the old
  // start stays), repairs D* Lite within the replan budget and publishes the
  // path to control() when it changed. `incomplete` is set when the budget
  // ran out (the previous path stays; the next replan continues).
  // `detour`: plan around its blockers (session-only blocked cells, in
  // place of the last detour's; a lift removes them) and never again
  // through the tight cells found along the published path; whenever there
  // is no path without them all are dropped and the path planned through
  // them.
  absl::Status ReplanControl(std::optional<Cell> robot, bool* incomplete,
                             std::optional<DetourRequest> detour = std::nullopt);

 private:
  absl::Status RequireOpen(const v1::NavigateRequest& message);
  absl::Status Open(const v1::NavigateOpen& open);
  // The kinematic part of Open, for a query naming a kinematic planner.
  absl::Status OpenKinematic(const v1::NavigateOpen& open, DecodedQuery decoded);
  // A fleet session's open (open.fleet set): joins its group, whose plan
  // `response` then carries.
  absl::Status OpenFleet(const v1::NavigateOpen& open, v1::NavigateResponse* response);
  // A fleet session's pose and observe messages.
  absl::Status HandleFleet(const v1::NavigateRequest& message, v1::NavigateResponse* response);
  // The kinematic session's view of the map for a replan.
  KinematicView ViewForKinematic();
  absl::Status ReserveMemory(const Grid& grid);
  absl::StatusOr<uint64_t> Observe(const v1::NavigateObservation& observe);
  absl::StatusOr<std::shared_ptr<const Grid>> EffectiveGrid(
      const MapSnapshot& snapshot);
  absl::Status Refresh(bool overlay_changed);
  // `outcome` (optional) receives the search's outcome.
  absl::Status PlanInto(v1::PlanResponse* plan, bool* changed,
                        PlanOutcome* outcome = nullptr);
  // Control sessions: publishes last_path_ and `plan` to control_.
  void PublishPath(const v1::PlanResponse& plan);
  // Stores the session's bytes and updates the reservation.
  void AccountBytes(int64_t state_bytes);

  // First, so it is destroyed last: the bytes it returns (and the trim it
  // may trigger) come after every other member is freed.
  MemoryBudget::Reservation reservation_;
  const Deps deps_;
  const std::string caller_;
  const absl::Status shared_observations_;
  const std::atomic<bool>* const cancelled_;
  std::atomic<int64_t>* const bytes_;
  const std::function<void(const std::string&)> on_open_;

  std::shared_ptr<const MapSnapshot> snapshot_;
  std::shared_ptr<const Grid> grid_;
  // Exactly one of these once open: a grid session's D* Lite, or a kinematic
  // session's replanning.
  std::unique_ptr<DStarLite> search_;
  std::unique_ptr<KinematicNavigation> kinematic_;
  // Control sessions (with search_): the control half.
  std::shared_ptr<ControlSession> control_;
  // A fleet session (neither search_ nor kinematic_): its robot is in a
  // group of deps_.fleets.
  bool fleet_ = false;
  bool answer_queued_ = false;
  // Kinematic sessions: the server's derived store for snapshot_ (when the
  // session plans on the version's own grid) and the version it is for.
  std::unique_ptr<DerivedStore> shared_derived_;
  uint64_t shared_derived_version_ = 0;
  // Session-only cell costs (cell index -> cost), laid over every version.
  std::map<size_t, uint8_t> overlay_;
  // Control sessions: the blocked cells around the last detour's blockers
  // (sorted indices, laid over the overlay), and the gaps found too tight
  // for the robot, kept while there is a path without them (sorted indices).
  std::vector<size_t> detour_cells_;
  std::vector<size_t> tight_cells_;
  Cell start_;
  Cell goal_;
  CostParams cost_;
  // What the session plans on: the map shaped for its robot (robot radius,
  // inflation and clearance costs).
  GridShape shape_;
  int64_t max_expansions_ = 0;
  // options.path_encoding of the open message: how pushed plans carry their path.
  v1::PathEncoding path_encoding_ = v1::PATH_ENCODING_UNSPECIFIED;
  int64_t repaired_cells_ = 0;
  int64_t plans_ = 0;
  std::vector<Cell> last_path_;
  // Control sessions: the path last published to control_.
  std::vector<Cell> published_path_;
};

}  // namespace pathd::server

#endif  // PATHD_SERVER_RPC_NAVIGATE_SEARCH_H_
