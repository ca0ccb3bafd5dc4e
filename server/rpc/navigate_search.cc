// The planning half of a Navigate session (navigate_search.h).
#include "server/rpc/navigate_search.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <utility>

#include "absl/strings/str_format.h"
#include "absl/time/time.h"
#include "core/local/local_types.h"
#include "core/map/inflation.h"
#include "core/planning/plan_query.h"
#include "core/search/endpoints.h"
#include "core/search/registry.h"
#include "core/search/stop_condition.h"
#include "core/status_macros.h"
#include "server/convert.h"
#include "server/incremental_cache.h"
#include "server/rpc/fleet_common.h"
#include "server/rpc/navigate.h"

namespace pathd::server {
namespace {

// The cells a detour blocks around its blockers: those whose centres lie in
// a blocker's disc, except within the robot's radius and a cell and a half
// of its centre, so that once the planning grid is inflated by the robot's
// radius the robot's own cell stays free and the path leaves it around the
// blockers. Sorted indices.
std::vector<size_t> BlockerCells(const DetourRequest& detour, const Grid& grid) {
  std::vector<size_t> cells;
  const double keep_free = detour.robot_radius + 1.5;
  for (const DetourRequest::Disc& disc : detour.blockers) {
    const int32_t x0 = std::max(0, static_cast<int32_t>(std::floor(disc.centre.x - disc.radius)));
    const int32_t x1 = std::min(grid.width() - 1,
                                static_cast<int32_t>(std::floor(disc.centre.x + disc.radius)));
    const int32_t y0 = std::max(0, static_cast<int32_t>(std::floor(disc.centre.y - disc.radius)));
    const int32_t y1 = std::min(grid.height() - 1,
                                static_cast<int32_t>(std::floor(disc.centre.y + disc.radius)));
    for (int32_t y = y0; y <= y1; ++y) {
      for (int32_t x = x0; x <= x1; ++x) {
        const double cx = x + 0.5, cy = y + 0.5;
        if (std::hypot(cx - disc.centre.x, cy - disc.centre.y) > disc.radius) continue;
        if (std::hypot(cx - detour.robot.x, cy - detour.robot.y) < keep_free) continue;
        cells.push_back(grid.Index(x, y));
      }
    }
  }
  std::sort(cells.begin(), cells.end());
  cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
  return cells;
}

// The distance from the centre of `cell` to the nearest blocked cell's area
// (lethal or unknown, or outside the map), looking `limit` cells around it;
// `limit` + 1 when nothing is that near.
double AreaClearance(const Grid& grid, Cell cell, double limit) {
  const int32_t reach = static_cast<int32_t>(std::ceil(limit + 0.5));
  double best = limit + 1.0;
  for (int32_t dy = -reach; dy <= reach; ++dy) {
    for (int32_t dx = -reach; dx <= reach; ++dx) {
      const Cell c{cell.x + dx, cell.y + dy};
      if (grid.InBounds(c) && grid.cost(c) < kLethalCost) continue;
      const double ex = std::max(std::abs(dx) - 0.5, 0.0);
      const double ey = std::max(std::abs(dy) - 0.5, 0.0);
      best = std::min(best, std::hypot(ex, ey));
    }
  }
  return best;
}

// The detour's tight cells (DetourRequest::clearance) along `path`, the
// path the robot follows: none unless the robot stands within the
// clearance and 1.5 cells of the map. Each candidate cell is measured once.
std::vector<Cell> TightCells(const Grid& grid, const std::vector<Cell>& path,
                             const DetourRequest& detour) {
  std::vector<Cell> tight;
  const double need = detour.clearance;
  const Cell robot{static_cast<int32_t>(std::floor(detour.robot.x)),
                   static_cast<int32_t>(std::floor(detour.robot.y))};
  if (need <= 0 || path.empty() || AreaClearance(grid, robot, need + 1.5) >= need + 1.5) {
    return tight;
  }
  std::vector<CellPoint> points;
  points.reserve(path.size());
  for (const Cell& c : path) points.push_back(CellPoint{c.x + 0.5, c.y + 0.5});
  const PathTarget at = FindPathTarget(points, detour.robot, 0.0);
  const double stretch = detour.ahead + 2.0 * need;
  const int32_t reach = static_cast<int32_t>(std::ceil(need + 1.0));
  std::vector<Cell> candidates;
  double walked = 0.0;
  for (size_t i = at.nearest_segment; i < path.size() && walked <= stretch; ++i) {
    if (i > at.nearest_segment) {
      walked += std::hypot(path[i].x - path[i - 1].x, path[i].y - path[i - 1].y);
    }
    for (int32_t dy = -reach; dy <= reach; ++dy) {
      for (int32_t dx = -reach; dx <= reach; ++dx) {
        const Cell c{path[i].x + dx, path[i].y + dy};
        if (grid.InBounds(c) && grid.cost(c) < kLethalCost) candidates.push_back(c);
      }
    }
  }
  const auto before = [](const Cell& a, const Cell& b) {
    return a.y != b.y ? a.y < b.y : a.x < b.x;
  };
  std::sort(candidates.begin(), candidates.end(), before);
  candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
  for (const Cell& c : candidates) {
    if (AreaClearance(grid, c, need) < need) tight.push_back(c);
  }
  return tight;
}

// The detour's tight cells, merged into `tight` (sorted indices), except
// near the robot (as for blockers) and near the goal (whose own clearance is
// the user's choice). True when `tight` grew.
bool MergeTightCells(const DetourRequest& detour, const std::vector<Cell>& found,
                     const Grid& grid, Cell goal, std::vector<size_t>* tight) {
  const double keep_free = detour.robot_radius + 1.5;
  std::vector<size_t> cells;
  for (const Cell& c : found) {
    if (!grid.InBounds(c)) continue;
    if (std::hypot(c.x + 0.5 - detour.robot.x, c.y + 0.5 - detour.robot.y) < keep_free) continue;
    if (std::hypot(c.x - goal.x, c.y - goal.y) < keep_free) continue;
    cells.push_back(grid.Index(c));
  }
  std::sort(cells.begin(), cells.end());
  std::vector<size_t> merged;
  merged.reserve(tight->size() + cells.size());
  std::set_union(tight->begin(), tight->end(), cells.begin(), cells.end(),
                 std::back_inserter(merged));
  merged.erase(std::unique(merged.begin(), merged.end()), merged.end());
  const bool grew = merged.size() != tight->size();
  *tight = std::move(merged);
  return grew;
}

}  // namespace

NavigationSearch::NavigationSearch(
    Deps deps, std::string caller, absl::Status shared_observations,
    const std::atomic<bool>* cancelled, std::atomic<int64_t>* bytes,
    std::function<void(const std::string&)> on_open)
    : deps_(deps),
      caller_(std::move(caller)),
      shared_observations_(std::move(shared_observations)),
      cancelled_(cancelled),
      bytes_(bytes),
      on_open_(std::move(on_open)) {}

absl::Status NavigationSearch::Handle(const v1::NavigateRequest& message,
                                      SearchScratch& scratch,
                                      v1::NavigateResponse* response) {
  response->set_seq(message.seq());
  switch (message.kind_case()) {
    case v1::NavigateRequest::kOpen:
      if (is_open()) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "message seq %d: the session is already open", message.seq()));
      }
      response->set_event(v1::NAVIGATE_EVENT_OPENED);
      if (message.open().has_fleet()) return OpenFleet(message.open(), response);
      PATHD_RETURN_IF_ERROR(Open(message.open()));
      break;
    case v1::NavigateRequest::kPose: {
      PATHD_RETURN_IF_ERROR(RequireOpen(message));
      if (fleet_) return HandleFleet(message, response);
      response->set_event(v1::NAVIGATE_EVENT_MOVED);
      if (kinematic_ != nullptr) {
        PATHD_ASSIGN_OR_RETURN(const PositionPose pose,
                               PoseFromPosition(message.pose(), *snapshot_->grid, "pose"));
        PATHD_RETURN_IF_ERROR(Refresh(/*overlay_changed=*/false));
        Pose robot = pose.pose;
        // A point without a heading: the robot turned no more than it said.
        if (!pose.has_yaw) robot.yaw = kinematic_->robot().yaw;
        kinematic_->SetRobot(robot);
        break;
      }
      PATHD_ASSIGN_OR_RETURN(
          const Cell cell,
          CellFromPosition(message.pose(), *snapshot_->grid, "pose"));
      if (!grid_->InBounds(cell)) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "pose %s is outside the %d x %d map", CellToString(cell),
            grid_->width(), grid_->height()));
      }
      PATHD_RETURN_IF_ERROR(Refresh(/*overlay_changed=*/false));
      start_ = cell;
      PATHD_RETURN_IF_ERROR(search_->SetStart(start_));
      break;
    }
    case v1::NavigateRequest::kObserve: {
      PATHD_RETURN_IF_ERROR(RequireOpen(message));
      if (fleet_) return HandleFleet(message, response);
      response->set_event(v1::NAVIGATE_EVENT_OBSERVED);
      PATHD_ASSIGN_OR_RETURN(uint64_t applied, Observe(message.observe()));
      response->set_applied_version(applied);
      break;
    }
    case v1::NavigateRequest::kState:
      // A control session's states never come here (the stream answers
      // them without the search).
      PATHD_RETURN_IF_ERROR(RequireOpen(message));
      return absl::InvalidArgumentError(absl::StrFormat(
          "message seq %d: state is only for control sessions (open.control)",
          message.seq()));
    case v1::NavigateRequest::KIND_NOT_SET:
      return absl::InvalidArgumentError(absl::StrFormat(
          "message seq %d sets none of open, pose, observe, state", message.seq()));
  }
  if (kinematic_ != nullptr) {
    const bool opening = message.kind_case() == v1::NavigateRequest::kOpen;
    PATHD_RETURN_IF_ERROR(kinematic_->Replan(ViewForKinematic(), opening, scratch, response));
    AccountBytes(kinematic_->bytes());
    ++plans_;
    return absl::OkStatus();
  }
  PATHD_RETURN_IF_ERROR(PlanInto(response->mutable_plan(), /*changed=*/nullptr));
  if (control_ != nullptr) PublishPath(response->plan());
  return absl::OkStatus();
}

