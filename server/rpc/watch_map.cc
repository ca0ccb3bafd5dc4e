// WatchMap streams. Each stream is a gRPC write reactor with a bounded event
// queue filled by the store listener. Lock order: MapWatchers::mu_ ->
// MapWatcher::mu_. gRPC never runs a user reactor's reactions inline from
// StartWrite/Finish, so those are called with the watcher's mu_ held.
#include "server/rpc/watch_map.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <optional>
#include <utility>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "server/convert.h"
#include "server/grpc_status.h"
#include "server/request_log.h"

namespace pathd::server {
namespace {

// Wire bytes of one ChangedRect besides its costs: the CellRect's four
// varints and the tags and lengths around them, rounded up.
constexpr size_t kRectOverheadBytes = 32;
// Wire bytes of a whole-map event besides its cells (kind, version, MapInfo
// with the name), roughly; only compared against an UPDATED event's size.
constexpr size_t kFullEventOverheadBytes = 64;

}  // namespace

std::vector<CellRectangle> CoverCells(absl::Span<const Cell> cells) {
  std::vector<CellRectangle> rects;
  // Indices into `rects` of the rectangles that reach the previous row,
  // sorted by x_min (runs are found left to right); only these can grow.
  std::vector<size_t> open, next_open;
  size_t open_at = 0;
  size_t i = 0;
  while (i < cells.size()) {
    const int32_t y = cells[i].y;
    if (i == 0 || cells[i - 1].y != y) {
      // A new row: keep only the rectangles that ended exactly one row up.
      open.clear();
      for (size_t index : next_open) {
        if (rects[index].y_max == y - 1) open.push_back(index);
      }
      next_open.clear();
      open_at = 0;
    }
    size_t j = i + 1;
    while (j < cells.size() && cells[j].y == y &&
           cells[j].x == cells[j - 1].x + 1) {
      ++j;
    }
    const int32_t x_min = cells[i].x;
    const int32_t x_max = cells[j - 1].x;
    while (open_at < open.size() && rects[open[open_at]].x_min < x_min)
      ++open_at;
    if (open_at < open.size() && rects[open[open_at]].x_min == x_min &&
        rects[open[open_at]].x_max == x_max) {
      rects[open[open_at]].y_max = y;
      next_open.push_back(open[open_at]);
    } else {
      next_open.push_back(rects.size());
      rects.push_back(CellRectangle{x_min, y, x_max, y});
    }
    i = j;
  }
  // Creation order is by first row, then column: already sorted.
  return rects;
}

std::shared_ptr<const v1::MapEvent> MakeUpdatedEvent(
    const MapSnapshot& snapshot) {
  if (!snapshot.changes_known) return nullptr;
  const Grid& grid = *snapshot.grid;
  const std::vector<CellRectangle> rects = CoverCells(snapshot.changed_cells);
  const size_t bytes =
      snapshot.changed_cells.size() + rects.size() * kRectOverheadBytes;
  if (bytes > grid.size() + snapshot.name.size() + kFullEventOverheadBytes) {
    return nullptr;
  }
  auto event = std::make_shared<v1::MapEvent>();
  event->set_kind(v1::MAP_EVENT_KIND_UPDATED);
  event->set_version(snapshot.version);
  for (const CellRectangle& r : rects) {
    v1::ChangedRect* change = event->add_changes();
    change->mutable_rect()->set_x_min(r.x_min);
    change->mutable_rect()->set_y_min(r.y_min);
    change->mutable_rect()->set_x_max(r.x_max);
    change->mutable_rect()->set_y_max(r.y_max);
    std::string* costs = change->mutable_costs();
    costs->reserve(static_cast<size_t>(r.x_max - r.x_min + 1) *
                   static_cast<size_t>(r.y_max - r.y_min + 1));
    for (int32_t y = r.y_min; y <= r.y_max; ++y) {
      for (int32_t x = r.x_min; x <= r.x_max; ++x) {
        costs->push_back(static_cast<char>(grid.cost(x, y)));
      }
    }
  }
  return event;
}

// ---- MapEventQueue ----

MapEventQueue::MapEventQueue(size_t max_events, const MapSnapshot& current,
                             size_t max_bytes)
    : max_events_(std::max<size_t>(max_events, 1)),
      max_bytes_(max_bytes),
      last_version_(current.version),
      map_id_(current.map_id) {}

void MapEventQueue::PushFull(std::shared_ptr<const MapSnapshot> snapshot,
                             v1::MapEventKind kind) {
  last_version_ = snapshot->version;
  map_id_ = snapshot->map_id;
  const size_t bytes = snapshot->grid->size();
  Push(Item{nullptr, snapshot, kind, bytes}, snapshot);
}

void MapEventQueue::Offer(std::shared_ptr<const MapSnapshot> snapshot,
                          std::shared_ptr<const v1::MapEvent> updated) {
  // Already covered by a whole-map event of a newer version.
  if (snapshot->version <= last_version_) return;
  if (snapshot->map_id != map_id_) {
    PushFull(std::move(snapshot), v1::MAP_EVENT_KIND_REPLACED);
    return;
  }
  if (snapshot->version != last_version_ + 1 || updated == nullptr) {
    PushFull(std::move(snapshot), v1::MAP_EVENT_KIND_RESYNC);
    return;
  }
  last_version_ = snapshot->version;
  const size_t bytes = updated->ByteSizeLong();
  Push(Item{std::move(updated), nullptr, v1::MAP_EVENT_KIND_UPDATED, bytes},
       snapshot);
}

void MapEventQueue::PushDeleted() {
  auto event = std::make_shared<v1::MapEvent>();
  event->set_kind(v1::MAP_EVENT_KIND_DELETED);
  event->set_version(last_version_);
  // Never dropped for a RESYNC: there is no map left to send.
  items_.push_back(
      Item{std::move(event), nullptr, v1::MAP_EVENT_KIND_DELETED, 0});
}

void MapEventQueue::Push(Item item,
                         const std::shared_ptr<const MapSnapshot>& snapshot) {
  const size_t max_bytes = max_bytes_ > 0
                               ? max_bytes_
                               : std::max(snapshot->grid->size(), kMinBacklogBytes);
  if (!items_.empty() &&
      (items_.size() >= max_events_ || bytes_ + item.bytes > max_bytes)) {
    // The client must replace its copy either way; REPLACED tells it the
    // map's size or pose may have changed within the dropped events.
    v1::MapEventKind kind = item.kind == v1::MAP_EVENT_KIND_REPLACED
                                ? v1::MAP_EVENT_KIND_REPLACED
                                : v1::MAP_EVENT_KIND_RESYNC;
    for (const Item& dropped : items_) {
      if (dropped.kind == v1::MAP_EVENT_KIND_REPLACED) kind = dropped.kind;
    }
    items_.clear();
    bytes_ = 0;
    ++backlog_drops_;
    item = Item{nullptr, snapshot, kind, snapshot->grid->size()};
  }
  bytes_ += item.bytes;
  items_.push_back(std::move(item));
}

std::shared_ptr<const v1::MapEvent> MapEventQueue::Pop() {
  Item item = std::move(items_.front());
  items_.pop_front();
  bytes_ -= item.bytes;
  if (item.event != nullptr) return std::move(item.event);
  auto event = std::make_shared<v1::MapEvent>();
  event->set_kind(item.kind);
  event->set_version(item.full->version);
  FillMapInfo(*item.full, event->mutable_info());
  const std::vector<uint8_t>& cells = item.full->grid->cells();
  event->set_cells(reinterpret_cast<const char*>(cells.data()), cells.size());
  return event;
}

// ---- MapWatcher ----

class MapWatcher final : public grpc::ServerWriteReactor<v1::MapEvent> {
 public:
  MapWatcher(MapWatchers& owner, std::string name)
      : owner_(owner), name_(std::move(name)), opened_at_(absl::Now()) {}

