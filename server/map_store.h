// The daemon's in-memory maps: each name holds a sequence of immutable
// versions handed out as shared_ptr<const MapSnapshot>, so planning keeps the
// version it started on while updates install new ones.
#ifndef PATHD_SERVER_MAP_STORE_H_
#define PATHD_SERVER_MAP_STORE_H_

#include <atomic>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/synchronization/mutex.h"
#include "absl/types/span.h"
#include "core/map/grid.h"

namespace pathd::server {

// The changed cells of a run of consecutive updates of one map, newest
// first: one version's cells and a link to the version before it, back to
// where the run starts (a create, a replace, an update whose changes were
// not tracked) or to the bounds below. Immutable; shared by the snapshots of
// the run. Caches whose value was made on an older version than the
// previous one (several updates arrived between two queries, and its grid
// buffer went back to the pool) advance with the union (ChangesSince)
// instead of building again.
struct ChangeHistory {
  // At most this many versions and this many cells in all are linked; a
  // longer run keeps its newest half.
  static constexpr size_t kMaxVersions = 64;
  static constexpr size_t kMaxCells = size_t{1} << 20;

  uint64_t version = 0;
  // The cells version - 1 and version differ in (MapSnapshot::changed_cells).
  std::vector<Cell> cells;
  // version - 1's link; null where the run starts.
  std::shared_ptr<const ChangeHistory> previous;
  // Links from this one back to the start, this one included, and their
  // cells.
  size_t versions = 1;
  size_t total_cells = 0;
};

// One version of one map. Immutable once published.
struct MapSnapshot {
  std::string name;
  // 1 at creation, +1 per update (a replacing create continues the count).
  uint64_t version = 0;
  // Which map this is a version of: every Create (a replacing one too) draws
  // a new id from the store, Update keeps it. Versions of one id differ only
  // by Update, so incremental state may be repaired across them; a deleted
  // and re-created map starts again at version 1 with a new id, which is how
  // caches tell it from the map they were built on.
  uint64_t map_id = 0;
  std::shared_ptr<const Grid> grid;
  // For a version made by Update: every cell whose cost differs from the
  // previous version, in row-major order, so incremental state (D* Lite,
  // shortest path maps) can repair in O(changed). Empty with
  // changes_known = false for a created or replaced map and for updates that
  // changed more than kMaxTrackedChanges cells or 1/8 of the map (consumers
  // then compare grids).
  std::vector<Cell> changed_cells;
  bool changes_known = false;
  // With changes_known: this version's link of the run of updates that led
  // to it (null otherwise).
  std::shared_ptr<const ChangeHistory> history;
};

// The history of `version` whose changed cells are `cells`, on top of
// `previous` when that is version - 1's (a new run otherwise); when the
// run would pass ChangeHistory's bounds, its newest half is copied first.
std::shared_ptr<const ChangeHistory> ExtendHistory(
    const std::shared_ptr<const ChangeHistory>& previous, uint64_t version,
    std::vector<Cell> cells);

// The cells in which version `from` of the snapshot's map may differ from
// the snapshot: the union of the changed cells of the versions after it,
// newest first, a cell possibly listed more than once or changed and then
// changed back. Nullopt when the snapshot's history does not reach back to
// version from + 1 (or from is not older than the snapshot).
std::optional<std::vector<Cell>> ChangesSince(const MapSnapshot& snapshot, uint64_t from);

// One change of an update batch: every cell of the inclusive rectangle
// [x_min, x_max] x [y_min, y_max] gets `cost`. A single cell is a 1x1
// rectangle with is_rect false (only used to word error messages).
struct MapChange {
  int32_t x_min = 0;
  int32_t y_min = 0;
  int32_t x_max = 0;
  int32_t y_max = 0;
  // Checked against 0..255 by MapStore::Update; wider here because the wire
  // type is uint32 and the store owns the validation.
  uint32_t cost = 0;
  bool is_rect = false;