absl::Status NavigationSearch::OpenFleet(const v1::NavigateOpen& open,
                                         v1::NavigateResponse* response) {
  if (deps_.fleets == nullptr) {
    return absl::UnimplementedError("this server runs no fleet sessions");
  }
  if (open.has_control()) {
    return absl::InvalidArgumentError(
        "open.fleet: a fleet session's robot follows its timed path; it cannot also be a "
        "control session (open.control)");
  }
  if (open.planner() != v1::PLANNER_UNSPECIFIED && open.planner() != v1::PLANNER_DSTAR_LITE) {
    return absl::InvalidArgumentError(
        "open.planner: a fleet session is planned by its group's multi-robot solver "
        "(open.fleet.solver); leave open.planner unset");
  }
  const v1::FleetSessionOptions& fleet = open.fleet();
  PATHD_RETURN_IF_ERROR(CheckFleetSolver(fleet.solver(), "open.fleet.solver"));
  const int64_t max_ms = absl::ToInt64Milliseconds(FleetGroups::kMaxTimeLimit);
  if (fleet.time_limit_ms() < 0 || fleet.time_limit_ms() > max_ms) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "open.fleet.time_limit_ms %d must be in [0, %d] (0: the group's, else %d)",
        fleet.time_limit_ms(), max_ms,
        absl::ToInt64Milliseconds(FleetGroups::kDefaultTimeLimit)));
  }
  PATHD_ASSIGN_OR_RETURN(
      DecodedQuery decoded,
      DecodePlanQuery(WireQueryOf(open), deps_.store,
                      QueryLimits{.max_expansions = deps_.max_expansions}));
  PATHD_RETURN_IF_ERROR(
      CheckPlanQuery(*decoded.snapshot->grid, /*stateful=*/true, &decoded.query));
  snapshot_ = decoded.snapshot;
  path_encoding_ = decoded.path_encoding;
  start_ = decoded.query.request.start;
  goal_ = decoded.query.request.goal;
  cost_ = decoded.query.request.cost;
  shape_ = PlanningShape(decoded.query);
  FleetGroups::Join join;
  join.session_id = deps_.session_id;
  join.snapshot = snapshot_;
  join.group = fleet.group();
  join.start = start_;
  join.goal = goal_;
  join.shape = shape_;
  join.cost = cost_;
  if (fleet.solver() != v1::FLEET_SOLVER_UNSPECIFIED) {
    join.solver = FleetSolverFromProto(fleet.solver());
  }
  if (fleet.time_limit_ms() > 0) join.time_limit = absl::Milliseconds(fleet.time_limit_ms());
  join.push = deps_.push;
  PATHD_RETURN_IF_ERROR(deps_.fleets->Add(std::move(join), response));
  answer_queued_ = true;
  fleet_ = true;
  on_open_(snapshot_->name);
  return absl::OkStatus();
}