  const std::string& name() const { return name_; }

  // Starts the stream at `current`; called under the owner's mu_ so no
  // version published after `current` can be notified before this runs.
  // `reservation` is what the stream holds in the memory budget.
  void Begin(std::shared_ptr<const MapSnapshot> current, uint64_t from_version,
             size_t max_events, MemoryBudget::Reservation reservation) {
    absl::MutexLock lock(&mu_);
    reservation_ = std::move(reservation);
    queue_.emplace(max_events, *current, owner_.options_.backlog_bytes);
    if (from_version != current->version) {
      queue_->PushFull(std::move(current), v1::MAP_EVENT_KIND_RESYNC);
      StartNextWriteLocked();
    }
  }

  void Refuse(const absl::Status& status) {
    absl::MutexLock lock(&mu_);
    FinishLocked(status, /*drain=*/false);
  }

  void Offer(const std::shared_ptr<const MapSnapshot>& snapshot,
             const std::shared_ptr<const v1::MapEvent>& updated) {
    absl::MutexLock lock(&mu_);
    if (finish_requested_) return;
    if (snapshot->map_id != queue_->map_id() && owner_.options_.budget != nullptr) {
      // Replaced: the worst case follows the new map's size.
      if (absl::Status fits = reservation_.Resize(MapWatchers::WatcherBytes(
              snapshot->grid->size(), owner_.options_.backlog_bytes));
          !fits.ok()) {
        FinishLocked(fits, /*drain=*/false);
        return;
      }
    }
    const int64_t drops_before = queue_->backlog_drops();
    queue_->Offer(snapshot, updated);
    if (queue_->backlog_drops() != drops_before) {
      ++backlog_drops_;
      owner_.backlog_drops_.fetch_add(1, std::memory_order_relaxed);
    }
    if (!writing_) StartNextWriteLocked();
  }

