// The AVX2 segmentation path (x86-64, chosen at run time when the CPU has AVX2; the rest of the
// build stays baseline x86-64). Per 32 pixels: the table indices built with two shuffles per 8
// pixels, four vpgatherdd (8 table loads each), three blends into 32 class bytes, and the class
// bits counted in 4-bit counters. A block with any board pixel also adds each board's columns,
// from a movemask and five POPCNTs a board, and their rows from the same count. Areas, columns and
// rows are identical to the scalar path (tested).
#include "segmentation_kernels.hpp"

#if HARMOLOC_SEGMENT_AVX2

#include <immintrin.h>

#define HARMOLOC_AVX2 __attribute__((target("avx2,popcnt")))
#define HARMOLOC_AVX2_INLINE __attribute__((target("avx2,popcnt"), always_inline)) inline

namespace harmoloc::algorithms::detail {

bool cpu_has_avx2() {
  // Safe before static constructors ran; libgcc's check includes the OS saving YMM registers.
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx2") != 0 && __builtin_cpu_supports("popcnt") != 0;
}

namespace {

constexpr std::uint32_t kBlock = 32;  // pixels a step: 32 class bytes, one register
// A 4-bit counter holds 15: the counters are emptied into 64-bit sums every 15 blocks.
constexpr std::uint32_t kBlocksPerFlush = 15;

// Counts the class bits of 32 pixels: bit j and bit j + 4 of every byte land in the two nibbles
// of counter j (masked with 0x11), so four adds count all eight boards. The four counters are
// separate variables, not an array, so that they stay in registers.
template <int kBoards>
struct Counters {
  static constexpr int kLow = kBoards < 4 ? kBoards : 4;
  static constexpr int kHigh = kBoards > 4 ? kBoards - 4 : 0;
  __m256i n0, n1, n2, n3;
};

template <int kBoards>
HARMOLOC_AVX2_INLINE void add(Counters<kBoards>& c, __m256i classes, __m256i bits) {
  constexpr int kLow = Counters<kBoards>::kLow;
  // 16-bit shifts: bits crossing into the neighbouring byte are masked off by 0x11.
  c.n0 = _mm256_add_epi8(c.n0, _mm256_and_si256(classes, bits));
  if constexpr (kLow > 1)
    c.n1 = _mm256_add_epi8(c.n1, _mm256_and_si256(_mm256_srli_epi16(classes, 1), bits));
  if constexpr (kLow > 2)
    c.n2 = _mm256_add_epi8(c.n2, _mm256_and_si256(_mm256_srli_epi16(classes, 2), bits));
  if constexpr (kLow > 3)
    c.n3 = _mm256_add_epi8(c.n3, _mm256_and_si256(_mm256_srli_epi16(classes, 3), bits));
}

// Adds counter @p n's boards j (low nibbles) and j + 4 (high nibbles) to the 64-bit sums.
template <int kBoards, int j>
HARMOLOC_AVX2_INLINE void flush_one(__m256i& n, __m256i (&sums)[8]) {
  if constexpr (j < Counters<kBoards>::kLow) {
    const __m256i low4 = _mm256_set1_epi8(0x0F);
    const __m256i zero = _mm256_setzero_si256();
    sums[j] = _mm256_add_epi64(sums[j], _mm256_sad_epu8(_mm256_and_si256(n, low4), zero));
    if constexpr (j < Counters<kBoards>::kHigh) {
      const __m256i high = _mm256_and_si256(_mm256_srli_epi16(n, 4), low4);
      sums[j + 4] = _mm256_add_epi64(sums[j + 4], _mm256_sad_epu8(high, zero));
    }
    n = zero;
  }
}

template <int kBoards>
HARMOLOC_AVX2_INLINE void flush(Counters<kBoards>& c, __m256i (&sums)[8]) {
  flush_one<kBoards, 0>(c.n0, sums);
  flush_one<kBoards, 1>(c.n1, sums);
  flush_one<kBoards, 2>(c.n2, sums);
  flush_one<kBoards, 3>(c.n3, sums);
}

// The class bytes of 32 pixels whose table indices are @p i0..i3. Each gather reads 4 table bytes
// from a base 0..3 bytes before the entry, so the entry lands in byte 0..3 of each 32-bit lane;
// two word blends and one byte blend then merge the four without masking.
HARMOLOC_AVX2_INLINE __m256i gather_classes(const std::uint8_t* table, __m256i i0, __m256i i1,
                                            __m256i i2, __m256i i3, __m256i odd_bytes) {
  const __m256i g0 = _mm256_i32gather_epi32(reinterpret_cast<const int*>(table), i0, 1);
  const __m256i g1 = _mm256_i32gather_epi32(reinterpret_cast<const int*>(table - 1), i1, 1);
  const __m256i g2 = _mm256_i32gather_epi32(reinterpret_cast<const int*>(table - 2), i2, 1);
  const __m256i g3 = _mm256_i32gather_epi32(reinterpret_cast<const int*>(table - 3), i3, 1);
  const __m256i even = _mm256_blend_epi16(g0, g2, 0xAA);  // entries in bytes 0 and 2
  const __m256i odd = _mm256_blend_epi16(g1, g3, 0xAA);   // entries in bytes 1 and 3
  return _mm256_blendv_epi8(even, odd, odd_bytes);
}

// Where the pixels of a block sit among its 32 class bytes. gather_classes puts pixel 8g + j
// (gather g, dword j) in byte 4j + g; a row's tail, classified one by one, is in pixel order.
enum class ByteOrder { kGathered, kPixels };

// Adds the columns of each board's pixels among the 32 class bytes of the block at column @p x0,
// and their row @p y once per pixel.
// Most blocks of a frame hold no board at all and cost one test. Bit k of every byte, shifted to
// bit 7 (16-bit shifts: the bits pulled in from below come from the same byte), is movemasked
// into a 32-bit set of bytes; the sum of their pixels' places in the block is taken bit by bit of
// the byte number, one POPCNT for each of its five bits, weighted by what that bit is worth.
template <int kBoards, ByteOrder kOrder>
HARMOLOC_AVX2_INLINE void add_places(__m256i classes, std::uint32_t x0, std::uint32_t y,
                                     std::uint64_t (&column_sums)[8],
                                     std::uint64_t (&row_sums)[8]) {
  if (_mm256_testz_si256(classes, classes)) return;
  // log2 of the place worth of byte-number bits 0..4: 1, 2, 4, 8, 16 in pixel order; in gathered
  // order bits 0-1 (g) are worth 8 and 16 and bits 2-4 (j) 1, 2 and 4.
  constexpr bool kG = kOrder == ByteOrder::kGathered;
  constexpr unsigned kShift[5] = {kG ? 3U : 0U, kG ? 4U : 1U, kG ? 0U : 2U, kG ? 1U : 3U,
                                  kG ? 2U : 4U};
  // The boards present in the block (the OR of its 32 bytes): a block at a board's edge holds one
  // or two of them, so only those are gone through.
  const __m128i half =
      _mm_or_si128(_mm256_castsi256_si128(classes), _mm256_extracti128_si256(classes, 1));
  auto folded = static_cast<std::uint64_t>(
      _mm_cvtsi128_si64(_mm_or_si128(half, _mm_unpackhi_epi64(half, half))));
  folded |= folded >> 32U;
  folded |= folded >> 16U;
  folded |= folded >> 8U;
  auto present = static_cast<std::uint32_t>(folded & ((1U << kBoards) - 1U));
  while (present != 0U) {
    const int k = __builtin_ctz(present);
    present &= present - 1U;
    const auto set = static_cast<std::uint32_t>(
        _mm256_movemask_epi8(_mm256_sll_epi16(classes, _mm_cvtsi32_si128(7 - k))));
    const auto count = [set](std::uint32_t bits) {
      return static_cast<std::uint32_t>(__builtin_popcount(set & bits));
    };
    const std::uint32_t places =
        (count(0xAAAAAAAAU) << kShift[0]) + (count(0xCCCCCCCCU) << kShift[1]) +
        (count(0xF0F0F0F0U) << kShift[2]) + (count(0xFF00FF00U) << kShift[3]) +
        (count(0xFFFF0000U) << kShift[4]);
    const std::uint64_t pixels = count(0xFFFFFFFFU);
    column_sums[k] += x0 * pixels + places;
    row_sums[k] += y * pixels;
  }
}

HARMOLOC_AVX2_INLINE __m256i load256(const std::uint8_t* p) {
  return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p));
}

