// The grid map: one cost byte per cell with Nav2 costmap conventions, plus the
// resolution and origin that place it in the world (ROS map_server frame).
#ifndef PATHD_CORE_MAP_GRID_H_
#define PATHD_CORE_MAP_GRID_H_

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/statusor.h"

namespace pathd {

// Cost values (Nav2 costmap_2d).
inline constexpr uint8_t kFreeCost = 0;
inline constexpr uint8_t kMaxTraversableCost = 252;
inline constexpr uint8_t kInscribedCost = 253;
inline constexpr uint8_t kLethalCost = 254;
inline constexpr uint8_t kUnknownCost = 255;

// Largest grid pathd accepts in either dimension; keeps width*height and cell
// indices well inside int32/size_t arithmetic.
inline constexpr int32_t kMaxGridDimension = 1 << 16;

// A grid cell; x is the column, y the row.
struct Cell {
  int32_t x = 0;
  int32_t y = 0;
  friend bool operator==(const Cell&, const Cell&) = default;
};

// A point in continuous cell coordinates: cell (x, y) covers [x, x+1) x
// [y, y+1), so its centre is (x + 0.5, y + 0.5).
struct CellPoint {
  double x = 0.0;
  double y = 0.0;
};

// A point in the world frame, metres.
struct WorldPoint {
  double x = 0.0;
  double y = 0.0;
};

// World pose of the grid: the outer corner of cell (0,0), and the rotation.
struct GridOrigin {
  double x = 0.0;
  double y = 0.0;
  double yaw = 0.0;
};

// A rectangular cost grid. Row y starts at index y * width. Cell (x, y) covers
// world [x, x+1) x [y, y+1) cells from the origin (rotated by origin.yaw only
// when honour_origin_yaw()), so
// ROS maps are stored bottom row first (the OccupancyGrid convention) and
// Moving AI maps keep their file order. A value type; not synchronised: share
// it as shared_ptr<const Grid> once built.
class Grid {
 public:
  // An empty 0x0 grid.
  Grid() = default;

  // Creates a width x height grid filled with `fill`. Fails with
  // INVALID_ARGUMENT when a dimension is not in 1..kMaxGridDimension.
  static absl::StatusOr<Grid> Create(int32_t width, int32_t height,
                                     uint8_t fill = kFreeCost);
  // Creates a grid from row-major cells. Fails with INVALID_ARGUMENT when a
  // dimension is out of range or cells.size() != width * height.
  static absl::StatusOr<Grid> FromCells(int32_t width, int32_t height,
                                        std::vector<uint8_t> cells);

  int32_t width() const { return width_; }
  int32_t height() const { return height_; }
  size_t size() const { return cells_.size(); }

  double resolution() const { return resolution_; }
  const GridOrigin& origin() const { return origin_; }
  // Precondition: resolution > 0 and finite (callers validate input).
  void set_resolution(double resolution) { resolution_ = resolution; }
  void set_origin(const GridOrigin& origin) { origin_ = origin; }
  // Whether world coordinates turn with origin().yaw. False by default: Nav2's
  // costmap ignores a map_server origin's yaw, so a map saved with one is
  // placed unrotated and world goals land on the cells Nav2 would use. The
  // yaw is kept (and saved) either way. pathd --honour_origin_yaw sets it.
  bool honour_origin_yaw() const { return honour_origin_yaw_; }
  void set_honour_origin_yaw(bool honour) { honour_origin_yaw_ = honour; }
  // The rotation world coordinates use: origin().yaw when honoured, else 0.
  // A heading in the grid frame plus frame_yaw() is the world heading.
  double frame_yaw() const { return honour_origin_yaw_ ? origin_.yaw : 0.0; }

  bool InBounds(int32_t x, int32_t y) const {
    return x >= 0 && y >= 0 && x < width_ && y < height_;
  }
  bool InBounds(Cell c) const { return InBounds(c.x, c.y); }

  // Row-major index of an in-bounds cell.
  size_t Index(int32_t x, int32_t y) const {
    return static_cast<size_t>(y) * static_cast<size_t>(width_) +
           static_cast<size_t>(x);
  }
  size_t Index(Cell c) const { return Index(c.x, c.y); }
  Cell CellAt(size_t index) const {
    return Cell{static_cast<int32_t>(index % static_cast<size_t>(width_)),
                static_cast<int32_t>(index / static_cast<size_t>(width_))};
  }

  // Cost of an in-bounds cell (precondition: InBounds).
  uint8_t cost(int32_t x, int32_t y) const { return cells_[Index(x, y)]; }
  uint8_t cost(Cell c) const { return cells_[Index(c)]; }
  void set_cost(int32_t x, int32_t y, uint8_t cost) { cells_[Index(x, y)] = cost; }
  void set_cost(Cell c, uint8_t cost) { cells_[Index(c)] = cost; }

  const std::vector<uint8_t>& cells() const { return cells_; }
  std::vector<uint8_t>& mutable_cells() { return cells_; }

  // World point at the centre of a cell.
  WorldPoint CellCenter(Cell c) const;
  // World point of a point in cell coordinates.
  WorldPoint CellPointToWorld(CellPoint p) const;
  // Cell coordinates of a world point, on the grid or not (no checks).
  CellPoint WorldToCellPoint(WorldPoint p) const;
  // The cell containing a world point; fails with OUT_OF_RANGE when the point
  // is outside the grid and INVALID_ARGUMENT when it is not finite.
  absl::StatusOr<Cell> WorldToCell(WorldPoint p) const;

  // Counts of cells with cost 0 and with cost >= kInscribedCost.
  int64_t CountFree() const;
  int64_t CountBlocked() const;

 private:
  int32_t width_ = 0;
  int32_t height_ = 0;
  double resolution_ = 1.0;
  GridOrigin origin_;
  bool honour_origin_yaw_ = false;
  std::vector<uint8_t> cells_;
};

// An inclusive rectangle of cells, [x0, x1] x [y0, y1].
struct CellRect {
  int32_t x0 = 0;
  int32_t y0 = 0;
  int32_t x1 = -1;
  int32_t y1 = -1;
  // Every cell of `grid`.
  static CellRect Of(const Grid& grid) {
    return CellRect{0, 0, grid.width() - 1, grid.height() - 1};
  }
};

// "(x, y)" for messages.
std::string CellToString(Cell c);

}  // namespace pathd

#endif  // PATHD_CORE_MAP_GRID_H_
