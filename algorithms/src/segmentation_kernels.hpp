#pragma once
/// @file What the segmentation paths share (private to algorithms/): the frame, the scalar
/// classification of a stretch of a row into class bytes (the NEON path's row buffer and the AVX2
/// path's row tails), and the SIMD entry points, which exist only where their guard holds.

#include <cstddef>
#include <cstdint>
#include <cstring>

#if (defined(__x86_64__) || defined(_M_X64)) && (defined(__GNUC__) || defined(__clang__)) && \
    !defined(HARMOLOC_SEGMENT_SCALAR_ONLY)
#define HARMOLOC_SEGMENT_AVX2 1
#endif
#if defined(__ARM_NEON) && !defined(HARMOLOC_SEGMENT_SCALAR_ONLY)
#define HARMOLOC_SEGMENT_NEON 1
#endif

namespace harmoloc::algorithms::detail {

struct Image {
  const std::uint8_t* data;
  std::uint32_t width_px, height_px, stride_bytes;
  const std::uint8_t* row(std::uint32_t y) const {
    return data + static_cast<std::size_t>(y) * stride_bytes;
  }
};

/// Pixels (or their columns or rows) summed per board; 64-bit while counting, so no frame size
/// overflows a partial sum.
using BoardTotals = std::uint64_t[8];

/// 4 bytes at @p p as a little-endian number (one unaligned load where the target allows it).
inline std::uint32_t load_le32(const std::uint8_t* p) {
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
  std::uint32_t v;
#if defined(__GNUC__) || defined(__clang__)
  __builtin_memcpy(&v, p, sizeof v);  // a load even with -ffreestanding, where memcpy is a call
#else
  std::memcpy(&v, p, sizeof v);
#endif
  return v;
#else
  return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8U) |
         (static_cast<std::uint32_t>(p[2]) << 16U) | (static_cast<std::uint32_t>(p[3]) << 24U);
#endif
}

/// ColourTable::index of the RGB24 pixel at @p p, when 4 bytes from @p p are inside the row.
inline std::uint32_t rgb_index4(const std::uint8_t* p) {
  return load_le32(p) & 0xFFFFFFU;
}
/// The same for a row's last pixel, whose fourth byte may lie past the frame.
inline std::uint32_t rgb_index3(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8U) |
         (static_cast<std::uint32_t>(p[2]) << 16U);
}

/// YuyvTable::index of a pair's two pixels from its 4 bytes Y0 U Y1 V read as one number.
inline std::uint32_t yuyv_index_odd(std::uint32_t pair) {
  return pair >> 8U;  // U | Y1 << 8 | V << 16
}
inline std::uint32_t yuyv_index_even(std::uint32_t pair) {
  return ((pair >> 8U) & 0xFF00FFU) | ((pair & 0xFFU) << 8U);
}

/// Class bytes of pixels [x0, x0 + n) of an RGB24 row into @p out.
inline void classify_rgb24_row(const std::uint8_t* row, std::uint32_t width_px, std::uint32_t x0,
                               std::uint32_t n, const std::uint8_t* table, std::uint8_t* out) {
  if (n == 0) return;
  const std::uint8_t* p = row + static_cast<std::size_t>(x0) * 3U;
  const std::uint32_t wide = x0 + n < width_px ? n : n - 1U;
  std::uint8_t* const end4 = out + (wide & ~3U);
  std::uint8_t* const end = out + wide;
  for (; out != end4; out += 4, p += 12) {
    out[0] = table[rgb_index4(p)];
    out[1] = table[rgb_index4(p + 3)];
    out[2] = table[rgb_index4(p + 6)];
    out[3] = table[rgb_index4(p + 9)];
  }
  for (; out != end; ++out, p += 3) *out = table[rgb_index4(p)];
  if (wide < n) *out = table[rgb_index3(p)];
}

/// Class bytes of pixels [x0, x0 + n) of a YUYV row into @p out; @p x0 even. A pair's 4 bytes
/// are all in the row even when its second pixel is past width_px (odd widths).
inline void classify_yuyv_row(const std::uint8_t* row, std::uint32_t x0, std::uint32_t n,
                              const std::uint8_t* table, std::uint8_t* out) {
  const std::uint8_t* p = row + static_cast<std::size_t>(x0) * 2U;
  std::uint8_t* const end4 = out + (n & ~3U);
  std::uint8_t* const end2 = out + (n & ~1U);
  for (; out != end4; out += 4, p += 8) {
    const std::uint32_t a = load_le32(p);
    const std::uint32_t b = load_le32(p + 4);
    out[0] = table[yuyv_index_even(a)];
    out[1] = table[yuyv_index_odd(a)];
    out[2] = table[yuyv_index_even(b)];
    out[3] = table[yuyv_index_odd(b)];
  }
  if (out != end2) {
    const std::uint32_t a = load_le32(p);
    out[0] = table[yuyv_index_even(a)];
    out[1] = table[yuyv_index_odd(a)];
    out += 2;
    p += 4;
  }
  if (n & 1U) *out = table[yuyv_index_even(load_le32(p))];
}

#if HARMOLOC_SEGMENT_AVX2
/// AVX2 and POPCNT (every AVX2 CPU has both; the column sums use POPCNT).
bool cpu_has_avx2();
/// Adds each board's pixels of the whole frame to @p totals, the sum of their columns to
/// @p column_sums and of their rows to @p row_sums (boards 1..8).
void count_rgb24_avx2(const Image& image, const std::uint8_t* table, std::size_t boards,
                      BoardTotals& totals, BoardTotals& column_sums, BoardTotals& row_sums);
void count_yuyv_avx2(const Image& image, const std::uint8_t* table, std::size_t boards,
                     BoardTotals& totals, BoardTotals& column_sums, BoardTotals& row_sums);
#endif
#if HARMOLOC_SEGMENT_NEON
void count_rgb24_neon(const Image& image, const std::uint8_t* table, std::size_t boards,
                      BoardTotals& totals, BoardTotals& column_sums, BoardTotals& row_sums);
void count_yuyv_neon(const Image& image, const std::uint8_t* table, std::size_t boards,
                     BoardTotals& totals, BoardTotals& column_sums, BoardTotals& row_sums);
#endif

}  // namespace harmoloc::algorithms::detail