absl::Status NavigationSearch::HandleFleet(const v1::NavigateRequest& message,
                                           v1::NavigateResponse* response) {
  if (message.kind_case() == v1::NavigateRequest::kObserve) {
    response->set_event(v1::NAVIGATE_EVENT_OBSERVED);
    if (message.observe().session_only()) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "message seq %d: a fleet session's observations update the shared map (the "
          "group plans on it); session_only is not for fleet sessions",
          message.seq()));
    }
    PATHD_ASSIGN_OR_RETURN(const std::vector<MapChange> changes,
                           MapChangesFromProto(message.observe().changes()));
    if (changes.empty()) return absl::InvalidArgumentError("observation has no changes");
    PATHD_RETURN_IF_ERROR(shared_observations_);
    PATHD_ASSIGN_OR_RETURN(const MapUpdateResult result,
                           deps_.store.Update(snapshot_->name, changes, std::nullopt));
    snapshot_ = result.snapshot;
    response->set_applied_version(result.snapshot->version);
    answer_queued_ = deps_.fleets->Describe(deps_.session_id, response);
    return absl::OkStatus();
  }
  response->set_event(v1::NAVIGATE_EVENT_MOVED);
  PATHD_ASSIGN_OR_RETURN(const Cell cell,
                         CellFromPosition(message.pose(), *snapshot_->grid, "pose"));
  if (!snapshot_->grid->InBounds(cell)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "pose %s is outside the %d x %d map", CellToString(cell), snapshot_->grid->width(),
        snapshot_->grid->height()));
  }
  PATHD_RETURN_IF_ERROR(deps_.fleets->Report(deps_.session_id, cell, response));
  answer_queued_ = true;
  return absl::OkStatus();
}

