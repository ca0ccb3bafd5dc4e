// Packing a cost grid into BitLines, as a portable loop and as SSE2 and
// AVX-512 loops picked at run time. The pass reads every cell of the map on
// every JPS query, which on a 512 x 512 map costs more than the search
// itself unless it handles 16 or 64 cells per instruction.
#include "core/planners/jps/bit_grid.h"

#include <algorithm>
#include <type_traits>

#include "core/map/cost_model.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if (defined(__x86_64__) || defined(__i386__)) && defined(__GNUC__)
#include <immintrin.h>
#define PATHD_BIT_GRID_AVX512 1
#endif

namespace pathd::internal {

void Transpose64(uint64_t a[64]) {
  // Swaps ever smaller off-diagonal blocks: 32 x 32, then 16 x 16 inside
  // each, ... (Hacker's Delight 7-3, for least-significant-bit-first rows).
  uint64_t mask = 0x00000000FFFFFFFFull;
  for (int j = 32; j != 0; j >>= 1, mask ^= mask << j) {
    for (int k = 0; k < 64; k = ((k | j) + 1) & ~j) {
      const uint64_t t = ((a[k] >> j) ^ a[k | j]) & mask;
      a[k | j] ^= t;
      a[k] ^= t << j;
    }
  }
}

namespace {

// Stores word k of a row, marking its tile when the word changed.
inline void StoreWord(uint64_t bits, uint64_t& word, uint8_t& dirty) {
  if (bits != word) {
    word = bits;
    dirty = 1;
  }
}

// Calls f(unknown_is_free, check_uniform) with both flags as compile-time
// constants, so each loop below is compiled once per combination.
template <typename F>
bool WithRuleFlags(const PackRule& rule, F&& f) {
  using Yes = std::true_type;
  using No = std::false_type;
  if (rule.unknown_is_free)
    return rule.check_uniform ? f(Yes{}, Yes{}) : f(Yes{}, No{});
  return rule.check_uniform ? f(No{}, Yes{}) : f(No{}, No{});
}

template <bool kUnknownIsFree, bool kCheckUniform>
bool PackRowsScalar(const Grid& grid, uint8_t uniform_cost, BitLines& rows,
                    uint8_t* dirty) {
  const int32_t w = grid.width();
  const int32_t tiles_x = (w + 63) / 64;
  bool mixed = false;
  for (int32_t y = 0; y < grid.height(); ++y) {
    const uint8_t* row = grid.cells().data() + static_cast<size_t>(y) * w;
    uint64_t* words = rows.MutableLine(y) + 1;
    uint8_t* dirty_row = dirty + static_cast<size_t>(y / 64) * tiles_x;
    for (int32_t k = 0; k < tiles_x; ++k) {
      const int32_t count = std::min(64, w - 64 * k);
      uint64_t bits = 0;
      for (int32_t i = 0; i < count; ++i) {
        const uint8_t v = row[64 * k + i];
        const bool open = Traversable(v, kUnknownIsFree);
        if constexpr (kCheckUniform) {
          mixed |= open && (v == kUnknownCost ? kFreeCost : v) != uniform_cost;
        }
        bits |= static_cast<uint64_t>(open) << i;
      }
      StoreWord(bits, words[k], dirty_row[k]);
    }
  }
  return !mixed;
}

#if defined(__SSE2__)
template <bool kUnknownIsFree, bool kCheckUniform>
bool PackRowsSse2(const Grid& grid, uint8_t uniform_cost, BitLines& rows,
                  uint8_t* dirty) {
  const int32_t w = grid.width();
  const int32_t tiles_x = (w + 63) / 64;
  const uint8_t* const end = grid.cells().data() + grid.size();
  const __m128i max_traversable =
      _mm_set1_epi8(static_cast<char>(kMaxTraversableCost));
  const __m128i unknown = _mm_set1_epi8(static_cast<char>(kUnknownCost));
  const __m128i uniform = _mm_set1_epi8(static_cast<char>(uniform_cost));
  __m128i bad = _mm_setzero_si128();
  // The last word of the last row is packed from a copy padded with blocked
  // cells, so no load goes past the grid.
  uint8_t padded[64];
  for (int32_t y = 0; y < grid.height(); ++y) {
    const uint8_t* row = grid.cells().data() + static_cast<size_t>(y) * w;
    uint64_t* words = rows.MutableLine(y) + 1;
    uint8_t* dirty_row = dirty + static_cast<size_t>(y / 64) * tiles_x;
    for (int32_t k = 0; k < tiles_x; ++k) {
      const uint8_t* src = row + 64 * k;
      const int32_t count = std::min(64, w - 64 * k);
      if (end - src < 64) {
        std::copy(src, src + count, padded);
        std::fill(padded + count, padded + 64, kLethalCost);
        src = padded;
      }
      // Cells past the row's end belong to the next row: their bits are
      // masked off below, and checking their cost early is harmless.
      uint64_t bits = 0;
      for (int q = 0; q < 4; ++q) {
        const __m128i v =
            _mm_loadu_si128(reinterpret_cast<const __m128i*>(src + 16 * q));
        // v <= 252 as unsigned bytes.
        __m128i open = _mm_cmpeq_epi8(_mm_min_epu8(v, max_traversable), v);
        __m128i same = _mm_cmpeq_epi8(v, uniform);
        if constexpr (kUnknownIsFree) {
          const __m128i is_unknown = _mm_cmpeq_epi8(v, unknown);
          open = _mm_or_si128(open, is_unknown);
          if (uniform_cost == kFreeCost) same = _mm_or_si128(same, is_unknown);
        }
        if constexpr (kCheckUniform)
          bad = _mm_or_si128(bad, _mm_andnot_si128(same, open));
        bits |= static_cast<uint64_t>(
                    static_cast<uint16_t>(_mm_movemask_epi8(open)))
                << (16 * q);
      }
      if (count < 64) bits &= (uint64_t{1} << count) - 1;
      StoreWord(bits, words[k], dirty_row[k]);
    }
  }
  return _mm_movemask_epi8(bad) == 0;
}
#endif  // __SSE2__

#if defined(PATHD_BIT_GRID_AVX512)
template <bool kUnknownIsFree, bool kCheckUniform>
__attribute__((target("avx512f,avx512bw"))) bool PackRowsAvx512(
    const Grid& grid, uint8_t uniform_cost, BitLines& rows, uint8_t* dirty) {
  const int32_t w = grid.width();
  const int32_t tiles_x = (w + 63) / 64;
  const __m512i max_traversable =
      _mm512_set1_epi8(static_cast<char>(kMaxTraversableCost));
  const __m512i unknown = _mm512_set1_epi8(static_cast<char>(kUnknownCost));
  const __m512i uniform = _mm512_set1_epi8(static_cast<char>(uniform_cost));
  const int32_t tail = w - 64 * (tiles_x - 1);
  const __mmask64 tail_mask =
      tail == 64 ? ~__mmask64{0} : (__mmask64{1} << tail) - 1;
  __mmask64 bad = 0;
  for (int32_t y = 0; y < grid.height(); ++y) {
    const uint8_t* row = grid.cells().data() + static_cast<size_t>(y) * w;
    uint64_t* words = rows.MutableLine(y) + 1;
    uint8_t* dirty_row = dirty + static_cast<size_t>(y / 64) * tiles_x;
    for (int32_t k = 0; k < tiles_x; ++k) {
      // A masked load does not touch (or fault on) the bytes it leaves out.
      const __mmask64 m = k + 1 < tiles_x ? ~__mmask64{0} : tail_mask;
      const __m512i v = _mm512_maskz_loadu_epi8(m, row + 64 * k);
      __mmask64 open = _mm512_mask_cmple_epu8_mask(m, v, max_traversable);
      __mmask64 same = _mm512_cmpeq_epi8_mask(v, uniform);
      if constexpr (kUnknownIsFree) {
        const __mmask64 is_unknown = _mm512_mask_cmpeq_epi8_mask(m, v, unknown);
        open |= is_unknown;
        if (uniform_cost == kFreeCost) same |= is_unknown;
      }
      if constexpr (kCheckUniform) bad |= open & ~same;
      StoreWord(open, words[k], dirty_row[k]);
    }
  }
  return bad == 0;
}
#endif  // PATHD_BIT_GRID_AVX512

}  // namespace

bool PackIsaAvailable(PackIsa isa) {
  switch (isa) {
    case PackIsa::kScalar:
      return true;
    case PackIsa::kSse2:
#if defined(__SSE2__)
      return true;
#else
      return false;
#endif
    case PackIsa::kAvx512:
#if defined(PATHD_BIT_GRID_AVX512)
      // Idempotent; needed when this runs before static constructors have.
      __builtin_cpu_init();
      // Also checks that the OS saves the AVX-512 registers.
      return __builtin_cpu_supports("avx512f") &&
             __builtin_cpu_supports("avx512bw");
#else
      return false;
#endif
  }
  return false;
}

PackIsa BestPackIsa() {
  for (PackIsa isa : {PackIsa::kAvx512, PackIsa::kSse2}) {
    if (PackIsaAvailable(isa)) return isa;
  }
  return PackIsa::kScalar;
}

bool PackRows(PackIsa isa, const Grid& grid, const PackRule& rule,
              BitLines& rows, std::vector<uint8_t>& dirty) {
  const uint8_t u = rule.uniform_cost;
  return WithRuleFlags(rule, [&](auto unknown_is_free, auto check_uniform) {
    constexpr bool kUnknown = decltype(unknown_is_free)::value;
    constexpr bool kCheck = decltype(check_uniform)::value;
    switch (isa) {
#if defined(PATHD_BIT_GRID_AVX512)
      case PackIsa::kAvx512:
        return PackRowsAvx512<kUnknown, kCheck>(grid, u, rows, dirty.data());
#endif
#if defined(__SSE2__)
      case PackIsa::kSse2:
        return PackRowsSse2<kUnknown, kCheck>(grid, u, rows, dirty.data());
#endif
      default:
        return PackRowsScalar<kUnknown, kCheck>(grid, u, rows, dirty.data());
    }
  });
}

}  // namespace pathd::internal
