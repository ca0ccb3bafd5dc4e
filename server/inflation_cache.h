// Shaped copies of map versions (core/map/inflation.h, GridShape: inflated
// by a robot radius, with clearance costs), computed once per (map version,
// shape) and shared by every request that asks for that shape.
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
#include "core/map/grid.h"
#include "core/map/inflation.h"

namespace pathd::server {

// Thread-safe LRU cache. Entries are keyed by the identity of the source grid
// (the shared_ptr<const Grid> of a map version, held weakly so a cached entry
// never keeps an old version alive and a freed version can never be matched
// by a new grid at the same address) and the radius. Concurrent requests for
// a missing entry compute it once: the first computes, the others wait.
class InflationCache {
 public:
  using InflateFn = std::function<absl::StatusOr<Grid>(const Grid&, const GridShape&)>;

  struct Stats {
    int64_t hits = 0;
    int64_t misses = 0;
    size_t entries = 0;
    size_t bytes = 0;
  };

  // Keeps at most `max_entries` shaped grids (at least 1).
  InflationCache(InflateFn inflate, size_t max_entries);

  // `source` shaped by `shape` (shape.shaped()), computing it on a miss.
  // Errors from the inflate function are returned and not cached.
  absl::StatusOr<std::shared_ptr<const Grid>> Get(
      const std::shared_ptr<const Grid>& source, const GridShape& shape)
      ABSL_LOCKS_EXCLUDED(mu_);
  // Only inflated by a robot radius.
  absl::StatusOr<std::shared_ptr<const Grid>> Get(
      const std::shared_ptr<const Grid>& source, double radius_cells)
      ABSL_LOCKS_EXCLUDED(mu_) {
    return Get(source, GridShape{.robot_radius_cells = radius_cells});
  }

  Stats stats() const ABSL_LOCKS_EXCLUDED(mu_);

 private:
  struct Entry {
    std::weak_ptr<const Grid> source;
    const Grid* source_address = nullptr;
    GridShape shape;
    // Read and written under the cache's mu_ (a nested struct cannot name it
    // in ABSL_GUARDED_BY); the computing thread sets `done` with the two
    // fields below, and waiters Await it.
    bool done = false;
    absl::Status status;
    std::shared_ptr<const Grid> inflated;
  };

  // Drops entries whose source version is gone, then the least recently used
  // ones beyond the capacity (never one still being computed).
  void EvictLocked() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_);

  const InflateFn inflate_;
  const size_t max_entries_;
  mutable absl::Mutex mu_;
  // Most recently used first.
  std::list<std::shared_ptr<Entry>> entries_ ABSL_GUARDED_BY(mu_);
  int64_t hits_ ABSL_GUARDED_BY(mu_) = 0;
  int64_t misses_ ABSL_GUARDED_BY(mu_) = 0;
};

}  // namespace pathd::server

#endif  // PATHD_SERVER_INFLATION_CACHE_H_