absl::Status NavigationSearch::RequireOpen(const v1::NavigateRequest& message) {
  if (is_open()) return absl::OkStatus();
  return absl::InvalidArgumentError(absl::StrFormat(
      "message seq %d: the first message of a session must be 'open'",
      message.seq()));
}

absl::Status NavigationSearch::Open(const v1::NavigateOpen& open) {
  PATHD_ASSIGN_OR_RETURN(
      DecodedQuery decoded,
      DecodePlanQuery(WireQueryOf(open), deps_.store,
                      QueryLimits{.max_expansions = deps_.max_expansions}));
  const Planner* named = PlannerRegistry::Default().Get(decoded.query.planner);
  if (open.has_control() && named != nullptr && named->traits().kinematic) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "open.control: a control session follows a dstar_lite path (its local planner "
        "handles the robot's kinematics), not %s",
        std::string(decoded.query.planner)));
  }
  if (named != nullptr && named->traits().kinematic) {
    return OpenKinematic(open, std::move(decoded));
  }
  if (open.planner() != v1::PLANNER_UNSPECIFIED && open.planner() != v1::PLANNER_DSTAR_LITE) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "open.planner: a Navigate session plans with dstar_lite (grid robots) or a "
        "kinematic planner (hybrid_astar, state_lattice), not %s",
        std::string(decoded.query.planner)));
  }
  path_encoding_ = decoded.path_encoding;
  snapshot_ = std::move(decoded.snapshot);
  const Grid& stored = *snapshot_->grid;
  // The session's search is its own D* Lite; the façade's rules still apply
  // (a stateful search: one goal, no via points).
  PATHD_RETURN_IF_ERROR(
      CheckPlanQuery(stored, /*stateful=*/true, &decoded.query));
  start_ = decoded.query.request.start;
  goal_ = decoded.query.request.goal;
  cost_ = decoded.query.request.cost;
  shape_ = PlanningShape(decoded.query);
  max_expansions_ = decoded.query.max_expansions;
  std::optional<ControlConfig> control;
  if (open.has_control()) {
    if (deps_.robots == nullptr) {
      return absl::UnimplementedError("this server runs no control sessions");
    }
    PATHD_ASSIGN_OR_RETURN(control, DecodeControlOptions(open.control(), open.options(), stored));
    // Every replan of a control session is bounded as a kinematic session's
    // is: the control cycles never wait for it, but the worker does.
    if (open.replan_max_expansions() < 0) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "open.replan_max_expansions %d must be >= 0 (0: options.max_expansions, else %d)",
          open.replan_max_expansions(), KinematicNavigation::kDefaultReplanExpansions));
    }
    int64_t budget = open.replan_max_expansions();
    if (budget == 0) budget = decoded.query.max_expansions;
    if (budget == 0) budget = KinematicNavigation::kDefaultReplanExpansions;
    if (deps_.max_expansions > 0) budget = std::min(budget, deps_.max_expansions);
    max_expansions_ = budget;
  }
  PATHD_RETURN_IF_ERROR(ReserveMemory(stored));
  PATHD_ASSIGN_OR_RETURN(grid_, EffectiveGrid(*snapshot_));
  if (shape_.robot_radius_cells > 0.0) {
    PATHD_RETURN_IF_ERROR(CheckRadiusEndpoints(stored, *grid_, shape_.robot_radius_cells,
                                               {{goal_, "goal"}}));
  }
  PATHD_ASSIGN_OR_RETURN(search_, DStarLite::Create(grid_, goal_, cost_));
  PATHD_RETURN_IF_ERROR(search_->SetStart(start_));
  if (control.has_value()) {
    control_ = std::make_shared<ControlSession>(
        ControlSession::Deps{deps_.store, deps_.derived, *deps_.robots}, *std::move(control),
        snapshot_->name, deps_.session_id);
  }
  on_open_(snapshot_->name);
  return absl::OkStatus();
}

