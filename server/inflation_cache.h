// Shaped copies of map versions (core/map/inflation.h, GridShape: inflated
// by a robot radius, with inflation and clearance costs), computed once per
// (map version, shape) and shared by every request that asks for that
// shape; a new version's is advanced from the previous version's around
// the changed cells (AdvanceShapedGrid) instead of shaped in full.
#ifndef PATHD_SERVER_INFLATION_CACHE_H_
#define PATHD_SERVER_INFLATION_CACHE_H_

#include <cstddef>
#include <cstdint>
#include <functional>
#include <list>
#include <memory>

#include "absl/base/thread_annotations.h"
#include "absl/status/statusor.h"
#include "absl/synchronization/mutex.h"
#include "absl/types/span.h"
#include "core/map/grid.h"
#include "core/map/inflation.h"
#include "server/map_store.h"

namespace pathd::server {

// Thread-safe LRU cache. Entries are keyed by the identity of the source grid
// (the shared_ptr<const Grid> of a map version, held weakly so a cached entry
// never keeps an old version's stored grid alive and a freed version can
// never be matched by a new grid at the same address) and the shape.
// Concurrent requests for a missing entry compute it once: the first
// computes, the others wait.
//
// Advancing: on a miss, the entry of the same map id and shape at the newest
// older version is advanced (AdvanceShapedGrid) with the cells that changed
// since: the new version's recorded changed cells when it is the next
// version, otherwise a comparison of the two stored grids while the older
// one is still alive. Without either, or when the changes cover too much,
// the grid is shaped in full. So that the next version finds it, the newest
// entry of each (map id, shape) stays after its version's stored grid is
// freed (it owns its shaped grid), until a newer version's entry replaces it
// or the LRU bound drops it.
class InflationCache {
 public:
  using InflateFn = std::function<absl::StatusOr<Grid>(const Grid&, const GridShape&)>;
  using AdvanceFn = std::function<absl::StatusOr<ShapedGridAdvance>(
      const Grid& previous_shaped, const Grid& stored, absl::Span<const Cell> changed,
      const GridShape& shape)>;

  struct Stats {
    int64_t hits = 0;
    int64_t misses = 0;
    // How misses got their grid: shaped in full, or advanced from an older
    // version's (an advance that found the changes too large counts as a
    // build).
    int64_t builds = 0;
    int64_t advances = 0;
    size_t entries = 0;
    size_t bytes = 0;
  };

  // Keeps at most `max_entries` shaped grids (at least 1), shaped by
  // ShapeGrid and advanced by AdvanceShapedGrid.
  explicit InflationCache(size_t max_entries);
  // The same with other shaping functions (tests).
  InflationCache(InflateFn inflate, AdvanceFn advance, size_t max_entries);

  // snapshot.grid shaped by `shape` (shape.shaped()), computing it on a miss.
  // Errors from the shaping functions are returned and not cached.
  absl::StatusOr<std::shared_ptr<const Grid>> Get(const MapSnapshot& snapshot,
                                                  const GridShape& shape)
      ABSL_LOCKS_EXCLUDED(mu_);
  // Only inflated by a robot radius.
  absl::StatusOr<std::shared_ptr<const Grid>> Get(const MapSnapshot& snapshot,
                                                  double radius_cells)
      ABSL_LOCKS_EXCLUDED(mu_) {
    return Get(snapshot, GridShape{.robot_radius_cells = radius_cells});
  }

  Stats stats() const ABSL_LOCKS_EXCLUDED(mu_);

 private:
  struct Entry {
    std::weak_ptr<const Grid> source;
    const Grid* source_address = nullptr;
    uint64_t map_id = 0;
    uint64_t version = 0;
    GridShape shape;
    // Read and written under the cache's mu_ (a nested struct cannot name it
    // in ABSL_GUARDED_BY); the computing thread sets `done` with the two
    // fields below, and waiters Await it.
    bool done = false;
    absl::Status status;
    std::shared_ptr<const Grid> inflated;
  };

  // Drops entries whose source version is gone unless they are the newest
  // of their (map id, shape), then the least recently used ones beyond the
  // capacity (never one still being computed).
  void EvictLocked() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_);

  const InflateFn inflate_;
  const AdvanceFn advance_;
  const size_t max_entries_;
  mutable absl::Mutex mu_;
  // Most recently used first.
  std::list<std::shared_ptr<Entry>> entries_ ABSL_GUARDED_BY(mu_);
  int64_t hits_ ABSL_GUARDED_BY(mu_) = 0;
  int64_t misses_ ABSL_GUARDED_BY(mu_) = 0;
  int64_t builds_ ABSL_GUARDED_BY(mu_) = 0;
  int64_t advances_ ABSL_GUARDED_BY(mu_) = 0;
};

}  // namespace pathd::server

#endif  // PATHD_SERVER_INFLATION_CACHE_H_
