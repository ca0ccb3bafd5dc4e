// MapStore: named, versioned, immutable map snapshots.
#include "server/map_store.h"

#include <algorithm>
#include <deque>
#include <iterator>
#include <utility>

#include "absl/strings/escaping.h"
#include "absl/strings/str_format.h"
#include "core/map/grid.h"
#include "server/map_store_grid_pool.h"
#include "spdlog/spdlog.h"

namespace pathd::server {
namespace {

bool IsNameChar(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') ||
         (c >= '0' && c <= '9') || c == '.' || c == '_' || c == '-';
}

absl::Status NotFound(std::string_view name) {
  return absl::NotFoundError(absl::StrFormat("map '%s' not found", name));
}

// Cells [x_min, x_max] of row y.
struct RowSpan {
  int32_t y = 0;
  int32_t x_min = 0;
  int32_t x_max = 0;
};

// The cells a batch writes, as row spans in row-major order with overlapping
// or touching spans merged, so each cell appears once. Bucketed by row, then
// sorted within each row: O(r + rows of the batch + sorting within rows) for
// r spans (rows summed over the changes). This is what lets an update find
// its changed cells without scanning the batch's bounding box (two far-apart
// cells span the map).
//
// The spans take 12 bytes per row of every change, which for many tall
// rectangles would be far more than the map itself; past the map's own size
// in bytes the whole rows from the first to the last touched one are
// returned instead: comparing them costs one pass over at most the map (what
// a full copy of it costs) and finds the same changed cells.
std::vector<RowSpan> CoveredSpans(absl::Span<const MapChange> changes,
                                  const Grid& grid) {
  int32_t y_lo = changes.front().y_min, y_hi = changes.front().y_max;
  size_t rows = 0;
  for (const MapChange& c : changes) {
    y_lo = std::min(y_lo, c.y_min);
    y_hi = std::max(y_hi, c.y_max);
    rows += static_cast<size_t>(c.y_max - c.y_min) + 1;
  }
  if (rows > grid.size() / sizeof(RowSpan)) {
    std::vector<RowSpan> whole;
    whole.reserve(static_cast<size_t>(y_hi - y_lo) + 1);
    for (int32_t y = y_lo; y <= y_hi; ++y) whole.push_back(RowSpan{y, 0, grid.width() - 1});
    return whole;
  }
  // first[y - y_lo] .. first[y - y_lo + 1]: the spans of row y.
  std::vector<size_t> first(static_cast<size_t>(y_hi - y_lo) + 2, 0);
  for (const MapChange& c : changes) {
    for (int32_t y = c.y_min; y <= c.y_max; ++y) ++first[static_cast<size_t>(y - y_lo) + 1];
  }
  for (size_t i = 1; i < first.size(); ++i) first[i] += first[i - 1];
  std::vector<RowSpan> spans(first.back());
  std::vector<size_t> next(first.begin(), first.end() - 1);
  for (const MapChange& c : changes) {
    for (int32_t y = c.y_min; y <= c.y_max; ++y) {
      spans[next[static_cast<size_t>(y - y_lo)]++] = RowSpan{y, c.x_min, c.x_max};
    }
  }
  size_t kept = 0;
  for (size_t row = 0; row + 1 < first.size(); ++row) {
    const auto begin = spans.begin() + static_cast<std::ptrdiff_t>(first[row]);
    const auto end = spans.begin() + static_cast<std::ptrdiff_t>(first[row + 1]);
    if (end - begin > 1) {
      std::sort(begin, end,
                [](const RowSpan& a, const RowSpan& b) { return a.x_min < b.x_min; });
    }
    const size_t row_start = kept;
    for (auto it = begin; it != end; ++it) {
      if (kept > row_start && it->x_min <= spans[kept - 1].x_max + 1) {
        spans[kept - 1].x_max = std::max(spans[kept - 1].x_max, it->x_max);
      } else {
        spans[kept++] = *it;
      }
    }
  }
  spans.resize(kept);
  return spans;
}

}  // namespace

namespace {

// One link of a history on top of `below` (null: a run's first).
std::shared_ptr<const ChangeHistory> Link(uint64_t version, std::vector<Cell> cells,
                                          std::shared_ptr<const ChangeHistory> below) {
  auto link = std::make_shared<ChangeHistory>();
  link->version = version;
  link->cells = std::move(cells);
  link->versions = below != nullptr ? below->versions + 1 : 1;
  link->total_cells = (below != nullptr ? below->total_cells : 0) + link->cells.size();
  link->previous = std::move(below);
  return link;
}

}  // namespace

std::shared_ptr<const ChangeHistory> ExtendHistory(
    const std::shared_ptr<const ChangeHistory>& previous, uint64_t version,
    std::vector<Cell> cells) {
  std::shared_ptr<const ChangeHistory> below =
      previous != nullptr && previous->version + 1 == version ? previous : nullptr;
  if (below != nullptr && (below->versions + 1 > ChangeHistory::kMaxVersions ||
                           below->total_cells + cells.size() > ChangeHistory::kMaxCells)) {
    // Keep the newest links within half the bounds, copied oldest first.
    std::vector<const ChangeHistory*> kept;
    size_t kept_cells = 0;
    for (const ChangeHistory* h = below.get(); h != nullptr; h = h->previous.get()) {
      if (kept.size() + 1 > ChangeHistory::kMaxVersions / 2 ||
          kept_cells + h->cells.size() + cells.size() > ChangeHistory::kMaxCells / 2) {
        break;
      }
      kept.push_back(h);
      kept_cells += h->cells.size();
    }
    std::shared_ptr<const ChangeHistory> copy;
    for (auto it = kept.rbegin(); it != kept.rend(); ++it) {
      copy = Link((*it)->version, (*it)->cells, std::move(copy));
    }
    below = std::move(copy);
  }
  return Link(version, std::move(cells), std::move(below));
}

std::optional<std::vector<Cell>> ChangesSince(const MapSnapshot& snapshot, uint64_t from) {
  if (from >= snapshot.version) return std::nullopt;
  // A snapshot made without a history (tests, restores) still knows its own
  // step.
  if (snapshot.history == nullptr) {
    if (snapshot.changes_known && from + 1 == snapshot.version) return snapshot.changed_cells;
    return std::nullopt;
  }
  std::vector<Cell> cells;
  uint64_t expect = snapshot.version;
  for (const ChangeHistory* h = snapshot.history.get(); h != nullptr; h = h->previous.get()) {
    if (h->version != expect) return std::nullopt;
    cells.insert(cells.end(), h->cells.begin(), h->cells.end());
    if (--expect == from) return cells;
  }
  return std::nullopt;
}

// Every check runs before the copy is made, which is what makes a batch
// all-or-nothing.
absl::Status MapStore::ValidateChange(const MapChange& change, size_t index,
                                      const Grid& grid) {
  if (change.cost > 255) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "change %d: cost %d is out of range 0..255", index, change.cost));
  }
  if (!change.is_rect) {
    if (!grid.InBounds(change.x_min, change.y_min)) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "change %d: cell (%d, %d) is outside the %d x %d map", index,
          change.x_min, change.y_min, grid.width(), grid.height()));
    }
    return absl::OkStatus();
  }
  if (change.x_min > change.x_max || change.y_min > change.y_max) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "change %d: rect (%d, %d)-(%d, %d) has min > max", index, change.x_min,
        change.y_min, change.x_max, change.y_max));
  }
  if (!grid.InBounds(change.x_min, change.y_min) ||
      !grid.InBounds(change.x_max, change.y_max)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "change %d: rect (%d, %d)-(%d, %d) reaches outside the %d x %d map",
        index, change.x_min, change.y_min, change.x_max, change.y_max,
        grid.width(), grid.height()));
  }
  return absl::OkStatus();
}

