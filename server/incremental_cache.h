// Incremental search state the server keeps between requests: shortest path
// maps (PLANNER_SPM, CostToGo) and D* Lite searches (PLANNER_DSTAR_LITE) per
// (map, goal, cost options, robot radius), within a byte budget, following the
// map's versions by repairing instead of rebuilding.
#ifndef PATHD_SERVER_INCREMENTAL_CACHE_H_
#define PATHD_SERVER_INCREMENTAL_CACHE_H_

#include <array>
#include <cstddef>
#include <cstdint>
#include <list>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/status/statusor.h"
#include "absl/synchronization/mutex.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/incremental/incremental_search.h"
#include "core/search/planner.h"
#include "server/inflation_cache.h"
#include "server/map_store.h"
#include "server/worker_pool.h"

namespace pathd::server {

// The cells whose cost differs between `before`, the grid planned on at version
// `before_version` of a map, and `after`, the grid to plan on for `next`, a
// later version of the same map (same map_id: the caller checks). Uses
// next.changed_cells when they describe exactly this step: `next` is
// before_version + 1, its changes are known, and `after` is next's own grid
// (an inflated copy changes more cells than the update did). Otherwise
// compares the grids, O(map). INVALID_ARGUMENT when the sizes differ.
absl::StatusOr<std::vector<Cell>> ChangesBetween(const Grid& before,
                                                 uint64_t before_version,
                                                 const Grid& after,
                                                 const MapSnapshot& next);

// Thread-safe. Two caches behind one LRU mechanism: shortest path maps and
// D* Lite searches, each with its own share of the byte budget and its own
// counters.
//
// Versions: every entry is at one version of its map. A request brings its
// entry up to the snapshot it took on arrival (repairing with the changed
// cells, or rebuilding when the map was re-created under the same name) and
// answers at the entry's version, which is newer than the request's when a
// repair queued by an update got there first; the version is always
// reported. Follow() makes every map update queue the repairs in the
// background and drops the entries of deleted maps.
//
// Concurrency: a shortest path map is immutable once published; requests
// read it through a shared_ptr without locks, and a repair works on a Clone()
// and swaps the pointer, so readers never wait for a repair. A D* Lite search
// is mutated by every plan (the start moves), so its plans are serialised per
// entry. Builds and repairs of one entry are serialised too, so concurrent
// misses build an entry once. An entry is never evicted while a request or a
// repair works on it.
class IncrementalCache {
 public:
  enum class Kind { kSpm = 0, kDStarLite = 1 };
  static constexpr int kKinds = 2;
  // "spm" / "dstar_lite", as in GetCacheStats.
  static std::string_view KindName(Kind kind);

  // What an entry is for, besides its kind. Doubles compare exactly: they
  // come from one conversion of the request's values, so equal requests get
  // equal keys.
  struct Key {
    std::string map;
    Cell goal;
    CostParams cost;
    // All 0: the map as stored; otherwise the InflationCache copy shaped
    // by them (GridShape::Of).
    double robot_radius_cells = 0.0;
    double inflation_radius_cells = 0.0;
    double cost_scaling_per_cell = 0.0;
    double min_clearance_cells = 0.0;
  };

  struct Stats {
    int64_t entries = 0;
    int64_t bytes = 0;
    int64_t budget_bytes = 0;
    int64_t hits = 0;
    int64_t misses = 0;
    int64_t evictions = 0;
    int64_t repairs = 0;
    int64_t rebuilds = 0;
  };

  // A shortest path map as a request gets it.
  struct SpmAnswer {
    // kFound: `field` is set. kTimeout / kCancelled / kExpansionLimit: the
    // build was stopped by the request's stop condition; nothing is set.
    PlanOutcome outcome = PlanOutcome::kFound;
    std::shared_ptr<const ShortestPathMap> field;
    // The grid the field was computed on (inflated when a radius is set) and
    // its map version.
    std::shared_ptr<const Grid> grid;
    uint64_t map_version = 0;
    // The entry existed for this map (possibly repaired) instead of being
    // built.
    bool cache_hit = false;
    // Expansions of the build or repair this request did (0 when it found the
    // entry current).
    int64_t expansions = 0;
    // Changed cells this request applied to the entry.
    int64_t repaired_cells = 0;
  };

