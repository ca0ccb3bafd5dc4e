// JPS+ jump tables (Harabor & Grastien 2014, "Improving Jump Point Search",
// ICAPS; Rabin & Silva 2015, "JPS+: An Extreme A* Speed Optimization for
// Static Uniform Cost Grids", Game AI Pro 2): for every cell and each of the
// eight directions, how far a jump from it goes, built once per map version
// and advanced line by line around changed cells instead of rebuilt.
#ifndef PATHD_CORE_PLANNERS_JPS_JUMP_TABLE_H_
#define PATHD_CORE_PLANNERS_JPS_JUMP_TABLE_H_

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "absl/types/span.h"
#include "core/map/grid.h"
#include "core/planners/jps/bit_grid.h"
#include "core/search/derived.h"

namespace pathd::internal {

// The largest map jps_plus plans on: 2^23 cells (2896 x 2896, 4096 x 2048)
// make a 256 MiB table, half the default --derived_cache_bytes.
inline constexpr int64_t kJumpTableMaxCells = int64_t{1} << 23;

// Jump distances of one map under JPS's rules on pathd's grids (8-connected,
// no corner cutting; core/planners/jps/jps.cc states the pruning rules).
// Entry(x, y, dx, dy) describes the jump from (x, y) in direction (dx, dy):
//  - straight: k > 0 when the k-th cell along it is the first jump point
//    (traversable with a forced neighbour for that direction); -k <= 0 when
//    the first k cells are traversable and plain and the next is blocked or
//    off the map.
//  - diagonal: k > 0 when the k-th diagonal step is the first cell whose
//    straight jump along either axis of the move is positive (a jump point
//    JPS's diagonal scan would find there); -k <= 0 when k legal steps are
//    possible and none reaches such a cell.
// Entries are defined for blocked cells too (by the same rule), so a table
// is a pure function of the passability and an advanced table equals a
// fresh build bit for bit.
//
// Storage: int32 entries (pathd's grids reach 65536 cells a side, past
// int16), 8 per cell, in 16 x 16-cell tiles shared between versions by
// shared_ptr: 32 bytes per cell plus one pointer per 256 cells. An advance
// copies the tile pointers and only the tiles it writes.
//
// Immutable once built; safe to share between threads.
class JumpTable {
 public:
  static constexpr int kTileBits = 4;
  static constexpr int32_t kTileSide = 1 << kTileBits;

  // The table of `grid`'s passability (unknown cells per `unknown_is_free`).
  // Polls `stop` (when given) every 64 rows: null when it fired, after
  // noting how far the build got. A 1024 x 1024 table takes 0.1-0.3 s.
  static std::shared_ptr<const JumpTable> Build(const Grid& grid, bool unknown_is_free,
                                                DerivedStop* stop = nullptr);

  // The table of `grid` from `previous`, the table of an older version of the
  // same map (same size and unknown_is_free) whose cells differ from `grid`
  // exactly in `changed` (cells listed without a change are allowed).
  // Recomputes only the runs of the rows, columns and diagonals whose
  // entries the changes reach: O(changed cells + entries that change), plus a
  // copy of the tile pointers and of the tiles written. A grid of another
  // size is built from scratch.
  static std::shared_ptr<const JumpTable> Advance(const JumpTable& previous,
                                                  const Grid& grid,
                                                  absl::Span<const Cell> changed);

  int32_t width() const { return width_; }
  int32_t height() const { return height_; }
  bool unknown_is_free() const { return unknown_is_free_; }

  // (x, y) must be on the map; dx, dy in -1..1, not both 0.
  int32_t Entry(int32_t x, int32_t y, int dx, int dy) const {
    return tiles_[TileOf(x, y)]->e[Slot(x, y, Dir(dx, dy))];
  }
  // Traversable; x in -1..width, y in -1..height (the border is blocked).
  bool Free(int32_t x, int32_t y) const { return BitLines::Get(rows_.Line(y), x); }

  // Memory held, counting shared tiles in full.
  size_t MemoryBytes() const;
  // Tiles this table does not share with the one it was advanced from.
  size_t OwnTiles() const { return own_tiles_; }

 private:
  struct Tile {
    int32_t e[kTileSide * kTileSide * 8];
  };

  static constexpr int Dir(int dx, int dy) {
    const int i = (dy + 1) * 3 + (dx + 1);
    return i > 4 ? i - 1 : i;
  }
  size_t TileOf(int32_t x, int32_t y) const {
    return static_cast<size_t>(y >> kTileBits) * tiles_x_ + (x >> kTileBits);
  }
  static size_t Slot(int32_t x, int32_t y, int dir) {
    return static_cast<size_t>(((y & (kTileSide - 1)) << kTileBits) |
                               (x & (kTileSide - 1))) *
               8 +
           dir;
  }

  void Init(const Grid& grid, bool unknown_is_free);
  // The entry of (x, y) in direction (dx, dy) from the passability and the
  // entries one step further along it.
  int32_t Compute(int32_t x, int32_t y, int dx, int dy) const;
  // Writes an entry, copying its tile first if it is shared.
  void Set(int32_t x, int32_t y, int dx, int dy, int32_t value);
  // Recomputes direction (dx, dy) from `seeds` (cells whose entry may have
  // changed for reasons other than the next cell's entry) and walks back
  // along the line from each while entries change; appends the cells whose
  // straight entry changed sign to `sign_changed`.
  void Repair(int dx, int dy, std::vector<Cell>& seeds, std::vector<Cell>* sign_changed);

  int32_t width_ = 0;
  int32_t height_ = 0;
  bool unknown_is_free_ = false;
  size_t tiles_x_ = 0;
  BitLines rows_;
  std::vector<std::shared_ptr<Tile>> tiles_;
  // During Advance: tile i was copied by this table (may be written).
  std::vector<uint8_t> own_;
  size_t own_tiles_ = 0;
};

}  // namespace pathd::internal

#endif  // PATHD_CORE_PLANNERS_JPS_JUMP_TABLE_H_