int64_t MapStore::MaxBatchWrites(const Grid& grid) {
  return std::max(kMaxWritesPerCell * static_cast<int64_t>(grid.size()), kMinBatchWrites);
}

absl::Status MapStore::ValidateChanges(absl::Span<const MapChange> changes,
                                       const Grid& grid) {
  // Each change covers at most 2^32 cells and the sum stops just past the
  // limit, so it cannot overflow.
  const int64_t limit = MaxBatchWrites(grid);
  int64_t writes = 0;
  for (size_t i = 0; i < changes.size(); ++i) {
    if (absl::Status s = ValidateChange(changes[i], i, grid); !s.ok()) return s;
    const MapChange& c = changes[i];
    writes += (int64_t{c.x_max} - c.x_min + 1) * (int64_t{c.y_max} - c.y_min + 1);
    if (writes > limit) {
      return absl::ResourceExhaustedError(absl::StrFormat(
          "changes 0..%d write %d cells in total (overlaps counted each time), "
          "more than the limit of %d for this %d x %d map (%d per map cell, at "
          "least %d): merge overlapping rectangles",
          i, writes, limit, grid.width(), grid.height(), kMaxWritesPerCell,
          kMinBatchWrites));
    }
  }
  return absl::OkStatus();
}

MapStore::MapStore(int64_t max_cells) : max_cells_(max_cells) {}

