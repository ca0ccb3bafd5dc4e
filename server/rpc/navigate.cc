// Navigate sessions. Each session is a gRPC bidi reactor plus a D* Lite
// search. Two locks per session: `mu_` guards the stream's state (reads,
// the write queue, finishing, lifetime) and is only ever held briefly; the
// longer `plan_mu_` guards the search and is held while planning on a worker.
// Lock order: owner's mu_ -> session mu_; plan_mu_ -> session mu_. gRPC never
// runs a user reactor's reactions inline from Start*/Finish (they are not
// InternalInlineable), so those may be called with mu_ held.
//
// Control sessions (navigate_control.h) answer a state message on the thread
// that read it, without plan_mu_: the cycle is bounded work and follows the
// newest published global path, while the D* Lite replans the robot's moves
// and the map's changes call for run as coalesced jobs on the worker pool.
#include "server/rpc/navigate.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <deque>
#include <functional>
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
#include "proto/path_codec.h"
#include "server/convert.h"
#include "server/grpc_status.h"
#include "server/incremental_cache.h"
#include "server/request_log.h"
#include "server/rpc/navigate_search.h"

namespace pathd::server {

using NavigateReactor = grpc::ServerBidiReactor<v1::NavigateRequest, v1::NavigateResponse>;

class NavigationSession final : public NavigateReactor {
 public:
  NavigationSession(NavigationSessions& owner, uint64_t id,
                    absl::Status shared_observations, std::string caller)
      : owner_(owner),
        id_(id),
        opened_at_(absl::Now()),
        search_(NavigationSearch::Deps{owner.store_, owner.inflation_,
                                       owner.options_.budget,
                                       owner.options_.max_expansions,
                                       owner.options_.derived, &owner.robots_, id,
                                       &owner.fleets_,
                                       [this](v1::NavigateResponse push) {
                                         PushFleet(std::move(push));
                                       }},
                std::move(caller), std::move(shared_observations), &cancelled_,
                &bytes_, [this](const std::string& map_name) {
                  absl::MutexLock lock(&mu_);
                  map_name_ = map_name;
                }) {
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

  // ListSessions' entry: the map, the last answer or push, the ages.
  // `map` empty matches every session; false when this one is not listed.
  bool Describe(std::string_view map, absl::Time now, v1::SessionInfo& info) const {
    absl::MutexLock lock(&mu_);
    if (!map.empty() && map_name_ != map) return false;
    info.set_session_id(id_);
    info.set_map(map_name_);
    if (last_sent_.has_value()) {
      *info.mutable_last() = *last_sent_;
      // Listed readable whatever the session asked for (its path_encoding
      // shapes its own stream, not what observers such as the viewer read);
      // the server's own bytes always decode.
      if (info.last().has_plan()) {
        UnpackPlanPath(info.mutable_last()->mutable_plan()).IgnoreError();
      }
    }
    info.set_age_seconds(absl::ToDoubleSeconds(now - opened_at_));
    info.set_idle_seconds(absl::ToDoubleSeconds(now - last_activity_));
    return true;
  }

  // A new version of this session's map: repair the search and push the path
  // if it changed. Coalesced: one pending push covers any number of versions.
  void SchedulePush() {
    absl::MutexLock lock(&mu_);
    if (control_ != nullptr) {
      // Control answers carry the repaired path; nothing is pushed.
      ScheduleReplanLocked(std::nullopt);
      return;
    }
    if (push_pending_ || finish_requested_ || done_) return;
    // A refused push is not worth failing the session for: its next message
    // repairs anyway.
    SubmitBackgroundLocked(&push_pending_,
                           [this](SearchScratch& scratch) { RunPush(scratch); });
  }

  // A fleet session's push, or its answer to a message, from its group
  // (FleetGroups holds the group's lock: queue only).
  void PushFleet(v1::NavigateResponse push) {
    absl::MutexLock lock(&mu_);
    if (finish_requested_ || done_) return;
    if (push.event() == v1::NAVIGATE_EVENT_FLEET) ++pushes_;
    EnqueueLocked(std::move(push));
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
    std::shared_ptr<ControlSession> control;
    v1::NavigateRequest state;
    {
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
      if (control_ == nullptr || request_.kind_case() != v1::NavigateRequest::kState) {
        SubmitMessageLocked();
        return;
      }
      control = control_;
      state = std::move(request_);
      request_.Clear();
    }
    RunControl(state, *control);
  }

 private:
  // Queues a message job for request_ (handling_ set and outstanding_ counted).
  void SubmitMessageLocked() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
    auto message = std::make_shared<v1::NavigateRequest>(std::move(request_));
    request_.Clear();
    const absl::Status submitted = owner_.pool_.Submit(MakeJob(
        [this, message](SearchScratch& scratch) { RunMessage(*message, scratch); },
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

  // One control cycle, on the reading thread (handling_ set, outstanding_
  // counted): answers the state and asks for a replan when the robot moved
  // to another cell.
  void RunControl(const v1::NavigateRequest& message, ControlSession& control) {
    const SteadyTime arrived = std::chrono::steady_clock::now();
    v1::NavigateResponse response;
    response.set_seq(message.seq());
    Cell cell;
    std::optional<DetourRequest> detour;
    const absl::Status status = control.Cycle(message.state(), &response, &cell, &detour);
    owner_.control_cycles_.Observe(
        std::chrono::duration<double>(std::chrono::steady_clock::now() - arrived).count());
    {
      absl::MutexLock lock(&mu_);
      handling_ = false;
      ++messages_;
      if (!status.ok()) {
        FinishLocked(status);
      } else {
        EnqueueLocked(std::move(response));
        if (detour.has_value()) {
          // Planned from wherever the robot stands, even its last cell.
          detour_ = std::move(detour);
          planned_cell_.reset();
        }
        ScheduleReplanLocked(cell);
        if (pending_end_.has_value()) {
          FinishLocked(*pending_end_);
        } else if (!finish_requested_) {
          StartRead(&request_);
        }
      }
    }
    Release();
  }

  // Control sessions: a D* Lite replan from `robot` (nullopt: the map
  // changed) on the worker pool, unless the robot is still in the cell the
  // last replan planned from and that replan finished. Coalesced: a pending
  // replan takes the newest cell.
  void ScheduleReplanLocked(std::optional<Cell> robot) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
    if (robot.has_value()) {
      if (planned_cell_.has_value() && *planned_cell_ == *robot && !replan_incomplete_) return;
      replan_cell_ = robot;
    }
    if (replan_pending_ || finish_requested_ || done_) return;
    if (!SubmitBackgroundLocked(&replan_pending_,
                                [this](SearchScratch&) { RunControlReplan(); })) {
      // The next state asks again.
      replan_incomplete_ = true;
    }
  }

  // Queues `run` on the worker pool as a job of the session besides its
  // messages (a push, a control replan): `*pending` (a flag guarded by mu_)
  // is set until the job clears it or fails. False when the pool refused it.
  bool SubmitBackgroundLocked(bool* pending, std::function<void(SearchScratch&)> run)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
    *pending = true;
    ++outstanding_;
    const absl::Status submitted = owner_.pool_.Submit(MakeJob(
        std::move(run), [this] { Release(); },
        [this, pending](const absl::Status& failed) {
          // The search may be half-repaired: the session cannot go on.
          {
            absl::MutexLock lock(&mu_);
            *pending = false;
            EndWithLocked(failed);
          }
          Release();
        }));
    if (submitted.ok()) return true;
    *pending = false;
    --outstanding_;
    return false;
  }

  void RunControlReplan() {
    std::optional<Cell> robot;
    std::optional<DetourRequest> detour;
    {
      absl::MutexLock lock(&mu_);
      replan_pending_ = false;
      robot = replan_cell_;
      planned_cell_ = replan_cell_;
      detour = std::exchange(detour_, std::nullopt);
    }
    bool incomplete = false;
    absl::Status status;
    {
      absl::MutexLock plan_lock(&plan_mu_);
      status = search_.ReplanControl(robot, &incomplete, std::move(detour));
    }
    {
      absl::MutexLock lock(&mu_);
      replan_incomplete_ = incomplete;
      if (!status.ok()) EndWithLocked(status);
    }
    Release();
  }

 public:
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
      // Whatever ended the call, its robot leaves while the registry is
      // certainly alive (the owner waits for Remove below).
      if (control_ != nullptr) owner_.robots_.Remove(map_name_, id_);
    }
    // A fleet session's robot leaves its group (no lock held: the group may
    // push to other sessions while it replans).
    owner_.fleets_.Remove(id_);
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
    // A closed session's robot is no obstacle from now on (not only once
    // gRPC is done with the call).
    if (control_ != nullptr) owner_.robots_.Remove(map_name_, id_);
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
    last_sent_ = response;
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