  static MapChange ForCell(int32_t x, int32_t y, uint32_t cost) {
    return MapChange{x, y, x, y, cost, false};
  }
  static MapChange ForRect(int32_t x_min, int32_t y_min, int32_t x_max,
                           int32_t y_max, uint32_t cost) {
    return MapChange{x_min, y_min, x_max, y_max, cost, true};
  }
};

// Makes a store's changes durable (server/storage/durable_store.h). The store calls
// Encode* without holding its locks, Append under the lock that orders the
// change (so the log order is the order versions are published, per map and
// between a map's Create, Update and Delete), and WaitDurable (or OnDurable)
// after releasing its locks: writers waiting together share one disk sync.
// A change is published to readers and listeners only once it is durable.
// Implementations are thread-safe.
class MapJournal {
 public:
  virtual ~MapJournal() = default;
  // OK while changes can be logged; otherwise the error the store returns
  // without applying the change.
  virtual absl::Status Writable() = 0;
  // A record of creating `name` at `version` with `grid`; RESOURCE_EXHAUSTED
  // when the map is too large to log.
  virtual absl::StatusOr<std::string> EncodeCreate(std::string_view name,
                                                   uint64_t version,
                                                   const Grid& grid) = 0;
  // A record of the update of `name` that produced `version`.
  virtual std::string EncodeUpdate(std::string_view name, uint64_t version,
                                   absl::Span<const MapChange> changes) = 0;
  // A record of deleting `name` at `last_version`.
  virtual std::string EncodeDelete(std::string_view name, uint64_t last_version) = 0;
  // Queues `record` (from an Encode* above) for the change that made
  // `current` the version of `name` (null: deleted). Called with the store's
  // lock held: must not block on I/O. Returns the record's sequence number.
  virtual uint64_t Append(std::string_view name, std::string record,
                          std::shared_ptr<const MapSnapshot> current) = 0;
  // Blocks until record `sequence` and every earlier one are on disk. An
  // error means the change may not survive a restart: the store never
  // publishes it, and later changes are refused (Writable).
  virtual absl::Status WaitDurable(uint64_t sequence) = 0;
  // Calls `done` with what WaitDurable(sequence) would return, without
  // blocking the caller when the implementation has a thread for it (the
  // default blocks). `done` calls arrive in sequence order.
  virtual void OnDurable(uint64_t sequence, std::function<void(absl::Status)> done) {
    done(WaitDurable(sequence));
  }
};

struct MapUpdateResult {
  std::shared_ptr<const MapSnapshot> snapshot;
  // Cells whose cost differs between the old and the new version.
  int64_t cells_changed = 0;
};

// Thread-safe. Readers (Get/List) hold the store lock only to copy a pointer;
// an update's work happens outside it, serialised per map name, so planning
// and reads of other maps never wait for it.
//
// With a journal, a change is visible (Get, List, listeners) only once the
// journal has it on disk: writers build on the newest version logged, readers
// see the newest version durable, and versions are published in log order.
// A change whose write fails is never published, and since the journal then
// refuses every later change, its version number is never shown for other
// content (docs/durability.md, "Full disk").
//
// An update costs O(changed area), not O(map): each map keeps a few grid
// buffers that no snapshot references any more (a snapshot's grid returns to
// its map's pool when the last reference goes) and a bounded log of the cells
// recent versions changed. An update takes the newest spare buffer, replays
// the logged cells of the versions it missed (copying them from the current
// grid), applies the batch and publishes the buffer. It copies the whole grid
// only when no spare exists (a new buffer), or the spare is older than the
// log reaches (docs/decisions.md, "Map updates recycle grid buffers").
class MapStore {
 public:
  static constexpr size_t kMaxNameLength = 128;
  static constexpr size_t kMaxTrackedChanges = 1 << 20;
  // A map keeps unreferenced grid buffers for later updates up to a total
  // (buffers in snapshots plus spares) of one more than the most buffers its
  // snapshots held at once over its last kSpareWindow updates: enough that
  // an update finds a spare as long as the load stays as it was, never more
  // than the copy-per-update scheme needed at that peak plus one, and
  // shrinking again when the load drops.
  static constexpr int kSpareWindow = 64;
  // The change log of a map keeps at most this many versions, and at most
  // width * height / kLogCellsDivisor + kLogMinCells changed cells: replaying
  // more scattered cells than that costs about what copying the grid does.
  static constexpr size_t kMaxLogVersions = 256;
  static constexpr size_t kLogCellsDivisor = 32;
  static constexpr size_t kLogMinCells = 64;

  // How updates got their grid buffer, since the store was created.
  struct BufferStats {
    // A spare buffer brought up to date by replaying logged changes.
    int64_t replayed = 0;
    // A spare buffer overwritten with the whole current grid (its version
    // was older than the log reaches, or the log was dropped by a large
    // update).
    int64_t copied = 0;
    // No spare buffer: a new grid allocated as a copy of the current one.
    int64_t allocated = 0;
  };

  // Called after a map got a new version (snapshot set) or was deleted
  // (snapshot null), once that is published (durable, with a journal). Calls
  // arrive one at a time in log order, so in version order per name, on the
  // thread that published them (a writer's, or the journal's completion
  // thread); a listener must return quickly (queue work, do not plan) and
  // must not call back into the store's writers.
  using Listener = std::function<void(std::string_view name,
                                      const std::shared_ptr<const MapSnapshot>& snapshot)>;

