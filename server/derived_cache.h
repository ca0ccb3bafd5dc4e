// Derived representations of map versions (core/search/derived.h): free-space
// bitmaps, visibility graphs, navigation meshes, Voronoi graphs, Euclidean
// shortest path maps. One value per (planning grid, key), built once under
// concurrency, advanced from the newest older version of the same map with
// that step's changed cells instead of rebuilt, bounded in bytes with LRU
// eviction and counted in the memory budget next to the other caches.
#ifndef PATHD_SERVER_DERIVED_CACHE_H_
#define PATHD_SERVER_DERIVED_CACHE_H_

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <list>
#include <memory>
#include <string>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/synchronization/mutex.h"
#include "absl/time/time.h"
#include "core/map/grid.h"
#include "core/search/derived.h"
#include "server/map_store.h"

namespace pathd::server {

// Thread-safe.
//
// Keys: an entry belongs to one planning grid, held weakly (a cached value
// never keeps an old version alive, and a freed grid can never be matched by
// a new one at the same address), and to a key string naming the kind and
// its parameters. The grid is a map version's own grid or its inflation for
// a robot radius; the map's id and version come with it.
//
// Advancing: on a miss, the newest entry with the same map id and key at an
// older version whose grid is still alive is advanced with the cells that
// differ (the version's recorded changes for one step of a stored grid,
// otherwise a comparison of the two grids), when the recipe can; otherwise
// the value is built.
//
// Stopping: builds run on the requesting query's thread under its stop
// condition (core/search/derived.h). A build that gives up drops its
// unfinished entry and wakes the queries waiting on it, which then build it
// themselves under their own stop conditions, so a patient query is never
// failed by an impatient one. A waiting query waits only until its own
// deadline or cancellation (looking at the cancel flag every
// kStopPollInterval) and then gives up alone; the build goes on.
class DerivedCache {
 public:
  struct Stats {
    int64_t hits = 0;
    int64_t builds = 0;
    int64_t advances = 0;
    // Dropped beyond the byte budget (entries of freed versions are not
    // counted).
    int64_t evictions = 0;
    // Builds and advances that gave up because the requesting query's
    // deadline passed or it was cancelled (their entries are dropped).
    int64_t stopped_builds = 0;
    // Queries that stopped waiting for another query's build.
    int64_t stopped_waits = 0;
    size_t entries = 0;
    size_t bytes = 0;
    size_t budget_bytes = 0;
  };
  // One cached value, for `pathctl maps stats`.
  struct EntryInfo {
    std::string map;
    uint64_t version = 0;
    std::string key;
    size_t bytes = 0;
    // How the value was made and how long it took.
    bool advanced = false;
    int64_t changed_cells = 0;
    absl::Duration time;
  };

  // How often a query waiting for another's build looks at its cancel flag
  // (its deadline wakes it on time).
  static constexpr absl::Duration kStopPollInterval = absl::Milliseconds(50);

  // Keeps at most `max_bytes` of values (the newest value stays even when
  // it alone is larger).
  explicit DerivedCache(size_t max_bytes);

  // The store a query planning on `grid` (the snapshot's own grid, or its
  // inflation by robot_radius_cells > 0) uses; valid while the cache lives.
  std::unique_ptr<DerivedStore> For(std::shared_ptr<const MapSnapshot> snapshot,
                                    std::shared_ptr<const Grid> grid,
                                    double robot_radius_cells);

  // Drops the entries of a map once it is deleted or replaced (another map
  // id under its name). Before any store writer runs
  // (MapStore::AddListener's rule); the cache must outlive the store's
  // writers. The values are freed on the listener's thread after the
  // cache's lock (a 16384² map's HPA* graph takes about half a second:
  // deletes and replaces of huge maps delay the store's next listener call
  // by that much).
  void Follow(MapStore& store);

  Stats stats() const ABSL_LOCKS_EXCLUDED(mu_);
  // The live entries of map `name`, newest version first.
  std::vector<EntryInfo> Entries(const std::string& name) const
      ABSL_LOCKS_EXCLUDED(mu_);

 private:
  class Store;
  struct Entry {
    std::string map;
    uint64_t map_id = 0;
    uint64_t version = 0;
    // The grid is the snapshot's own (not an inflated copy): its recorded
    // changed cells describe it.
    bool stored_grid = false;
    std::weak_ptr<const Grid> grid;
    const Grid* grid_address = nullptr;
    std::string key;
    // Under the cache's mu_: the maker sets them with done, waiters Await it.
    // Done with a null value: the maker gave up (stopped or threw) and the
    // entry left the list.
    // Atomic although only read and written under mu_: absl evaluates a
    // waiter's Condition inside Mutex::Unlock of another thread, where
    // ThreadSanitizer (with Debian's uninstrumented absl) sees no lock and
    // reported the flag as a race.
    std::atomic<bool> done{false};
    std::shared_ptr<const void> value;
    size_t bytes = 0;
    bool advanced = false;
    int64_t changed_cells = 0;
    absl::Duration time;
  };

  std::shared_ptr<const void> Get(const MapSnapshot& snapshot,
                                  const std::shared_ptr<const Grid>& grid,
                                  const std::string& key,
                                  const DerivedRecipe& recipe, DerivedStop& stop)
      ABSL_LOCKS_EXCLUDED(mu_);
  // Waits until `entry` is done or `stop` fires; returns whether it is done.
  bool AwaitLocked(Entry* entry, const DerivedStop& stop)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_);
  // Drops `entry`, which its maker gave up on, and wakes its waiters.
  void AbandonLocked(const std::shared_ptr<Entry>& entry)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_);
  // Entries dropped under mu_, released after it (their values can be
  // hundreds of MiB in a million allocations: freeing an HPA* graph of a
  // 16384² map took 0.5 s, which other queries waiting on mu_ would share).
  using Graveyard = std::vector<std::shared_ptr<Entry>>;
  void EvictLocked(Graveyard& dropped) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_);
  // Removes one entry and its bytes into `dropped`; returns the next.
  std::list<std::shared_ptr<Entry>>::iterator DropLocked(
      std::list<std::shared_ptr<Entry>>::iterator it, Graveyard& dropped)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_);

  const size_t max_bytes_;
  mutable absl::Mutex mu_;
  // Signalled whenever an entry becomes done (AwaitLocked's waiters).
  absl::CondVar done_cv_;
  // Most recently used first.
  std::list<std::shared_ptr<Entry>> entries_ ABSL_GUARDED_BY(mu_);
  size_t bytes_ ABSL_GUARDED_BY(mu_) = 0;
  int64_t hits_ ABSL_GUARDED_BY(mu_) = 0;
  int64_t builds_ ABSL_GUARDED_BY(mu_) = 0;
  int64_t advances_ ABSL_GUARDED_BY(mu_) = 0;
  int64_t evictions_ ABSL_GUARDED_BY(mu_) = 0;
  int64_t stopped_builds_ ABSL_GUARDED_BY(mu_) = 0;
  int64_t stopped_waits_ ABSL_GUARDED_BY(mu_) = 0;
};

}  // namespace pathd::server

#endif  // PATHD_SERVER_DERIVED_CACHE_H_