  // The map `name_` was deleted; `live_map_id` is the id of a map now stored
  // under that name, if any.
  void Deleted(std::optional<uint64_t> live_map_id) {
    absl::MutexLock lock(&mu_);
    if (finish_requested_) return;
    // A late notification of an earlier incarnation's deletion: ours lives.
    if (live_map_id == queue_->map_id()) return;
    queue_->PushDeleted();
    FinishLocked(absl::OkStatus(), /*drain=*/true);
  }

  void EndWith(const absl::Status& status) {
    absl::MutexLock lock(&mu_);
    FinishLocked(status, /*drain=*/false);
  }

  void OnWriteDone(bool ok) override {
    absl::MutexLock lock(&mu_);
    writing_ = false;
    current_.reset();
    if (!ok) {
      FinishLocked(absl::CancelledError("the client stopped reading"), false);
    } else {
      ++events_;
    }
    if (queue_.has_value() && !queue_->empty()) {
      StartNextWriteLocked();
    } else if (finish_requested_ && !finished_) {
      DoFinishLocked();
    }
  }

  void OnCancel() override {
    absl::MutexLock lock(&mu_);
    FinishLocked(absl::CancelledError("the client cancelled the watch"), false);
  }

  void OnDone() override {
    owner_.Remove(this);
    delete this;
  }

 private:
  // With `drain`, queued events are still written before the status.
  void FinishLocked(const absl::Status& status, bool drain)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
    if (finish_requested_) return;
    finish_requested_ = true;
    final_status_ = status;
    if (!drain) queue_.reset();
    if (writing_) return;  // OnWriteDone continues
    if (queue_.has_value() && !queue_->empty()) {
      StartNextWriteLocked();
    } else {
      DoFinishLocked();
    }
  }

  void DoFinishLocked() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
    finished_ = true;
    LogRequest(
        "WatchMap", name_,
        absl::StrFormat("events=%d backlog_drops=%d", events_, backlog_drops_),
        final_status_, opened_at_, RequestLabels{.planner = {}, .stream = true});
    Finish(ToGrpcStatus(final_status_));
  }

  void StartNextWriteLocked() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
    std::shared_ptr<const v1::MapEvent> next = queue_->Pop();
    const int64_t max_bytes = owner_.options_.max_message_bytes;
    if (const size_t bytes = next->ByteSizeLong();
        max_bytes > 0 && bytes > static_cast<size_t>(max_bytes)) {
      // gRPC would fail the write with a message naming neither the event
      // nor the flag; the client cannot keep a copy without it, so end here.
      queue_.reset();
      finish_requested_ = true;
      final_status_ = absl::ResourceExhaustedError(absl::StrFormat(
          "the %s event of map '%s' version %d is %d bytes, more than the "
          "limit of %d bytes (--max_message_bytes)",
          v1::MapEventKind_Name(next->kind()), name_, next->version(), bytes,
          max_bytes));
      DoFinishLocked();
      return;
    }
    writing_ = true;
    current_ = std::move(next);
    StartWrite(current_.get());
  }

  // First, so it is destroyed last: its bytes are returned (and memory
  // trimmed) after the queue and the event in flight are freed.
  MemoryBudget::Reservation reservation_;
  MapWatchers& owner_;
  const std::string name_;
  const absl::Time opened_at_;

  absl::Mutex mu_;
  // Empty until Begin and after an end that drops what was queued.
  std::optional<MapEventQueue> queue_ ABSL_GUARDED_BY(mu_);
  // The event being written; gRPC reads it until OnWriteDone.
  std::shared_ptr<const v1::MapEvent> current_ ABSL_GUARDED_BY(mu_);
  bool writing_ ABSL_GUARDED_BY(mu_) = false;
  bool finish_requested_ ABSL_GUARDED_BY(mu_) = false;
  bool finished_ ABSL_GUARDED_BY(mu_) = false;
  absl::Status final_status_ ABSL_GUARDED_BY(mu_);
  int64_t events_ ABSL_GUARDED_BY(mu_) = 0;
  int64_t backlog_drops_ ABSL_GUARDED_BY(mu_) = 0;
};

// ---- MapWatchers ----

int64_t MapWatchers::WatcherBytes(size_t map_bytes, size_t backlog_bytes) {
  const size_t backlog = backlog_bytes > 0
                             ? std::max(backlog_bytes, map_bytes)
                             : std::max(map_bytes, MapEventQueue::kMinBacklogBytes);
  return static_cast<int64_t>(2 * map_bytes + backlog);
}

