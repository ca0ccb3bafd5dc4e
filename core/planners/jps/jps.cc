// Jump Point Search (Harabor & Grastien 2011, "Online Graph Pruning for
// Pathfinding on Grid Maps", AAAI) on pathd's uniform-cost 8-connected grids
// without corner cutting, with the block-based scans and intermediate-node
// pruning of Harabor & Grastien 2014, "Improving Jump Point Search", ICAPS.
//
// Pruning rules when a diagonal move needs both side cells free:
//  - A diagonal move has no forced neighbours: every cell behind it is reached
//    at least as cheaply by straight moves through its side cells, which the
//    move itself needs free. It continues straight along both of its axes and
//    diagonally.
//  - A straight move into n (say east, from m = n - 1) forces the side
//    neighbour s of n (north or south) when s is free but the cell beside m on
//    that side is blocked: no other canonical path reaches s as cheaply. Then
//    n is a jump point whose successors are the side direction and the
//    diagonal between it and the move; otherwise the move only continues.
//  - Diagonal scans run the two straight scans at every step and relax the
//    jump points those find directly (the "intermediate node" the 2011 paper
//    puts in the open list is skipped), so only straight-arrival jump points,
//    the start and the goal ever reach the open list.
//
// Scans read 64 cells per word from bit maps of the passability (by rows and,
// transposed, by columns) and of where a scan in each direction must stop.
// They live in the SearchScratch between queries; each query re-packs the
// grid to check they still match it (a Grid may be edited in place) and
// derives the rest again only if something changed.
//
// The search is the best-first loop of core/search/best_first.h with
// JpsExpansion as its expansion policy (node ids are jump-point ids, the
// successors the jump points the scans find) and the octile heuristic.
//
// jps_plus (JPS+, the offline jump points of the same 2014 paper) is the
// same search with the scans answered from a per-version jump table
// (core/planners/jps/jump_table.h) instead of the bit maps: JpsExpansion
// takes its scanner as a template parameter, BitScans or TableScans, so the
// two planners share pruning, ties, path output and preconditions.
#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "absl/base/attributes.h"
#include "absl/strings/str_format.h"
#include "core/planners/jps/bit_grid.h"
#include "core/planners/jps/jump_table.h"
#include "core/planners/planners.h"
#include "core/search/best_first.h"
#include "core/search/derived.h"
#include "core/search/endpoints.h"
#include "core/search/grid_planner.h"
#include "core/search/heuristics.h"
#include "core/search/path_measure.h"
#include "core/status_macros.h"

namespace pathd {
namespace {

using internal::BitLines;
using internal::PackIsa;
using internal::PackRule;

// The map as JPS reads it: passability bits by rows and by columns, and for
// each of the four straight directions a "go" map whose bit is set where a
// scan in that direction passes the cell without stopping (traversable, no
// forced neighbour), so a scan reads one word per 64 cells. Update() makes it
// match a grid exactly.
class JpsMap {
 public:
  // Re-packs the grid's rows, comparing them with what is held; when any
  // changed, rebuilds the columns of the 64 x 64 tiles that did and the go
  // maps. Returns false when the rule's uniform-cost check fails (the bits
  // are then still exact). The grid is read in full on every call because a
  // Grid may be edited in place between queries; everything else is derived
  // only when that finds a change.
  bool Update(const Grid& grid, const PackRule& rule) {
    static const PackIsa kIsa = internal::BestPackIsa();
    const int32_t w = grid.width();
    const int32_t h = grid.height();
    const int32_t tiles_x = (w + 63) / 64;
    const int32_t tiles_y = (h + 63) / 64;
    bool resized = false;
    if (w != width_ || h != height_ ||
        rule.unknown_is_free != unknown_is_free_) {
      width_ = w;
      height_ = h;
      unknown_is_free_ = rule.unknown_is_free;
      rows_.Reset(h, w);
      cols_.Reset(w, h);
      east_.Reset(h, w);
      west_.Reset(h, w);
      south_.Reset(w, h);
      north_.Reset(w, h);
      resized = true;
    }
    dirty_.assign(static_cast<size_t>(tiles_x) * tiles_y, resized ? 1 : 0);
    const bool uniform = internal::PackRows(kIsa, grid, rule, rows_, dirty_);
    bool changed = false;
    for (int32_t ty = 0; ty < tiles_y; ++ty) {
      for (int32_t tx = 0; tx < tiles_x; ++tx) {
        if (dirty_[static_cast<size_t>(ty) * tiles_x + tx]) {
          TransposeTile(tx, ty);
          changed = true;
        }
      }
    }
    if (changed) {
      BuildGo(rows_, h, w, east_, west_);
      BuildGo(cols_, w, h, south_, north_);
    }
    return uniform;
  }

