// Navigate sessions. Each session is a gRPC bidi reactor plus a D* Lite
// search. Two locks per session: `mu_` guards the stream's state (reads,
// the write queue, finishing, lifetime) and is only ever held briefly; the
// longer `plan_mu_` guards the search and is held while planning on a worker.
// Lock order: owner's mu_ -> session mu_; plan_mu_ -> session mu_. gRPC never
// runs a user reactor's reactions inline from Start*/Finish (they are not
// InternalInlineable), so those may be called with mu_ held.
#include "server/rpc/navigate.h"

#include <algorithm>
#include <atomic>
#include <deque>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <spdlog/spdlog.h>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "core/search/endpoints.h"
#include "core/incremental/incremental_search.h"
#include "core/map/inflation.h"
#include "core/planning/plan_query.h"
#include "core/search/planner.h"
#include "core/status_macros.h"
#include "server/convert.h"
#include "server/grpc_status.h"
#include "server/incremental_cache.h"
#include "server/request_log.h"

namespace pathd::server {

using NavigateReactor = grpc::ServerBidiReactor<v1::NavigateRequest, v1::NavigateResponse>;

class NavigationSession final : public NavigateReactor {
 public:
  NavigationSession(NavigationSessions& owner, uint64_t id,
                    absl::Status shared_observations, std::string caller)
      : owner_(owner),
        id_(id),
        caller_(std::move(caller)),
        opened_at_(absl::Now()),
        shared_observations_(std::move(shared_observations)) {
    absl::MutexLock lock(&mu_);
    last_activity_ = opened_at_;
  }

  // The handler's last step: start reading, or refuse the call.
  void Begin(const absl::Status& admitted) {
    absl::MutexLock lock(&mu_);
    if (!admitted.ok()) {
      removed_ = true;  // never registered
      FinishLocked(admitted);
      return;
    }
    StartRead(&request_);
  }

  uint64_t id() const { return id_; }
  int64_t bytes() const { return bytes_.load(std::memory_order_relaxed); }

  bool OnMap(std::string_view name) const {
    absl::MutexLock lock(&mu_);
    return map_name_ == name;
  }

  // A new version of this session's map: repair the search and push the path
  // if it changed. Coalesced: one pending push covers any number of versions.
  void SchedulePush() {
    absl::MutexLock lock(&mu_);
    if (push_pending_ || finish_requested_ || done_) return;
    push_pending_ = true;
    ++outstanding_;
    const absl::Status submitted = owner_.pool_.Submit(MakeJob(
        [this](SearchScratch&) { RunPush(); }, [this] { Release(); },
        [this](const absl::Status& failed) {
          // The search may be half-repaired: the session cannot go on.
          {
            absl::MutexLock lock(&mu_);
            push_pending_ = false;
            EndWithLocked(failed);
          }
          Release();
        }));
    if (!submitted.ok()) {
      // Not worth failing the session for: its next message repairs anyway.
      push_pending_ = false;
      --outstanding_;
    }
  }

  // Ends the session with `status` as soon as no message is being handled.
  void EndWith(const absl::Status& status) {
    absl::MutexLock lock(&mu_);
    EndWithLocked(status);
  }

  void EndIfIdle(absl::Time now, absl::Duration timeout) {
    absl::MutexLock lock(&mu_);
    if (handling_ || now - last_activity_ < timeout) return;
    FinishLocked(absl::DeadlineExceededError(absl::StrFormat(
        "navigation session %d closed: no message for %s", id_,
        absl::FormatDuration(timeout))));
  }

  void OnReadDone(bool ok) override {
    absl::MutexLock lock(&mu_);
    // A message that raced with the end of the session is not answered.
    if (finish_requested_) return;
    if (!ok) {
      // The client closed its side (or the call is cancelled): done.
      FinishLocked(absl::OkStatus());
      return;
    }
    last_activity_ = absl::Now();
    if (pending_end_.has_value()) {
      FinishLocked(*pending_end_);
      return;
    }
    handling_ = true;
    ++outstanding_;
    auto message = std::make_shared<v1::NavigateRequest>(std::move(request_));
    request_.Clear();
    const absl::Status submitted = owner_.pool_.Submit(MakeJob(
        [this, message](SearchScratch&) { RunMessage(*message); },
        [this] {
          {
            absl::MutexLock lock(&mu_);
            handling_ = false;
            FinishLocked(absl::UnavailableError("server is shutting down"));
          }
          Release();
        },
        [this](const absl::Status& failed) {
          // RunMessage threw before its Release: answer and let go.
          {
            absl::MutexLock lock(&mu_);
            handling_ = false;
            ++messages_;
            FinishLocked(failed);
          }
          Release();
        }));
    if (!submitted.ok()) {
      handling_ = false;
      --outstanding_;
      FinishLocked(submitted);
    }
  }