MapWatchers::MapWatchers(MapStore& store, Options options)
    : store_(store), options_(options) {
  store_.AddListener(
      [this](std::string_view name,
             const std::shared_ptr<const MapSnapshot>& snapshot) {
        OnMapChanged(name, snapshot);
      });
}

MapWatchers::~MapWatchers() {
  absl::MutexLock lock(&mu_);
  // gRPC runs OnDone (which unregisters) before Server::Wait returns; the
  // bounded wait only guards against a caller that skipped the shutdown.
  auto none_left = [this]()
                       ABSL_SHARED_LOCKS_REQUIRED(mu_) { return count_ == 0; };
  if (!mu_.AwaitWithTimeout(absl::Condition(&none_left), absl::Seconds(10))) {
    spdlog::error("{} WatchMap stream(s) still open at destruction", count_);
  }
}

grpc::ServerWriteReactor<v1::MapEvent>* MapWatchers::Start(
    grpc::CallbackServerContext* context,
    const v1::WatchMapRequest& request) {
  auto* watcher = new MapWatcher(*this, request.name());
  absl::MutexLock lock(&mu_);
  if (stopping_) {
    watcher->Refuse(absl::UnavailableError("server is shutting down"));
    return watcher;
  }
  if (absl::Status valid = MapStore::ValidateName(request.name());
      !valid.ok()) {
    watcher->Refuse(valid);
    return watcher;
  }
  // Under mu_: a version installed after this Get is notified only once the
  // watcher is registered, and one installed before is at most `current`.
  absl::StatusOr<std::shared_ptr<const MapSnapshot>> current =
      store_.Get(request.name());
  if (!current.ok()) {
    watcher->Refuse(current.status());
    return watcher;
  }
  MemoryBudget::Reservation reservation;
  if (options_.budget != nullptr) {
    const Grid& grid = *(*current)->grid;
    absl::StatusOr<MemoryBudget::Reservation> reserved = options_.budget->Reserve(
        MemoryBudget::Part::kWatchers, options_.budget->CallerOf(*context),
        WatcherBytes(grid.size(), options_.backlog_bytes),
        absl::StrFormat("a WatchMap stream of the %d x %d map '%s'", grid.width(),
                        grid.height(), request.name()));
    if (!reserved.ok()) {
      watcher->Refuse(reserved.status());
      return watcher;
    }
    reservation = *std::move(reserved);
  }
  watchers_[request.name()].insert(watcher);
  ++count_;
  watcher->Begin(*std::move(current), request.from_version(),
                 options_.max_queued_events, std::move(reservation));
  return watcher;
}

void MapWatchers::Remove(MapWatcher* watcher) {
  absl::MutexLock lock(&mu_);
  auto it = watchers_.find(watcher->name());
  // A refused watcher was never registered.
  if (it == watchers_.end() || it->second.erase(watcher) == 0) return;
  if (it->second.empty()) watchers_.erase(it);
  --count_;
}

void MapWatchers::Shutdown() {
  absl::MutexLock lock(&mu_);
  stopping_ = true;
  for (const auto& [name, set] : watchers_) {
    for (MapWatcher* watcher : set) {
      watcher->EndWith(absl::UnavailableError("server is shutting down"));
    }
  }
}

void MapWatchers::OnMapChanged(
    std::string_view name, const std::shared_ptr<const MapSnapshot>& snapshot) {
  {
    absl::MutexLock lock(&mu_);
    if (watchers_.find(name) == watchers_.end()) return;
  }
  // Built outside mu_ so other maps' notifications do not wait for it. A
  // watcher registering meanwhile read a current version at least this new,
  // so it ignores this one.
  std::shared_ptr<const v1::MapEvent> updated;
  std::optional<uint64_t> live_map_id;
  if (snapshot != nullptr) {
    updated = MakeUpdatedEvent(*snapshot);
  } else if (auto live = store_.Get(name); live.ok()) {
    live_map_id = (*live)->map_id;
  }
  absl::MutexLock lock(&mu_);
  auto it = watchers_.find(name);
  if (it == watchers_.end()) return;
  for (MapWatcher* watcher : it->second) {
    if (snapshot != nullptr) {
      watcher->Offer(snapshot, updated);
    } else {
      watcher->Deleted(live_map_id);
    }
  }
}

int64_t MapWatchers::count() const {
  absl::MutexLock lock(&mu_);
  return count_;
}

int64_t MapWatchers::backlog_drops() const {
  return backlog_drops_.load(std::memory_order_relaxed);
}

}  // namespace pathd::server
