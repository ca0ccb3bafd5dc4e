// Grids packed one bit per cell for planners that scan 64 cells at a time
// (JPS): a line layout with blocked borders, the 64 x 64 bit transpose that
// turns rows into columns, and the packing of a cost grid, vectorised where
// the CPU allows because it runs on every query.
#ifndef PATHD_CORE_PLANNERS_JPS_BIT_GRID_H_
#define PATHD_CORE_PLANNERS_JPS_BIT_GRID_H_

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/map/grid.h"
#include "core/search/endpoints.h"

namespace pathd::internal {

// Lines of cells (the rows of a grid, or its columns) packed one bit per
// cell, 1 = traversable. Each line has a zero word before its first cell and
// at least one after its last, and there is an all-zero line before the first
// and after the last line, so reads up to one cell past any edge see blocked
// cells and need no bounds checks. A value type; not synchronised.
class BitLines {
 public:
  // `lines` lines of `length` cells, all blocked.
  void Reset(int32_t lines, int32_t length) {
    stride_ = static_cast<size_t>(length + 64) / 64 + 2;
    words_.assign((static_cast<size_t>(lines) + 2) * stride_, 0);
  }

  // Line `line` in -1..lines. Word 1 holds cells 0..63 (bit i = cell i),
  // word k + 1 cells 64k..64k+63.
  const uint64_t* Line(int32_t line) const {
    return words_.data() + static_cast<size_t>(line + 1) * stride_;
  }
  uint64_t* MutableLine(int32_t line) {
    return words_.data() + static_cast<size_t>(line + 1) * stride_;
  }

  // Cells pos..pos+63 of a line, bit i = cell pos + i; pos in -64..length.
  static uint64_t From(const uint64_t* line, int32_t pos) {
    const auto p = static_cast<uint32_t>(pos + 64);
    const uint64_t lo = line[p >> 6];
    const uint64_t hi = line[(p >> 6) + 1];
    const uint32_t s = p & 63;
    // hi << (64 - s) without the undefined shift by 64 when s == 0.
    return (lo >> s) | ((hi << 1) << (63 - s));
  }
  // Cells pos-63..pos of a line, bit 63 = cell pos; pos in -1..length.
  static uint64_t To(const uint64_t* line, int32_t pos) {
    return From(line, pos - 63);
  }
  // One cell; pos in -1..length.
  static bool Get(const uint64_t* line, int32_t pos) {
    const auto p = static_cast<uint32_t>(pos + 64);
    return (line[p >> 6] >> (p & 63)) & 1;
  }

  size_t MemoryBytes() const { return words_.capacity() * sizeof(uint64_t); }

 private:
  size_t stride_ = 0;
  std::vector<uint64_t> words_;
};

// Transposes a 64 x 64 bit matrix in place: afterwards bit c of a[r] is what
// bit r of a[c] was.
void Transpose64(uint64_t a[64]);

// How PackRows reads cells. With check_uniform set it also checks that every
// traversable cell has the effective cost `uniform_cost` (unknown cells
// traversed as free count as kFreeCost): the uniform-cost precondition of
// ValidateRequest, folded into the pass that reads every cell anyway.
struct PackRule {
  bool unknown_is_free = false;
  bool check_uniform = false;
  uint8_t uniform_cost = kFreeCost;
};

// Instruction sets PackRows can use; all give the same result.
enum class PackIsa { kScalar, kSse2, kAvx512 };

// True when this build and this CPU can run `isa`.
bool PackIsaAvailable(PackIsa isa);
// The fastest available instruction set.
PackIsa BestPackIsa();

// Packs the passability of every row of `grid` into `rows`, which must have
// been Reset(grid.height(), grid.width()), comparing each word with the one
// held: for every word k of row y that changes, sets
// dirty[(y / 64) * ceil(width / 64) + k] (dirty must have that many tiles).
// Returns false when rule.check_uniform is set and a traversable cell breaks
// it; the bits are exact either way. Precondition: PackIsaAvailable(isa).
bool PackRows(PackIsa isa, const Grid& grid, const PackRule& rule,
              BitLines& rows, std::vector<uint8_t>& dirty);

}  // namespace pathd::internal

#endif  // PATHD_CORE_PLANNERS_JPS_BIT_GRID_H_
