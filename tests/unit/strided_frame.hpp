// A camera frame for the tests that record or replay frames, with rows padded to a larger stride
// as a driver may hand them (header-only).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "harmoloc/hal/frame.hpp"

namespace harmoloc::test {

/// A frame as a driver may hand one: each row's pixel bytes followed by 16 bytes of padding
/// (0xEE) up to the stride. Pixel byte x of row y is @p value(y, x).
class StridedFrame {
 public:
  template <typename Value>
  StridedFrame(std::uint32_t width_px, std::uint32_t height_px, hal::PixelFormat format,
               std::uint64_t timestamp_ns, Value value)
      : row_bytes_(width_px * (format == hal::PixelFormat::kRgb24 ? 3U : 2U)) {
    const std::uint32_t stride = row_bytes_ + 16;
    bytes_.assign(std::size_t{stride} * height_px, 0xEE);
    for (std::uint32_t y = 0; y < height_px; ++y) {
      for (std::uint32_t x = 0; x < row_bytes_; ++x)
        bytes_[std::size_t{y} * stride + x] = static_cast<std::uint8_t>(value(y, x));
    }
    view_.data = bytes_.data();
    view_.width_px = width_px;
    view_.height_px = height_px;
    view_.stride_bytes = stride;
    view_.format = format;
    view_.timestamp_ns = timestamp_ns;
  }
  StridedFrame(const StridedFrame&) = delete;
  StridedFrame& operator=(const StridedFrame&) = delete;

  const hal::FrameView& view() const { return view_; }
  std::uint32_t row_bytes() const { return row_bytes_; }

 private:
  std::uint32_t row_bytes_;
  std::vector<std::uint8_t> bytes_;
  hal::FrameView view_;
};

}  // namespace harmoloc::test
