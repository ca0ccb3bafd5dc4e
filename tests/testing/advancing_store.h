// A DerivedStore (core/search/derived.h) for tests and benchmarks that
// advances instead of rebuilding: it keeps the last value per key together
// with the grid it belongs to, and when asked for the key on a different
// grid of the same size it calls recipe.advance(previous, grid, changed)
// with the cells whose cost differs between the two grids (found by
// comparing them, as the server's cache does when it has no recorded
// changes). So a test can run a planner through random update sequences on
// an advanced structure and compare every answer with a fresh build (a null
// store), and a benchmark can time builds and advances (events()).
#ifndef PATHD_TESTS_TESTING_ADVANCING_STORE_H_
#define PATHD_TESTS_TESTING_ADVANCING_STORE_H_

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/synchronization/mutex.h"
#include "absl/time/clock.h"
#include "absl/time/time.h"
#include "absl/types/span.h"
#include "core/map/grid.h"
#include "core/search/derived.h"

namespace pathd::testing {

// Thread-safe. Usage: SetGrid(grid) before each Plan on `grid` with
// request.derived = &store; the planner's GetDerived lands in Get().
class AdvancingStore : public DerivedStore {
 public:
  struct Options {
    // Also list the in-bounds 4-neighbours of every changed cell (unchanged
    // cells), as a batch update that rewrites cells with their own value
    // would: advance must not depend on every listed cell having changed.
    bool pad_with_unchanged = false;
  };
  // One Get that built or advanced a value (hits are only counted).
  struct Event {
    std::string key;
    // Advanced (else built: first time, or advance missing or declined).
    bool advanced = false;
    // Cells passed to advance (0 for builds).
    size_t changed = 0;
    // Time in recipe.advance (and recipe.build after a declined advance).
    absl::Duration time;
    // recipe.bytes of the new value.
    size_t bytes = 0;
  };
  struct Stats {
    int64_t builds = 0;
    int64_t advances = 0;
    // Of the builds: an older value was there but advance was missing or
    // returned null.
    int64_t rebuilds = 0;
    int64_t hits = 0;
    // Cells passed to the last successful advance.
    size_t last_changed = 0;
  };

  AdvancingStore() = default;
  explicit AdvancingStore(Options options) : options_(options) {}

  // The grid the following Get calls are for (copied; the copy lives as
  // long as a value made for it).
  void SetGrid(const Grid& grid) ABSL_LOCKS_EXCLUDED(mu_) {
    absl::MutexLock lock(&mu_);
    grid_ = std::make_shared<const Grid>(grid);
  }

  // Builds and advances run without the lock held, so a recipe may ask the
  // store for another key (a structure made from another one).
  std::shared_ptr<const void> Get(const std::string& key, const DerivedRecipe& recipe,
                                  DerivedStop& stop) override ABSL_LOCKS_EXCLUDED(mu_) {
    Entry previous;
    std::shared_ptr<const Grid> grid;
    {
      absl::MutexLock lock(&mu_);
      grid = grid_;
      auto it = entries_.find(key);
      if (it != entries_.end()) previous = it->second;
      if (previous.value != nullptr &&
          (previous.grid == grid || previous.grid->cells() == grid->cells())) {
        ++stats_.hits;
        it->second.grid = grid;
        return previous.value;
      }
    }
    std::shared_ptr<const void> value;
    bool advanced = false, rebuilt = false;
    size_t changed_count = 0;
    // Timed: the build or advance, not the diff that finds the changed cells
    // (O(map) here; a map store records them as it applies an update).
    absl::Time started = absl::Now();
    if (previous.value != nullptr && previous.grid->width() == grid->width() &&
        previous.grid->height() == grid->height()) {
      const std::vector<Cell> changed = ChangedCells(*previous.grid, *grid);
      changed_count = changed.size();
      started = absl::Now();
      if (recipe.advance) value = recipe.advance(previous.value.get(), *grid, changed, stop);
      advanced = value != nullptr;
      rebuilt = !advanced;
    }
    if (value == nullptr) value = recipe.build(*grid, stop);
    // Stopped: nothing to keep.
    if (value == nullptr) return nullptr;
    const absl::Duration took = absl::Now() - started;
    const size_t bytes = recipe.bytes ? recipe.bytes(value.get()) : 0;
    absl::MutexLock lock(&mu_);
    events_.push_back(Event{key, advanced, advanced ? changed_count : 0, took, bytes});
    if (advanced) {
      ++stats_.advances;
      stats_.last_changed = changed_count;
    } else {
      ++stats_.builds;
      if (rebuilt) ++stats_.rebuilds;
    }
    entries_[key] = Entry{grid, value};
    return value;
  }

  // For tests of the store itself: never stops.
  std::shared_ptr<const void> Get(const std::string& key, const DerivedRecipe& recipe)
      ABSL_LOCKS_EXCLUDED(mu_) {
    DerivedStop never;
    return Get(key, recipe, never);
  }

  Stats stats() const ABSL_LOCKS_EXCLUDED(mu_) {
    absl::MutexLock lock(&mu_);
    return stats_;
  }

  // Every build and advance so far, in order.
  std::vector<Event> events() const ABSL_LOCKS_EXCLUDED(mu_) {
    absl::MutexLock lock(&mu_);
    return events_;
  }

  // Forgets every value (the next Get builds).
  void Clear() ABSL_LOCKS_EXCLUDED(mu_) {
    absl::MutexLock lock(&mu_);
    entries_.clear();
  }

  // The cells whose cost differs between two grids of the same size, row by
  // row.
  static std::vector<Cell> Diff(const Grid& before, const Grid& after) {
    std::vector<Cell> changed;
    for (size_t i = 0; i < after.size(); ++i) {
      if (before.cells()[i] != after.cells()[i]) changed.push_back(after.CellAt(i));
    }
    return changed;
  }

 private:
  struct Entry {
    std::shared_ptr<const Grid> grid;
    std::shared_ptr<const void> value;
  };

  std::vector<Cell> ChangedCells(const Grid& before, const Grid& after) const {
    std::vector<Cell> changed = Diff(before, after);
    if (!options_.pad_with_unchanged) return changed;
    std::vector<uint8_t> listed(after.size(), 0);
    for (Cell c : changed) listed[after.Index(c)] = 1;
    const size_t n = changed.size();
    for (size_t i = 0; i < n; ++i) {
      const Cell c = changed[i];
      for (Cell d : {Cell{1, 0}, Cell{-1, 0}, Cell{0, 1}, Cell{0, -1}}) {
        const Cell e{c.x + d.x, c.y + d.y};
        if (after.InBounds(e) && !listed[after.Index(e)]) {
          listed[after.Index(e)] = 1;
          changed.push_back(e);
        }
      }
    }
    return changed;
  }

  const Options options_;
  mutable absl::Mutex mu_;
  std::shared_ptr<const Grid> grid_ ABSL_GUARDED_BY(mu_);
  std::map<std::string, Entry> entries_ ABSL_GUARDED_BY(mu_);
  Stats stats_ ABSL_GUARDED_BY(mu_);
  std::vector<Event> events_ ABSL_GUARDED_BY(mu_);
};

}  // namespace pathd::testing

#endif  // PATHD_TESTS_TESTING_ADVANCING_STORE_H_
