#include "server/derived_cache.h"

#include <algorithm>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "server/incremental_cache.h"

namespace pathd::server {

// The store one query uses: the cache, bound to the query's snapshot and
// planning grid.
class DerivedCache::Store : public DerivedStore {
 public:
  Store(DerivedCache* cache, std::shared_ptr<const MapSnapshot> snapshot,
        std::shared_ptr<const Grid> grid, double robot_radius_cells)
      : cache_(cache),
        snapshot_(std::move(snapshot)),
        grid_(std::move(grid)),
        prefix_(robot_radius_cells > 0.0
                    ? absl::StrFormat("radius=%g ", robot_radius_cells)
                    : std::string()) {}

  std::shared_ptr<const void> Get(const std::string& key, const DerivedRecipe& recipe,
                                  DerivedStop& stop) override {
    return cache_->Get(*snapshot_, grid_, prefix_ + key, recipe, stop);
  }

 private:
  DerivedCache* cache_;
  std::shared_ptr<const MapSnapshot> snapshot_;
  std::shared_ptr<const Grid> grid_;
  // Values of inflated grids advance only from the same radius's.
  std::string prefix_;
};

DerivedCache::DerivedCache(size_t max_bytes) : max_bytes_(max_bytes) {}

std::unique_ptr<DerivedStore> DerivedCache::For(
    std::shared_ptr<const MapSnapshot> snapshot, std::shared_ptr<const Grid> grid,
    double robot_radius_cells) {
  return std::make_unique<Store>(this, std::move(snapshot), std::move(grid),
                                 robot_radius_cells);
}

std::shared_ptr<const void> DerivedCache::Get(const MapSnapshot& snapshot,
                                              const std::shared_ptr<const Grid>& grid,
                                              const std::string& key,
                                              const DerivedRecipe& recipe,
                                              DerivedStop& stop) {
  const std::string& what = recipe.what.empty() ? key : recipe.what;
  std::shared_ptr<Entry> entry;
  // The newest older version's entry to advance from, with its grid.
  std::shared_ptr<Entry> base;
  std::shared_ptr<const Grid> base_grid;
  // Until this query has the value, makes it, or stops: a maker that gave up
  // leaves no entry, and the next pass here finds or makes a new one.
  while (true) {
    entry = nullptr;
    base = nullptr;
    absl::MutexLock lock(&mu_);
    for (auto it = entries_.begin(); it != entries_.end(); ++it) {
      const Entry& e = **it;
      if (e.key != key || e.map_id != snapshot.map_id) continue;
      if (e.grid_address == grid.get() && e.grid.lock() == grid) {
        entry = *it;
        entries_.splice(entries_.begin(), entries_, it);
        break;
      }
      if (e.done && e.value != nullptr && e.version < snapshot.version &&
          e.stored_grid == (grid == snapshot.grid) &&
          (base == nullptr || e.version > base->version)) {
        base = *it;
      }
    }
    if (entry == nullptr) {
      // A query already stopped starts no build (and gets no value it would
      // not use).
      if (stop.Stopped()) {
        stop.Note("building " + what);
        return nullptr;
      }
      entry = std::make_shared<Entry>();
      entry->map = snapshot.name;
      entry->map_id = snapshot.map_id;
      entry->version = snapshot.version;
      entry->stored_grid = grid == snapshot.grid;
      entry->grid = grid;
      entry->grid_address = grid.get();
      entry->key = key;
      entries_.push_front(entry);
      break;
    }
    if (!AwaitLocked(entry.get(), stop)) {
      ++stopped_waits_;
      stop.Note("waiting for another query's build of " + what);
      return nullptr;
    }
    if (entry->value != nullptr) {
      ++hits_;
      return entry->value;
    }
    // The maker gave up (stopped or threw) and dropped the entry: look again.
  }

  // A build that gives up or throws (out of memory) must not leave waiters
  // waiting on an entry that never completes: drop it, wake them, and let
  // them build it (the job reports the failure or the stop).
  struct AbandonUnlessDone {
    DerivedCache* cache;
    std::shared_ptr<Entry> entry;
    ~AbandonUnlessDone() {
      absl::MutexLock lock(&cache->mu_);
      if (!entry->done) cache->AbandonLocked(entry);
    }
  } abandon_unless_done{this, entry};

  const absl::Time start = absl::Now();
  std::shared_ptr<const void> value;
  int64_t changed_cells = 0;
  bool advanced = false;
  if (base != nullptr && recipe.advance) {
    base_grid = base->grid.lock();
    std::vector<Cell> changed;
    bool known = false;
    // A value of the stored grid advances with the changed cells the map's
    // history lists since its version (a superset where a cell changed back,
    // which every recipe allows); else, while its grid lives, with the two
    // grids compared.
    std::optional<std::vector<Cell>> since;
    if (base->stored_grid) since = ChangesSince(snapshot, base->version);
    if (since.has_value()) {
      changed = *std::move(since);
      known = true;
    } else if (base_grid != nullptr) {
      absl::StatusOr<std::vector<Cell>> between =
          ChangesBetween(*base_grid, base->version, *grid, snapshot);
      if (between.ok()) {
        changed = *std::move(between);
        known = true;
      }
    }
    if (known) {
      value = recipe.advance(base->value.get(), *grid, changed, stop);
      advanced = value != nullptr;
      changed_cells = static_cast<int64_t>(changed.size());
    }
  }
  // An advance that declined may also have been stopped: no build then.
  if (value == nullptr && !stop.Stopped()) value = recipe.build(*grid, stop);
  if (value == nullptr) {
    stop.Note("building " + what);
    absl::MutexLock lock(&mu_);
    AbandonLocked(entry);
    ++stopped_builds_;
    return nullptr;
  }
  const size_t bytes = recipe.bytes ? recipe.bytes(value.get()) : 0;

  // Declared before the lock: released after it.
  Graveyard dropped;
  absl::MutexLock lock(&mu_);
  entry->value = value;
  entry->bytes = bytes;
  entry->advanced = advanced;
  entry->changed_cells = changed_cells;
  entry->time = absl::Now() - start;
  entry->done = true;
  done_cv_.SignalAll();
  bytes_ += bytes;
  ++(advanced ? advances_ : builds_);
  EvictLocked(dropped);
  return value;
}

void DerivedCache::Follow(MapStore& store) {
  store.AddListener([this](std::string_view name,
                           const std::shared_ptr<const MapSnapshot>& snapshot) {
    Graveyard dropped;
    absl::MutexLock lock(&mu_);
    for (auto it = entries_.begin(); it != entries_.end();) {
      const Entry& e = **it;
      it = e.done && e.map == name && (snapshot == nullptr || e.map_id != snapshot->map_id)
               ? DropLocked(it, dropped)
               : std::next(it);
    }
  });
}

bool DerivedCache::AwaitLocked(Entry* entry, const DerivedStop& stop) {
  // A CondVar and the flag checked here, not Await with a Condition: Abseil
  // evaluates a waiter's Condition (an object on the waiter's stack) inside
  // another thread's Unlock, which ThreadSanitizer with Debian's
  // uninstrumented Abseil reported as a race on that stack (as the memory
  // budget's trimmer did). The deadline wakes the wait on time; the cancel
  // flag is only read, so the wait comes up for it every kStopPollInterval.
  while (!entry->done.load()) {
    if (done_cv_.WaitWithDeadline(
            &mu_, std::min(stop.deadline(), absl::Now() + kStopPollInterval)) &&
        !entry->done.load() && stop.Stopped()) {
      return false;
    }
  }
  return true;
}

void DerivedCache::AbandonLocked(const std::shared_ptr<Entry>& entry) {
  entries_.remove(entry);
  entry->done = true;
  done_cv_.SignalAll();
}

std::list<std::shared_ptr<DerivedCache::Entry>>::iterator DerivedCache::DropLocked(
    std::list<std::shared_ptr<Entry>>::iterator it, Graveyard& dropped) {
  bytes_ -= (*it)->bytes;
  dropped.push_back(*it);
  return entries_.erase(it);
}

void DerivedCache::EvictLocked(Graveyard& dropped) {
  // An entry whose grid is freed serves no query of its own version any
  // more, but the newest one of its map and key made on the stored grid is
  // what the next version advances from (with the map's change history):
  // it stays until a newer one of its kind exists, or the budget, a delete
  // or a replace drops it. Others go (an inflated grid's changes are only
  // known while both grids live).
  // (A loop, not a lambda: the thread-safety analysis does not see mu_
  // held inside one.)
  for (auto it = entries_.begin(); it != entries_.end();) {
    const Entry& e = **it;
    bool drop = e.done && e.grid.expired();
    if (drop && e.stored_grid) {
      drop = false;
      for (const std::shared_ptr<Entry>& other : entries_) {
        if (other->done && other->value != nullptr && other->key == e.key &&
            other->map_id == e.map_id && other->stored_grid && other->version > e.version) {
          drop = true;
          break;
        }
      }
    }
    it = drop ? DropLocked(it, dropped) : std::next(it);
  }
  // Least recently used first, never one being made, never the newest.
  while (bytes_ > max_bytes_ && entries_.size() > 1) {
    auto victim = entries_.end();
    for (auto it = std::next(entries_.begin()); it != entries_.end(); ++it) {
      if ((*it)->done) victim = it;
    }
    if (victim == entries_.end()) break;
    DropLocked(victim, dropped);
    ++evictions_;
  }
}

DerivedCache::Stats DerivedCache::stats() const {
  absl::MutexLock lock(&mu_);
  Stats s;
  s.hits = hits_;
  s.builds = builds_;
  s.advances = advances_;
  s.evictions = evictions_;
  s.stopped_builds = stopped_builds_;
  s.stopped_waits = stopped_waits_;
  s.budget_bytes = max_bytes_;
  s.entries = entries_.size();
  s.bytes = bytes_;
  return s;
}

std::vector<DerivedCache::EntryInfo> DerivedCache::Entries(
    const std::string& name) const {
  std::vector<EntryInfo> out;
  absl::MutexLock lock(&mu_);
  for (const std::shared_ptr<Entry>& e : entries_) {
    if (e->map != name || !e->done || e->grid.expired()) continue;
    out.push_back(EntryInfo{e->map, e->version, e->key, e->bytes, e->advanced,
                            e->changed_cells, e->time});
  }
  std::stable_sort(out.begin(), out.end(), [](const EntryInfo& a, const EntryInfo& b) {
    return a.version > b.version;
  });
  return out;
}

}  // namespace pathd::server