// RGB24: 8 pixels are 24 bytes. A dword permute puts pixels 0..3 in the low 128-bit lane and
// 4..7 in the high one, then a byte shuffle widens each pixel to R | G << 8 | B << 16. The last
// 8 pixels of a block are loaded from 8 bytes earlier, so no load reaches past the block.
struct Rgb24Layout {
  __m256i perm, perm_last, shuffle;
  static constexpr std::uint32_t kBytesPerBlock = 96;

  HARMOLOC_AVX2_INLINE static Rgb24Layout make() {
    return {_mm256_setr_epi32(0, 1, 2, 3, 3, 4, 5, 6), _mm256_setr_epi32(2, 3, 4, 5, 5, 6, 7, 7),
            _mm256_setr_epi8(0, 1, 2, -128, 3, 4, 5, -128, 6, 7, 8, -128, 9, 10, 11, -128, 0, 1, 2,
                             -128, 3, 4, 5, -128, 6, 7, 8, -128, 9, 10, 11, -128)};
  }
  HARMOLOC_AVX2_INLINE __m256i indices(const std::uint8_t* p, __m256i permutation) const {
    return _mm256_shuffle_epi8(_mm256_permutevar8x32_epi32(load256(p), permutation), shuffle);
  }
  HARMOLOC_AVX2_INLINE __m256i classes(const std::uint8_t* block, const std::uint8_t* table,
                                       __m256i odd_bytes) const {
    return gather_classes(table, indices(block, perm), indices(block + 24, perm),
                          indices(block + 48, perm), indices(block + 64, perm_last), odd_bytes);
  }
  static void tail(const std::uint8_t* row, std::uint32_t width_px, std::uint32_t x,
                   std::uint32_t n, const std::uint8_t* table, std::uint8_t* out) {
    classify_rgb24_row(row, width_px, x, n, table, out);
  }
};

