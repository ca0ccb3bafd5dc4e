// The definition of MapStore::GridPool (spare grid buffers and the change
// log of one map id), kept apart from map_store.cc so each file stays short.
// Included by map_store.cc only.
#ifndef PATHD_SERVER_MAP_STORE_GRID_POOL_H_
#define PATHD_SERVER_MAP_STORE_GRID_POOL_H_

#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <utility>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/synchronization/mutex.h"
#include "core/map/grid.h"
#include "server/map_store.h"

namespace pathd::server {

// Spare grid buffers of one map id, and the cells its recent versions
// changed. Owned by the map's store entry alone; a published grid's deleter
// holds it weakly and hands the buffer back when the last snapshot drops it.
class MapStore::GridPool {
 public:
  explicit GridPool(size_t grid_cells)
      : log_budget_(grid_cells / kLogCellsDivisor + kLogMinCells) {}

  // The shared_ptr deleter of a published grid.
  struct Release {
    std::weak_ptr<GridPool> pool;
    uint64_t version = 0;
    void operator()(Grid* grid) const {
      std::unique_ptr<Grid> owned(grid);
      // A pool that is gone (map deleted or replaced, store destroyed) lets
      // the buffer be freed here.
      if (std::shared_ptr<GridPool> live = pool.lock()) {
        live->Return(std::move(owned), version);
      }
    }
  };

  // Publishes `grid` as the buffer of `version`. Every call makes a new
  // control block, so weak references to an earlier version held in the same
  // buffer (the inflation cache's keys) can never match this one.
  static std::shared_ptr<const Grid> Publish(const std::shared_ptr<GridPool>& pool,
                                             std::unique_ptr<Grid> grid,
                                             uint64_t version) {
    {
      absl::MutexLock lock(&pool->mu_);
      ++pool->published_;
    }
    return std::shared_ptr<const Grid>(grid.release(), Release{pool, version});
  }

  // The newest spare (null when there is none) and, when the log reaches back
  // to it, the changed cells of every version after it up to `to`, oldest
  // first (`replayable`). Otherwise the caller copies the whole grid.
  struct Taken {
    std::unique_ptr<Grid> grid;
    bool replayable = false;
    std::vector<std::shared_ptr<const std::vector<Cell>>> replay;
  };
  Taken Take(uint64_t to) {
    absl::MutexLock lock(&mu_);
    if (published_ >= peak_published_ || ++peak_age_ > kSpareWindow) {
      peak_published_ = published_;
      peak_age_ = 0;
    }
    Taken taken;
    if (spares_.empty()) return taken;
    auto newest = std::max_element(
        spares_.begin(), spares_.end(),
        [](const Spare& a, const Spare& b) { return a.version < b.version; });
    const uint64_t from = newest->version;
    taken.grid = std::move(newest->grid);
    spares_.erase(newest);
    if (from == to) {
      taken.replayable = true;
    } else if (!log_.empty() && log_.back().version == to &&
               log_.front().version <= from + 1) {
      taken.replayable = true;
      for (const LogEntry& entry : log_) {
        if (entry.version > from) taken.replay.push_back(entry.cells);
      }
    }
    return taken;
  }

  // Logs what version `snapshot` changed. A version whose changes are unknown
  // or larger than the log's budget drops the log: no spare can be replayed
  // across it.
  void Record(const MapSnapshot& snapshot) {
    absl::MutexLock lock(&mu_);
    if (!snapshot.changes_known || snapshot.changed_cells.size() > log_budget_) {
      log_.clear();
      log_cells_ = 0;
      return;
    }
    log_.push_back(LogEntry{snapshot.version, std::make_shared<const std::vector<Cell>>(
                                                  snapshot.changed_cells)});
    log_cells_ += snapshot.changed_cells.size();
    while (log_cells_ > log_budget_ || log_.size() > kMaxLogVersions) {
      log_cells_ -= log_.front().cells->size();
      log_.pop_front();
    }
  }

 private:
  struct Spare {
    std::unique_ptr<Grid> grid;
    uint64_t version = 0;
  };
  // Cells that differ between version - 1 and version.
  struct LogEntry {
    uint64_t version = 0;
    std::shared_ptr<const std::vector<Cell>> cells;
  };

  // Keeps a released buffer while the pool holds fewer than the recent peak
  // of published buffers plus one (see kSpareWindow), dropping the oldest
  // spares beyond that: the newest needs the shortest replay.
  void Return(std::unique_ptr<Grid> grid, uint64_t version) {
    // Declared before the lock so buffers dropped here are freed after
    // unlocking.
    std::vector<Spare> dropped;
    absl::MutexLock lock(&mu_);
    --published_;
    spares_.push_back(Spare{std::move(grid), version});
    const size_t keep = peak_published_ + 1 > published_ ? peak_published_ + 1 - published_ : 0;
    if (spares_.size() <= keep) return;
    std::sort(spares_.begin(), spares_.end(),
              [](const Spare& a, const Spare& b) { return a.version > b.version; });
    std::move(spares_.begin() + static_cast<std::ptrdiff_t>(keep), spares_.end(),
              std::back_inserter(dropped));
    spares_.resize(keep);
  }

  const size_t log_budget_;
  absl::Mutex mu_;
  std::vector<Spare> spares_ ABSL_GUARDED_BY(mu_);
  // Consecutive versions, oldest first, ending at the newest update.
  std::deque<LogEntry> log_ ABSL_GUARDED_BY(mu_);
  size_t log_cells_ ABSL_GUARDED_BY(mu_) = 0;
  // Buffers published and not yet returned, and their most at an update
  // within the last kSpareWindow updates (peak_age_ updates ago).
  size_t published_ ABSL_GUARDED_BY(mu_) = 0;
  size_t peak_published_ ABSL_GUARDED_BY(mu_) = 0;
  int peak_age_ ABSL_GUARDED_BY(mu_) = 0;
};

}  // namespace pathd::server

#endif  // PATHD_SERVER_MAP_STORE_GRID_POOL_H_
