// IncrementalCache: slots of incremental state, the per-kind LRU index over
// them, and the repairs that follow map versions.
#include "server/incremental_cache.h"

#include <iterator>
#include <tuple>
#include <utility>

#include "absl/cleanup/cleanup.h"
#include "absl/status/status.h"
#include "core/status_macros.h"

namespace pathd::server {

absl::StatusOr<std::vector<Cell>> ChangesBetween(const Grid& before,
                                                 uint64_t before_version,
                                                 const Grid& after,
                                                 const MapSnapshot& next) {
  if (next.changes_known && next.version == before_version + 1 &&
      &after == next.grid.get() && before.width() == after.width() &&
      before.height() == after.height()) {
    return next.changed_cells;
  }
  return ChangedCells(before, after);
}

namespace {

// A build stopped by its stop condition reports the stop as a status
// (ShortestPathMap::Build); this turns it back into the plan outcome.
PlanOutcome StopOutcome(const absl::Status& status) {
  switch (status.code()) {
    case absl::StatusCode::kDeadlineExceeded:
      return PlanOutcome::kTimeout;
    case absl::StatusCode::kCancelled:
      return PlanOutcome::kCancelled;
    case absl::StatusCode::kResourceExhausted:
      return PlanOutcome::kExpansionLimit;
    default:
      return PlanOutcome::kFound;
  }
}

}  // namespace

std::string_view IncrementalCache::KindName(Kind kind) {
  return kind == Kind::kSpm ? "spm" : "dstar_lite";
}

bool IncrementalCache::KeyLess::operator()(const Key& a, const Key& b) const {
  return std::tie(a.map, a.goal.x, a.goal.y, a.cost.connectivity, a.cost.cost_weight,
                  a.cost.unknown_is_free, a.robot_radius_cells, a.inflation_radius_cells,
                  a.cost_scaling_per_cell, a.min_clearance_cells) <
         std::tie(b.map, b.goal.x, b.goal.y, b.cost.connectivity, b.cost.cost_weight,
                  b.cost.unknown_is_free, b.robot_radius_cells, b.inflation_radius_cells,
                  b.cost_scaling_per_cell, b.min_clearance_cells);
}

IncrementalCache::IncrementalCache(InflationCache& inflation, size_t budget_bytes)
    : inflation_(inflation) {
  absl::MutexLock lock(&mu_);
  // An even split: a D* Lite search takes about four times the bytes per cell
  // of a field, but the two serve different clients and neither should be
  // able to evict the other.
  for (Shard& shard : shards_) shard.budget = budget_bytes / kKinds;
}

void IncrementalCache::Follow(MapStore& store, WorkerPool& pool) {
  pool_ = &pool;
  store.AddListener([this](std::string_view name,
                           const std::shared_ptr<const MapSnapshot>& snapshot) {
    OnMapChanged(name, snapshot);
  });
}

std::shared_ptr<IncrementalCache::Slot> IncrementalCache::PinLocked(Kind kind,
                                                                    const Key& key) {
  Shard& shard = shards_[static_cast<int>(kind)];
  auto it = shard.index.find(key);
  if (it == shard.index.end()) {
    it = shard.index.emplace(key, Node()).first;
    it->second.slot = std::make_shared<Slot>(kind, key);
    shard.lru.push_front(&it->first);
    it->second.lru = shard.lru.begin();
  } else {
    shard.lru.splice(shard.lru.begin(), shard.lru, it->second.lru);
  }
  ++it->second.users;
  return it->second.slot;
}

IncrementalCache::Node* IncrementalCache::NodeOfLocked(const Slot& slot) {
  Shard& shard = shards_[static_cast<int>(slot.kind)];
  auto it = shard.index.find(slot.key);
  if (it == shard.index.end() || it->second.slot.get() != &slot) return nullptr;
  return &it->second;
}

void IncrementalCache::Unpin(const Slot& slot) {
  absl::MutexLock lock(&mu_);
  Shard& shard = shards_[static_cast<int>(slot.kind)];
  if (Node* node = NodeOfLocked(slot); node != nullptr) {
    --node->users;
    // A build that failed or was stopped leaves an empty node; nobody would
    // ever evict it (it holds no bytes), so it goes now.
    if (node->users == 0 && node->at.map_id == 0) {
      EraseLocked(shard, shard.index.find(slot.key));
    }
  }
  EvictLocked(shard);
}

void IncrementalCache::EraseLocked(Shard& shard, Index::iterator it) {
  shard.bytes -= it->second.bytes;
  shard.lru.erase(it->second.lru);
  shard.index.erase(it);
}

void IncrementalCache::EvictLocked(Shard& shard) {
  // Walks from the least recently used end; `pos` is one past the next
  // candidate, which stays valid when the candidate is erased.
  auto pos = shard.lru.end();
  while (shard.bytes > shard.budget && pos != shard.lru.begin()) {
    auto candidate = std::prev(pos);
    auto it = shard.index.find(**candidate);
    if (it->second.users > 0) {
      pos = candidate;
      continue;
    }
    EraseLocked(shard, it);
    ++shard.counters.evictions;
  }
}

absl::StatusOr<std::shared_ptr<const Grid>> IncrementalCache::PlanningGrid(
    const Key& key, const MapSnapshot& snapshot) {
  const GridShape shape =
      GridShape::Of(key.robot_radius_cells, key.inflation_radius_cells,
                    key.cost_scaling_per_cell, key.min_clearance_cells,
                    key.cost.unknown_is_free);
  if (!shape.shaped()) return snapshot.grid;
  return inflation_.Get(snapshot, shape);
}

absl::StatusOr<IncrementalCache::Advance> IncrementalCache::AdvanceSlot(
    Slot& slot, const MapSnapshot& snapshot, std::shared_ptr<const Grid> grid,
    const StopCondition& stop, bool is_request) {
  Advance advance;
  // Map ids start at 1, so an empty slot never matches.
  advance.had_state = slot.at.map_id == snapshot.map_id;
  const Lookup lookup =
      !is_request ? Lookup::kNone : (advance.had_state ? Lookup::kHit : Lookup::kMiss);
  if (advance.had_state && slot.at.version >= snapshot.version) {
    Publish(slot, advance, lookup);
    return advance;
  }
  const At target{snapshot.map_id, snapshot.version, grid};
  if (!advance.had_state) {
    if (!is_request) return advance;
    // State of another map under this name (deleted and re-created, or
    // replaced) is worthless: start afresh.
    slot.Reset();
    if (slot.kind == Kind::kSpm) {
      absl::StatusOr<std::unique_ptr<ShortestPathMap>> built =
          ShortestPathMap::Build(grid, slot.key.goal, slot.key.cost, stop);
      if (!built.ok()) {
        advance.stopped = StopOutcome(built.status());
        if (advance.stopped == PlanOutcome::kFound) return built.status();
        Publish(slot, advance, lookup);
        return advance;
      }
      slot.field = *std::move(built);
      advance.expansions = slot.field->last_stats().expansions;
    } else {
      PATHD_ASSIGN_OR_RETURN(slot.dstar,
                             DStarLite::Create(grid, slot.key.goal, slot.key.cost));
    }
    slot.at = target;
    Publish(slot, advance, lookup);
    return advance;
  }

  PATHD_ASSIGN_OR_RETURN(const std::vector<Cell> changes,
                         ChangesBetween(*slot.at.grid, slot.at.version, *grid, snapshot));
  if (slot.kind == Kind::kSpm) {
    // Readers keep the published field while the copy is repaired.
    std::unique_ptr<ShortestPathMap> repaired = slot.field->Clone();
    PATHD_RETURN_IF_ERROR(repaired->UpdateMap(grid, changes));
    advance.expansions = repaired->last_stats().expansions;
    advance.rebuilt = repaired->last_stats().rebuilt;
    slot.field = std::move(repaired);
  } else {
    if (absl::Status s = slot.dstar->UpdateMap(grid, changes); !s.ok()) {
      // The search may be half updated; nothing can trust it any more.
      slot.Reset();
      Publish(slot, Advance(), Lookup::kNone);
      return s;
    }
    advance.expansions = slot.dstar->last_stats().expansions;
  }
  advance.repaired = true;
  advance.changed_cells = static_cast<int64_t>(changes.size());
  slot.at = target;
  Publish(slot, advance, lookup);
  return advance;
}

void IncrementalCache::Publish(const Slot& slot, const Advance& advance,
                               Lookup lookup) {
  const size_t bytes = slot.MemoryBytes();
  absl::MutexLock lock(&mu_);
  Shard& shard = shards_[static_cast<int>(slot.kind)];
  if (lookup == Lookup::kHit) ++shard.counters.hits;
  if (lookup == Lookup::kMiss) ++shard.counters.misses;
  if (advance.repaired) ++shard.counters.repairs;
  if (advance.rebuilt) ++shard.counters.rebuilds;
  Node* node = NodeOfLocked(slot);
  // Dropped (map deleted) or evicted meanwhile: the state dies with the slot.
  if (node == nullptr) return;
  node->field = slot.field;
  node->at = slot.at;
  shard.bytes = shard.bytes - node->bytes + bytes;
  node->bytes = bytes;
  EvictLocked(shard);
}

absl::StatusOr<IncrementalCache::SpmAnswer> IncrementalCache::GetSpm(
    const Key& key, const std::shared_ptr<const MapSnapshot>& snapshot,
    const StopCondition& stop) {
  std::shared_ptr<Slot> slot;
  {
    absl::MutexLock lock(&mu_);
    Shard& shard = shards_[static_cast<int>(Kind::kSpm)];
    auto it = shard.index.find(key);
    if (it != shard.index.end()) {
      const Node& node = it->second;
      if (node.field != nullptr && node.at.map_id == snapshot->map_id &&
          node.at.version >= snapshot->version) {
        shard.lru.splice(shard.lru.begin(), shard.lru, node.lru);
        ++shard.counters.hits;
        SpmAnswer answer;
        answer.field = node.field;
        answer.grid = node.at.grid;
        answer.map_version = node.at.version;
        answer.cache_hit = true;
        return answer;
      }
    }
    slot = PinLocked(Kind::kSpm, key);
  }
  absl::Cleanup unpin = [this, &slot] { Unpin(*slot); };
  PATHD_ASSIGN_OR_RETURN(std::shared_ptr<const Grid> grid, PlanningGrid(key, *snapshot));
  absl::MutexLock lock(&slot->mu);
  PATHD_ASSIGN_OR_RETURN(const Advance advance,
                         AdvanceSlot(*slot, *snapshot, std::move(grid), stop,
                                     /*is_request=*/true));
  SpmAnswer answer;
  answer.outcome = advance.stopped;
  if (advance.stopped != PlanOutcome::kFound) return answer;
  answer.field = slot->field;
  answer.grid = slot->at.grid;
  answer.map_version = slot->at.version;
  answer.cache_hit = advance.had_state;
  answer.expansions = advance.expansions;
  answer.repaired_cells = advance.changed_cells;
  return answer;
}

absl::StatusOr<IncrementalCache::DStarAnswer> IncrementalCache::PlanDStarLite(
    const Key& key, const std::shared_ptr<const MapSnapshot>& snapshot, Cell start,
    const StopCondition& stop) {
  std::shared_ptr<Slot> slot;
  {
    absl::MutexLock lock(&mu_);
    slot = PinLocked(Kind::kDStarLite, key);
  }
  absl::Cleanup unpin = [this, &slot] { Unpin(*slot); };
  PATHD_ASSIGN_OR_RETURN(std::shared_ptr<const Grid> grid, PlanningGrid(key, *snapshot));
  absl::MutexLock lock(&slot->mu);
  PATHD_ASSIGN_OR_RETURN(const Advance advance,
                         AdvanceSlot(*slot, *snapshot, std::move(grid), stop,
                                     /*is_request=*/true));
  PATHD_RETURN_IF_ERROR(slot->dstar->SetStart(start));
  slot->has_start = true;
  absl::StatusOr<PlanResult> result = slot->dstar->Plan(stop);
  if (!result.ok()) {
    if (absl::IsInternal(result.status())) {
      // Broken invariants: drop the search so the next request rebuilds it.
      slot->Reset();
      Publish(*slot, Advance(), Lookup::kNone);
    }
    return result.status();
  }
  // The search grew its open list and visited cells.
  Publish(*slot, Advance(), Lookup::kNone);
  DStarAnswer answer;
  answer.result = *std::move(result);
  answer.result.expansions += advance.expansions;
  answer.grid = slot->at.grid;
  answer.map_version = slot->at.version;
  answer.cache_hit = advance.had_state;
  answer.repaired_cells = advance.changed_cells;
  return answer;
}

void IncrementalCache::OnMapChanged(std::string_view name,
                                    const std::shared_ptr<const MapSnapshot>& snapshot) {
  // Repairs may fill at most half of the interactive queue (a batch backlog
  // does not hold them back), so they never take the slots requests need; a skipped entry is repaired by its next request. (Read
  // before mu_: the pool has its own lock.)
  size_t room = 0;
  if (pool_ != nullptr && snapshot != nullptr) {
    const size_t half = (pool_->queue_depth() + 1) / 2;
    const size_t queued = pool_->queued(WorkerPool::Priority::kInteractive);
    room = queued < half ? half - queued : 0;
  }
  std::vector<std::shared_ptr<Slot>> to_repair;
  {
    absl::MutexLock lock(&mu_);
    for (Shard& shard : shards_) {
      auto it = shard.index.lower_bound(name);
      while (it != shard.index.end() && it->first.map == name) {
        Node& node = it->second;
        // Deleted, or replaced by a different map: the state cannot be
        // repaired into the new one. A slot still being built (map_id 0)
        // stays; its request answers and the next one sees the new id.
        if (snapshot == nullptr ||
            (node.at.map_id != 0 && node.at.map_id != snapshot->map_id)) {
          EraseLocked(shard, it++);
          continue;
        }
        if (to_repair.size() < room && node.at.map_id == snapshot->map_id &&
            node.at.version < snapshot->version) {
          ++node.users;
          to_repair.push_back(node.slot);
        }
        ++it;
      }
    }
  }
  for (const std::shared_ptr<Slot>& slot : to_repair) {
    auto job = MakeJob(
        [this, slot, snapshot](SearchScratch&) {
          // Also when the repair throws (out of memory): a pinned entry
          // would never be evicted.
          absl::Cleanup unpin = [this, &slot] { Unpin(*slot); };
          RepairInBackground(*slot, snapshot);
        },
        [this, slot] { Unpin(*slot); });
    if (!pool_->Submit(std::move(job)).ok()) Unpin(*slot);
  }
}

void IncrementalCache::RepairInBackground(
    Slot& slot, const std::shared_ptr<const MapSnapshot>& snapshot) {
  absl::StatusOr<std::shared_ptr<const Grid>> grid = PlanningGrid(slot.key, *snapshot);
  // A failure here is the next request's to report.
  if (!grid.ok()) return;
  absl::MutexLock lock(&slot.mu);
  absl::StatusOr<Advance> advance = AdvanceSlot(slot, *snapshot, *std::move(grid),
                                                StopCondition::None(),
                                                /*is_request=*/false);
  if (!advance.ok() || !advance->repaired) return;
  if (slot.kind == Kind::kDStarLite && slot.has_start) {
    // Run the search now so the robot's next request only extracts the path.
    // A robot that is now on a blocked cell is its next request's error.
    if (slot.dstar->Plan(StopCondition::None()).ok()) {
      Publish(slot, Advance(), Lookup::kNone);
    }
  }
}

IncrementalCache::Stats IncrementalCache::stats(Kind kind) const {
  absl::MutexLock lock(&mu_);
  const Shard& shard = shards_[static_cast<int>(kind)];
  Stats s = shard.counters;
  s.entries = static_cast<int64_t>(shard.index.size());
  s.bytes = static_cast<int64_t>(shard.bytes);
  s.budget_bytes = static_cast<int64_t>(shard.budget);
  return s;
}

}  // namespace pathd::server
