#include "harmoloc/algorithms/segmentation.hpp"

#include <algorithm>
#include <cmath>

#include "segmentation_kernels.hpp"

namespace harmoloc::algorithms {

bool operator==(const ColourThreshold& a, const ColourThreshold& b) {
  return a.hue_min_deg == b.hue_min_deg && a.hue_max_deg == b.hue_max_deg &&
         a.saturation_min == b.saturation_min && a.value_min == b.value_min &&
         a.value_max == b.value_max;
}

bool operator==(const ThresholdSet& a, const ThresholdSet& b) {
  if (a.count != b.count) return false;
  for (std::size_t i = 0; i < a.count; ++i) {
    if (!(a.boards[i] == b.boards[i])) return false;
  }
  return true;
}

BoardClassifier::BoardClassifier() {
  // OpenCV's division tables for 8-bit HSV (rounded to nearest, as its saturate_cast does).
  for (int i = 1; i < 256; ++i) {
    sdiv_[static_cast<std::size_t>(i)] =
        static_cast<std::int32_t>(std::lrint((255 << kShift) / (1.0 * i)));
    hdiv_[static_cast<std::size_t>(i)] =
        static_cast<std::int32_t>(std::lrint((180 << kShift) / (6.0 * i)));
  }
}

void BoardClassifier::build(const ThresholdSet& thresholds) {
  hue_.fill(0);
  sat_.fill(0);
  val_.fill(0);
  boards_ = std::min(thresholds.count, kMaxBoards);
  for (std::size_t k = 0; k < boards_; ++k) {
    const ColourThreshold& t = thresholds.boards[k];
    const auto bit = static_cast<std::uint8_t>(1U << k);
    const int lo = static_cast<int>(std::ceil(t.hue_min_deg / 2.0F));
    const int hi = static_cast<int>(std::floor(t.hue_max_deg / 2.0F));
    for (int h = 0; h < 180; ++h) {
      const bool in = t.hue_min_deg <= t.hue_max_deg ? (h >= lo && h <= hi) : (h >= lo || h <= hi);
      if (in) hue_[static_cast<std::size_t>(h)] |= bit;
    }
    for (int v = 0; v < 256; ++v) {
      if (v >= t.saturation_min) sat_[static_cast<std::size_t>(v)] |= bit;
      if (v >= t.value_min && v <= t.value_max) val_[static_cast<std::size_t>(v)] |= bit;
    }
  }
}

namespace {

// Pixels (and their columns) are tallied by their board mask (256 possible) and only expanded to
// per-board figures once per frame, so the per-pixel work does not grow with the number of boards.
using MaskCounts = std::array<std::uint32_t, 256>;
using MaskColumns = std::array<std::uint64_t, 256>;

void counts_from_masks(const MaskCounts& by_mask, const MaskColumns& columns_by_mask,
                       const MaskColumns& rows_by_mask, std::size_t boards, AreaVector& areas) {
  areas.pixels.fill(0U);
  areas.column_sum.fill(0U);
  areas.row_sum.fill(0U);
  areas.count = boards;
  for (std::size_t mask = 1; mask < 256; ++mask) {
    if (by_mask[mask] == 0) continue;
    for (std::size_t k = 0; k < boards; ++k) {
      if ((mask >> k) & 1U) {
        areas.pixels[k] += by_mask[mask];
        areas.column_sum[k] += columns_by_mask[mask];
        areas.row_sum[k] += rows_by_mask[mask];
      }
    }
  }
}

void counts_from_totals(const detail::BoardTotals& totals, const detail::BoardTotals& column_sums,
                        const detail::BoardTotals& row_sums, std::size_t boards,
                        AreaVector& areas) {
  areas.pixels.fill(0U);
  areas.column_sum.fill(0U);
  areas.row_sum.fill(0U);
  areas.count = boards;
  for (std::size_t k = 0; k < boards; ++k) {
    areas.pixels[k] = static_cast<std::uint32_t>(totals[k]);
    areas.column_sum[k] = column_sums[k];
    areas.row_sum[k] = row_sums[k];
  }
}

// The boards' pixels in the first and last column, which every path leaves to this one scalar
// pass (2 pixels a row). @p class_of(row, x) is the class byte of pixel x of the row.
template <typename ClassOf>
void measure_sides(const detail::Image& im, std::size_t boards, ClassOf class_of,
                   AreaVector& areas) {
  areas.side_pixels.fill(0U);
  areas.width_px = im.width_px;
  areas.height_px = im.height_px;
  if (im.width_px == 0) return;
  const std::uint32_t last = im.width_px - 1U;
  for (std::uint32_t y = 0; y < im.height_px; ++y) {
    const std::uint8_t* row = im.row(y);
    const std::uint32_t left = class_of(row, 0U);
    const std::uint32_t right = last > 0U ? class_of(row, last) : 0U;
    if ((left | right) == 0U) continue;  // most rows: no board on either side
    for (std::size_t k = 0; k < boards; ++k)
      areas.side_pixels[k] += ((left >> k) & 1U) + ((right >> k) & 1U);
  }
}

inline std::uint8_t clamp_u8(int v) {
  return static_cast<std::uint8_t>(std::clamp(v, 0, 255));
}

// OpenCV's COLOR_YUV2RGB_YUYV in its 20-bit fixed point (BT.601 limited range), split into the
// chroma terms a pixel pair shares and the luma term each pixel has.
struct ChromaTerms {
  int rv, guv, bu;
};
inline ChromaTerms chroma_terms(int u, int v) {
  const int du = u - 128;
  const int dv = v - 128;
  return {(1 << 19) + 1673527 * dv, (1 << 19) - 852492 * dv - 409993 * du,
          (1 << 19) + 2116026 * du};
}
inline Rgb8 decode_yuv(int y, const ChromaTerms& c) {
  const int luma = std::max(0, y - 16) * 1220542;
  return {clamp_u8((luma + c.rv) >> 20), clamp_u8((luma + c.guv) >> 20),
          clamp_u8((luma + c.bu) >> 20)};
}

}  // namespace

Rgb8 yuv_to_rgb_opencv(std::uint8_t y, std::uint8_t u, std::uint8_t v) {
  return decode_yuv(y, chroma_terms(u, v));
}

const char* segment_path_name(SegmentPath path) {
  switch (path) {
    case SegmentPath::kScalar:
      return "scalar";
    case SegmentPath::kAvx2:
      return "avx2";
    case SegmentPath::kNeon:
      return "neon";
  }
  return "unknown";
}

bool segment_path_supported(SegmentPath path) {
  switch (path) {
    case SegmentPath::kScalar:
      return true;
    case SegmentPath::kAvx2:
#if HARMOLOC_SEGMENT_AVX2
      return detail::cpu_has_avx2();
#else
      return false;
#endif
    case SegmentPath::kNeon:
#if HARMOLOC_SEGMENT_NEON
      return true;
#else
      return false;
#endif
  }
  return false;
}

SegmentPath best_segment_path() {
  for (SegmentPath p : {SegmentPath::kAvx2, SegmentPath::kNeon}) {
    if (segment_path_supported(p)) return p;
  }
  return SegmentPath::kScalar;
}

bool MaskTable::set_path(SegmentPath path) {
  if (!segment_path_supported(path)) return false;
  path_ = path;
  return true;
}

std::uint8_t* MaskTable::prepare(const BoardClassifier& classifier, std::uint8_t* storage) {
  std::fill(storage, storage + kGuardBytes, std::uint8_t{0});
  std::fill(storage + kGuardBytes + kColours, storage + kStorageBytes, std::uint8_t{0});
  boards_ = classifier.board_count();
  path_ = best_segment_path();
  return storage + kGuardBytes;
}

void ColourTable::build(const BoardClassifier& classifier, std::uint8_t* storage) {
  std::uint8_t* entries = prepare(classifier, storage);
  // In index order (R fastest), so the 16 MiB are written front to back.
  std::size_t i = 0;
  for (int b = 0; b < 256; ++b) {
    for (int g = 0; g < 256; ++g) {
      for (int r = 0; r < 256; ++r) {
        entries[i++] =
            classifier.classify(static_cast<std::uint8_t>(r), static_cast<std::uint8_t>(g),
                                static_cast<std::uint8_t>(b));
      }
    }
  }
  table_ = entries;
}

void YuyvTable::build(const BoardClassifier& classifier, std::uint8_t* storage) {
  std::uint8_t* entries = prepare(classifier, storage);
  std::size_t i = 0;  // index order: U fastest, then Y, then V
  for (int v = 0; v < 256; ++v) {
    for (int y = 0; y < 256; ++y) {
      for (int u = 0; u < 256; ++u) {
        const Rgb8 c = decode_yuv(y, chroma_terms(u, v));
        entries[i++] = classifier.classify(c.r, c.g, c.b);
      }
    }
  }
  table_ = entries;
}

namespace {

template <typename Classifier>
void segment_rgb24_with(const std::uint8_t* data, std::uint32_t width_px, std::uint32_t height_px,
                        std::uint32_t stride_bytes, const Classifier& classifier,
                        AreaVector& areas) {
  MaskCounts by_mask{};
  MaskColumns columns_by_mask{};
  MaskColumns rows_by_mask{};
  for (std::uint32_t y = 0; y < height_px; ++y) {
    const std::uint8_t* p = data + static_cast<std::size_t>(y) * stride_bytes;
    for (std::uint32_t x = 0; x < width_px; ++x, p += 3) {
      const std::uint8_t m = classifier.classify(p[0], p[1], p[2]);
      ++by_mask[m];
      columns_by_mask[m] += x;
      rows_by_mask[m] += y;
    }
  }
  counts_from_masks(by_mask, columns_by_mask, rows_by_mask, classifier.board_count(), areas);
  measure_sides(
      detail::Image{data, width_px, height_px, stride_bytes}, classifier.board_count(),
      [&classifier](const std::uint8_t* row, std::uint32_t x) -> std::uint32_t {
        const std::uint8_t* p = row + static_cast<std::size_t>(x) * 3U;
        return classifier.classify(p[0], p[1], p[2]);
      },
      areas);
}

template <typename Classifier>
void segment_yuyv_with(const std::uint8_t* data, std::uint32_t width_px, std::uint32_t height_px,
                       std::uint32_t stride_bytes, const Classifier& classifier,
                       AreaVector& areas) {
  MaskCounts by_mask{};
  MaskColumns columns_by_mask{};
  MaskColumns rows_by_mask{};
  for (std::uint32_t y = 0; y < height_px; ++y) {
    const std::uint8_t* row = data + static_cast<std::size_t>(y) * stride_bytes;
    for (std::uint32_t x = 0; x < width_px; x += 2U) {
      const std::uint8_t* p = row + 2U * x;
      const ChromaTerms c = chroma_terms(p[1], p[3]);
      for (std::uint32_t i = 0; i < 2U && x + i < width_px; ++i) {
        const Rgb8 rgb = decode_yuv(p[i * 2U], c);
        const std::uint8_t m = classifier.classify(rgb.r, rgb.g, rgb.b);
        ++by_mask[m];
        columns_by_mask[m] += x + i;
        rows_by_mask[m] += y;
      }
    }
  }
  counts_from_masks(by_mask, columns_by_mask, rows_by_mask, classifier.board_count(), areas);
  measure_sides(
      detail::Image{data, width_px, height_px, stride_bytes}, classifier.board_count(),
      [&classifier](const std::uint8_t* row, std::uint32_t x) -> std::uint32_t {
        const std::uint8_t* p = row + 2U * static_cast<std::size_t>(x & ~1U);
        const Rgb8 rgb = decode_yuv(p[(x & 1U) * 2U], chroma_terms(p[1], p[3]));
        return classifier.classify(rgb.r, rgb.g, rgb.b);
      },
      areas);
}

// The scalar table paths classify a row a chunk at a time into a buffer of class bytes and only
// then tally the chunk. Incrementing a counter chosen by the table load right away makes every
// later table load wait on that store: on a frame of noise (a cache miss a pixel) that was 8
// times slower (21 ms against 2.6 ms at 640x480 on the x86-64 host). Four histograms are used in
// turn, so that runs of one class do not wait on each other's increments either. Beside each count
// is the pixels' place, column + (row << 32): one add gives both sums, which are split into the
// boards' column and row sums before either half can carry into the other.
constexpr std::uint32_t kChunk = 256;
constexpr std::uint64_t kHalf = 0xFFFFFFFFU;  // what a half of a place sum holds
struct Histograms {
  std::array<MaskCounts, 4> counts;
  std::array<MaskColumns, 4> places;
  detail::BoardTotals column_sums;
  detail::BoardTotals row_sums;
  // Bounds on what any mask's halves hold since the last split.
  std::uint64_t columns_bound;
  std::uint64_t rows_bound;
};

// Moves the place sums of the board masks into the boards' column and row sums.
void split_places(Histograms& h, std::size_t boards) {
  for (std::size_t m = 1; m < 256; ++m) {
    const std::uint64_t p = h.places[0][m] + h.places[1][m] + h.places[2][m] + h.places[3][m];
    h.places[0][m] = h.places[1][m] = h.places[2][m] = h.places[3][m] = 0;
    if (p == 0) continue;
    for (std::size_t k = 0; k < boards; ++k) {
      if ((m >> k) & 1U) {
        h.column_sums[k] += p & kHalf;
        h.row_sums[k] += p >> 32U;
      }
    }
  }
  h.columns_bound = h.rows_bound = 0;
}

// Tallies @p n class bytes of row @p y from column @p x0; splits the place sums first if this
// chunk could carry a half over (frames wider or taller than a few thousand pixels).
void tally(const std::uint8_t* classes, std::uint32_t n, std::uint32_t x0, std::uint32_t y,
           std::size_t boards, Histograms& h) {
  const std::uint64_t columns = std::uint64_t{n} * (x0 + n - 1U);
  const std::uint64_t rows = std::uint64_t{n} * y;
  if (h.columns_bound + columns > kHalf || h.rows_bound + rows > kHalf) split_places(h, boards);
  h.columns_bound += columns;
  h.rows_bound += rows;
  const std::uint8_t* c = classes;
  const std::uint8_t* const end4 = classes + (n & ~3U);
  std::uint64_t place = x0 + (std::uint64_t{y} << 32U);
  for (; c != end4; c += 4, place += 4) {
    ++h.counts[0][c[0]];
    ++h.counts[1][c[1]];
    ++h.counts[2][c[2]];
    ++h.counts[3][c[3]];
    h.places[0][c[0]] += place;
    h.places[1][c[1]] += place + 1U;
    h.places[2][c[2]] += place + 2U;
    h.places[3][c[3]] += place + 3U;
  }
  for (; c != classes + n; ++c, ++place) {
    ++h.counts[0][*c];
    h.places[0][*c] += place;
  }
}

void merge_histograms(Histograms& h, std::size_t boards, AreaVector& areas) {
  split_places(h, boards);
  detail::BoardTotals totals{};
  for (std::size_t m = 1; m < 256; ++m) {
    const std::uint64_t n =
        std::uint64_t{h.counts[0][m]} + h.counts[1][m] + h.counts[2][m] + h.counts[3][m];
    for (std::size_t k = 0; k < boards; ++k) totals[k] += ((m >> k) & 1U) * n;
  }
  counts_from_totals(totals, h.column_sums, h.row_sums, boards, areas);
}

template <bool kYuyv>
void segment_scalar(const detail::Image& im, const std::uint8_t* table, std::size_t boards,
                    Histograms& h) {
  std::uint8_t classes[kChunk];
  for (std::uint32_t y = 0; y < im.height_px; ++y) {
    const std::uint8_t* row = im.row(y);
    for (std::uint32_t x = 0; x < im.width_px; x += kChunk) {
      const std::uint32_t n = im.width_px - x < kChunk ? im.width_px - x : kChunk;
      if constexpr (kYuyv)
        detail::classify_yuyv_row(row, x, n, table, classes);
      else
        detail::classify_rgb24_row(row, im.width_px, x, n, table, classes);
      tally(classes, n, x, y, boards, h);
    }
  }
}

enum class Format { kRgb24, kYuyv };

// The class byte of pixel @p x of a row, read through the table as the paths read it.
std::uint32_t table_class(Format format, const std::uint8_t* entries, const std::uint8_t* row,
                          std::uint32_t x) {
  if (format == Format::kRgb24)
    return entries[detail::rgb_index3(row + static_cast<std::size_t>(x) * 3U)];
  const std::uint32_t pair = detail::load_le32(row + static_cast<std::size_t>(x & ~1U) * 2U);
  return entries[(x & 1U) != 0U ? detail::yuyv_index_odd(pair) : detail::yuyv_index_even(pair)];
}

void segment_by_path(Format format, const detail::Image& im, const MaskTable& table,
                     AreaVector& areas) {
  const std::size_t boards = table.board_count();
  const std::uint8_t* entries = table.entries();
  switch (table.path()) {
#if HARMOLOC_SEGMENT_AVX2
    case SegmentPath::kAvx2: {
      detail::BoardTotals totals{};
      detail::BoardTotals column_sums{};
      detail::BoardTotals row_sums{};
      if (format == Format::kRgb24)
        detail::count_rgb24_avx2(im, entries, boards, totals, column_sums, row_sums);
      else
        detail::count_yuyv_avx2(im, entries, boards, totals, column_sums, row_sums);
      counts_from_totals(totals, column_sums, row_sums, boards, areas);
      return;
    }
#endif
#if HARMOLOC_SEGMENT_NEON
    case SegmentPath::kNeon: {
      detail::BoardTotals totals{};
      detail::BoardTotals column_sums{};
      detail::BoardTotals row_sums{};
      if (format == Format::kRgb24)
        detail::count_rgb24_neon(im, entries, boards, totals, column_sums, row_sums);
      else
        detail::count_yuyv_neon(im, entries, boards, totals, column_sums, row_sums);
      counts_from_totals(totals, column_sums, row_sums, boards, areas);
      return;
    }
#endif
    default: {
      Histograms h{};
      if (format == Format::kRgb24)
        segment_scalar<false>(im, entries, boards, h);
      else
        segment_scalar<true>(im, entries, boards, h);
      merge_histograms(h, boards, areas);
      return;
    }
  }
}

void segment_with_table(Format format, const detail::Image& im, const MaskTable& table,
                        AreaVector& areas) {
  const std::size_t boards = table.board_count();
  if (!table.ready() || boards == 0 || im.width_px == 0 || im.height_px == 0) {
    areas.pixels.fill(0U);
    areas.column_sum.fill(0U);
    areas.side_pixels.fill(0U);
    areas.row_sum.fill(0U);
    areas.width_px = table.ready() ? im.width_px : 0U;
    areas.height_px = table.ready() ? im.height_px : 0U;
    areas.count = table.ready() ? boards : 0;
    return;
  }
  segment_by_path(format, im, table, areas);
  const std::uint8_t* entries = table.entries();
  measure_sides(
      im, boards,
      [format, entries](const std::uint8_t* row, std::uint32_t x) {
        return table_class(format, entries, row, x);
      },
      areas);
}

}  // namespace

void segment_rgb24(const std::uint8_t* data, std::uint32_t width_px, std::uint32_t height_px,
                   std::uint32_t stride_bytes, const BoardClassifier& classifier,
                   AreaVector& areas) {
  segment_rgb24_with(data, width_px, height_px, stride_bytes, classifier, areas);
}

void segment_rgb24(const std::uint8_t* data, std::uint32_t width_px, std::uint32_t height_px,
                   std::uint32_t stride_bytes, const ColourTable& table, AreaVector& areas) {
  segment_with_table(Format::kRgb24, detail::Image{data, width_px, height_px, stride_bytes}, table,
                     areas);
}

void segment_yuyv(const std::uint8_t* data, std::uint32_t width_px, std::uint32_t height_px,
                  std::uint32_t stride_bytes, const BoardClassifier& classifier,
                  AreaVector& areas) {
  segment_yuyv_with(data, width_px, height_px, stride_bytes, classifier, areas);
}

void segment_yuyv(const std::uint8_t* data, std::uint32_t width_px, std::uint32_t height_px,
                  std::uint32_t stride_bytes, const YuyvTable& table, AreaVector& areas) {
  segment_with_table(Format::kYuyv, detail::Image{data, width_px, height_px, stride_bytes}, table,
                     areas);
}

void segment_yuyv(const std::uint8_t* data, std::uint32_t width_px, std::uint32_t height_px,
                  std::uint32_t stride_bytes, const ColourTable& table, AreaVector& areas) {
  segment_yuyv_with(data, width_px, height_px, stride_bytes, table, areas);
}

void segment_rgb24(const std::uint8_t* data, std::uint32_t width_px, std::uint32_t height_px,
                   std::uint32_t stride_bytes, const ThresholdSet& thresholds, AreaVector& areas) {
  segment_rgb24(data, width_px, height_px, stride_bytes, BoardClassifier(thresholds), areas);
}

void segment_yuyv(const std::uint8_t* data, std::uint32_t width_px, std::uint32_t height_px,
                  std::uint32_t stride_bytes, const ThresholdSet& thresholds, AreaVector& areas) {
  segment_yuyv(data, width_px, height_px, stride_bytes, BoardClassifier(thresholds), areas);
}

}  // namespace harmoloc::algorithms