absl::Status MapStore::ValidateName(std::string_view name) {
  if (name.empty()) return absl::InvalidArgumentError("map name is empty");
  if (name.size() > kMaxNameLength) {
    return absl::InvalidArgumentError(
        absl::StrFormat("map name is %d characters long; the limit is %d",
                        name.size(), kMaxNameLength));
  }
  if (name.front() == '.') {
    return absl::InvalidArgumentError(absl::StrFormat(
        "map name '%s' must not start with '.'",
        absl::CHexEscape(absl::string_view(name.data(), name.size()))));
  }
  for (size_t i = 0; i < name.size(); ++i) {
    if (!IsNameChar(name[i])) {
      // Quote the byte as a number: it may be a control or non-UTF-8 byte.
      return absl::InvalidArgumentError(absl::StrFormat(
          "map name '%s' has character 0x%02x at position %d; allowed are "
          "A-Z a-z 0-9 . _ -",
          absl::CHexEscape(absl::string_view(name.data(), name.size())), static_cast<unsigned char>(name[i]), i));
    }
  }
  return absl::OkStatus();
}

absl::Status MapStore::CheckSize(int64_t width, int64_t height) const {
  // Dimensions are bounded by kMaxGridDimension elsewhere, but this runs on
  // untrusted header values, so guard the product against overflow too.
  if (width > 0 && height > 0 && width <= max_cells_ &&
      height <= max_cells_ / width) {
    return absl::OkStatus();
  }
  if (width <= 0 || height <= 0) {
    return absl::InvalidArgumentError(
        absl::StrFormat("map size %d x %d must be positive", width, height));
  }
  return absl::ResourceExhaustedError(absl::StrFormat(
      "a %d x %d map exceeds the server's limit of %d cells (--max_map_cells)",
      width, height, max_cells_));
}

void MapStore::StampOriginYaw(std::string_view name, Grid* grid) const {
  grid->set_honour_origin_yaw(honour_origin_yaw_);
  if (!honour_origin_yaw_ && grid->origin().yaw != 0.0) {
    spdlog::warn(
        "map '{}': origin yaw {} rad is ignored in world coordinates, as Nav2's "
        "costmap ignores it; start pathd with --honour_origin_yaw to apply it",
        std::string(name), grid->origin().yaw);
  }
}

