// Fuzz target: segmentation of arbitrary bytes as a camera frame (algorithms::segment_rgb24 and
// segment_yuyv with a BoardClassifier). The input's first bytes choose the pixel format, the
// board windows (within what config and map validation admit: hue 0..360, 8-bit S and V), the
// width, the height and the stride; the frame is the input's tail, laid out so that its last row
// ends exactly at the end of the input: any read past the frame hits AddressSanitizer's redzone.
//
// Frame contract (what FileCamera and the V4L2 driver give the cycle): rows `stride_bytes`
// apart, each row at least 3 * width bytes (RGB24) or 4 * ceil(width / 2) bytes (YUYV, whole
// Y0 U Y1 V pairs); the stride may be smaller than a row (rows overlap) or 0.

#include <algorithm>
#include <cstdint>
#include <cstring>

#include "fuzz_common.hpp"
#include "harmoloc/algorithms/segmentation.hpp"

using namespace harmoloc::algorithms;

namespace {

constexpr std::size_t kHeader = 1 + 6 + kMaxBoards * 7;
constexpr std::uint32_t kMaxSide = 2048;
constexpr std::uint64_t kMaxPixels = std::uint64_t{1} << 18;  // keeps one run under ~10 ms

std::uint16_t u16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>(p[0] | (p[1] << 8));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < kHeader) return 0;
  const bool yuyv = (data[0] & 1U) != 0;
  ThresholdSet set;
  set.count = (data[0] >> 1U) % (kMaxBoards + 1);  // 0..8 boards
  std::uint32_t width = u16(data + 1) % (kMaxSide + 1);
  std::uint32_t height = u16(data + 3) % (kMaxSide + 1);
  const std::uint32_t stride = u16(data + 5);
  const std::uint8_t* b = data + 7;
  for (std::size_t k = 0; k < kMaxBoards; ++k, b += 7) {
    ColourThreshold& t = set.boards[k];
    t.hue_min_deg = static_cast<float>(u16(b) % 7201) / 20.0F;  // 0..360 in 0.05 degree steps
    t.hue_max_deg = static_cast<float>(u16(b + 2) % 7201) / 20.0F;
    t.saturation_min = b[4];
    t.value_min = b[5];
    t.value_max = b[6];
  }
  const std::uint8_t* pixels = data + kHeader;
  const std::size_t avail = size - kHeader;

  const std::size_t row = yuyv ? 4U * ((std::size_t{width} + 1U) / 2U) : 3U * std::size_t{width};
  if (row > avail) return 0;
  if (height > 1 && stride > 0)
    height = std::min<std::uint64_t>(height, (avail - row) / stride + 1U);
  if (std::uint64_t{width} * height > kMaxPixels)
    height = static_cast<std::uint32_t>(kMaxPixels / std::max(width, 1U));
  const std::size_t need = height == 0 ? 0 : std::size_t{height - 1U} * stride + row;
  if (need > avail) return 0;
  const std::uint8_t* frame = pixels + (avail - need);  // the frame ends where the input ends

  const BoardClassifier classifier(set);
  HARMOLOC_FUZZ_CHECK(classifier.board_count() == set.count, "board count lost");
  AreaVector areas;
  if (yuyv)
    segment_yuyv(frame, width, height, stride, classifier, areas);
  else
    segment_rgb24(frame, width, height, stride, classifier, areas);
  HARMOLOC_FUZZ_CHECK(areas.count == set.count, "area vector has the wrong board count");
  const std::uint64_t pixel_count = std::uint64_t{width} * height;
  for (std::size_t k = 0; k < kMaxBoards; ++k) {
    HARMOLOC_FUZZ_CHECK(areas.pixels[k] <= pixel_count, "more board pixels than pixels");
    if (k >= set.count) HARMOLOC_FUZZ_CHECK(areas.pixels[k] == 0, "area for a board not asked");
    // Every pixel's column is below the width, and a side pixel is a board pixel.
    const std::uint64_t last_column = width == 0 ? 0 : width - 1U;
    HARMOLOC_FUZZ_CHECK(areas.column_sum[k] <= std::uint64_t{areas.pixels[k]} * last_column,
                        "column sum past the frame's width");
    HARMOLOC_FUZZ_CHECK(areas.side_pixels[k] <= areas.pixels[k] &&
                            areas.side_pixels[k] <= 2U * std::uint64_t{height},
                        "more side pixels than board pixels or sides");
    const std::uint64_t last_row = height == 0 ? 0 : height - 1U;
    HARMOLOC_FUZZ_CHECK(areas.row_sum[k] <= std::uint64_t{areas.pixels[k]} * last_row,
                        "row sum past the frame's height");
  }
  HARMOLOC_FUZZ_CHECK(areas.width_px == width, "columns counted in the wrong width");
  HARMOLOC_FUZZ_CHECK(areas.height_px == height, "rows counted in the wrong height");

  // The convenience overload (thresholds compiled on the stack) must agree.
  AreaVector again;
  if (yuyv)
    segment_yuyv(frame, width, height, stride, set, again);
  else
    segment_rgb24(frame, width, height, stride, set, again);
  HARMOLOC_FUZZ_CHECK(again.count == areas.count && again.pixels == areas.pixels &&
                          again.column_sum == areas.column_sum &&
                          again.side_pixels == areas.side_pixels && again.row_sum == areas.row_sum,
                      "overloads disagree");
  return 0;
}