  // Brings a copy of an older version's map up to `grid`, whose cells
  // differ from those it was packed from only in `changed` (cells listed
  // that did not change are harmless; same size and unknown rule): the bits
  // of cells whose passability flipped, the columns of their 64 x 64 tiles
  // and the go-map lines beside them. Bands of lines not written stay shared
  // with the older version (BitLines). O(changed), not O(map).
  void Advance(const Grid& grid, absl::Span<const Cell> changed) {
    const int32_t tiles_x = (width_ + 63) / 64;
    std::vector<uint32_t> tiles;
    std::vector<int32_t> row_lines;
    std::vector<int32_t> col_lines;
    for (const Cell& c : changed) {
      if (!grid.InBounds(c)) continue;
      const bool open = Traversable(grid.cost(c), unknown_is_free_);
      if (open == BitLines::Get(rows_.Line(c.y), c.x)) continue;
      const auto p = static_cast<uint32_t>(c.x + 64);
      rows_.MutableLine(c.y)[p >> 6] ^= uint64_t{1} << (p & 63);
      tiles.push_back(static_cast<uint32_t>(c.y / 64 * tiles_x + c.x / 64));
      for (int32_t d = -1; d <= 1; ++d) {
        if (c.y + d >= 0 && c.y + d < height_) row_lines.push_back(c.y + d);
        if (c.x + d >= 0 && c.x + d < width_) col_lines.push_back(c.x + d);
      }
    }
    auto unique = [](auto& v) {
      std::sort(v.begin(), v.end());
      v.erase(std::unique(v.begin(), v.end()), v.end());
    };
    unique(tiles);
    unique(row_lines);
    unique(col_lines);
    for (const uint32_t t : tiles) {
      TransposeTile(static_cast<int32_t>(t % tiles_x),
                    static_cast<int32_t>(t / tiles_x));
    }
    for (const int32_t l : row_lines)
      BuildGoLine(rows_, l, width_, east_, west_);
    for (const int32_t l : col_lines)
      BuildGoLine(cols_, l, height_, south_, north_);
  }

  int32_t width() const { return width_; }
  int32_t height() const { return height_; }
  const BitLines& rows() const { return rows_; }
  const BitLines& cols() const { return cols_; }
  // Go maps of scans along rows towards +x (east) and -x (west), and along
  // columns towards +y (south) and -y (north).
  const BitLines& east() const { return east_; }
  const BitLines& west() const { return west_; }
  const BitLines& south() const { return south_; }
  const BitLines& north() const { return north_; }

  size_t MemoryBytes() const {
    return rows_.MemoryBytes() + cols_.MemoryBytes() + east_.MemoryBytes() +
           west_.MemoryBytes() + south_.MemoryBytes() + north_.MemoryBytes() +
           dirty_.capacity();
  }

 private:
  void TransposeTile(int32_t tx, int32_t ty) {
    uint64_t block[64];
    for (int32_t i = 0; i < 64; ++i) {
      const int32_t y = 64 * ty + i;
      block[i] = y < height_ ? rows_.Line(y)[1 + tx] : 0;
    }
    internal::Transpose64(block);
    for (int32_t j = 0; j < 64 && 64 * tx + j < width_; ++j) {
      cols_.MutableLine(64 * tx + j)[1 + ty] = block[j];
    }
  }

  // Go maps of `lines` lines of `length` cells for scans towards increasing
  // (`forward`) and decreasing (`backward`) positions: a cell stops a scan
  // when it is blocked, or when a side cell is open but the side cell one
  // step back along the scan is blocked (a forced neighbour).
  static void BuildGo(const BitLines& open, int32_t lines, int32_t length,
                      BitLines& forward, BitLines& backward) {
    for (int32_t l = 0; l < lines; ++l)
      BuildGoLine(open, l, length, forward, backward);
  }
  // Line l of both go maps, from lines l - 1 .. l + 1 of `open`.
  static void BuildGoLine(const BitLines& open, int32_t l, int32_t length,
                          BitLines& forward, BitLines& backward) {
    const int32_t words = (length + 63) / 64;
    const uint64_t* c = open.Line(l);
    const uint64_t* u = open.Line(l - 1);
    const uint64_t* d = open.Line(l + 1);
    uint64_t* fwd = forward.MutableLine(l);
    uint64_t* bwd = backward.MutableLine(l);
    // Word 0 and word words + 1 are the blocked padding.
    for (int32_t k = 1; k <= words; ++k) {
      // Bit i of *_before = the side cell one position lower, of *_after
      // one higher, carried across word boundaries.
      const uint64_t u_before = (u[k] << 1) | (u[k - 1] >> 63);
      const uint64_t d_before = (d[k] << 1) | (d[k - 1] >> 63);
      const uint64_t u_after = (u[k] >> 1) | (u[k + 1] << 63);
      const uint64_t d_after = (d[k] >> 1) | (d[k + 1] << 63);
      fwd[k] = c[k] & ~((u[k] & ~u_before) | (d[k] & ~d_before));
      bwd[k] = c[k] & ~((u[k] & ~u_after) | (d[k] & ~d_after));
    }
  }

