// The NEON segmentation path (AArch64, and ARMv7 built with NEON). NEON has no gather, so the
// table loads stay scalar, into a row buffer of class bytes; the buffer is then counted 16 bytes
// at a time (one bit test and one subtract per board), which replaces the scalar path's
// load-add-store of a histogram counter per pixel. The columns are summed beside the counts: the
// same bit test, masked with the byte's place in the 256-pixel chunk (which fits a byte), is
// added pairwise into 16-bit lanes; the rows are the chunk's pixels times its row. Areas, columns
// and rows are identical to the scalar path (tested under qemu-aarch64 and qemu-arm).
#include "segmentation_kernels.hpp"

#if HARMOLOC_SEGMENT_NEON

#include <arm_neon.h>

namespace harmoloc::algorithms::detail {

namespace {

constexpr std::uint32_t kChunk = 256;  // pixels classified into the buffer at a time
constexpr std::uint32_t kLanes = 16;
// An 8-bit lane counts to 255: the counters are emptied before more vectors than that.
constexpr std::uint32_t kVectorsPerFlush = 255;

inline std::uint64_t sum_lanes(uint8x16_t v) {
#if defined(__aarch64__)
  return vaddlvq_u8(v);
#else
  const uint64x2_t s = vpaddlq_u32(vpaddlq_u16(vpaddlq_u8(v)));
  return vgetq_lane_u64(s, 0) + vgetq_lane_u64(s, 1);
#endif
}

inline std::uint64_t sum_lanes(uint16x8_t v) {
#if defined(__aarch64__)
  return vaddlvq_u16(v);
#else
  const uint64x2_t s = vpaddlq_u32(vpaddlq_u16(v));
  return vgetq_lane_u64(s, 0) + vgetq_lane_u64(s, 1);
#endif
}

inline bool any_set(uint8x16_t v) {
#if defined(__aarch64__)
  return vmaxvq_u8(v) != 0;
#else
  const uint64x2_t w = vreinterpretq_u64_u8(v);
  return (vgetq_lane_u64(w, 0) | vgetq_lane_u64(w, 1)) != 0U;
#endif
}

struct Rgb24Rows {
  static void classify(const std::uint8_t* row, std::uint32_t width_px, std::uint32_t x,
                       std::uint32_t n, const std::uint8_t* table, std::uint8_t* out) {
    classify_rgb24_row(row, width_px, x, n, table, out);
  }
};

struct YuyvRows {
  static void classify(const std::uint8_t* row, std::uint32_t, std::uint32_t x, std::uint32_t n,
                       const std::uint8_t* table, std::uint8_t* out) {
    classify_yuyv_row(row, x, n, table, out);
  }
};

template <typename Rows, int kBoards>
void count_frame(const Image& im, const std::uint8_t* table, BoardTotals& totals,
                 BoardTotals& column_sums, BoardTotals& row_sums) {
  static_assert(kChunk <= 256, "a pixel's place in the chunk must fit a byte");
  alignas(16) static constexpr std::uint8_t kPlaces[kLanes] = {0, 1, 2,  3,  4,  5,  6,  7,
                                                               8, 9, 10, 11, 12, 13, 14, 15};
  alignas(16) std::uint8_t classes[kChunk];
  uint8x16_t bit[kBoards];
  uint8x16_t count[kBoards];
  for (int k = 0; k < kBoards; ++k) {
    bit[k] = vdupq_n_u8(static_cast<std::uint8_t>(1U << k));
    count[k] = vdupq_n_u8(0);
  }
  std::uint32_t pending = 0;  // vectors counted since the last flush
  const auto flush = [&] {
    for (int k = 0; k < kBoards; ++k) {
      totals[k] += sum_lanes(count[k]);
      count[k] = vdupq_n_u8(0);
    }
    pending = 0;
  };
  for (std::uint32_t y = 0; y < im.height_px; ++y) {
    const std::uint8_t* row = im.row(y);
    for (std::uint32_t x = 0; x < im.width_px;) {
      const std::uint32_t n = im.width_px - x < kChunk ? im.width_px - x : kChunk;
      Rows::classify(row, im.width_px, x, n, table, classes);
      const std::uint32_t vectors = (n + kLanes - 1U) / kLanes;
      // Bytes past the row's end count as class 0: no board.
      for (std::uint32_t i = n; i < vectors * kLanes; ++i) classes[i] = 0;
      if (pending + vectors > kVectorsPerFlush) flush();
      // The chunk's pixels per board are the change of the 8-bit counters over it (at most 16 a
      // lane, so the difference modulo 256 is exact); they carry the chunk's first column.
      uint8x16_t before[kBoards];
      uint16x8_t places[kBoards];
      for (int k = 0; k < kBoards; ++k) {
        before[k] = count[k];
        places[k] = vdupq_n_u16(0);
      }
      uint8x16_t place = vld1q_u8(kPlaces);
      const uint8x16_t step = vdupq_n_u8(static_cast<std::uint8_t>(kLanes));
      for (std::uint32_t v = 0; v < vectors; ++v, place = vaddq_u8(place, step)) {
        const uint8x16_t c = vld1q_u8(classes + v * kLanes);
        // Most of a frame is no board: such vectors add nothing to any count or column.
        if (!any_set(c)) continue;
        for (int k = 0; k < kBoards; ++k) {
          // vtst gives 0xFF (-1) where the board's bit is set: subtracting it adds 1.
          const uint8x16_t in = vtstq_u8(c, bit[k]);
          count[k] = vsubq_u8(count[k], in);
          places[k] = vpadalq_u8(places[k], vandq_u8(in, place));
        }
      }
      for (int k = 0; k < kBoards; ++k) {
        const std::uint64_t pixels = sum_lanes(vsubq_u8(count[k], before[k]));
        column_sums[k] += pixels * x + sum_lanes(places[k]);
        row_sums[k] += pixels * y;
      }
      pending += vectors;
      x += n;
    }
  }
  flush();
}

template <typename Rows>
void count_boards(const Image& im, const std::uint8_t* table, std::size_t boards,
                  BoardTotals& totals, BoardTotals& column_sums, BoardTotals& row_sums) {
  switch (boards) {
    case 1:
      return count_frame<Rows, 1>(im, table, totals, column_sums, row_sums);
    case 2:
      return count_frame<Rows, 2>(im, table, totals, column_sums, row_sums);
    case 3:
      return count_frame<Rows, 3>(im, table, totals, column_sums, row_sums);
    case 4:
      return count_frame<Rows, 4>(im, table, totals, column_sums, row_sums);
    case 5:
      return count_frame<Rows, 5>(im, table, totals, column_sums, row_sums);
    case 6:
      return count_frame<Rows, 6>(im, table, totals, column_sums, row_sums);
    case 7:
      return count_frame<Rows, 7>(im, table, totals, column_sums, row_sums);
    default:
      return count_frame<Rows, 8>(im, table, totals, column_sums, row_sums);
  }
}

}  // namespace

void count_rgb24_neon(const Image& image, const std::uint8_t* table, std::size_t boards,
                      BoardTotals& totals, BoardTotals& column_sums, BoardTotals& row_sums) {
  count_boards<Rgb24Rows>(image, table, boards, totals, column_sums, row_sums);
}

void count_yuyv_neon(const Image& image, const std::uint8_t* table, std::size_t boards,
                     BoardTotals& totals, BoardTotals& column_sums, BoardTotals& row_sums) {
  count_boards<YuyvRows>(image, table, boards, totals, column_sums, row_sums);
}

}  // namespace harmoloc::algorithms::detail

#endif  // HARMOLOC_SEGMENT_NEON
