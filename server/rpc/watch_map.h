// WatchMap: streams each new version of a map to its watchers as the cells
// that changed (merged into rectangles, with their new costs), or as the whole
// map when the changes cannot be sent, so clients can mirror a map exactly.
#ifndef PATHD_SERVER_RPC_WATCH_MAP_H_
#define PATHD_SERVER_RPC_WATCH_MAP_H_

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/synchronization/mutex.h"
#include "absl/types/span.h"
#include "core/map/grid.h"
#include "pathd/v1/map_service.grpc.pb.h"
#include "server/map_store.h"
#include "server/memory_budget.h"

namespace pathd::server {

// An inclusive rectangle of cells.
struct CellRectangle {
  int32_t x_min = 0;
  int32_t y_min = 0;
  int32_t x_max = 0;
  int32_t y_max = 0;

  friend bool operator==(const CellRectangle&, const CellRectangle&) = default;
};

// Disjoint rectangles covering exactly `cells`: each row's runs of adjacent
// cells, with runs spanning the same columns in consecutive rows merged into
// one rectangle. Sorted by y_min, then x_min. O(cells).
// Precondition: `cells` is in row-major order without repeats (as
// MapSnapshot::changed_cells is).
std::vector<CellRectangle> CoverCells(absl::Span<const Cell> cells);

// The UPDATED event of `snapshot`: its changed cells as CoverCells rectangles
// with their new costs. Null when the snapshot does not know its changes or
// when the event would be larger than a whole-map event (a RESYNC is then
// the cheaper message).
std::shared_ptr<const v1::MapEvent> MakeUpdatedEvent(
    const MapSnapshot& snapshot);

// The events one watcher has yet to receive, bounded: when a slow reader lets
// more than `max_events` events (or more bytes than the map itself, at least
// kMinBacklogBytes) pile up, the backlog is dropped for a single RESYNC of the
// newest version, so a watcher costs at most about one map of memory.
// The store publishes versions in log order, once durable, so they arrive in
// order; the queue still copes with any order (defence in depth): an older
// version than one already queued is ignored, and a gap is bridged by a
// whole-map event. Not thread-safe: the owner locks.
class MapEventQueue {
 public:
  static constexpr size_t kMinBacklogBytes = size_t{64} << 10;

  // `current` is the version the client is taken to hold after any event
  // queued by the caller at start (see PushFull). `max_bytes` bounds the
  // queued events' bytes (0: the map's size, at least kMinBacklogBytes); one
  // whole-map event is always let in, however large.
  MapEventQueue(size_t max_events, const MapSnapshot& current, size_t max_bytes = 0);

  // Queues the whole of `snapshot` as `kind` (RESYNC or REPLACED).
  void PushFull(std::shared_ptr<const MapSnapshot> snapshot,
                v1::MapEventKind kind);

  // Queues a new version. `updated` is MakeUpdatedEvent(*snapshot), used when
  // it follows the last queued version of the same map.
  void Offer(std::shared_ptr<const MapSnapshot> snapshot,
             std::shared_ptr<const v1::MapEvent> updated);

  // Queues the final DELETED event.
  void PushDeleted();

  bool empty() const { return items_.empty(); }
  size_t size() const { return items_.size(); }
  // Removes and returns the oldest event (a whole-map event is built here,
  // not when queued, so a dropped backlog never copied the map).
  // Precondition: !empty().
  std::shared_ptr<const v1::MapEvent> Pop();

  // The version and map identity the client will hold after the last queued
  // event.
  uint64_t last_version() const { return last_version_; }
  uint64_t map_id() const { return map_id_; }
  // How many times a backlog was dropped for a RESYNC.
  int64_t backlog_drops() const { return backlog_drops_; }

 private:
  struct Item {
    // Ready event (UPDATED, DELETED); null for a whole-map event.
    std::shared_ptr<const v1::MapEvent> event;
    // The version a whole-map event carries.
    std::shared_ptr<const MapSnapshot> full;
    v1::MapEventKind kind = v1::MAP_EVENT_KIND_UNSPECIFIED;
    size_t bytes = 0;
  };

  // Appends `item` (a version of `snapshot`), dropping the backlog for a
  // whole-map event of `snapshot` when it is over the bounds.
  void Push(Item item, const std::shared_ptr<const MapSnapshot>& snapshot);

  const size_t max_events_;
  const size_t max_bytes_;
  std::deque<Item> items_;
  size_t bytes_ = 0;
  uint64_t last_version_;
  uint64_t map_id_;
  int64_t backlog_drops_ = 0;
};

class MapWatcher;

// Thread-safe registry of WatchMap streams. Follows the store through a
// listener: each new version's UPDATED event is built once (only when the map
// has watchers) and shared by every watcher of that map.
class MapWatchers {
 public:
  struct Options {
    // Events queued per watcher before its backlog is replaced by one RESYNC
    // (--watch_queue_events).
    size_t max_queued_events = 64;
    // Largest event the stream may send (--max_message_bytes; 0: unchecked).
    // A larger one ends the stream with RESOURCE_EXHAUSTED naming the flag,
    // where gRPC's own refusal would name neither the event nor the flag.
    int64_t max_message_bytes = 0;
    // Bytes of events queued per watcher before its backlog is replaced by
    // one RESYNC (--watch_backlog_bytes); 0 = the map's size, at least
    // MapEventQueue::kMinBacklogBytes.
    size_t backlog_bytes = 0;
    // Where each stream reserves WatcherBytes() when it opens (and the count
    // of streams is checked); null = no limit. Must outlive this object.
    MemoryBudget* budget = nullptr;
  };

  // What a watcher of a map of `map_bytes` cells may hold at worst: its
  // backlog, plus the whole-map event being written and gRPC's serialized
  // copy of it.
  static int64_t WatcherBytes(size_t map_bytes, size_t backlog_bytes);

  // Registers a listener on `store`, so construct before serving; `store`
  // must outlive this object.
  MapWatchers(MapStore& store, Options options);
  // Every stream must have ended (the gRPC server shut down) before this runs.
  ~MapWatchers();
  MapWatchers(const MapWatchers&) = delete;
  MapWatchers& operator=(const MapWatchers&) = delete;

  // The reactor for one WatchMap call (gRPC deletes it when done).
  grpc::ServerWriteReactor<v1::MapEvent>* Start(
      grpc::CallbackServerContext* context, const v1::WatchMapRequest& request);

  // Refuses new streams and ends open ones with UNAVAILABLE after the event
  // being written, so a draining server need not wait for watchers to hang up.
  void Shutdown();

  // Open streams.
  int64_t count() const;
  // Backlogs dropped for a RESYNC because a reader was too slow, over all
  // streams so far.
  int64_t backlog_drops() const;

 private:
  friend class MapWatcher;

  void OnMapChanged(std::string_view name,
                    const std::shared_ptr<const MapSnapshot>& snapshot);
  void Remove(MapWatcher* watcher);

  MapStore& store_;
  const Options options_;

  mutable absl::Mutex mu_;
  // By map name. Holding mu_ keeps every listed watcher alive: a watcher is
  // deleted only after Remove.
  std::map<std::string, std::set<MapWatcher*>, std::less<>> watchers_
      ABSL_GUARDED_BY(mu_);
  int64_t count_ ABSL_GUARDED_BY(mu_) = 0;
  std::atomic<int64_t> backlog_drops_{0};
  bool stopping_ ABSL_GUARDED_BY(mu_) = false;
};

}  // namespace pathd::server

#endif  // PATHD_SERVER_RPC_WATCH_MAP_H_