absl::StatusOr<std::shared_ptr<const MapSnapshot>> MapStore::Create(
    std::string_view name, Grid grid, bool replace) {
  if (absl::Status s = ValidateName(name); !s.ok()) return s;
  if (grid.size() == 0) {
    return absl::InvalidArgumentError(absl::StrFormat("map '%s' is empty", name));
  }
  if (absl::Status s = CheckSize(grid.width(), grid.height()); !s.ok()) return s;
  if (journal_ != nullptr) {
    if (absl::Status s = journal_->Writable(); !s.ok()) return s;
  }

  StampOriginYaw(name, &grid);
  auto buffer = std::make_unique<Grid>(std::move(grid));
  auto pool = std::make_shared<GridPool>(buffer->size());
  // The journal record holds the version, which is only settled under the
  // lock; it is encoded (a copy of the whole map) before taking it, for the
  // version the map would get then, and again in the rare case that a
  // concurrent writer changed that meanwhile.
  std::string record;
  uint64_t record_version = 0;
  uint64_t sequence = 0;
  uint64_t ticket = 0;
  // A replaced version and its pool are released after unlocking: freeing
  // large grids should not stall other callers.
  std::shared_ptr<const MapSnapshot> old_latest;
  std::shared_ptr<GridPool> old_pool;
  std::shared_ptr<const MapSnapshot> made;
  for (;;) {
    if (journal_ != nullptr) {
      uint64_t version = 1;
      {
        absl::ReaderMutexLock lock(&mu_);
        auto it = maps_.find(name);
        if (it != maps_.end() && it->second.latest != nullptr) {
          version = it->second.latest->version + 1;
        }
      }
      if (version != record_version) {
        absl::StatusOr<std::string> encoded = journal_->EncodeCreate(name, version, *buffer);
        if (!encoded.ok()) return encoded.status();
        record = *std::move(encoded);
        record_version = version;
      }
    }
    absl::MutexLock lock(&mu_);
    auto it = maps_.find(name);
    const bool exists = it != maps_.end() && it->second.latest != nullptr;
    if (exists && !replace) {
      return absl::AlreadyExistsError(absl::StrFormat(
          "map '%s' already exists (version %d); set replace to overwrite it", name,
          it->second.latest->version));
    }
    // Continuing the count on replace keeps "version" monotonic per name, so a
    // client holding expected_version from the old map cannot update the new
    // one by accident.
    const uint64_t version = exists ? it->second.latest->version + 1 : 1;
    if (journal_ != nullptr && version != record_version) continue;
    auto snapshot = std::make_shared<MapSnapshot>();
    snapshot->name = std::string(name);
    snapshot->map_id = ++last_map_id_;
    snapshot->version = version;
    snapshot->grid = GridPool::Publish(pool, std::move(buffer), snapshot->version);
    if (it == maps_.end()) {
      it = maps_.emplace(std::string(name), Entry{}).first;
    }
    Entry& entry = it->second;
    old_latest = std::exchange(entry.latest, snapshot);
    // The new map gets its own pool: the old one's buffers have the old
    // size, and an update still working on the old map must not feed it.
    old_pool = std::exchange(entry.pool, std::move(pool));
    // A map created again after a logged deletion is a new map to updates
    // waiting on the old one's lock.
    if (!exists || entry.update_mu == nullptr) entry.update_mu = std::make_shared<absl::Mutex>();
    if (journal_ != nullptr) sequence = journal_->Append(name, std::move(record), snapshot);
    ticket = QueueChange(name, snapshot, exists ? ChangeKind::kReplaced : ChangeKind::kCreated);
    made = std::move(snapshot);
    break;
  }
  if (absl::Status s = Complete(ticket, sequence); !s.ok()) return s;
  return made;
}

absl::StatusOr<std::shared_ptr<const MapSnapshot>> MapStore::Restore(
    std::string_view name, Grid grid, uint64_t version) {
  if (absl::Status s = ValidateName(name); !s.ok()) return s;
  if (grid.size() == 0) {
    return absl::InvalidArgumentError(absl::StrFormat("map '%s' is empty", name));
  }
  if (absl::Status s = CheckSize(grid.width(), grid.height()); !s.ok()) return s;
  StampOriginYaw(name, &grid);
  auto buffer = std::make_unique<Grid>(std::move(grid));
  auto pool = std::make_shared<GridPool>(buffer->size());
  absl::MutexLock lock(&mu_);
  if (maps_.find(name) != maps_.end()) {
    return absl::FailedPreconditionError(
        absl::StrFormat("map '%s' exists already; cannot restore it", name));
  }
  auto snapshot = std::make_shared<MapSnapshot>();
  snapshot->name = std::string(name);
  // A fresh id: caches built before a restart do not exist, so nothing can
  // mistake the restored map for another.
  snapshot->map_id = ++last_map_id_;
  snapshot->version = version;
  snapshot->grid = GridPool::Publish(pool, std::move(buffer), version);
  maps_.emplace(std::string(name), Entry{snapshot, snapshot, std::make_shared<absl::Mutex>(),
                                         std::move(pool)});
  ++visible_;
  return std::shared_ptr<const MapSnapshot>(std::move(snapshot));
}