  int32_t width_ = -1;
  int32_t height_ = -1;
  bool unknown_is_free_ = false;
  BitLines rows_;
  BitLines cols_;
  BitLines east_;
  BitLines west_;
  BitLines south_;
  BitLines north_;
  // Per 64 x 64 tile during Update(): its rows changed.
  std::vector<uint8_t> dirty_;
};

// Where a straight scan stopped: at a jump point, or at a blocked cell (or the
// map edge) with nothing of interest before it.
struct ScanStop {
  int32_t pos;
  bool jump;
};

// Scans forward from `from` (exclusive) along a line with go map `go` and
// passability `open` to the first cell that stops it. Always inlined: with
// two BitScans instantiations the compiler stopped inlining the scans into
// the diagonal loop, which cost JPS 8-17% per query.
ABSL_ATTRIBUTE_ALWAYS_INLINE inline ScanStop ScanForward(const uint64_t* go,
                                                         const uint64_t* open,
                                                         int32_t from) {
  for (int32_t p = from + 1;; p += 64) {
    const uint64_t stop = ~BitLines::From(go, p);
    if (stop != 0) {
      const int32_t pos = p + std::countr_zero(stop);
      return {pos, BitLines::Get(open, pos)};
    }
  }
}

// ScanForward towards decreasing positions.
ABSL_ATTRIBUTE_ALWAYS_INLINE inline ScanStop ScanBackward(const uint64_t* go,
                                                          const uint64_t* open,
                                                          int32_t from) {
  for (int32_t p = from - 1;; p -= 64) {
    const uint64_t stop = ~BitLines::To(go, p);
    if (stop != 0) {
      const int32_t pos = p - std::countl_zero(stop);
      return {pos, BitLines::Get(open, pos)};
    }
  }
}

int Sign(int32_t v) { return (v > 0) - (v < 0); }

// A jump point met by the current query.
struct JumpPoint {
  int32_t x;
  int32_t y;
};

// Numbers the jump points of one query densely, in the order the search meets
// them. Their SearchScratch records are indexed by that number, so the few
// hundred a query touches share a few cache lines instead of being scattered
// over a map-sized array, where every relaxation would miss the cache.
class JumpPointTable {
 public:
  // Forgets the previous query's points. O(1) except when the 32-bit stamp
  // wraps.
  void Clear() {
    points_.clear();
    if (++stamp_ == 0) {
      for (Slot& slot : slots_) slot.stamp = 0;
      stamp_ = 1;
    }
    if (slots_.empty()) Rehash(kInitialSlots);
  }

  // The number of cell (x, y) with row-major index `cell`, assigned now if
  // the cell is new to this query.
  uint32_t Id(uint32_t cell, int32_t x, int32_t y) {
    for (uint32_t i = Hash(cell);; i = (i + 1) & mask_) {
      Slot& slot = slots_[i];
      if (slot.stamp != stamp_) {
        const auto id = static_cast<uint32_t>(points_.size());
        slot = Slot{stamp_, cell, id};
        points_.push_back(JumpPoint{x, y});
        // Keep the table at most half full so probes stay short.
        if (2 * points_.size() > slots_.size()) Rehash(2 * slots_.size());
        return id;
      }
      if (slot.cell == cell) return slot.id;
    }
  }

  const JumpPoint& point(uint32_t id) const { return points_[id]; }

  size_t MemoryBytes() const {
    return slots_.capacity() * sizeof(Slot) +
           points_.capacity() * sizeof(JumpPoint);
  }

 private:
  static constexpr size_t kInitialSlots = 1024;

  struct Slot {
    uint32_t stamp;
    uint32_t cell;
    uint32_t id;
  };

  uint32_t Hash(uint32_t cell) const {
    // Fibonacci hashing: the top bits of a multiplicative hash.
    return static_cast<uint32_t>((cell * 0x9E3779B97F4A7C15ull) >> shift_);
  }

  void Rehash(size_t slots) {
    std::vector<Slot> old;
    old.swap(slots_);
    slots_.assign(slots, Slot{0, 0, 0});
    mask_ = static_cast<uint32_t>(slots - 1);
    shift_ = 64 - std::countr_zero(slots);
    for (const Slot& slot : old) {
      if (slot.stamp != stamp_) continue;
      uint32_t i = Hash(slot.cell);
      while (slots_[i].stamp == stamp_) i = (i + 1) & mask_;
      slots_[i] = slot;
    }
  }

  std::vector<Slot> slots_;
  uint32_t mask_ = 0;
  int shift_ = 64;
  uint32_t stamp_ = 0;
  std::vector<JumpPoint> points_;
};

// What JPS keeps in a SearchScratch between queries.
struct JpsScratch final : public SearchScratch::Extension {
  JpsMap map;
  JumpPointTable points;
  size_t MemoryBytes() const override {
    return map.MemoryBytes() + points.MemoryBytes();
  }
};

// Bit c of word c / 64: some traversable cell among `cells` has effective
// cost c (unknown cells traversed as free count as kFreeCost).
void AddCosts(const Grid& grid, absl::Span<const Cell> cells,
              bool unknown_is_free, std::array<uint64_t, 4>& costs) {
  for (const Cell& cell : cells) {
    const uint8_t c = grid.cost(cell);
    if (!Traversable(c, unknown_is_free)) continue;
    const int effective = c == kUnknownCost ? kFreeCost : c;
    costs[effective / 64] |= uint64_t{1} << (effective % 64);
  }
}

// The same for every cell of `grid`.
std::array<uint64_t, 4> CostsOf(const Grid& grid, bool unknown_is_free) {
  std::array<bool, 256> seen{};
  for (const uint8_t c : grid.cells()) seen[c] = true;
  std::array<uint64_t, 4> costs{};
  for (int c = 0; c < 256; ++c) {
    if (!seen[c] || !Traversable(static_cast<uint8_t>(c), unknown_is_free))
      continue;
    const int effective = c == kUnknownCost ? kFreeCost : c;
    costs[effective / 64] |= uint64_t{1} << (effective % 64);
  }
  return costs;
}

// The cost set of a version advanced from one whose set was `previous`:
// the changed cells' costs added (a superset: a cost no cell has any more
// stays), except that a set of more than one cost is counted again from
// the grid, once for the version. A map that became uniform again would
// otherwise send every later query to the full check, O(map) each time.
std::array<uint64_t, 4> AdvancedCosts(std::array<uint64_t, 4> previous, const Grid& grid,
                                      absl::Span<const Cell> changed,
                                      bool unknown_is_free) {
  AddCosts(grid, changed, unknown_is_free, previous);
  int costs = 0;
  for (const uint64_t word : previous) costs += std::popcount(word);
  return costs > 1 ? CostsOf(grid, unknown_is_free) : previous;
}

// The map as JPS reads it for one map version, shared by every query on that
// version through the derived store (core/search/derived.h): packed once per
// version instead of re-read on every query, which cost 2.4 us on a 512 x 512
// game map and up to 8 us on open ones, most of a short query. A new version
// shares the previous one's bands of lines and re-derives only the bits
// around its changed cells (JpsMap::Advance): on a 16384 x 16384 map the
// first query of each version copied all 192 MiB of bit planes before.
struct JpsVersion {
  JpsMap map;
  // Bit c of word c / 64: some traversable cell has effective cost c
  // (unknown cells traversed as free count as kFreeCost), so a query checks
  // the uniform-cost precondition in O(1). An advance adds the costs of the
  // changed cells (AdvancedCosts), so a one-cost set may keep a cost no cell
  // has any more: a superset, which can only send a query to the full check
  // (ValidateRequest), never let a non-uniform map through.
  std::array<uint64_t, 4> costs{};