absl::Status NavigationSearch::OpenKinematic(const v1::NavigateOpen& open,
                                             DecodedQuery decoded) {
  if (open.replan_max_expansions() < 0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "open.replan_max_expansions %d must be >= 0 (0: options.max_expansions, else %d)",
        open.replan_max_expansions(), KinematicNavigation::kDefaultReplanExpansions));
  }
  path_encoding_ = decoded.path_encoding;
  snapshot_ = std::move(decoded.snapshot);
  const Grid& stored = *snapshot_->grid;
  PATHD_RETURN_IF_ERROR(CheckPlanQuery(stored, /*stateful=*/false, &decoded.query));
  // decoded.query.max_expansions is options.max_expansions under the
  // server's cap (0: neither set).
  int64_t budget = open.replan_max_expansions();
  if (budget == 0) budget = decoded.query.max_expansions;
  if (budget == 0) budget = KinematicNavigation::kDefaultReplanExpansions;
  if (deps_.max_expansions > 0) budget = std::min(budget, deps_.max_expansions);
  const Planner* planner = PlannerRegistry::Default().Get(decoded.query.planner);
  if (planner == nullptr) {
    return absl::InternalError(absl::StrFormat("planner %s is not registered",
                                               std::string(decoded.query.planner)));
  }
  start_ = decoded.query.request.start;
  goal_ = decoded.query.request.goal;
  cost_ = decoded.query.request.cost;
  shape_ = PlanningShape(decoded.query);
  max_expansions_ = budget;
  PATHD_RETURN_IF_ERROR(ReserveMemory(stored));
  PATHD_ASSIGN_OR_RETURN(grid_, EffectiveGrid(*snapshot_));
  kinematic_ = std::make_unique<KinematicNavigation>(std::move(decoded.query), planner, budget,
                                                     decoded.path_encoding, cancelled_);
  on_open_(snapshot_->name);
  return absl::OkStatus();
}

KinematicView NavigationSearch::ViewForKinematic() {
  // No per-cell state is repaired or reused from a previous plan (the
  // derived values are the cache's), so cache_hit and repaired_cells stay 0.
  KinematicView view{grid_, snapshot_->version, nullptr};
  // The server's per-version values fit only the version's own grid.
  if (deps_.derived != nullptr && grid_ == snapshot_->grid) {
    if (shared_derived_ == nullptr || shared_derived_version_ != snapshot_->version) {
      shared_derived_ = deps_.derived->For(snapshot_, grid_, /*robot_radius_cells=*/0.0);
      shared_derived_version_ = snapshot_->version;
    }
    view.shared_derived = shared_derived_.get();
  } else {
    shared_derived_.reset();
  }
  return view;
}