// YUYV: 8 pixels are 16 bytes (4 pairs Y0 U Y1 V), copied to both lanes; the shuffle builds
// U | Y << 8 | V << 16 for pixels 0..3 in the low lane and 4..7 in the high one.
struct YuyvLayout {
  __m256i shuffle;
  static constexpr std::uint32_t kBytesPerBlock = 64;

  HARMOLOC_AVX2_INLINE static YuyvLayout make() {
    return {_mm256_setr_epi8(1, 0, 3, -128, 1, 2, 3, -128, 5, 4, 7, -128, 5, 6, 7, -128, 9, 8, 11,
                             -128, 9, 10, 11, -128, 13, 12, 15, -128, 13, 14, 15, -128)};
  }
  HARMOLOC_AVX2_INLINE __m256i indices(const std::uint8_t* p) const {
    const __m256i pairs =
        _mm256_broadcastsi128_si256(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p)));
    return _mm256_shuffle_epi8(pairs, shuffle);
  }
  HARMOLOC_AVX2_INLINE __m256i classes(const std::uint8_t* block, const std::uint8_t* table,
                                       __m256i odd_bytes) const {
    return gather_classes(table, indices(block), indices(block + 16), indices(block + 32),
                          indices(block + 48), odd_bytes);
  }
  static void tail(const std::uint8_t* row, std::uint32_t, std::uint32_t x, std::uint32_t n,
                   const std::uint8_t* table, std::uint8_t* out) {
    classify_yuyv_row(row, x, n, table, out);
  }
};