  static std::shared_ptr<const JpsVersion> Build(const Grid& grid,
                                                 bool unknown_is_free) {
    auto version = std::make_shared<JpsVersion>();
    version->map.Update(grid, PackRule{.unknown_is_free = unknown_is_free});
    version->costs = CostsOf(grid, unknown_is_free);
    return version;
  }

  // The version of `grid` from the one of an older version whose cells
  // differ only in `changed`: sharing every band of lines the change does
  // not write. A change of more than a sixteenth of the map is packed
  // again in full (what the per-cell advance would cost more than).
  static std::shared_ptr<const JpsVersion> Advance(
      const JpsVersion& previous, const Grid& grid,
      absl::Span<const Cell> changed, bool unknown_is_free) {
    if (grid.width() != previous.map.width() ||
        grid.height() != previous.map.height() ||
        changed.size() > grid.size() / 16) {
      return Build(grid, unknown_is_free);
    }
    auto version = std::make_shared<JpsVersion>(previous);
    version->map.Advance(grid, changed);
    version->costs = AdvancedCosts(previous.costs, grid, changed, unknown_is_free);
    return version;
  }

  // True when every traversable cell's effective cost is `cost`.
  bool OnlyCost(uint8_t cost) const {
    std::array<uint64_t, 4> only{};
    only[cost / 64] = uint64_t{1} << (cost % 64);
    return costs == only;
  }
};

// The version's JpsVersion from the store under its key.
std::shared_ptr<const JpsVersion> SharedJpsVersion(DerivedStore* store,
                                                   const Grid& grid,
                                                   bool unknown_is_free) {
  return GetDerived<JpsVersion>(
      store, grid,
      std::string("jps_map unknown_is_free=") + (unknown_is_free ? "1" : "0"),
      [unknown_is_free](const Grid& g) {
        return JpsVersion::Build(g, unknown_is_free);
      },
      [unknown_is_free](const JpsVersion& previous, const Grid& g,
                        absl::Span<const Cell> changed) {
        return JpsVersion::Advance(previous, g, changed, unknown_is_free);
      },
      [](const JpsVersion& v) {
        return sizeof(JpsVersion) + v.map.MemoryBytes();
      });
}

// One plane of a JpsMap as the scans read it: with kOneBand (the map's
// lines are one band, BitLines::one_band()) at base + (line + 1) * stride,
// which the compiler keeps in registers across a scan, else through the
// band lookup.
template <bool kOneBand>
class PlaneLines {
 public:
  explicit PlaneLines(const BitLines& lines)
      : lines_(lines), base_(lines.one_band()), stride_(lines.stride()) {}
  const uint64_t* Line(int32_t line) const {
    if constexpr (kOneBand) {
      return base_ + static_cast<size_t>(line + 1) * stride_;
    } else {
      return lines_.Line(line);
    }
  }

 private:
  const BitLines& lines_;
  const uint64_t* base_;
  size_t stride_;
};

// Scans of the online search: straight scans read the go maps 64 cells at a
// time, diagonal ones step cell by cell and scan straight at every step.
// Successors reach `relax(x, y, g)`. Single use; not thread-safe.
// Precondition: kOneBand == (map.rows().one_band() != nullptr).
template <bool kOneBand>
class BitScans {
 public:
  BitScans(const JpsMap& map, Cell goal)
      : rows_(map.rows()),
        cols_(map.cols()),
        east_(map.east()),
        west_(map.west()),
        south_(map.south()),
        north_(map.north()),
        goal_(goal) {}

  bool Free(int32_t x, int32_t y) const {
    return BitLines::Get(rows_.Line(y), x);
  }