void NavigationSearch::AccountBytes(int64_t state_bytes) {
  // A private grid (overlay) is a copy of the map; map nodes ~48 bytes.
  const bool private_grid =
      !overlay_.empty() || !detour_cells_.empty() || !tight_cells_.empty();
  const int64_t bytes = state_bytes + static_cast<int64_t>(overlay_.size()) * 48 +
                        static_cast<int64_t>((detour_cells_.capacity() + tight_cells_.capacity()) *
                                             sizeof(size_t)) +
                        (private_grid ? static_cast<int64_t>(grid_->size()) : 0) +
                        (control_ != nullptr ? control_->bytes() : 0);
  bytes_->store(bytes, std::memory_order_relaxed);
  reservation_.Update(bytes);
}

// Reserves the search state's estimated bytes before anything is built, so
// sessions on a big map are refused instead of exhausting memory.
absl::Status NavigationSearch::ReserveMemory(const Grid& grid) {
  MemoryBudget* budget = deps_.budget;
  if (budget == nullptr) return absl::OkStatus();
  const int64_t estimate = static_cast<int64_t>(grid.size()) *
                           NavigationSessions::kSessionBytesPerCell;
  PATHD_ASSIGN_OR_RETURN(
      reservation_,
      budget->Reserve(
          MemoryBudget::Part::kSessions, caller_, estimate,
          absl::StrFormat("a navigation session on the %d x %d map '%s'",
                          grid.width(), grid.height(), snapshot_->name)));
  return absl::OkStatus();
}

// Applies sensed changes: to the shared map through the store (the same
// validation and versioning as UpdateMap), or to this session's overlay.
absl::StatusOr<uint64_t> NavigationSearch::Observe(
    const v1::NavigateObservation& observe) {
  PATHD_ASSIGN_OR_RETURN(const std::vector<MapChange> changes,
                         MapChangesFromProto(observe.changes()));
  if (changes.empty()) {
    return absl::InvalidArgumentError("observation has no changes");
  }
  if (!observe.session_only()) {
    PATHD_RETURN_IF_ERROR(shared_observations_);
    PATHD_ASSIGN_OR_RETURN(
        const MapUpdateResult result,
        deps_.store.Update(snapshot_->name, changes, std::nullopt));
    PATHD_RETURN_IF_ERROR(Refresh(/*overlay_changed=*/false));
    return result.snapshot->version;
  }
  const Grid& stored = *snapshot_->grid;
  PATHD_RETURN_IF_ERROR(MapStore::ValidateChanges(changes, stored));
  for (const MapChange& change : changes) {
    for (int32_t y = change.y_min; y <= change.y_max; ++y) {
      for (int32_t x = change.x_min; x <= change.x_max; ++x) {
        overlay_[stored.Index(x, y)] = static_cast<uint8_t>(change.cost);
      }
    }
  }
  PATHD_RETURN_IF_ERROR(Refresh(/*overlay_changed=*/true));
  return uint64_t{0};
}

// The grid the search runs on: the stored version, with this session's
// private cells over it, shaped for the robot (radius, clearance costs;
// shared shapes come from the cache, private ones are computed here).
absl::StatusOr<std::shared_ptr<const Grid>> NavigationSearch::EffectiveGrid(
    const MapSnapshot& snapshot) {
  const GridShape& shape = shape_;
  if (overlay_.empty() && detour_cells_.empty() && tight_cells_.empty()) {
    if (!shape.shaped()) return snapshot.grid;
    return deps_.inflation.Get(snapshot, shape);
  }
  Grid merged = *snapshot.grid;
  for (const auto& [index, cost] : overlay_) {
    merged.mutable_cells()[index] = cost;
  }
  for (const std::vector<size_t>* cells : {&detour_cells_, &tight_cells_}) {
    for (const size_t index : *cells) {
      uint8_t& cost = merged.mutable_cells()[index];
      cost = std::max(cost, kLethalCost);
    }
  }
  if (shape.shaped()) {
    PATHD_ASSIGN_OR_RETURN(merged, ShapeGrid(merged, shape));
  }
  return std::make_shared<const Grid>(std::move(merged));
}

