// MapStore: named, versioned, immutable map snapshots.
#include "server/map_store.h"

#include <algorithm>
#include <utility>

#include "absl/strings/escaping.h"
#include "absl/strings/str_format.h"
#include "core/grid.h"

namespace pathd::server {
namespace {

bool IsNameChar(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') ||
         (c >= '0' && c <= '9') || c == '.' || c == '_' || c == '-';
}

absl::Status NotFound(std::string_view name) {
  return absl::NotFoundError(absl::StrFormat("map '%s' not found", name));
}

}  // namespace

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

MapStore::MapStore(int64_t max_cells) : max_cells_(max_cells) {}

absl::Status MapStore::ValidateName(std::string_view name) {
  if (name.empty()) return absl::InvalidArgumentError("map name is empty");
  if (name.size() > kMaxNameLength) {
    return absl::InvalidArgumentError(
        absl::StrFormat("map name is %d characters long; the limit is %d",
                        name.size(), kMaxNameLength));
  }
  if (name.front() == '.') {
    return absl::InvalidArgumentError(
        absl::StrFormat("map name '%s' must not start with '.'", name));
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

absl::StatusOr<std::shared_ptr<const MapSnapshot>> MapStore::Create(
    std::string_view name, Grid grid, bool replace) {
  if (absl::Status s = ValidateName(name); !s.ok()) return s;
  if (grid.size() == 0) {
    return absl::InvalidArgumentError(absl::StrFormat("map '%s' is empty", name));
  }
  if (absl::Status s = CheckSize(grid.width(), grid.height()); !s.ok()) return s;

  auto shared_grid = std::make_shared<const Grid>(std::move(grid));
  bool replaced = false;
  absl::ReleasableMutexLock lock(&mu_);
  auto it = maps_.find(name);
  if (it != maps_.end() && !replace) {
    return absl::AlreadyExistsError(absl::StrFormat(
        "map '%s' already exists (version %d); set replace to overwrite it", name,
        it->second.current->version));
  }
  auto snapshot = std::make_shared<MapSnapshot>();
  snapshot->name = std::string(name);
  snapshot->map_id = ++last_map_id_;
  snapshot->grid = std::move(shared_grid);
  if (it == maps_.end()) {
    snapshot->version = 1;
    maps_.emplace(std::string(name),
                  Entry{snapshot, std::make_shared<absl::Mutex>()});
  } else {
    // Continuing the count keeps "version" monotonic per name, so a client
    // holding expected_version from the old map cannot update the new one by
    // accident.
    snapshot->version = it->second.current->version + 1;
    it->second.current = snapshot;
    replaced = true;
  }
  lock.Release();
  std::shared_ptr<const MapSnapshot> published = std::move(snapshot);
  if (replaced) Notify(name, published);
  return published;
}

absl::StatusOr<std::shared_ptr<const MapSnapshot>> MapStore::Get(
    std::string_view name) const {
  absl::ReaderMutexLock lock(&mu_);
  auto it = maps_.find(name);
  if (it == maps_.end()) return NotFound(name);
  return it->second.current;
}

std::vector<std::shared_ptr<const MapSnapshot>> MapStore::List() const {
  absl::ReaderMutexLock lock(&mu_);
  std::vector<std::shared_ptr<const MapSnapshot>> out;
  out.reserve(maps_.size());
  for (const auto& [name, entry] : maps_) out.push_back(entry.current);
  return out;
}

absl::StatusOr<uint64_t> MapStore::Delete(std::string_view name) {
  // Releasing the snapshot happens outside the lock: freeing a large grid
  // (when nobody else holds it) should not stall other callers.
  std::shared_ptr<const MapSnapshot> removed;
  {
    absl::MutexLock lock(&mu_);
    auto it = maps_.find(name);
    if (it == maps_.end()) return NotFound(name);
    removed = std::move(it->second.current);
    maps_.erase(it);
  }
  Notify(name, nullptr);
  return removed->version;
}

absl::StatusOr<MapUpdateResult> MapStore::Update(
    std::string_view name, absl::Span<const MapChange> changes,
    std::optional<uint64_t> expected_version) {
  // Loops only when the map was replaced or deleted-and-recreated while this
  // update copied it; the retry then validates against the new version.
  for (;;) {
    std::shared_ptr<absl::Mutex> update_mu;
    {
      absl::ReaderMutexLock lock(&mu_);
      auto it = maps_.find(name);
      if (it == maps_.end()) return NotFound(name);
      update_mu = it->second.update_mu;
    }
    absl::MutexLock update_lock(update_mu.get());

    std::shared_ptr<const MapSnapshot> base;
    {
      absl::ReaderMutexLock lock(&mu_);
      auto it = maps_.find(name);
      if (it == maps_.end()) return NotFound(name);
      if (it->second.update_mu != update_mu) continue;
      base = it->second.current;
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
    int32_t x_lo = old_grid.width(), y_lo = old_grid.height(), x_hi = -1, y_hi = -1;
    for (size_t i = 0; i < changes.size(); ++i) {
      if (absl::Status s = ValidateChange(changes[i], i, old_grid); !s.ok()) {
        return s;
      }
      x_lo = std::min(x_lo, changes[i].x_min);
      y_lo = std::min(y_lo, changes[i].y_min);
      x_hi = std::max(x_hi, changes[i].x_max);
      y_hi = std::max(y_hi, changes[i].y_max);
    }

    // O(map) copy per update. Acceptable for now; DESIGN.md asks for
    // O(changed area) via tile-level copy-on-write, which a later issue brings.
    auto grid = std::make_shared<Grid>(old_grid);
    for (const MapChange& change : changes) {
      const auto cost = static_cast<uint8_t>(change.cost);
      for (int32_t y = change.y_min; y <= change.y_max; ++y) {
        for (int32_t x = change.x_min; x <= change.x_max; ++x) {
          grid->set_cost(x, y, cost);
        }
      }
    }
    // Counting against the old version (not per change) makes a batch that
    // sets a cell and later restores it count zero, as the contract says
    // "actually changed". Only the batch's bounding box can differ.
    auto snapshot = std::make_shared<MapSnapshot>();
    const size_t track_limit = std::min(kMaxTrackedChanges, old_grid.size() / 8 + 1);
    snapshot->changes_known = true;
    int64_t cells_changed = 0;
    for (int32_t y = y_lo; y <= y_hi; ++y) {
      for (int32_t x = x_lo; x <= x_hi; ++x) {
        if (grid->cost(x, y) == old_grid.cost(x, y)) continue;
        ++cells_changed;
        if (!snapshot->changes_known) continue;
        if (snapshot->changed_cells.size() == track_limit) {
          snapshot->changes_known = false;
          snapshot->changed_cells = {};
          continue;
        }
        snapshot->changed_cells.push_back(Cell{x, y});
      }
    }

    snapshot->name = base->name;
    snapshot->map_id = base->map_id;
    snapshot->version = base->version + 1;
    snapshot->grid = std::move(grid);
    {
      absl::MutexLock lock(&mu_);
      auto it = maps_.find(name);
      // A Delete that raced with the copy wins: the map is gone.
      if (it == maps_.end()) return NotFound(name);
      if (it->second.current != base) continue;  // replaced meanwhile
      it->second.current = snapshot;
    }
    // Still under update_mu: listeners see this map's versions in order.
    Notify(name, snapshot);
    return MapUpdateResult{std::move(snapshot), cells_changed};
  }
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
  return maps_.size();
}

}  // namespace pathd::server