  // Scans from (x, y) in the straight direction (dx, dy) and offers the goal
  // or the jump point found; (x, y) is reached at cost g.
  template <typename Relax>
  ABSL_ATTRIBUTE_ALWAYS_INLINE void Straight(int32_t x, int32_t y, int dx,
                                             int dy, double g,
                                             Relax& relax) const {
    if (dx != 0) {
      const uint64_t* open = rows_.Line(y);
      const ScanStop stop = dx > 0 ? ScanForward(east_.Line(y), open, x)
                                   : ScanBackward(west_.Line(y), open, x);
      if (goal_.y == y && (goal_.x - x) * dx > 0 &&
          (stop.pos - goal_.x) * dx >= 0) {
        relax(goal_.x, y, g + std::abs(goal_.x - x));
      } else if (stop.jump) {
        relax(stop.pos, y, g + std::abs(stop.pos - x));
      }
    } else {
      const uint64_t* open = cols_.Line(x);
      const ScanStop stop = dy > 0 ? ScanForward(south_.Line(x), open, y)
                                   : ScanBackward(north_.Line(x), open, y);
      if (goal_.x == x && (goal_.y - y) * dy > 0 &&
          (stop.pos - goal_.y) * dy >= 0) {
        relax(x, goal_.y, g + std::abs(goal_.y - y));
      } else if (stop.jump) {
        relax(x, stop.pos, g + std::abs(stop.pos - y));
      }
    }
  }

  // Steps diagonally from (x, y) while the move is legal, scanning straight
  // along both axes at every step; jump points found that way get the
  // expanded node as their parent.
  template <typename Relax>
  ABSL_ATTRIBUTE_NOINLINE void Diagonal(int32_t x, int32_t y, int dx, int dy,
                                        double g, Relax& relax) const {
    for (int32_t k = 1;; ++k) {
      if (!Free(x + dx, y) || !Free(x, y + dy) || !Free(x + dx, y + dy)) return;
      x += dx;
      y += dy;
      const double gk = g + k * kSqrt2;
      if (x == goal_.x && y == goal_.y) {
        relax(x, y, gk);
        return;
      }
      Straight(x, y, dx, 0, gk, relax);
      Straight(x, y, 0, dy, gk, relax);
    }
  }

 private:
  const PlaneLines<kOneBand> rows_, cols_, east_, west_, south_, north_;
  const Cell goal_;
};

// The same scans answered from a JPS+ jump table (core/planners/jps/
// jump_table.h): one lookup per straight scan, one per diagonal jump point
// instead of one step per cell. They offer the same successors in the same
// order at the same costs as BitScans (diagonal costs as g + k * sqrt(2)
// from the expanded node, as there), so jps_plus ties and paths are jps's.
// The goal is checked where it could interrupt a jump ("goal bounding"): on
// the straight run before the jump point or wall, and on the diagonal at the
// step that reaches its row or column. Single use; not thread-safe.
class TableScans {
 public:
  TableScans(const internal::JumpTable& table, Cell goal)
      : table_(table), goal_(goal) {}

  bool Free(int32_t x, int32_t y) const { return table_.Free(x, y); }

  template <typename Relax>
  void Straight(int32_t x, int32_t y, int dx, int dy, double g,
                Relax& relax) const {
    const int32_t e = table_.Entry(x, y, dx, dy);
    // Cells up to `reach` along the direction are traversable (the goal is).
    const int32_t reach = e > 0 ? e : -e;
    if (dx != 0) {
      if (goal_.y == y && (goal_.x - x) * dx > 0 &&
          std::abs(goal_.x - x) <= reach) {
        relax(goal_.x, y, g + std::abs(goal_.x - x));
      } else if (e > 0) {
        relax(x + e * dx, y, g + e);
      }
    } else {
      if (goal_.x == x && (goal_.y - y) * dy > 0 &&
          std::abs(goal_.y - y) <= reach) {
        relax(x, goal_.y, g + std::abs(goal_.y - y));
      } else if (e > 0) {
        relax(x, y + e * dy, g + e);
      }
    }
  }

  template <typename Relax>
  void Diagonal(int32_t x, int32_t y, int dx, int dy, double g,
                Relax& relax) const {
    // Steps taken from the expanded node, for its costs.
    int32_t k = 0;
    for (;;) {
      const int32_t e = table_.Entry(x, y, dx, dy);
      const int32_t reach = e > 0 ? e : -e;
      // Before the next diagonal jump point (or the last legal step) the
      // straight scans can only find the goal, at the one step that lands on
      // its row or column.
      if ((goal_.x - x) * dx > 0 && (goal_.y - y) * dy > 0) {
        const int32_t to_goal =
            std::min(std::abs(goal_.x - x), std::abs(goal_.y - y));
        if (to_goal <= reach && to_goal != e) {
          const int32_t gx = x + to_goal * dx;
          const int32_t gy = y + to_goal * dy;
          const double gk = g + (k + to_goal) * kSqrt2;
          if (gx == goal_.x && gy == goal_.y) {
            relax(gx, gy, gk);
            return;
          }
          Straight(gx, gy, dx, 0, gk, relax);
          Straight(gx, gy, 0, dy, gk, relax);
        }
      }
      if (e <= 0) return;
      x += e * dx;
      y += e * dy;
      k += e;
      const double gk = g + k * kSqrt2;
      if (x == goal_.x && y == goal_.y) {
        relax(x, y, gk);
        return;
      }
      Straight(x, y, dx, 0, gk, relax);
      Straight(x, y, 0, dy, gk, relax);
    }
  }