// Moves the search to the map's current version (and the current overlay):
// only the changed cells are handed to D* Lite.
absl::Status NavigationSearch::Refresh(bool overlay_changed) {
  absl::StatusOr<std::shared_ptr<const MapSnapshot>> latest =
      deps_.store.Get(snapshot_->name);
  if (!latest.ok()) {
    return absl::NotFoundError(absl::StrFormat(
        "map '%s' was deleted during the navigation session", snapshot_->name));
  }
  if ((*latest)->version == snapshot_->version && !overlay_changed) {
    return absl::OkStatus();
  }
  const Grid& before = *grid_;
  if (kinematic_ != nullptr) {
    // Kinematic sessions keep no per-cell state to repair: the next replan
    // plans on the new view (its field from the version's cache).
    if ((*latest)->grid->width() != before.width() ||
        (*latest)->grid->height() != before.height()) {
      return absl::FailedPreconditionError(absl::StrFormat(
          "map '%s' was replaced by a %d x %d map; open a new session", snapshot_->name,
          (*latest)->grid->width(), (*latest)->grid->height()));
    }
    PATHD_ASSIGN_OR_RETURN(std::shared_ptr<const Grid> after, EffectiveGrid(**latest));
    snapshot_ = *std::move(latest);
    grid_ = std::move(after);
    return absl::OkStatus();
  }
  if ((*latest)->grid->width() != before.width() ||
      (*latest)->grid->height() != before.height()) {
    return absl::FailedPreconditionError(absl::StrFormat(
        "map '%s' was replaced by a %d x %d map; open a new session",
        snapshot_->name, (*latest)->grid->width(), (*latest)->grid->height()));
  }
  PATHD_ASSIGN_OR_RETURN(std::shared_ptr<const Grid> after,
                         EffectiveGrid(**latest));
  // A replaced map (new map_id) has no change list, so this compares.
  PATHD_ASSIGN_OR_RETURN(
      const std::vector<Cell> changed,
      ChangesBetween(before, snapshot_->version, *after, **latest));
  PATHD_RETURN_IF_ERROR(search_->UpdateMap(after, changed));
  repaired_cells_ += static_cast<int64_t>(changed.size());
  snapshot_ = *std::move(latest);
  grid_ = std::move(after);
  return absl::OkStatus();
}

absl::Status NavigationSearch::Push(SearchScratch& scratch, v1::NavigateResponse* response,
                                    bool* changed) {
  // A fleet session's group follows the map itself (FleetGroups).
  if (fleet_) return absl::OkStatus();
  const uint64_t version = snapshot_->version;
  PATHD_RETURN_IF_ERROR(Refresh(/*overlay_changed=*/false));
  if (snapshot_->version == version) return absl::OkStatus();
  response->set_event(v1::NAVIGATE_EVENT_MAP_CHANGED);
  if (kinematic_ != nullptr) {
    // Replanned only when the change may touch the path's sweep (or there
    // was no path): an unrelated update leaves a feasible path feasible.
    KinematicView view = ViewForKinematic();
    PATHD_ASSIGN_OR_RETURN(const bool blocked, kinematic_->PathBlocked(view));
    if (!blocked) {
      AccountBytes(kinematic_->bytes());
      return absl::OkStatus();
    }
    const bool had_path = kinematic_->has_path();
    PATHD_RETURN_IF_ERROR(kinematic_->Replan(view, /*opening=*/false, scratch, response));
    AccountBytes(kinematic_->bytes());
    ++plans_;
    *changed = had_path || kinematic_->has_path();
    return absl::OkStatus();
  }
  if (control_ != nullptr) {
    // A push that raced with the open of a control session: the path goes
    // to its control answers, never out as a push.
    bool incomplete = false;
    *changed = false;
    return ReplanControl(std::nullopt, &incomplete);
  }
  return PlanInto(response->mutable_plan(), changed);
}

