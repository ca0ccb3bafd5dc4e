#include "server/inflation_cache.h"

#include <iterator>
#include <optional>
#include <utility>
#include <vector>

#include "server/incremental_cache.h"

namespace pathd::server {

InflationCache::InflationCache(size_t max_entries)
    : InflationCache(&ShapeGrid, &AdvanceShapedGrid, max_entries) {}

InflationCache::InflationCache(InflateFn inflate, AdvanceFn advance, size_t max_entries)
    : inflate_(std::move(inflate)),
      advance_(std::move(advance)),
      max_entries_(max_entries == 0 ? 1 : max_entries) {}

absl::StatusOr<std::shared_ptr<const Grid>> InflationCache::Get(
    const MapSnapshot& snapshot, const GridShape& shape) {
  const std::shared_ptr<const Grid>& source = snapshot.grid;
  std::shared_ptr<Entry> entry;
  // The newest older version's shaped grid to advance from, and that
  // version's stored grid while it lives.
  std::shared_ptr<const Grid> base_shaped;
  std::shared_ptr<const Grid> base_source;
  uint64_t base_version = 0;
  bool compute = false;
  {
    absl::MutexLock lock(&mu_);
    const Entry* base = nullptr;
    for (auto it = entries_.begin(); it != entries_.end(); ++it) {
      Entry& e = **it;
      // Same shape exactly: its values come from one conversion of the
      // request's, so equal requests compare equal.
      if (!(e.shape == shape)) continue;
      // Same live grid object.
      if (e.source_address == source.get() && e.source.lock() == source) {
        entry = *it;
        entries_.splice(entries_.begin(), entries_, it);
        break;
      }
      if (e.map_id == snapshot.map_id && e.version < snapshot.version && e.done &&
          e.inflated != nullptr && (base == nullptr || e.version > base->version)) {
        base = &e;
      }
    }
    if (entry == nullptr) {
      if (base != nullptr) {
        base_shaped = base->inflated;
        base_source = base->source.lock();
        base_version = base->version;
      }
      entry = std::make_shared<Entry>();
      entry->source = source;
      entry->source_address = source.get();
      entry->map_id = snapshot.map_id;
      entry->version = snapshot.version;
      entry->shape = shape;
      entries_.push_front(entry);
      compute = true;
      ++misses_;
      EvictLocked();
    } else {
      ++hits_;
    }
  }
  if (compute) {
    std::optional<absl::StatusOr<ShapedGridAdvance>> advanced;
    if (base_shaped != nullptr) {
      if (std::optional<std::vector<Cell>> since = ChangesSince(snapshot, base_version)) {
        // The cells the map's history lists since the base's version (a
        // cell changed back is listed too: more is harmless to the advance).
        advanced = advance_(*base_shaped, *source, *since, shape);
      } else if (base_source != nullptr) {
        // Beyond the history: the two stored grids compared.
        absl::StatusOr<std::vector<Cell>> changed =
            ChangesBetween(*base_source, base_version, *source, snapshot);
        if (changed.ok()) advanced = advance_(*base_shaped, *source, *changed, shape);
      }
    }
    bool was_advanced = false;
    absl::StatusOr<Grid> shaped = absl::UnknownError("not shaped");
    if (advanced.has_value() && advanced->ok()) {
      was_advanced = (*advanced)->advanced;
      shaped = std::move((*advanced)->grid);
    } else if (advanced.has_value()) {
      shaped = advanced->status();
    } else {
      shaped = inflate_(*source, shape);
    }
    absl::MutexLock lock(&mu_);
    if (shaped.ok()) {
      entry->inflated = std::make_shared<const Grid>(*std::move(shaped));
      ++(was_advanced ? advances_ : builds_);
    } else {
      entry->status = shaped.status();
      // Not cached: the next request tries again.
      entries_.remove(entry);
    }
    entry->done = true;
    // The base entry may have become droppable.
    EvictLocked();
  } else {
    absl::MutexLock lock(&mu_);
    mu_.Await(absl::Condition(
        +[](Entry* e) { return e->done; }, entry.get()));
  }
  absl::MutexLock lock(&mu_);
  if (!entry->status.ok()) return entry->status;
  return entry->inflated;
}

void InflationCache::EvictLocked() {
  // An entry whose version's stored grid is gone can only be a base to
  // advance from: kept while no newer version of its map has a shaped grid
  // of its shape.
  for (auto it = entries_.begin(); it != entries_.end();) {
    const Entry& e = **it;
    bool superseded = false;
    if (e.done && e.source.expired()) {
      for (const std::shared_ptr<Entry>& f : entries_) {
        if (f->map_id == e.map_id && f->version > e.version && f->shape == e.shape &&
            f->done && f->inflated != nullptr) {
          superseded = true;
          break;
        }
      }
    }
    it = superseded ? entries_.erase(it) : std::next(it);
  }
  while (entries_.size() > max_entries_) {
    auto victim = entries_.end();
    for (auto it = entries_.begin(); it != entries_.end(); ++it) {
      if ((*it)->done) victim = it;
    }
    if (victim == entries_.end()) break;  // all being computed
    entries_.erase(victim);
  }
}

InflationCache::Stats InflationCache::stats() const {
  absl::MutexLock lock(&mu_);
  Stats s;
  s.hits = hits_;
  s.misses = misses_;
  s.builds = builds_;
  s.advances = advances_;
  s.entries = entries_.size();
  for (const auto& e : entries_) {
    if (e->inflated != nullptr) s.bytes += e->inflated->size();
  }
  return s;
}

}  // namespace pathd::server