 private:
  const internal::JumpTable& table_;
  const Cell goal_;
};

// The expansion policy of one JPS query: node ids are JumpPointTable ids (so
// the SearchScratch records are indexed by them, not by cells), successors are
// the jump points (and the goal) the scans from a node find, pruned by the
// direction its parent reached it in. Searches with unit cell factor (the
// map's single factor scales every path alike); the caller scales the
// reported cost. `Scans` is BitScans (jps) or TableScans (jps_plus). Single
// use; not thread-safe.
template <typename Scans>
class JpsExpansion {
 public:
  JpsExpansion(const Scans& scans, JumpPointTable& points, int32_t width,
               const SearchScratch& scratch)
      : scans_(scans), points_(points), width_(width), scratch_(scratch) {}

  uint32_t Id(Cell c) const { return points_.Id(Index(c.x, c.y), c.x, c.y); }
  Cell CellOf(uint32_t id) const {
    const JumpPoint& p = points_.point(id);
    return Cell{p.x, p.y};
  }

  // Calls visit(id, x, y, g) for each successor of jump point `id` (reached
  // at cost g).
  template <typename Visit>
  void ForEachSuccessor(uint32_t id, double g, Visit&& visit) const {
    auto relax = [this, &visit](int32_t x, int32_t y, double gx) {
      visit(points_.Id(Index(x, y), x, y), x, y, gx);
    };
    const auto [x, y] = points_.point(id);
    const uint32_t parent = scratch_.Raw(id).parent;
    if (parent == SearchScratch::kNoParent) {
      for (int d = -1; d <= 1; d += 2) {
        scans_.Straight(x, y, d, 0, g, relax);
        scans_.Straight(x, y, 0, d, g, relax);
        scans_.Diagonal(x, y, d, -1, g, relax);
        scans_.Diagonal(x, y, d, 1, g, relax);
      }
      return;
    }
    // Paths between jump points go diagonally first, so the last move is
    // along the longer axis of the offset from the parent.
    const JumpPoint& from = points_.point(parent);
    const int32_t ox = x - from.x;
    const int32_t oy = y - from.y;
    if (std::abs(ox) > std::abs(oy)) {
      const int dx = Sign(ox);
      scans_.Straight(x, y, dx, 0, g, relax);
      for (int s = -1; s <= 1; s += 2) {
        if (scans_.Free(x, y + s) && !scans_.Free(x - dx, y + s)) {
          scans_.Straight(x, y, 0, s, g, relax);
          scans_.Diagonal(x, y, dx, s, g, relax);
        }
      }
    } else {
      // Only the goal is ever reached by a purely diagonal path, and it is
      // never expanded, so |oy| > |ox| here.
      const int dy = Sign(oy);
      scans_.Straight(x, y, 0, dy, g, relax);
      for (int s = -1; s <= 1; s += 2) {
        if (scans_.Free(x + s, y) && !scans_.Free(x + s, y - dy)) {
          scans_.Straight(x, y, s, 0, g, relax);
          scans_.Diagonal(x, y, s, dy, g, relax);
        }
      }
    }
  }

 private:
  uint32_t Index(int32_t x, int32_t y) const {
    return static_cast<uint32_t>(y) * static_cast<uint32_t>(width_) +
           static_cast<uint32_t>(x);
  }

  // A copy (two references and the goal): one indirection less per scan.
  const Scans scans_;
  JumpPointTable& points_;
  const int32_t width_;
  const SearchScratch& scratch_;
};

// Expands the chain of jump points ending at `goal` into single moves
// (diagonal first between consecutive jump points, as the scans went) and
// sums cost and length step by step in path order, as MeasurePath does.
void FillPath(const JumpPointTable& points, const SearchScratch& scratch,
              uint32_t goal, double factor, PlanResult& result) {
  std::vector<uint32_t> jumps;
  for (uint32_t at = goal; at != SearchScratch::kNoParent;
       at = scratch.Raw(at).parent) {
    jumps.push_back(at);
  }
  auto cell = [&points](uint32_t id) {
    const JumpPoint& p = points.point(id);
    return Cell{p.x, p.y};
  };
  std::vector<Cell>& path = result.path;
  path.push_back(cell(jumps.back()));
  for (size_t j = jumps.size() - 1; j-- > 0;) {
    const Cell to = cell(jumps[j]);
    Cell at = path.back();
    const int sx = Sign(to.x - at.x);
    const int sy = Sign(to.y - at.y);
    while (at.x != to.x || at.y != to.y) {
      const int mx = at.x != to.x ? sx : 0;
      const int my = at.y != to.y ? sy : 0;
      at.x += mx;
      at.y += my;
      const double length = mx != 0 && my != 0 ? kSqrt2 : 1.0;
      result.length += length;
      result.cost += length * factor;
      path.push_back(at);
    }
  }
}

// The best-first search over jump points that jps and jps_plus share, with
// `scans` finding successors. result.expansions counts jump points taken
// from the open list (the start and goal included), not the cells the scans
// pass over.
template <typename Scans>
PlanResult SearchJumpPoints(const Scans& scans, const GridQuery& q,
                            JumpPointTable& points) {
  const Grid& grid = q.grid;
  const PlanRequest& request = q.request;
  SearchScratch& scratch = q.scratch;
  scratch.BeginSearch(grid.size());
  points.Clear();
  const JpsExpansion<Scans> expansion(scans, points, grid.width(), scratch);
  const internal::AStarPriority<internal::OctileHeuristic> priority{
      {request.goal}};
  internal::OpenList open(scratch);
  const uint32_t start = expansion.Id(request.start);
  const uint32_t goal = expansion.Id(request.goal);
  internal::PushRoot(scratch, open, start, request.start, priority);
  PlanResult result;
  result.outcome = internal::WithExpansionListener(
      request.expansion_recorder, expansion, [&](auto listener) {
        return internal::BestFirstSearch(
            scratch, open, goal, q.stop, result.expansions, priority, expansion,
            internal::PlainParentUpdate(), listener);
      });
  if (result.found()) {
    // Every traversable cell has the factor of the start cell.
    const uint8_t start_cost = grid.cost(request.start);
    const double factor = CellFactor(start_cost, request.cost.cost_weight);
    FillPath(points, scratch, goal, factor, result);
  }
  return result;
}

// How a query reads the uniform-cost precondition from PackRows.
PackRule RuleFor(const Grid& grid, const PlanRequest& request) {
  const uint8_t start_cost = grid.cost(request.start);
  return PackRule{
      .unknown_is_free = request.cost.unknown_is_free,
      .check_uniform = request.cost.cost_weight != 0.0,
      .uniform_cost = start_cost == kUnknownCost ? kFreeCost : start_cost,
  };
}

// What jps and jps_plus share: traits, and endpoint checks apart from the
// uniform-cost precondition (the map pass of each checks that).
class JumpPlannerBase : public GridPlanner {
 protected:
  // `name` and `description` must outlive the planner (string literals).
  JumpPlannerBase(std::string_view name, std::string_view description)
      : GridPlanner(name, PlannerTraits{.optimal = true,
                                        .needs_uniform_cost = true,
                                        .needs_eight_connected = true,
                                        .description = description}) {}