// Repairs the search, extracts the path from the robot's cell and fills
// `plan`. `changed` (optional) says whether the path differs from the one
// last sent. A robot standing on a blocked cell is an answer, not an error.
absl::Status NavigationSearch::PlanInto(v1::PlanResponse* plan, bool* changed,
                                        PlanOutcome* outcome) {
  const StopCondition stop(absl::InfiniteFuture(), cancelled_, max_expansions_);
  absl::StatusOr<PlanResult> result = search_->Plan(stop);
  if (!result.ok() &&
      result.status().code() != absl::StatusCode::kInvalidArgument) {
    return result.status();
  }
  PlanQuery query;
  query.planner = "dstar_lite";
  query.request = PlanRequest::Between(start_, goal_, cost_);
  query.requested_goal = goal_;
  query.robot_radius_cells = shape_.robot_radius_cells;
  query.inflation_radius_cells = shape_.inflation_radius_cells;
  query.cost_scaling_per_cell = shape_.cost_scaling_per_cell;
  query.min_clearance_cells = shape_.min_clearance_cells;
  query.max_expansions = max_expansions_;
  PlanAnswer answer;
  answer.goal = goal_;
  answer.source =
      PlanSource{grid_, snapshot_->version, plans_ > 0, repaired_cells_};
  if (result.ok()) answer.result = *std::move(result);
  if (outcome != nullptr) *outcome = result.ok() ? answer.result.outcome : PlanOutcome::kNoPath;
  ReportClearance(query, &answer);
  SetSingleLeg(&answer);
  BuildPlanResponse(query, answer, /*expansion_limit_source=*/"", path_encoding_, plan);
  if (!result.ok()) plan->set_reason(std::string(result.status().message()));
  repaired_cells_ = 0;
  ++plans_;
  std::vector<Cell> path = std::move(answer.result.path);
  if (changed != nullptr) *changed = path != last_path_;
  last_path_ = std::move(path);
  AccountBytes(static_cast<int64_t>(search_->MemoryBytes()));
  return absl::OkStatus();
}

absl::Status NavigationSearch::ReplanControl(std::optional<Cell> robot, bool* incomplete,
                                             std::optional<DetourRequest> detour) {
  *incomplete = false;
  bool detour_changed = false;
  if (detour.has_value()) {
    // The request's blockers replace the last ones (a lift removes them, a
    // stall with none keeps them); its tight cells join those found before.
    if (detour->lift || !detour->blockers.empty()) {
      std::vector<size_t> blockers = BlockerCells(*detour, *snapshot_->grid);
      if (blockers != detour_cells_) {
        detour_cells_ = std::move(blockers);
        detour_changed = true;
      }
    }
    const Grid& stored = *snapshot_->grid;
    const std::vector<Cell> found = TightCells(stored, published_path_, *detour);
    if (MergeTightCells(*detour, found, stored, goal_, &tight_cells_)) detour_changed = true;
  }
  PATHD_RETURN_IF_ERROR(Refresh(detour_changed));
  // A robot whose centre strays onto a cell the planning grid blocks (it
  // slid along a wall the grid inflates by its radius) keeps following the
  // path from the old start; a start there would have no path at all.
  if (robot.has_value() && grid_->InBounds(*robot) && *robot != start_ &&
      Traversable(grid_->cost(*robot), cost_.unknown_is_free)) {
    start_ = *robot;
    PATHD_RETURN_IF_ERROR(search_->SetStart(start_));
  }
  v1::PlanResponse plan;
  bool changed = false;
  PlanOutcome outcome = PlanOutcome::kNoPath;
  PATHD_RETURN_IF_ERROR(PlanInto(&plan, &changed, &outcome));
  if ((!detour_cells_.empty() || !tight_cells_.empty()) && outcome != PlanOutcome::kFound &&
      outcome != PlanOutcome::kExpansionLimit) {
    // No way around the blockers or the tight gaps (after this detour, or
    // after a map change): the path through them (blockers may move).
    detour_cells_.clear();
    tight_cells_.clear();
    PATHD_RETURN_IF_ERROR(Refresh(/*overlay_changed=*/true));
    PATHD_RETURN_IF_ERROR(PlanInto(&plan, &changed, &outcome));
  }
  if (outcome == PlanOutcome::kExpansionLimit) {
    *incomplete = true;
    return absl::OkStatus();
  }
  // The rest of the published path (the robot moved along it) is not
  // published again: the local planner follows the published one from the
  // point nearest the robot.
  const bool rest_of_published =
      !last_path_.empty() && last_path_.size() <= published_path_.size() &&
      std::equal(last_path_.begin(), last_path_.end(),
                 published_path_.end() - static_cast<std::ptrdiff_t>(last_path_.size()));
  if (changed && !rest_of_published) PublishPath(plan);
  return absl::OkStatus();
}

void NavigationSearch::PublishPath(const v1::PlanResponse& plan) {
  GlobalPath path;
  path.map_version = snapshot_->version;
  path.points.reserve(last_path_.size());
  for (const Cell& c : last_path_) path.points.push_back(CellPoint{c.x + 0.5, c.y + 0.5});
  path.plan = plan;
  published_path_ = last_path_;
  control_->SetPath(std::move(path));
  AccountBytes(static_cast<int64_t>(search_->MemoryBytes()));
}

}  // namespace pathd::server