  // A D* Lite plan as a request gets it.
  struct DStarAnswer {
    // result.expansions counts this request's repair and search.
    PlanResult result;
    std::shared_ptr<const Grid> grid;
    uint64_t map_version = 0;
    bool cache_hit = false;
    int64_t repaired_cells = 0;
  };

  // `inflation` must outlive the cache. Each kind may hold budget_bytes / 2
  // (by MemoryBytes() of its entries).
  IncrementalCache(InflationCache& inflation, size_t budget_bytes);
  IncrementalCache(const IncrementalCache&) = delete;
  IncrementalCache& operator=(const IncrementalCache&) = delete;

  // Registers a listener on `store`: a new version queues a repair job per
  // entry of that map on `pool` (skipped when the queue is more than half
  // full, so repairs never crowd out requests; the next request then repairs
  // lazily), a deleted or replaced map drops its entries. Call once, at
  // start-up (MapStore::AddListener's rule). The cache must outlive the
  // store's writers, and the pool must be shut down before the cache goes.
  void Follow(MapStore& store, WorkerPool& pool);

  // The shortest path map of key.goal on `snapshot` (or on a later version the
  // entry already reached), building or repairing it as needed. The build
  // obeys `stop`; repairs run to the end (they are what makes the next request
  // cheap). Errors: INVALID_ARGUMENT when the goal is blocked on the planning
  // grid or the cost parameters are invalid; errors of the inflation.
  absl::StatusOr<SpmAnswer> GetSpm(const Key& key,
                                   const std::shared_ptr<const MapSnapshot>& snapshot,
                                   const StopCondition& stop)
      ABSL_LOCKS_EXCLUDED(mu_);

  // Moves the key's D* Lite search to `start` and plans, after bringing it to
  // `snapshot` as GetSpm does. A stop leaves the search valid for the next
  // request. Errors as DStarLite::Create/SetStart/Plan.
  absl::StatusOr<DStarAnswer> PlanDStarLite(
      const Key& key, const std::shared_ptr<const MapSnapshot>& snapshot,
      Cell start, const StopCondition& stop) ABSL_LOCKS_EXCLUDED(mu_);

  Stats stats(Kind kind) const ABSL_LOCKS_EXCLUDED(mu_);

 private:
  // The version a slot is at; map_id 0 = no state.
  struct At {
    uint64_t map_id = 0;
    uint64_t version = 0;
    std::shared_ptr<const Grid> grid;
  };
  // The state of one key. `mu` serialises everything that reads or changes
  // the state: builds, repairs and D* Lite plans. Shortest path map readers
  // never take it: they use the field published in the index node.
  struct Slot {
    Slot(Kind kind, Key key) : kind(kind), key(std::move(key)) {}

    const Kind kind;
    const Key key;
    absl::Mutex mu;
    At at ABSL_GUARDED_BY(mu);
    // kSpm.
    std::shared_ptr<const ShortestPathMap> field ABSL_GUARDED_BY(mu);
    // kDStarLite; `has_start` once a request has set the robot's position, so
    // a background repair can run the search to the end.
    std::unique_ptr<DStarLite> dstar ABSL_GUARDED_BY(mu);
    bool has_start ABSL_GUARDED_BY(mu) = false;

