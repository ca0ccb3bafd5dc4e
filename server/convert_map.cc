// proto <-> core translation of maps: map metadata, update changes, a
// created map's pose and raw cells (declared in server/convert.h).
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "server/convert.h"

namespace pathd::server {
namespace {

// Formats a double so NaN and infinities read as such in messages.
std::string Num(double v) { return absl::StrFormat("%g", v); }

}  // namespace

void FillMapInfo(const MapSnapshot& snapshot, v1::MapInfo* info) {
  const Grid& grid = *snapshot.grid;
  info->set_name(snapshot.name);
  info->set_width(grid.width());
  info->set_height(grid.height());
  info->set_resolution(grid.resolution());
  v1::Origin* origin = info->mutable_origin();
  origin->set_x(grid.origin().x);
  origin->set_y(grid.origin().y);
  origin->set_yaw(grid.origin().yaw);
  info->set_version(snapshot.version);
  info->set_free_cells(grid.CountFree());
  info->set_blocked_cells(grid.CountBlocked());
}

absl::StatusOr<std::vector<MapChange>> MapChangesFromProto(
    const google::protobuf::RepeatedPtrField<v1::CellChange>& changes) {
  std::vector<MapChange> out;
  out.reserve(static_cast<size_t>(changes.size()));
  for (int i = 0; i < changes.size(); ++i) {
    const v1::CellChange& c = changes.Get(i);
    switch (c.target_case()) {
      case v1::CellChange::kCell:
        out.push_back(MapChange::ForCell(c.cell().x(), c.cell().y(), c.cost()));
        break;
      case v1::CellChange::kRect:
        out.push_back(MapChange::ForRect(c.rect().x_min(), c.rect().y_min(),
                                         c.rect().x_max(), c.rect().y_max(),
                                         c.cost()));
        break;
      case v1::CellChange::TARGET_NOT_SET:
        return absl::InvalidArgumentError(
            absl::StrFormat("change %d: neither cell nor rect is set", i));
    }
  }
  return out;
}

absl::StatusOr<double> ResolutionFromProto(double resolution) {
  if (resolution == 0.0) return 1.0;
  if (!std::isfinite(resolution) || resolution < 0.0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "resolution %s must be finite and > 0", Num(resolution)));
  }
  return resolution;
}

absl::StatusOr<GridOrigin> OriginFromProto(const v1::Origin& origin) {
  const std::pair<const char*, double> parts[] = {
      {"origin.x", origin.x()}, {"origin.y", origin.y()}, {"origin.yaw", origin.yaw()}};
  for (const auto& [field, value] : parts) {
    if (!std::isfinite(value)) {
      return absl::InvalidArgumentError(
          absl::StrFormat("%s %s must be finite", field, Num(value)));
    }
  }
  return GridOrigin{origin.x(), origin.y(), origin.yaw()};
}

absl::StatusOr<Grid> GridFromRawCells(const v1::RawCells& raw, const MapStore& store) {
  if (raw.width() <= 0 || raw.height() <= 0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "raw: width %d and height %d must be positive", raw.width(), raw.height()));
  }
  if (absl::Status s = store.CheckSize(raw.width(), raw.height()); !s.ok()) return s;
  const int64_t expected = int64_t{raw.width()} * int64_t{raw.height()};
  if (static_cast<int64_t>(raw.cells().size()) != expected) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "raw: width %d x height %d needs %d cells, got %d", raw.width(),
        raw.height(), expected, raw.cells().size()));
  }
  std::vector<uint8_t> cells(raw.cells().begin(), raw.cells().end());
  absl::StatusOr<Grid> grid = Grid::FromCells(raw.width(), raw.height(), std::move(cells));
  if (!grid.ok()) {
    return absl::InvalidArgumentError(
        absl::StrFormat("raw: %s", grid.status().message()));
  }
  return grid;
}

}  // namespace pathd::server