  // The uniform-cost precondition needs every cell read, and so does the
  // map update: Search() checks the precondition in the same pass, and the
  // full ValidateRequest runs only to word the error when it fails.
  absl::Status Validate(const Grid& grid,
                        const PlanRequest& request) const override {
    PlannerTraits endpoint_traits = traits();
    endpoint_traits.needs_uniform_cost = false;
    return ValidateRequest(grid, request, name(), endpoint_traits);
  }
};

class JpsPlanner final : public JumpPlannerBase {
 public:
  JpsPlanner()
      : JumpPlannerBase("jps",
                        "Jump Point Search with block-based scans; optimal, "
                        "for 8-connected maps whose traversable cells all "
                        "cost the same; expansions count jump points") {}

 protected:
  absl::StatusOr<PlanResult> Search(const GridQuery& q) const override {
    const Grid& grid = q.grid;
    const PlanRequest& request = q.request;
    const PackRule rule = RuleFor(grid, request);
    JpsScratch& state = q.scratch.extension<JpsScratch>();
    // With a store the version's map is packed once; without one (a robot
    // linking core, benchmarks) the scratch's copy is brought up to date.
    std::shared_ptr<const JpsVersion> version;
    if (request.derived != nullptr) {
      version = SharedJpsVersion(request.derived, grid, rule.unknown_is_free);
      if (rule.check_uniform && !version->OnlyCost(rule.uniform_cost)) {
        // The costs may be a stale superset: only the full check decides.
        absl::Status status = ValidateRequest(grid, request, name(), traits());
        if (!status.ok()) return status;
      }
    } else if (!state.map.Update(grid, rule)) {
      return ValidateRequest(grid, request, name(), traits());
    }
    const JpsMap& map = version != nullptr ? version->map : state.map;
    if (map.rows().one_band() != nullptr) {
      return SearchJumpPoints(BitScans<true>(map, request.goal), q,
                              state.points);
    }
    return SearchJumpPoints(BitScans<false>(map, request.goal), q,
                            state.points);
  }
};

// The jump table of one map version with the costs its traversable cells
// have; an advance keeps them as JpsVersion does (AdvancedCosts): a
// one-cost set may be a superset, which can only send a query to the full
// check (ValidateRequest), never let a non-uniform map through.
struct JpsPlusVersion {
  std::shared_ptr<const internal::JumpTable> table;
  std::array<uint64_t, 4> costs{};

  // Null when `stop` fired.
  static std::shared_ptr<const JpsPlusVersion> Build(const Grid& grid,
                                                     bool unknown_is_free,
                                                     DerivedStop& stop) {
    auto version = std::make_shared<JpsPlusVersion>();
    version->table = internal::JumpTable::Build(grid, unknown_is_free, &stop);
    if (version->table == nullptr) return nullptr;
    version->costs = CostsOf(grid, unknown_is_free);
    return version;
  }

  static std::shared_ptr<const JpsPlusVersion> Advance(
      const JpsPlusVersion& previous, const Grid& grid,
      absl::Span<const Cell> changed) {
    auto version = std::make_shared<JpsPlusVersion>();
    version->table =
        internal::JumpTable::Advance(*previous.table, grid, changed);
    version->costs = AdvancedCosts(previous.costs, grid, changed,
                                   previous.table->unknown_is_free());
    return version;
  }