  void RunMessage(const v1::NavigateRequest& message, SearchScratch& scratch) {
    v1::NavigateResponse response;
    absl::Status status;
    std::shared_ptr<ControlSession> control;
    bool queued;
    {
      absl::MutexLock plan_lock(&plan_mu_);
      status = search_.Handle(message, scratch, &response);
      control = search_.control();
      queued = search_.TakeAnswerQueued();
    }
    {
      absl::MutexLock lock(&mu_);
      control_ = std::move(control);
      handling_ = false;
      ++messages_;
      if (!status.ok()) {
        FinishLocked(status);
      } else {
        if (!queued) EnqueueLocked(std::move(response));
        if (pending_end_.has_value()) {
          FinishLocked(*pending_end_);
        } else if (!finish_requested_) {
          StartRead(&request_);
        }
      }
    }
    Release();
  }

  void RunPush(SearchScratch& scratch) {
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
      if (search_.is_open()) status = search_.Push(scratch, &response, &changed);
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

  NavigationSessions& owner_;
  const uint64_t id_;
  const absl::Time opened_at_;
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
  // Control sessions: the control half (set once the open succeeded), and
  // the replans: one queued, the robot's newest cell for it, the cell the
  // last one planned from, and whether it ran out of its budget.
  std::shared_ptr<ControlSession> control_ ABSL_GUARDED_BY(mu_);
  bool replan_pending_ ABSL_GUARDED_BY(mu_) = false;
  std::optional<Cell> replan_cell_ ABSL_GUARDED_BY(mu_);
  std::optional<Cell> planned_cell_ ABSL_GUARDED_BY(mu_);
  bool replan_incomplete_ ABSL_GUARDED_BY(mu_) = false;
  // A stalled robot's detour, for the next control replan.
  std::optional<DetourRequest> detour_ ABSL_GUARDED_BY(mu_);
  std::optional<absl::Status> pending_end_ ABSL_GUARDED_BY(mu_);
  std::deque<v1::NavigateResponse> writes_ ABSL_GUARDED_BY(mu_);
  // The last answer or push queued, for ListSessions.
  std::optional<v1::NavigateResponse> last_sent_ ABSL_GUARDED_BY(mu_);
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
  // The D* Lite search and the session's reservation; declared last so it is
  // destroyed first, while the flags it points to still exist.
  NavigationSearch search_ ABSL_GUARDED_BY(plan_mu_);
};

NavigationSessions::NavigationSessions(MapStore& store, WorkerPool& pool,
                                       InflationCache& inflation, Options options)
    : store_(store),
      pool_(pool),
      inflation_(inflation),
      options_(options),
      fleets_(store, inflation, pool) {
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

void NavigationSessions::List(std::string_view map, v1::ListSessionsResponse& out) const {
  const absl::Time now = absl::Now();
  // Holding mu_ keeps every listed session alive (deletion waits for Remove).
  absl::MutexLock lock(&mu_);
  for (const auto& [id, session] : sessions_) {
    v1::SessionInfo info;
    if (session->Describe(map, now, info)) *out.add_sessions() = std::move(info);
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
