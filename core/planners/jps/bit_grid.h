// Grids packed one bit per cell for planners that scan 64 cells at a time
// (JPS): a line layout with blocked borders, the 64 x 64 bit transpose that
// turns rows into columns, and the packing of a cost grid, vectorised where
// the CPU allows because it runs on every query.
#ifndef PATHD_CORE_PLANNERS_JPS_BIT_GRID_H_
#define PATHD_CORE_PLANNERS_JPS_BIT_GRID_H_

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "core/map/grid.h"
#include "core/search/endpoints.h"

namespace pathd::internal {

// Lines of cells (the rows of a grid, or its columns) packed one bit per
// cell, 1 = traversable. Each line has a zero word before its first cell and
// at least one after its last, and there is an all-zero line before the first
// and after the last line, so reads up to one cell past any edge see blocked
// cells and need no bounds checks. The lines are stored in bands of
// 1 << kBandShift lines (one band on maps up to 4096 x 4096), shared between
// copies until one writes to a band (MutableLine copies it then), so a copy of
// a huge map's lines that changes a few cells costs a few bands, not the whole
// map. A value type; not synchronised: a copy may be read while another is
// written, but one copy may not be read and written at once.
class BitLines {
 public:
  // Lines a band holds when there are more than kOneBandCells cells;
  // fewer are one band, which scans read without the band lookup (see
  // one_band(): the lookup cost JPS 10-17% per query on 512 x 512 maps),
  // and which a copy duplicates whole on its first write (at most 2 MiB).
  static constexpr int kBandShift = 3;
  static constexpr int64_t kOneBandCells = int64_t{1} << 24;

  // `lines` lines of `length` cells, all blocked.
  void Reset(int32_t lines, int32_t length) {
    stride_ = static_cast<size_t>(length + 64) / 64 + 2;
    const size_t total = static_cast<size_t>(lines) + 2;
    shift_ = kBandShift;
    if (int64_t{lines} * length <= kOneBandCells) {
      shift_ = 0;
      while ((size_t{1} << shift_) < total) ++shift_;
    }
    band_words_ = std::min(total, size_t{1} << shift_) * stride_;
    bands_.assign((total + (size_t{1} << shift_) - 1) >> shift_, nullptr);
    for (std::shared_ptr<uint64_t[]>& band : bands_) {
      band = std::make_shared<uint64_t[]>(band_words_);
    }
  }

  // Line `line` in -1..lines. Word 1 holds cells 0..63 (bit i = cell i),
  // word k + 1 cells 64k..64k+63.
  const uint64_t* Line(int32_t line) const {
    const auto l = static_cast<size_t>(line + 1);
    return bands_[l >> shift_].get() +
           (l & ((size_t{1} << shift_) - 1)) * stride_;
  }
  // The same line to write, its band copied first when another copy of
  // these lines shares it.
  uint64_t* MutableLine(int32_t line) {
    const auto l = static_cast<size_t>(line + 1);
    std::shared_ptr<uint64_t[]>& band = bands_[l >> shift_];
    if (band.use_count() > 1) {
      auto own = std::make_shared_for_overwrite<uint64_t[]>(band_words_);
      std::copy(band.get(), band.get() + band_words_, own.get());
      band = std::move(own);
    }
    return band.get() + (l & ((size_t{1} << shift_) - 1)) * stride_;
  }
  // When the lines are one band: its words, line l at one_band() + (l + 1)
  // * stride(); else null. Valid until the next MutableLine or Reset.
  const uint64_t* one_band() const {
    return bands_.size() == 1 ? bands_[0].get() : nullptr;
  }
  size_t stride() const { return stride_; }

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

  // Every band counted in full, shared or not, with its pointer and
  // control block.
  size_t MemoryBytes() const {
    return bands_.capacity() * sizeof(bands_[0]) +
           bands_.size() * (band_words_ * sizeof(uint64_t) + 16);
  }

 private:
  size_t stride_ = 0;
  // Lines per band: 1 << shift_.
  int shift_ = 0;
  size_t band_words_ = 0;
  std::vector<std::shared_ptr<uint64_t[]>> bands_;
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