template <typename Layout, int kBoards>
HARMOLOC_AVX2 void count_frame(const Image& im, const std::uint8_t* table, BoardTotals& totals,
                               BoardTotals& column_sums, BoardTotals& row_sums) {
  const Layout layout = Layout::make();
  const __m256i odd_bytes = _mm256_set1_epi16(static_cast<short>(0xFF00));
  const __m256i bits = _mm256_set1_epi8(0x11);
  Counters<kBoards> c{_mm256_setzero_si256(), _mm256_setzero_si256(), _mm256_setzero_si256(),
                      _mm256_setzero_si256()};
  __m256i sums[8];
  for (__m256i& s : sums) s = _mm256_setzero_si256();
  std::uint32_t pending = 0;  // blocks counted since the last flush
  for (std::uint32_t y = 0; y < im.height_px; ++y) {
    const std::uint8_t* row = im.row(y);
    std::uint32_t x = 0;
    while (im.width_px - x >= kBlock) {
      const std::uint32_t blocks = (im.width_px - x) / kBlock;
      const std::uint32_t n =
          blocks < kBlocksPerFlush - pending ? blocks : kBlocksPerFlush - pending;
      const std::uint8_t* block =
          row + static_cast<std::size_t>(x) * (Layout::kBytesPerBlock / kBlock);
      const std::uint8_t* const end = block + static_cast<std::size_t>(n) * Layout::kBytesPerBlock;
      for (std::uint32_t bx = x; block != end; block += Layout::kBytesPerBlock, bx += kBlock) {
        const __m256i classes = layout.classes(block, table, odd_bytes);
        add(c, classes, bits);
        add_places<kBoards, ByteOrder::kGathered>(classes, bx, y, column_sums, row_sums);
      }
      x += n * kBlock;
      pending += n;
      if (pending == kBlocksPerFlush) {
        flush(c, sums);
        pending = 0;
      }
    }
    if (x < im.width_px) {
      // The row's last pixels, classified one by one; the unused bytes stay 0, no board's class.
      alignas(32) std::uint8_t rest[kBlock] = {};
      Layout::tail(row, im.width_px, x, im.width_px - x, table, rest);
      const __m256i classes = load256(rest);
      add(c, classes, bits);
      add_places<kBoards, ByteOrder::kPixels>(classes, x, y, column_sums, row_sums);
      if (++pending == kBlocksPerFlush) {
        flush(c, sums);
        pending = 0;
      }
    }
  }
  flush(c, sums);
  for (int k = 0; k < kBoards; ++k) {
    alignas(32) std::uint64_t lanes[4];
    _mm256_store_si256(reinterpret_cast<__m256i*>(lanes), sums[k]);
    totals[k] += lanes[0] + lanes[1] + lanes[2] + lanes[3];
  }
}

template <typename Layout>
void count_boards(const Image& im, const std::uint8_t* table, std::size_t boards,
                  BoardTotals& totals, BoardTotals& column_sums, BoardTotals& row_sums) {
  switch (boards) {
    case 1:
      return count_frame<Layout, 1>(im, table, totals, column_sums, row_sums);
    case 2:
      return count_frame<Layout, 2>(im, table, totals, column_sums, row_sums);
    case 3:
      return count_frame<Layout, 3>(im, table, totals, column_sums, row_sums);
    case 4:
      return count_frame<Layout, 4>(im, table, totals, column_sums, row_sums);
    case 5:
      return count_frame<Layout, 5>(im, table, totals, column_sums, row_sums);
    case 6:
      return count_frame<Layout, 6>(im, table, totals, column_sums, row_sums);
    case 7:
      return count_frame<Layout, 7>(im, table, totals, column_sums, row_sums);
    default:
      return count_frame<Layout, 8>(im, table, totals, column_sums, row_sums);
  }
}

}  // namespace

void count_rgb24_avx2(const Image& image, const std::uint8_t* table, std::size_t boards,
                      BoardTotals& totals, BoardTotals& column_sums, BoardTotals& row_sums) {
  count_boards<Rgb24Layout>(image, table, boards, totals, column_sums, row_sums);
}

void count_yuyv_avx2(const Image& image, const std::uint8_t* table, std::size_t boards,
                     BoardTotals& totals, BoardTotals& column_sums, BoardTotals& row_sums) {
  count_boards<YuyvLayout>(image, table, boards, totals, column_sums, row_sums);
}

}  // namespace harmoloc::algorithms::detail

#endif  // HARMOLOC_SEGMENT_AVX2