  // max_cells bounds width * height of any stored map (--max_map_cells).
  explicit MapStore(int64_t max_cells);
  MapStore(const MapStore&) = delete;
  MapStore& operator=(const MapStore&) = delete;

  // OK when `name` is 1..128 characters of [A-Za-z0-9._-] not starting with
  // '.'; otherwise INVALID_ARGUMENT naming the problem.
  static absl::Status ValidateName(std::string_view name);

  // INVALID_ARGUMENT "change N: ..." when `change` (the index-th of a batch)
  // has a cost over 255, a rectangle with min > max, or reaches off `grid`.
  static absl::Status ValidateChange(const MapChange& change, size_t index,
                                     const Grid& grid);
  // Every change of a batch as ValidateChange, and the batch as a whole:
  // RESOURCE_EXHAUSTED when its changes together write more than
  // MaxBatchWrites(grid) cells (overlapping rectangles counted each time).
  // Without it a 1 MiB request of whole-map rectangles would rewrite a large
  // map ~10^5 times while holding the map's update lock.
  static absl::Status ValidateChanges(absl::Span<const MapChange> changes,
                                      const Grid& grid);
  // kMaxWritesPerCell writes per cell of `grid`, at least kMinBatchWrites.
  static int64_t MaxBatchWrites(const Grid& grid);
  static constexpr int64_t kMaxWritesPerCell = 16;
  static constexpr int64_t kMinBatchWrites = int64_t{1} << 20;
  // RESOURCE_EXHAUSTED naming the limit when a width x height map would exceed
  // max_cells; OK otherwise. Lets callers refuse before parsing/allocating.
  absl::Status CheckSize(int64_t width, int64_t height) const;
  int64_t max_cells() const { return max_cells_; }

  // Stores `grid` as version 1 of `name`. When the name exists: ALREADY_EXISTS
  // unless `replace`, in which case the new map becomes the old version + 1.
  // INVALID_ARGUMENT for a bad name or an empty grid, RESOURCE_EXHAUSTED when
  // it exceeds max_cells.
  absl::StatusOr<std::shared_ptr<const MapSnapshot>> Create(std::string_view name,
                                                            Grid grid,
                                                            bool replace);

  // The current version of `name`; NOT_FOUND "map 'x' not found",
  // INVALID_ARGUMENT (as ValidateName) for a name no map can have.
  absl::StatusOr<std::shared_ptr<const MapSnapshot>> Get(std::string_view name) const;

  // The current version of every map, sorted by name.
  std::vector<std::shared_ptr<const MapSnapshot>> List() const;

  // Removes `name` and returns its last version; NOT_FOUND when unknown,
  // INVALID_ARGUMENT for an invalid name.
  // Snapshots already handed out stay valid.
  absl::StatusOr<uint64_t> Delete(std::string_view name);

  // Applies `changes` in order to a copy of the current version (a recycled
  // buffer, see the class comment) and installs it as version + 1; all or
  // nothing. Errors: NOT_FOUND for an unknown map, INVALID_ARGUMENT for an
  // invalid name;
  // ABORTED when expected_version is set and differs from the current version;
  // INVALID_ARGUMENT for an empty batch, a cost > 255, a rectangle with
  // min > max, or a change reaching off the map (naming the change index);
  // RESOURCE_EXHAUSTED for a batch over MaxBatchWrites (ValidateChanges).
  absl::StatusOr<MapUpdateResult> Update(std::string_view name,
                                         absl::Span<const MapChange> changes,
                                         std::optional<uint64_t> expected_version);

  // Update without waiting for the disk: applies the batch on the calling
  // thread and calls `done` with Update's result once the new version is
  // durable and published, on the journal's completion thread (or inline
  // for an error found before logging, or without a journal). `changes` is
  // read before this returns.
  using UpdateDone = std::function<void(absl::StatusOr<MapUpdateResult>)>;
  void UpdateAsync(std::string_view name, absl::Span<const MapChange> changes,
                   std::optional<uint64_t> expected_version, UpdateDone done);

  // Installs `grid` as `name` at `version`, as recovered from --data_dir:
  // not journaled, no listener called. Errors as Create; FAILED_PRECONDITION
  // when the name exists. For start-up, before serving.
  absl::StatusOr<std::shared_ptr<const MapSnapshot>> Restore(std::string_view name,
                                                             Grid grid,
                                                             uint64_t version);