  bool OnlyCost(uint8_t cost) const {
    std::array<uint64_t, 4> only{};
    only[cost / 64] = uint64_t{1} << (cost % 64);
    return costs == only;
  }
};

// What jps_plus keeps in a SearchScratch between queries without a store:
// the packed rows to notice an edited grid, and the table they gave.
struct JpsPlusScratch final : public SearchScratch::Extension {
  int32_t width = -1;
  int32_t height = -1;
  bool unknown_is_free = false;
  BitLines rows;
  std::vector<uint8_t> dirty;
  std::shared_ptr<const internal::JumpTable> table;
  JumpPointTable points;
  size_t MemoryBytes() const override {
    return rows.MemoryBytes() + dirty.capacity() + points.MemoryBytes() +
           (table != nullptr ? table->MemoryBytes() : 0);
  }
};

// JPS+ (Harabor & Grastien 2014, "Improving Jump Point Search", ICAPS;
// Rabin & Silva 2015, "JPS+", Game AI Pro 2): jps's search with every scan
// answered by the version's jump table (core/planners/jps/jump_table.h),
// which the derived store builds once per map version and advances line by
// line around the changed cells of the next one.
class JpsPlusPlanner final : public JumpPlannerBase {
 public:
  JpsPlusPlanner()
      : JumpPlannerBase("jps_plus",
                        "JPS+: Jump Point Search reading per-cell jump "
                        "distances built once per map version and repaired "
                        "line by line on updates; optimal, same preconditions "
                        "and answers as jps; expansions count jump points") {}

 protected:
  // The table is 32 bytes a cell whatever the query: a bound on the map, so
  // a client cannot make a worker allocate gigabytes (a 16384 x 16384 map's
  // table would be 8 GiB; jps needs about a bit per cell there).
  absl::Status Validate(const Grid& grid,
                        const PlanRequest& request) const override {
    PATHD_RETURN_IF_ERROR(JumpPlannerBase::Validate(grid, request));
    if (static_cast<int64_t>(grid.size()) > internal::kJumpTableMaxCells) {
      return absl::FailedPreconditionError(absl::StrFormat(
          "planner jps_plus supports maps of up to %d cells (its jump table "
          "holds 32 bytes per cell); this map has %d x %d: use jps or hpa_star",
          internal::kJumpTableMaxCells, grid.width(), grid.height()));
    }
    return absl::OkStatus();
  }

  absl::StatusOr<PlanResult> Search(const GridQuery& q) const override {
    const Grid& grid = q.grid;
    const PlanRequest& request = q.request;
    const PackRule rule = RuleFor(grid, request);
    JpsPlusScratch& state = q.scratch.extension<JpsPlusScratch>();
    std::shared_ptr<const internal::JumpTable> table;
    // A table build is O(map) (0.1-0.3 s for 1024 x 1024): it polls the
    // query's deadline and cancellation.
    DerivedStop derived_stop(q.stop);
    if (request.derived != nullptr) {
      const bool unknown_is_free = rule.unknown_is_free;
      std::shared_ptr<const JpsPlusVersion> version =
          GetDerived<JpsPlusVersion>(
              request.derived, grid,
              std::string("jps_plus_table unknown_is_free=") +
                  (unknown_is_free ? "1" : "0"),
              "the jump table of this map version", derived_stop,
              [unknown_is_free](const Grid& g, DerivedStop& s) {
                return JpsPlusVersion::Build(g, unknown_is_free, s);
              },
              [](const JpsPlusVersion& previous, const Grid& g,
                 absl::Span<const Cell> changed, DerivedStop&) {
                return JpsPlusVersion::Advance(previous, g, changed);
              },
              [](const JpsPlusVersion& v) {
                return sizeof(JpsPlusVersion) + v.table->MemoryBytes();
              });
      if (version == nullptr) return StoppedWhileDeriving(derived_stop);
      if (rule.check_uniform && !version->OnlyCost(rule.uniform_cost)) {
        // The costs may be a stale superset: only the full check decides.
        absl::Status status = ValidateRequest(grid, request, name(), traits());
        if (!status.ok()) return status;
      }
      table = version->table;
    } else {
      // A Grid may be edited in place between queries: re-pack it, and
      // rebuild the table when any row changed.
      const bool resized = grid.width() != state.width ||
                           grid.height() != state.height ||
                           rule.unknown_is_free != state.unknown_is_free;
      if (resized) {
        state.width = grid.width();
        state.height = grid.height();
        state.unknown_is_free = rule.unknown_is_free;
        state.rows.Reset(grid.height(), grid.width());
        state.table = nullptr;
      }
      state.dirty.assign(static_cast<size_t>((grid.width() + 63) / 64) *
                             static_cast<size_t>((grid.height() + 63) / 64),
                         0);
      static const PackIsa kIsa = internal::BestPackIsa();
      if (!internal::PackRows(kIsa, grid, rule, state.rows, state.dirty)) {
        // The rows now match the grid but the table may not: the next query
        // would find nothing dirty.
        state.table = nullptr;
        return ValidateRequest(grid, request, name(), traits());
      }
      if (state.table == nullptr ||
          std::find(state.dirty.begin(), state.dirty.end(), 1) !=
              state.dirty.end()) {
        state.table = internal::JumpTable::Build(grid, rule.unknown_is_free,
                                                 &derived_stop);
        if (state.table == nullptr) return StoppedWhileDeriving(derived_stop);
      }
      table = state.table;
    }
    return SearchJumpPoints(TableScans(*table, request.goal), q, state.points);
  }
};

}  // namespace

std::unique_ptr<Planner> MakeJpsPlanner() {
  return std::make_unique<JpsPlanner>();
}

std::unique_ptr<Planner> MakeJpsPlusPlanner() {
  return std::make_unique<JpsPlusPlanner>();
}

}  // namespace pathd
