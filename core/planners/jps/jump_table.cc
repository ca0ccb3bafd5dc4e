// Jump tables built in scan order and repaired backwards along lines.
//
// Every entry is a function of the passability near a cell and of the entry
// one step further in the same direction (see Compute), so a build fills each
// direction in an order that visits (x + dx, y + dy) before (x, y). A
// changed cell p changes the inputs of that function only for the 3 x 3
// cells around p (a straight entry at c reads the next cell, its two side
// cells and the two side cells of c; a diagonal entry the three cells of
// its move: all within one cell of c), and for diagonal entries whose next
// cell's straight entry changed sign (gained or lost a jump point ahead).
// The seeds are those cells. Repair recomputes them, per direction, in
// build order and walks back along each one's line while the entry changes:
// once an entry comes out unchanged, every entry behind it reads the same
// inputs as before, unless it is a seed itself, which is visited in its turn.
#include "core/planners/jps/jump_table.h"

#include <algorithm>
#include <tuple>

#include "absl/strings/str_format.h"
#include "core/map/cost_model.h"

namespace pathd::internal {

namespace {

// The four straight directions, then the four diagonal ones: diagonal
// entries read straight ones.
constexpr int kDirs[8][2] = {{1, 0},  {-1, 0}, {0, 1},  {0, -1},
                             {1, 1},  {-1, 1}, {1, -1}, {-1, -1}};

}  // namespace

void JumpTable::Init(const Grid& grid, bool unknown_is_free) {
  width_ = grid.width();
  height_ = grid.height();
  unknown_is_free_ = unknown_is_free;
  tiles_x_ = static_cast<size_t>((width_ + kTileSide - 1) >> kTileBits);
  const size_t tiles_y = static_cast<size_t>((height_ + kTileSide - 1) >> kTileBits);
  rows_.Reset(height_, width_);
  std::vector<uint8_t> dirty(static_cast<size_t>((width_ + 63) / 64) *
                             static_cast<size_t>((height_ + 63) / 64));
  PackRows(BestPackIsa(), grid, PackRule{.unknown_is_free = unknown_is_free}, rows_,
           dirty);
  tiles_.resize(tiles_x_ * tiles_y);
  for (auto& tile : tiles_) tile = std::make_shared<Tile>();
  own_.assign(tiles_.size(), 1);
  own_tiles_ = tiles_.size();
}

int32_t JumpTable::Compute(int32_t x, int32_t y, int dx, int dy) const {
  const int32_t nx = x + dx;
  const int32_t ny = y + dy;
  if (dx == 0 || dy == 0) {
    if (!Free(nx, ny)) return 0;
    // The next cell is a jump point when a side cell is open and the side
    // cell one step back (beside (x, y)) is blocked: a forced neighbour.
    const int sx = dy;
    const int sy = dx;
    if ((Free(nx + sx, ny + sy) && !Free(x + sx, y + sy)) ||
        (Free(nx - sx, ny - sy) && !Free(x - sx, y - sy))) {
      return 1;
    }
  } else {
    if (!Free(nx, y) || !Free(x, ny) || !Free(nx, ny)) return 0;
    if (Entry(nx, ny, dx, 0) > 0 || Entry(nx, ny, 0, dy) > 0) return 1;
  }
  const int32_t next = Entry(nx, ny, dx, dy);
  return next > 0 ? next + 1 : next - 1;
}

void JumpTable::Set(int32_t x, int32_t y, int dx, int dy, int32_t value) {
  const size_t t = TileOf(x, y);
  if (!own_[t]) {
    tiles_[t] = std::make_shared<Tile>(*tiles_[t]);
    own_[t] = 1;
    ++own_tiles_;
  }
  tiles_[t]->e[Slot(x, y, Dir(dx, dy))] = value;
}

std::shared_ptr<const JumpTable> JumpTable::Build(const Grid& grid, bool unknown_is_free,
                                                  DerivedStop* stop) {
  auto table = std::make_shared<JumpTable>();
  table->Init(grid, unknown_is_free);
  const int32_t w = table->width_;
  const int32_t h = table->height_;
  // Two sweeps over the rows instead of one per direction, so each row's
  // tiles are written while in cache (a 1024 x 1024 table is 32 MiB): up
  // the map for the directions that read the row below (south ones) and the
  // row-local east and west, then down the map for the north ones. A
  // diagonal entry reads the straight entries of its next cell, one row
  // back in the same sweep (east and west of a north-bound one come from
  // the first sweep).
  auto stopped = [&](int32_t rows_done) {
    if (stop == nullptr || rows_done % 64 != 0 || !stop->Stopped()) return false;
    stop->Note(absl::StrFormat(
        "building the jump table of this map version (row %d of %d in its two sweeps)",
        rows_done, 2 * h));
    return true;
  };
  for (int32_t y = h - 1; y >= 0; --y) {
    if (stopped(h - 1 - y)) return nullptr;
    for (int32_t x = w - 1; x >= 0; --x) table->Set(x, y, 1, 0, table->Compute(x, y, 1, 0));
    for (int32_t x = 0; x < w; ++x) {
      table->Set(x, y, -1, 0, table->Compute(x, y, -1, 0));
      table->Set(x, y, 0, 1, table->Compute(x, y, 0, 1));
      table->Set(x, y, 1, 1, table->Compute(x, y, 1, 1));
      table->Set(x, y, -1, 1, table->Compute(x, y, -1, 1));
    }
  }
  for (int32_t y = 0; y < h; ++y) {
    if (stopped(h + y)) return nullptr;
    for (int32_t x = 0; x < w; ++x) {
      table->Set(x, y, 0, -1, table->Compute(x, y, 0, -1));
      table->Set(x, y, 1, -1, table->Compute(x, y, 1, -1));
      table->Set(x, y, -1, -1, table->Compute(x, y, -1, -1));
    }
  }
  table->own_.clear();
  return table;
}

void JumpTable::Repair(int dx, int dy, std::vector<Cell>& seeds,
                       std::vector<Cell>* sign_changed) {
  // Build order: the cell one step along (dx, dy) first.
  auto key = [dx, dy](const Cell& c) {
    return std::make_tuple(dy > 0 ? -c.y : c.y, dx > 0 ? -c.x : c.x);
  };
  std::sort(seeds.begin(), seeds.end(),
            [&key](const Cell& a, const Cell& b) { return key(a) < key(b); });
  seeds.erase(std::unique(seeds.begin(), seeds.end(),
                          [](const Cell& a, const Cell& b) {
                            return a.x == b.x && a.y == b.y;
                          }),
              seeds.end());
  for (const Cell& seed : seeds) {
    int32_t x = seed.x;
    int32_t y = seed.y;
    while (x >= 0 && x < width_ && y >= 0 && y < height_) {
      const int32_t old = Entry(x, y, dx, dy);
      const int32_t now = Compute(x, y, dx, dy);
      if (now == old) break;
      Set(x, y, dx, dy, now);
      if (sign_changed != nullptr && (now > 0) != (old > 0)) {
        sign_changed->push_back(Cell{x, y});
      }
      x -= dx;
      y -= dy;
    }
  }
}

std::shared_ptr<const JumpTable> JumpTable::Advance(const JumpTable& previous,
                                                    const Grid& grid,
                                                    absl::Span<const Cell> changed) {
  if (grid.width() != previous.width_ || grid.height() != previous.height_) {
    return Build(grid, previous.unknown_is_free_);
  }
  auto table = std::make_shared<JumpTable>();
  table->width_ = previous.width_;
  table->height_ = previous.height_;
  table->unknown_is_free_ = previous.unknown_is_free_;
  table->tiles_x_ = previous.tiles_x_;
  table->rows_ = previous.rows_;
  table->tiles_ = previous.tiles_;
  table->own_.assign(table->tiles_.size(), 0);
  // Only cells whose passability flipped change any entry.
  std::vector<Cell> flipped;
  for (const Cell& c : changed) {
    const bool free = Traversable(grid.cost(c), table->unknown_is_free_);
    if (free == table->Free(c.x, c.y)) continue;
    uint64_t* line = table->rows_.MutableLine(c.y);
    const auto p = static_cast<uint32_t>(c.x + 64);
    line[p >> 6] ^= uint64_t{1} << (p & 63);
    flipped.push_back(c);
  }
  if (!flipped.empty()) {
    std::vector<Cell> near;
    near.reserve(flipped.size() * 9);
    for (const Cell& p : flipped) {
      for (int32_t y = std::max(0, p.y - 1); y <= std::min(table->height_ - 1, p.y + 1); ++y) {
        for (int32_t x = std::max(0, p.x - 1); x <= std::min(table->width_ - 1, p.x + 1);
             ++x) {
          near.push_back(Cell{x, y});
        }
      }
    }
    std::vector<Cell> sign_changed;
    std::vector<Cell> seeds;
    for (int i = 0; i < 4; ++i) {
      seeds = near;
      table->Repair(kDirs[i][0], kDirs[i][1], seeds, &sign_changed);
    }
    for (int i = 4; i < 8; ++i) {
      const int dx = kDirs[i][0];
      const int dy = kDirs[i][1];
      seeds = near;
      for (const Cell& n : sign_changed) {
        const Cell c{n.x - dx, n.y - dy};
        if (c.x >= 0 && c.x < table->width_ && c.y >= 0 && c.y < table->height_) {
          seeds.push_back(c);
        }
      }
      table->Repair(dx, dy, seeds, nullptr);
    }
  }
  table->own_.clear();
  table->own_.shrink_to_fit();
  return table;
}

size_t JumpTable::MemoryBytes() const {
  return sizeof(JumpTable) + rows_.MemoryBytes() +
         tiles_.capacity() * sizeof(std::shared_ptr<Tile>) +
         tiles_.size() * sizeof(Tile);
}

}  // namespace pathd::internal