  // Logs every later Create, Update and Delete to `journal` (which must
  // outlive the store's writers) before they return; null stops logging.
  // Not thread-safe with respect to writers: set at start-up.
  void SetJournal(MapJournal* journal) { journal_ = journal; }
  // Whether the grids of later Creates and Restores honour their origin's
  // yaw in world coordinates (Grid::honour_origin_yaw; pathd
  // --honour_origin_yaw). Off, a map with a non-zero yaw is logged with a
  // warning when it is created. Call before serving.
  void SetHonourOriginYaw(bool honour) { honour_origin_yaw_ = honour; }

  size_t size() const;

  BufferStats buffer_stats() const;

  // Registers a listener for every later Create (replacing), Update and
  // Delete. Not thread-safe with respect to writers: register at start-up.
  void AddListener(Listener listener);

 private:
  // Sets the grid's honour_origin_yaw from the store's, warning about an
  // ignored yaw.
  void StampOriginYaw(std::string_view name, Grid* grid) const;
  // Spare grid buffers and the change log of one map id (map_store.cc).
  class GridPool;

  void Notify(std::string_view name,
              const std::shared_ptr<const MapSnapshot>& snapshot) const;

  // A change logged (or, without a journal, made) and not yet published.
  enum class ChangeKind { kCreated, kReplaced, kUpdated, kDeleted };
  struct PendingChange {
    uint64_t ticket = 0;
    std::string name;
    // The new version; null for kDeleted.
    std::shared_ptr<const MapSnapshot> snapshot;
    ChangeKind kind = ChangeKind::kUpdated;
  };
  // Queues a change in publication order and returns its ticket.
  uint64_t QueueChange(std::string_view name, std::shared_ptr<const MapSnapshot> snapshot,
                       ChangeKind kind) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_);
  // Publishes every queued change up to `ticket` in order (their records
  // are durable), calling the listeners for each.
  void PublishThrough(uint64_t ticket) ABSL_LOCKS_EXCLUDED(mu_, publish_mu_);
  // Forgets the queued changes from `ticket` on: their write failed.
  void DropFrom(uint64_t ticket) ABSL_LOCKS_EXCLUDED(mu_);
  // After the change of `ticket` (journal record `sequence`) was queued:
  // waits for the disk and publishes it, or drops it on a write error.
  absl::Status Complete(uint64_t ticket, uint64_t sequence);

  // An update applied and logged, waiting to be durable and published.
  struct PreparedUpdate {
    MapUpdateResult result;
    uint64_t ticket = 0;
    uint64_t sequence = 0;
  };
  absl::StatusOr<PreparedUpdate> PrepareUpdate(std::string_view name,
                                               absl::Span<const MapChange> changes,
                                               std::optional<uint64_t> expected_version);

  // A buffer equal to `base`'s grid that no snapshot references: a recycled
  // spare from `pool` or a new copy. Counts which in grids_*_.
  std::unique_ptr<Grid> AcquireGrid(GridPool& pool, const MapSnapshot& base);

  struct Entry {
    // What readers see: the newest published version; null while a created
    // map is not yet durable, or once its deletion is published.
    std::shared_ptr<const MapSnapshot> current;
    // What writers build on: the newest version logged; null once a
    // deletion is logged (the entry goes when that is published).
    std::shared_ptr<const MapSnapshot> latest;
    // Serialises updates of this name so two writers do not both copy the
    // map only for one to lose; shared so an updater can hold it without the
    // store lock while a concurrent Delete drops the entry.
    std::shared_ptr<absl::Mutex> update_mu;
    // The only owning reference: released grids hold it weakly, so deleting
    // or replacing the map (or destroying the store) frees them instead.
    std::shared_ptr<GridPool> pool;
  };

  const int64_t max_cells_;
  // Held while publishing, so listeners see changes in log order.
  absl::Mutex publish_mu_ ABSL_ACQUIRED_BEFORE(mu_);
  mutable absl::Mutex mu_;
  std::deque<PendingChange> pending_ ABSL_GUARDED_BY(mu_);
  uint64_t next_ticket_ ABSL_GUARDED_BY(mu_) = 1;
  // Readable maps (current set), for size().
  size_t visible_ ABSL_GUARDED_BY(mu_) = 0;
  // std::map keeps List() sorted without a sort per call.
  std::map<std::string, Entry, std::less<>> maps_ ABSL_GUARDED_BY(mu_);
  uint64_t last_map_id_ ABSL_GUARDED_BY(mu_) = 0;
  std::atomic<int64_t> grids_replayed_{0};
  std::atomic<int64_t> grids_copied_{0};
  std::atomic<int64_t> grids_allocated_{0};
  std::vector<Listener> listeners_;
  MapJournal* journal_ = nullptr;
  bool honour_origin_yaw_ = false;
};

}  // namespace pathd::server

#endif  // PATHD_SERVER_MAP_STORE_H_