absl::StatusOr<std::shared_ptr<const MapSnapshot>> MapStore::Get(
    std::string_view name) const {
  // Lookups check the name first: a name no map can have is a bad request,
  // not a missing map, and only a valid name (at most kMaxNameLength plain
  // characters) may be quoted back in NotFound's message. Quoting a 1 MiB
  // name would overflow gRPC's metadata limit and reach the client as an
  // unrelated RESOURCE_EXHAUSTED.
  if (absl::Status s = ValidateName(name); !s.ok()) return s;
  absl::ReaderMutexLock lock(&mu_);
  auto it = maps_.find(name);
  if (it == maps_.end() || it->second.current == nullptr) return NotFound(name);
  return it->second.current;
}

std::vector<std::shared_ptr<const MapSnapshot>> MapStore::List() const {
  absl::ReaderMutexLock lock(&mu_);
  std::vector<std::shared_ptr<const MapSnapshot>> out;
  out.reserve(visible_);
  for (const auto& [name, entry] : maps_) {
    if (entry.current != nullptr) out.push_back(entry.current);
  }
  return out;
}

absl::StatusOr<uint64_t> MapStore::Delete(std::string_view name) {
  if (absl::Status s = ValidateName(name); !s.ok()) return s;
  // Releasing the snapshot happens outside the lock: freeing a large grid
  // (when nobody else holds it) should not stall other callers.
  std::shared_ptr<const MapSnapshot> removed;
  std::shared_ptr<GridPool> pool;
  uint64_t sequence = 0;
  uint64_t ticket = 0;
  if (journal_ != nullptr) {
    if (absl::Status s = journal_->Writable(); !s.ok()) return s;
  }
  {
    absl::MutexLock lock(&mu_);
    auto it = maps_.find(name);
    if (it == maps_.end() || it->second.latest == nullptr) return NotFound(name);
    removed = std::move(it->second.latest);
    pool = std::move(it->second.pool);
    // Updates waiting on the old lock find no latest version and give up.
    it->second.update_mu = nullptr;
    if (journal_ != nullptr) {
      // A few bytes: encoding under the lock costs nothing worth avoiding.
      sequence = journal_->Append(name, journal_->EncodeDelete(name, removed->version),
                                  nullptr);
    }
    ticket = QueueChange(name, nullptr, ChangeKind::kDeleted);
  }
  if (absl::Status s = Complete(ticket, sequence); !s.ok()) return s;
  return removed->version;
}

uint64_t MapStore::QueueChange(std::string_view name,
                               std::shared_ptr<const MapSnapshot> snapshot,
                               ChangeKind kind) {
  const uint64_t ticket = next_ticket_++;
  pending_.push_back(PendingChange{ticket, std::string(name), std::move(snapshot), kind});
  return ticket;
}

void MapStore::PublishThrough(uint64_t ticket) {
  absl::MutexLock publish_lock(&publish_mu_);
  for (;;) {
    PendingChange change;
    std::shared_ptr<const MapSnapshot> replaced;
    {
      absl::MutexLock lock(&mu_);
      if (pending_.empty() || pending_.front().ticket > ticket) return;
      change = std::move(pending_.front());
      pending_.pop_front();
      // Entries are erased only by publishing their deletion with nothing
      // logged after it, so the entry of a queued change exists.
      auto it = maps_.find(change.name);
      Entry& entry = it->second;
      if (entry.current == nullptr && change.snapshot != nullptr) ++visible_;
      if (entry.current != nullptr && change.snapshot == nullptr) --visible_;
      replaced = std::exchange(entry.current, change.snapshot);
      if (entry.current == nullptr && entry.latest == nullptr) maps_.erase(it);
    }
    // A created map has no watchers to tell; the others do, in log order
    // (publish_mu_ is held).
    if (change.kind != ChangeKind::kCreated) Notify(change.name, change.snapshot);
  }
}

void MapStore::DropFrom(uint64_t ticket) {
  absl::MutexLock lock(&mu_);
  while (!pending_.empty() && pending_.back().ticket >= ticket) pending_.pop_back();
}

