#pragma once
/// @file Camera frame as the cycle sees it: a view into a buffer the camera owns.

#include <cstddef>
#include <cstdint>

namespace harmoloc::hal {

/// Pixel layouts a camera may hand to the cycle. Segmentation reads each natively.
enum class PixelFormat : std::uint8_t {
  kRgb24 = 0,  ///< 3 bytes a pixel, R G B (binary PPM, libcamera RGB888)
  kYuyv = 1,   ///< 4 bytes per 2 pixels, Y0 U Y1 V (V4L2_PIX_FMT_YUYV)
};

/// Bytes one pixel takes on average (YUYV shares chroma between two pixels).
constexpr std::size_t bytes_per_pixel_x2(PixelFormat format) {
  return format == PixelFormat::kRgb24 ? 6U : 4U;
}

/// A captured frame. The data stays valid until Camera::release().
struct FrameView {
  const std::uint8_t* data = nullptr;
  std::uint32_t width_px = 0;
  std::uint32_t height_px = 0;
  std::uint32_t stride_bytes = 0;  ///< bytes from one row to the next
  PixelFormat format = PixelFormat::kRgb24;
  std::uint64_t timestamp_ns = 0;  ///< capture time on the data clock
  std::uint32_t sequence = 0;      ///< camera's frame counter; gaps mean dropped frames
};

}  // namespace harmoloc::hal