    size_t MemoryBytes() const ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
      if (field != nullptr) return field->MemoryBytes();
      if (dstar != nullptr) return dstar->MemoryBytes();
      return 0;
    }
    void Reset() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
      at = At();
      field.reset();
      dstar.reset();
      has_start = false;
    }
  };
  // What bringing a slot to a snapshot did.
  struct Advance {
    bool had_state = false;
    bool repaired = false;
    bool rebuilt = false;
    int64_t expansions = 0;
    int64_t changed_cells = 0;
    // Build stopped by the stop condition (kFound: not stopped).
    PlanOutcome stopped = PlanOutcome::kFound;
  };
  // Orders keys by map name first, so one map's entries are a range; also
  // compares a key with a bare map name.
  struct KeyLess {
    using is_transparent = void;
    bool operator()(const Key& a, const Key& b) const;
    bool operator()(const Key& a, std::string_view b) const { return a.map < b; }
    bool operator()(std::string_view a, const Key& b) const { return a < b.map; }
  };
  struct Node {
    std::shared_ptr<Slot> slot;
    // kSpm: the field readers take without touching the slot.
    std::shared_ptr<const ShortestPathMap> field;
    At at;
    size_t bytes = 0;
    // Requests and repair jobs working on the slot; never evicted while > 0.
    int users = 0;
    // The node's place in its shard's LRU list (which points at the key).
    std::list<const Key*>::iterator lru;
  };
  using Index = std::map<Key, Node, KeyLess>;
  // One kind's entries, most recently used first in `lru`.
  struct Shard {
    Index index;
    std::list<const Key*> lru;
    size_t bytes = 0;
    size_t budget = 0;
    Stats counters;
  };
  // How a request's use of an entry counts.
  enum class Lookup { kHit, kMiss, kNone };

  // The node for (kind, key), created empty when missing, marked most
  // recently used and pinned (users + 1). Returns its slot.
  std::shared_ptr<Slot> PinLocked(Kind kind, const Key& key)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_);
  // Releases a pin taken by PinLocked or Follow's listener, then evicts.
  void Unpin(const Slot& slot) ABSL_LOCKS_EXCLUDED(mu_);
  // The node still holding `slot` (nullptr after a drop or eviction).
  Node* NodeOfLocked(const Slot& slot) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_);
  void EvictLocked(Shard& shard) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_);
  void EraseLocked(Shard& shard, Index::iterator it) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_);

  // The grid the key plans on for `snapshot`.
  absl::StatusOr<std::shared_ptr<const Grid>> PlanningGrid(
      const Key& key, const MapSnapshot& snapshot);
  // Brings the slot to `snapshot` (planning grid `grid`), or leaves it when it
  // is at or past it; builds with `stop` when the slot has no state for this
  // map (a request; a background repair only repairs). Publishes the result
  // and counts it as `lookup` says.
  absl::StatusOr<Advance> AdvanceSlot(Slot& slot, const MapSnapshot& snapshot,
                                      std::shared_ptr<const Grid> grid,
                                      const StopCondition& stop, bool is_request)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(slot.mu) ABSL_LOCKS_EXCLUDED(mu_);
  // Copies the slot's state into its node (field, version, bytes), counts
  // the lookup and the advance's repair, and evicts. Lock order: slot.mu,
  // then mu_.
  void Publish(const Slot& slot, const Advance& advance, Lookup lookup)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(slot.mu) ABSL_LOCKS_EXCLUDED(mu_);

  // Listener body: queues repairs of `name`'s entries, or drops them.
  void OnMapChanged(std::string_view name,
                    const std::shared_ptr<const MapSnapshot>& snapshot)
      ABSL_LOCKS_EXCLUDED(mu_);
  void RepairInBackground(Slot& slot,
                          const std::shared_ptr<const MapSnapshot>& snapshot)
      ABSL_LOCKS_EXCLUDED(mu_, slot.mu);

  InflationCache& inflation_;
  WorkerPool* pool_ = nullptr;
  mutable absl::Mutex mu_;
  std::array<Shard, kKinds> shards_ ABSL_GUARDED_BY(mu_);
};

}  // namespace pathd::server

#endif  // PATHD_SERVER_INCREMENTAL_CACHE_H_