  void OnWriteDone(bool ok) override {
    absl::MutexLock lock(&mu_);
    writing_ = false;
    if (!ok) {
      writes_.clear();
      FinishLocked(absl::CancelledError("the client stopped reading"));
    }
    if (!writes_.empty()) {
      StartNextWriteLocked();
    } else if (finish_requested_ && !finished_) {
      DoFinishLocked();
    }
  }

  void OnCancel() override { cancelled_.store(true, std::memory_order_relaxed); }

  void OnDone() override {
    bool registered;
    {
      absl::MutexLock lock(&mu_);
      done_ = true;
      registered = !removed_;
    }
    if (registered) owner_.Remove(this);
    bool destroy;
    {
      absl::MutexLock lock(&mu_);
      removed_ = true;
      destroy = TakeDeletionLocked();
    }
    if (destroy) delete this;
  }

 private:
  // ---- stream state (mu_) ----

  void FinishLocked(const absl::Status& status) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
    if (finish_requested_) return;
    finish_requested_ = true;
    final_status_ = status;
    // Stops a push still planning for a session nobody will read.
    cancelled_.store(true, std::memory_order_relaxed);
    if (!writing_) DoFinishLocked();
  }

  void DoFinishLocked() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
    finished_ = true;
    LogRequest("Navigate", map_name_,
               absl::StrFormat("session=%d messages=%d pushes=%d", id_, messages_,
                               pushes_),
               final_status_, opened_at_, RequestLabels{.planner = {}, .stream = true});
    Finish(ToGrpcStatus(final_status_));
  }

  void EnqueueLocked(v1::NavigateResponse response) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
    if (finish_requested_) return;
    response.set_session_id(id_);
    writes_.push_back(std::move(response));
    if (!writing_) StartNextWriteLocked();
  }

  void StartNextWriteLocked() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
    writing_ = true;
    current_write_ = std::move(writes_.front());
    writes_.pop_front();
    StartWrite(&current_write_);
  }

  // Ends one job's hold on the session.
  void Release() {
    bool destroy;
    {
      absl::MutexLock lock(&mu_);
      --outstanding_;
      destroy = TakeDeletionLocked();
    }
    if (destroy) delete this;
  }

  // True exactly once: when gRPC is done with the call, the registry no longer
  // lists the session and no job holds it.
  bool TakeDeletionLocked() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
    if (!done_ || !removed_ || outstanding_ > 0 || deleting_) return false;
    deleting_ = true;
    return true;
  }

  // ---- jobs (worker threads) ----

  void RunMessage(const v1::NavigateRequest& message) {
    v1::NavigateResponse response;
    absl::Status status;
    {
      absl::MutexLock plan_lock(&plan_mu_);
      status = Handle(message, &response);
    }
    {
      absl::MutexLock lock(&mu_);
      handling_ = false;
      ++messages_;
      if (!status.ok()) {
        FinishLocked(status);
      } else {
        EnqueueLocked(std::move(response));
        if (pending_end_.has_value()) {
          FinishLocked(*pending_end_);
        } else if (!finish_requested_) {
          StartRead(&request_);
        }
      }
    }
    Release();
  }

  void RunPush() {
    {
      absl::MutexLock lock(&mu_);
      // Cleared before planning so a version published meanwhile schedules
      // another push instead of being folded into this one unseen.
      push_pending_ = false;
    }
    v1::NavigateResponse response;
    bool changed = false;
    absl::Status status;
    {
      absl::MutexLock plan_lock(&plan_mu_);
      if (search_ != nullptr) status = Push(&response, &changed);
    }
    {
      absl::MutexLock lock(&mu_);
      if (!status.ok()) {
        EndWithLocked(status);
      } else if (changed) {
        ++pushes_;
        EnqueueLocked(std::move(response));
      }
    }
    Release();
  }

  void EndWithLocked(const absl::Status& status) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
    if (handling_) {
      if (!pending_end_.has_value()) pending_end_ = status;
      return;
    }
    FinishLocked(status);
  }

  // ---- navigation (plan_mu_) ----

  absl::Status Handle(const v1::NavigateRequest& message, v1::NavigateResponse* response)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(plan_mu_) {
    response->set_seq(message.seq());
    switch (message.kind_case()) {
      case v1::NavigateRequest::kOpen:
        if (search_ != nullptr) {
          return absl::InvalidArgumentError(absl::StrFormat(
              "message seq %d: the session is already open", message.seq()));
        }
        response->set_event(v1::NAVIGATE_EVENT_OPENED);
        PATHD_RETURN_IF_ERROR(Open(message.open()));
        break;
      case v1::NavigateRequest::kPose: {
        PATHD_RETURN_IF_ERROR(RequireOpen(message));
        response->set_event(v1::NAVIGATE_EVENT_MOVED);
        PATHD_ASSIGN_OR_RETURN(
            const Cell cell, CellFromPosition(message.pose(), *snapshot_->grid, "pose"));
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
        response->set_event(v1::NAVIGATE_EVENT_OBSERVED);
        PATHD_ASSIGN_OR_RETURN(uint64_t applied, Observe(message.observe()));
        response->set_applied_version(applied);
        break;
      }
      case v1::NavigateRequest::KIND_NOT_SET:
        return absl::InvalidArgumentError(absl::StrFormat(
            "message seq %d sets none of open, pose, observe", message.seq()));
    }
    return PlanInto(response->mutable_plan(), /*changed=*/nullptr);
  }

  absl::Status RequireOpen(const v1::NavigateRequest& message)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(plan_mu_) {
    if (search_ != nullptr) return absl::OkStatus();
    return absl::InvalidArgumentError(absl::StrFormat(
        "message seq %d: the first message of a session must be 'open'",
        message.seq()));
  }

  absl::Status Open(const v1::NavigateOpen& open) ABSL_EXCLUSIVE_LOCKS_REQUIRED(plan_mu_) {
    PATHD_ASSIGN_OR_RETURN(
        DecodedQuery decoded,
        DecodePlanQuery(WireQueryOf(open), owner_.store_,
                        QueryLimits{.max_expansions = owner_.options_.max_expansions}));
    snapshot_ = std::move(decoded.snapshot);
    const Grid& stored = *snapshot_->grid;
    // The session's search is its own D* Lite; the façade's rules still apply
    // (a stateful search: one goal, no via points).
    PATHD_RETURN_IF_ERROR(CheckPlanQuery(stored, /*stateful=*/true, &decoded.query));
    start_ = decoded.query.request.start;
    goal_ = decoded.query.request.goal;
    cost_ = decoded.query.request.cost;
    radius_cells_ = decoded.query.robot_radius_cells;
    max_expansions_ = decoded.query.max_expansions;
    PATHD_RETURN_IF_ERROR(ReserveMemory(stored));
    PATHD_ASSIGN_OR_RETURN(grid_, EffectiveGrid(*snapshot_));
    if (radius_cells_ > 0.0) {
      PATHD_RETURN_IF_ERROR(
          CheckRadiusEndpoints(stored, *grid_, radius_cells_, {{goal_, "goal"}}));
    }
    PATHD_ASSIGN_OR_RETURN(search_, DStarLite::Create(grid_, goal_, cost_));
    PATHD_RETURN_IF_ERROR(search_->SetStart(start_));
    {
      absl::MutexLock lock(&mu_);
      map_name_ = snapshot_->name;
    }
    return absl::OkStatus();
  }

  // Reserves the search state's estimated bytes before anything is built, so
  // sessions on a big map are refused instead of exhausting memory.
  absl::Status ReserveMemory(const Grid& grid) ABSL_EXCLUSIVE_LOCKS_REQUIRED(plan_mu_) {
    MemoryBudget* budget = owner_.options_.budget;
    if (budget == nullptr) return absl::OkStatus();
    const int64_t estimate =
        static_cast<int64_t>(grid.size()) * NavigationSessions::kSessionBytesPerCell;
    PATHD_ASSIGN_OR_RETURN(
        reservation_,
        budget->Reserve(MemoryBudget::Part::kSessions, caller_, estimate,
                        absl::StrFormat("a navigation session on the %d x %d map '%s'",
                                        grid.width(), grid.height(), snapshot_->name)));
    return absl::OkStatus();
  }

  // Applies sensed changes: to the shared map through the store (the same
  // validation and versioning as UpdateMap), or to this session's overlay.
  absl::StatusOr<uint64_t> Observe(const v1::NavigateObservation& observe)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(plan_mu_) {
    PATHD_ASSIGN_OR_RETURN(const std::vector<MapChange> changes,
                           MapChangesFromProto(observe.changes()));
    if (changes.empty()) {
      return absl::InvalidArgumentError("observation has no changes");
    }
    if (!observe.session_only()) {
      PATHD_RETURN_IF_ERROR(shared_observations_);
      PATHD_ASSIGN_OR_RETURN(const MapUpdateResult result,
                             owner_.store_.Update(snapshot_->name, changes, std::nullopt));
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
  // private cells over it, inflated by the robot radius (shared inflations
  // come from the cache; private ones are computed here).
  absl::StatusOr<std::shared_ptr<const Grid>> EffectiveGrid(const MapSnapshot& snapshot)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(plan_mu_) {
    if (overlay_.empty()) {
      if (radius_cells_ <= 0.0) return snapshot.grid;
      return owner_.inflation_.Get(snapshot.grid, radius_cells_);
    }
    Grid merged = *snapshot.grid;
    for (const auto& [index, cost] : overlay_) {
      merged.mutable_cells()[index] = cost;
    }
    if (radius_cells_ > 0.0) {
      PATHD_ASSIGN_OR_RETURN(merged, InflateObstacles(merged, radius_cells_));
    }
    return std::make_shared<const Grid>(std::move(merged));
  }

  // Moves the search to the map's current version (and the current overlay):
  // only the changed cells are handed to D* Lite.
  absl::Status Refresh(bool overlay_changed) ABSL_EXCLUSIVE_LOCKS_REQUIRED(plan_mu_) {
    absl::StatusOr<std::shared_ptr<const MapSnapshot>> latest =
        owner_.store_.Get(snapshot_->name);
    if (!latest.ok()) {
      return absl::NotFoundError(absl::StrFormat(
          "map '%s' was deleted during the navigation session", snapshot_->name));
    }
    if ((*latest)->version == snapshot_->version && !overlay_changed) {
      return absl::OkStatus();
    }
    const Grid& before = *grid_;
    if ((*latest)->grid->width() != before.width() ||
        (*latest)->grid->height() != before.height()) {
      return absl::FailedPreconditionError(absl::StrFormat(
          "map '%s' was replaced by a %d x %d map; open a new session",
          snapshot_->name, (*latest)->grid->width(), (*latest)->grid->height()));
    }
    PATHD_ASSIGN_OR_RETURN(std::shared_ptr<const Grid> after, EffectiveGrid(**latest));
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

  absl::Status Push(v1::NavigateResponse* response, bool* changed)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(plan_mu_) {
    const uint64_t version = snapshot_->version;
    PATHD_RETURN_IF_ERROR(Refresh(/*overlay_changed=*/false));
    if (snapshot_->version == version) return absl::OkStatus();
    response->set_event(v1::NAVIGATE_EVENT_MAP_CHANGED);
    return PlanInto(response->mutable_plan(), changed);
  }

  // Repairs the search, extracts the path from the robot's cell and fills
  // `plan`. `changed` (optional) says whether the path differs from the one
  // last sent. A robot standing on a blocked cell is an answer, not an error.
  absl::Status PlanInto(v1::PlanResponse* plan, bool* changed)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(plan_mu_) {
    const StopCondition stop(absl::InfiniteFuture(), &cancelled_, max_expansions_);
    absl::StatusOr<PlanResult> result = search_->Plan(stop);
    if (!result.ok() && result.status().code() != absl::StatusCode::kInvalidArgument) {
      return result.status();
    }
    PlanQuery query;
    query.planner = "dstar_lite";
    query.request = PlanRequest::Between(start_, goal_, cost_);
    query.requested_goal = goal_;
    query.robot_radius_cells = radius_cells_;
    query.max_expansions = max_expansions_;
    PlanAnswer answer;
    answer.goal = goal_;
    answer.source = PlanSource{grid_, snapshot_->version, plans_ > 0, repaired_cells_};
    if (result.ok()) answer.result = *std::move(result);
    SetSingleLeg(&answer);
    BuildPlanResponse(query, answer, /*expansion_limit_source=*/"", plan);
    if (!result.ok()) plan->set_reason(std::string(result.status().message()));
    repaired_cells_ = 0;
    ++plans_;
    std::vector<Cell> path = std::move(answer.result.path);
    if (changed != nullptr) *changed = path != last_path_;
    last_path_ = std::move(path);
    // A private grid (overlay) is a copy of the map; map nodes ~48 bytes.
    const int64_t bytes = static_cast<int64_t>(
        search_->MemoryBytes() + overlay_.size() * 48 +
        (overlay_.empty() ? 0 : grid_->size()));
    bytes_.store(bytes, std::memory_order_relaxed);
    reservation_.Update(bytes);
    return absl::OkStatus();
  }

  // First, so it is destroyed last: the bytes it returns (and the trim it
  // may trigger) come after every other member is freed.
  MemoryBudget::Reservation reservation_;
  NavigationSessions& owner_;
  const uint64_t id_;
  // Whose share of the memory budget the session counts against.
  const std::string caller_;
  const absl::Time opened_at_;
  // What a shared observation gets: OK, or the caller's PERMISSION_DENIED.
  const absl::Status shared_observations_;
  std::atomic<bool> cancelled_{false};
  std::atomic<int64_t> bytes_{0};

  mutable absl::Mutex mu_;
  std::string map_name_ ABSL_GUARDED_BY(mu_);
  absl::Time last_activity_ ABSL_GUARDED_BY(mu_);
  // Owned by gRPC between StartRead and OnReadDone.
  v1::NavigateRequest request_;
  // A message job is queued or running; the next read starts when it ends.
  bool handling_ ABSL_GUARDED_BY(mu_) = false;
  bool push_pending_ ABSL_GUARDED_BY(mu_) = false;
  std::optional<absl::Status> pending_end_ ABSL_GUARDED_BY(mu_);
  std::deque<v1::NavigateResponse> writes_ ABSL_GUARDED_BY(mu_);
  // Owned by gRPC between StartWrite and OnWriteDone.
  v1::NavigateResponse current_write_;
  bool writing_ ABSL_GUARDED_BY(mu_) = false;
  bool finish_requested_ ABSL_GUARDED_BY(mu_) = false;
  bool finished_ ABSL_GUARDED_BY(mu_) = false;
  absl::Status final_status_ ABSL_GUARDED_BY(mu_);
  int64_t messages_ ABSL_GUARDED_BY(mu_) = 0;
  int64_t pushes_ ABSL_GUARDED_BY(mu_) = 0;
  // Lifetime: gRPC's OnDone ran, the registry dropped us, pool jobs holding us.
  bool done_ ABSL_GUARDED_BY(mu_) = false;
  bool removed_ ABSL_GUARDED_BY(mu_) = false;
  int outstanding_ ABSL_GUARDED_BY(mu_) = 0;
  bool deleting_ ABSL_GUARDED_BY(mu_) = false;

  absl::Mutex plan_mu_;
  std::shared_ptr<const MapSnapshot> snapshot_ ABSL_GUARDED_BY(plan_mu_);
  std::shared_ptr<const Grid> grid_ ABSL_GUARDED_BY(plan_mu_);
  std::unique_ptr<DStarLite> search_ ABSL_GUARDED_BY(plan_mu_);
  // Session-only cell costs (cell index -> cost), laid over every version.
  std::map<size_t, uint8_t> overlay_ ABSL_GUARDED_BY(plan_mu_);
  Cell start_ ABSL_GUARDED_BY(plan_mu_);
  Cell goal_ ABSL_GUARDED_BY(plan_mu_);
  CostParams cost_ ABSL_GUARDED_BY(plan_mu_);
  double radius_cells_ ABSL_GUARDED_BY(plan_mu_) = 0.0;
  int64_t max_expansions_ ABSL_GUARDED_BY(plan_mu_) = 0;
  int64_t repaired_cells_ ABSL_GUARDED_BY(plan_mu_) = 0;
  int64_t plans_ ABSL_GUARDED_BY(plan_mu_) = 0;
  std::vector<Cell> last_path_ ABSL_GUARDED_BY(plan_mu_);
};

NavigationSessions::NavigationSessions(MapStore& store, WorkerPool& pool,
                                       InflationCache& inflation, Options options)
    : store_(store), pool_(pool), inflation_(inflation), options_(options) {
  store_.AddListener(
      [this](std::string_view name, const std::shared_ptr<const MapSnapshot>& snapshot) {
        OnMapChanged(name, snapshot);
      });
  reaper_ = std::thread([this] { ReapIdle(); });
}

NavigationSessions::~NavigationSessions() {
  {
    absl::MutexLock lock(&mu_);
    stopping_ = true;
    // gRPC runs OnDone (which unregisters) before Server::Wait returns; the
    // bounded wait only guards against a caller that skipped the shutdown.
    auto none_left = [this]() ABSL_SHARED_LOCKS_REQUIRED(mu_) { return sessions_.empty(); };
    if (!mu_.AwaitWithTimeout(absl::Condition(&none_left), absl::Seconds(10))) {
      spdlog::error("{} navigation session(s) still open at destruction", sessions_.size());
    }
  }
  reaper_.join();
}

void NavigationSessions::Shutdown() {
  absl::MutexLock lock(&mu_);
  stopping_ = true;
  for (const auto& [id, session] : sessions_) {
    session->EndWith(absl::UnavailableError("server is shutting down"));
  }
}

grpc::ServerBidiReactor<v1::NavigateRequest, v1::NavigateResponse>*
NavigationSessions::Start(grpc::CallbackServerContext* context,
                          absl::Status shared_observations) {
  uint64_t id;
  {
    absl::MutexLock lock(&mu_);
    id = next_id_++;
  }
  std::string caller =
      options_.budget != nullptr ? options_.budget->CallerOf(*context) : std::string();
  auto* session = new NavigationSession(*this, id, std::move(shared_observations),
                                        std::move(caller));
  session->Begin(Add(session));
  return session;
}

absl::Status NavigationSessions::Add(NavigationSession* session) {
  absl::MutexLock lock(&mu_);
  if (stopping_) return absl::UnavailableError("server is shutting down");
  if (sessions_.size() >= options_.max_sessions) {
    return absl::ResourceExhaustedError(absl::StrFormat(
        "%d navigation sessions are open (--max_sessions); close one or retry later",
        sessions_.size()));
  }
  sessions_.emplace(session->id(), session);
  return absl::OkStatus();
}

void NavigationSessions::Remove(NavigationSession* session) {
  absl::MutexLock lock(&mu_);
  sessions_.erase(session->id());
}

void NavigationSessions::OnMapChanged(std::string_view name,
                                      const std::shared_ptr<const MapSnapshot>& snapshot) {
  // Holding mu_ keeps every listed session alive (deletion waits for Remove).
  absl::MutexLock lock(&mu_);
  for (const auto& [id, session] : sessions_) {
    if (!session->OnMap(name)) continue;
    if (snapshot == nullptr) {
      session->EndWith(absl::NotFoundError(absl::StrFormat(
          "map '%s' was deleted during the navigation session", name)));
    } else {
      session->SchedulePush();
    }
  }
}

void NavigationSessions::ReapIdle() {
  const absl::Duration interval =
      std::clamp(options_.idle_timeout / 4, absl::Milliseconds(10), absl::Seconds(1));
  absl::MutexLock lock(&mu_);
  while (!stopping_) {
    mu_.AwaitWithTimeout(absl::Condition(&stopping_), interval);
    const absl::Time now = absl::Now();
    for (const auto& [id, session] : sessions_) {
      session->EndIfIdle(now, options_.idle_timeout);
    }
  }
}

int64_t NavigationSessions::count() const {
  absl::MutexLock lock(&mu_);
  return static_cast<int64_t>(sessions_.size());
}

int64_t NavigationSessions::bytes() const {
  absl::MutexLock lock(&mu_);
  int64_t total = 0;
  for (const auto& [id, session] : sessions_) total += session->bytes();
  return total;
}

}  // namespace pathd::server