absl::Status MapStore::Complete(uint64_t ticket, uint64_t sequence) {
  if (journal_ != nullptr) {
    if (absl::Status s = journal_->WaitDurable(sequence); !s.ok()) {
      DropFrom(ticket);
      return s;
    }
  }
  PublishThrough(ticket);
  return absl::OkStatus();
}

absl::StatusOr<MapUpdateResult> MapStore::Update(
    std::string_view name, absl::Span<const MapChange> changes,
    std::optional<uint64_t> expected_version) {
  absl::StatusOr<PreparedUpdate> prepared = PrepareUpdate(name, changes, expected_version);
  if (!prepared.ok()) return prepared.status();
  // Outside update_mu, so further updates of this map can queue their records
  // behind this one and share its disk sync.
  if (absl::Status s = Complete(prepared->ticket, prepared->sequence); !s.ok()) return s;
  return std::move(prepared->result);
}

void MapStore::UpdateAsync(std::string_view name, absl::Span<const MapChange> changes,
                           std::optional<uint64_t> expected_version, UpdateDone done) {
  absl::StatusOr<PreparedUpdate> prepared = PrepareUpdate(name, changes, expected_version);
  if (!prepared.ok()) {
    done(prepared.status());
    return;
  }
  if (journal_ == nullptr) {
    PublishThrough(prepared->ticket);
    done(std::move(prepared->result));
    return;
  }
  const uint64_t ticket = prepared->ticket;
  journal_->OnDurable(prepared->sequence,
                      [this, ticket, result = std::move(prepared->result),
                       done = std::move(done)](absl::Status status) mutable {
                        if (!status.ok()) {
                          DropFrom(ticket);
                          done(status);
                          return;
                        }
                        PublishThrough(ticket);
                        done(std::move(result));
                      });
}

absl::StatusOr<MapStore::PreparedUpdate> MapStore::PrepareUpdate(
    std::string_view name, absl::Span<const MapChange> changes,
    std::optional<uint64_t> expected_version) {
  if (absl::Status s = ValidateName(name); !s.ok()) return s;
  if (journal_ != nullptr) {
    if (absl::Status s = journal_->Writable(); !s.ok()) return s;
  }
  // Loops only when the map was replaced or deleted-and-recreated while this
  // update copied it; the retry then validates against the new version.
  for (;;) {
    std::shared_ptr<absl::Mutex> update_mu;
    {
      absl::ReaderMutexLock lock(&mu_);
      auto it = maps_.find(name);
      if (it == maps_.end() || it->second.latest == nullptr) return NotFound(name);
      update_mu = it->second.update_mu;
    }
    absl::MutexLock update_lock(update_mu.get());

    std::shared_ptr<const MapSnapshot> base;
    std::shared_ptr<GridPool> pool;
    {
      absl::ReaderMutexLock lock(&mu_);
      auto it = maps_.find(name);
      if (it == maps_.end() || it->second.latest == nullptr) return NotFound(name);
      if (it->second.update_mu != update_mu) continue;
      base = it->second.latest;
      pool = it->second.pool;
    }
    if (expected_version.has_value() && *expected_version != base->version) {
      return absl::AbortedError(absl::StrFormat(
          "map '%s' is at version %d, expected %d", name, base->version,
          *expected_version));
    }
    if (changes.empty()) {
      return absl::InvalidArgumentError(
          absl::StrFormat("update of map '%s' has no changes", name));
    }
    const Grid& old_grid = *base->grid;
    if (absl::Status s = ValidateChanges(changes, old_grid); !s.ok()) return s;

    std::unique_ptr<Grid> grid = AcquireGrid(*pool, *base);
    uint8_t* after = grid->mutable_cells().data();
    for (const MapChange& change : changes) {
      const auto cost = static_cast<uint8_t>(change.cost);
      const auto width = static_cast<size_t>(change.x_max - change.x_min) + 1;
      for (int32_t y = change.y_min; y <= change.y_max; ++y) {
        std::fill_n(after + grid->Index(change.x_min, y), width, cost);
      }
    }
    // Counting against the old version (not per change) makes a batch that
    // sets a cell and later restores it count zero, as the contract says
    // "actually changed". Only cells the batch wrote can differ.
    const uint8_t* before = old_grid.cells().data();
    auto snapshot = std::make_shared<MapSnapshot>();
    const size_t track_limit = std::min(kMaxTrackedChanges, old_grid.size() / 8 + 1);
    snapshot->changes_known = true;
    int64_t cells_changed = 0;
    for (const RowSpan& span : CoveredSpans(changes, old_grid)) {
      const size_t row = old_grid.Index(0, span.y);
      // Counted first in a loop the compiler vectorises: a large batch then
      // costs a pass over its cells, and cells are listed only while tracked.
      int64_t in_span = 0;
      for (int32_t x = span.x_min; x <= span.x_max; ++x) {
        in_span += after[row + x] != before[row + x] ? 1 : 0;
      }
      cells_changed += in_span;
      if (in_span == 0 || !snapshot->changes_known) continue;
      if (static_cast<size_t>(cells_changed) > track_limit) {
        snapshot->changes_known = false;
        snapshot->changed_cells = {};
        continue;
      }
      for (int32_t x = span.x_min; x <= span.x_max; ++x) {
        if (after[row + x] != before[row + x]) snapshot->changed_cells.push_back(Cell{x, span.y});
      }
    }

    snapshot->name = base->name;
    snapshot->map_id = base->map_id;
    snapshot->version = base->version + 1;
    if (snapshot->changes_known) {
      snapshot->history =
          ExtendHistory(base->history, snapshot->version, snapshot->changed_cells);
    }
    snapshot->grid = GridPool::Publish(pool, std::move(grid), snapshot->version);
    std::string record;
    if (journal_ != nullptr) record = journal_->EncodeUpdate(name, snapshot->version, changes);
    PreparedUpdate prepared;
    {
      absl::MutexLock lock(&mu_);
      auto it = maps_.find(name);
      // A Delete that raced with the copy wins: the map is gone.
      if (it == maps_.end() || it->second.latest == nullptr) return NotFound(name);
      if (it->second.latest != base) continue;  // replaced meanwhile
      it->second.latest = snapshot;
      if (journal_ != nullptr) {
        prepared.sequence = journal_->Append(name, std::move(record), snapshot);
      }
      prepared.ticket = QueueChange(name, snapshot, ChangeKind::kUpdated);
    }
    // Under update_mu, so the next update of this map sees this version
    // logged.
    pool->Record(*snapshot);
    prepared.result = MapUpdateResult{std::move(snapshot), cells_changed};
    return prepared;
  }
}

