// Grid construction and world <-> cell conversion.
#include "core/map/grid.h"

#include <algorithm>
#include <cmath>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"

namespace pathd {
namespace {

absl::Status CheckDimensions(int32_t width, int32_t height) {
  if (width < 1 || width > kMaxGridDimension) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "width %d is out of range 1..%d", width, kMaxGridDimension));
  }
  if (height < 1 || height > kMaxGridDimension) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "height %d is out of range 1..%d", height, kMaxGridDimension));
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<Grid> Grid::Create(int32_t width, int32_t height, uint8_t fill) {
  if (absl::Status s = CheckDimensions(width, height); !s.ok()) return s;
  Grid grid;
  grid.width_ = width;
  grid.height_ = height;
  grid.cells_.assign(static_cast<size_t>(width) * static_cast<size_t>(height), fill);
  return grid;
}

absl::StatusOr<Grid> Grid::FromCells(int32_t width, int32_t height,
                                     std::vector<uint8_t> cells) {
  if (absl::Status s = CheckDimensions(width, height); !s.ok()) return s;
  const size_t expected = static_cast<size_t>(width) * static_cast<size_t>(height);
  if (cells.size() != expected) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "%d x %d grid needs %d cells, got %d", width, height, expected,
        cells.size()));
  }
  Grid grid;
  grid.width_ = width;
  grid.height_ = height;
  grid.cells_ = std::move(cells);
  return grid;
}

WorldPoint Grid::CellCenter(Cell c) const {
  return CellPointToWorld(CellPoint{c.x + 0.5, c.y + 0.5});
}

WorldPoint Grid::CellPointToWorld(CellPoint p) const {
  const double lx = p.x * resolution_;
  const double ly = p.y * resolution_;
  const double cs = std::cos(frame_yaw());
  const double sn = std::sin(frame_yaw());
  return WorldPoint{origin_.x + cs * lx - sn * ly, origin_.y + sn * lx + cs * ly};
}

CellPoint Grid::WorldToCellPoint(WorldPoint p) const {
  // Undo the rotation, then scale into cells.
  const double dx = p.x - origin_.x;
  const double dy = p.y - origin_.y;
  const double cs = std::cos(frame_yaw());
  const double sn = std::sin(frame_yaw());
  return CellPoint{(cs * dx + sn * dy) / resolution_, (-sn * dx + cs * dy) / resolution_};
}

absl::StatusOr<Cell> Grid::WorldToCell(WorldPoint p) const {
  if (!std::isfinite(p.x) || !std::isfinite(p.y)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("world point (%g, %g) is not finite", p.x, p.y));
  }
  const CellPoint g = WorldToCellPoint(p);
  const double gx = g.x;
  const double gy = g.y;
  if (!(gx >= 0.0 && gy >= 0.0 && gx < width_ && gy < height_)) {
    return absl::OutOfRangeError(absl::StrFormat(
        "world point (%g, %g) is outside the %d x %d map (resolution %g, "
        "origin (%g, %g))",
        p.x, p.y, width_, height_, resolution_, origin_.x, origin_.y));
  }
  return Cell{static_cast<int32_t>(gx), static_cast<int32_t>(gy)};
}

int64_t Grid::CountFree() const {
  return std::count(cells_.begin(), cells_.end(), kFreeCost);
}

int64_t Grid::CountBlocked() const {
  return std::count_if(cells_.begin(), cells_.end(),
                       [](uint8_t c) { return c >= kInscribedCost; });
}

std::string CellToString(Cell c) { return absl::StrFormat("(%d, %d)", c.x, c.y); }

}  // namespace pathd
