#include "server/inflation_cache.h"

#include <utility>

namespace pathd::server {

InflationCache::InflationCache(InflateFn inflate, size_t max_entries)
    : inflate_(std::move(inflate)), max_entries_(max_entries == 0 ? 1 : max_entries) {}

absl::StatusOr<std::shared_ptr<const Grid>> InflationCache::Get(
    const std::shared_ptr<const Grid>& source, const GridShape& shape) {
  std::shared_ptr<Entry> entry;
  bool compute = false;
  {
    absl::MutexLock lock(&mu_);
    for (auto it = entries_.begin(); it != entries_.end(); ++it) {
      Entry& e = **it;
      // Same live grid object and same shape (exact: its values come from
      // one conversion of the request's, so equal requests compare equal).
      if (e.source_address == source.get() && e.shape == shape &&
          e.source.lock() == source) {
        entry = *it;
        entries_.splice(entries_.begin(), entries_, it);
        break;
      }
    }
    if (entry == nullptr) {
      entry = std::make_shared<Entry>();
      entry->source = source;
      entry->source_address = source.get();
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
    absl::StatusOr<Grid> inflated = inflate_(*source, shape);
    absl::MutexLock lock(&mu_);
    if (inflated.ok()) {
      entry->inflated = std::make_shared<const Grid>(*std::move(inflated));
    } else {
      entry->status = inflated.status();
      // Not cached: the next request tries again.
      entries_.remove(entry);
    }
    entry->done = true;
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
  entries_.remove_if([](const std::shared_ptr<Entry>& e) {
    return e->done && e->source.expired();
  });
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
  s.entries = entries_.size();
  for (const auto& e : entries_) {
    if (e->inflated != nullptr) s.bytes += e->inflated->size();
  }
  return s;
}

}  // namespace pathd::server