std::unique_ptr<Grid> MapStore::AcquireGrid(GridPool& pool, const MapSnapshot& base) {
  const Grid& current = *base.grid;
  GridPool::Taken taken = pool.Take(base.version);
  if (taken.grid == nullptr) {
    grids_allocated_.fetch_add(1, std::memory_order_relaxed);
    return std::make_unique<Grid>(current);
  }
  if (!taken.replayable) {
    grids_copied_.fetch_add(1, std::memory_order_relaxed);
    // Same size: the assignment reuses the buffer's memory.
    *taken.grid = current;
    return std::move(taken.grid);
  }
  // Every cell that differs between the spare's version and the current one
  // was changed by one of the versions in between, so copying those cells
  // from the current grid makes the two equal.
  grids_replayed_.fetch_add(1, std::memory_order_relaxed);
  for (const auto& cells : taken.replay) {
    for (const Cell c : *cells) taken.grid->set_cost(c, current.cost(c));
  }
  return std::move(taken.grid);
}

MapStore::BufferStats MapStore::buffer_stats() const {
  BufferStats stats;
  stats.replayed = grids_replayed_.load(std::memory_order_relaxed);
  stats.copied = grids_copied_.load(std::memory_order_relaxed);
  stats.allocated = grids_allocated_.load(std::memory_order_relaxed);
  return stats;
}

void MapStore::AddListener(Listener listener) {
  listeners_.push_back(std::move(listener));
}

void MapStore::Notify(std::string_view name,
                      const std::shared_ptr<const MapSnapshot>& snapshot) const {
  for (const Listener& listener : listeners_) listener(name, snapshot);
}

size_t MapStore::size() const {
  absl::ReaderMutexLock lock(&mu_);
  return visible_;
}

}  // namespace pathd::server
