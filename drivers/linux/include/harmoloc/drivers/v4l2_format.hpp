#pragma once
/// @file Which pixel format to ask a V4L2 capture device for: pure logic over the formats the
/// device enumerates (VIDIOC_ENUM_FMT), unit-tested without a device.

#include <cstddef>
#include <cstdint>
#include <string>

#include "harmoloc/hal/frame.hpp"

namespace harmoloc::drivers {

/// What the config asks for: "auto" (YUYV, else RGB24), "yuyv" or "rgb24".
enum class FormatRequest : std::uint8_t { kAuto = 0, kYuyv = 1, kRgb24 = 2 };

constexpr std::uint32_t fourcc(char a, char b, char c, char d) {
  return static_cast<std::uint32_t>(static_cast<std::uint8_t>(a)) |
         (static_cast<std::uint32_t>(static_cast<std::uint8_t>(b)) << 8U) |
         (static_cast<std::uint32_t>(static_cast<std::uint8_t>(c)) << 16U) |
         (static_cast<std::uint32_t>(static_cast<std::uint8_t>(d)) << 24U);
}
/// Same values as V4L2_PIX_FMT_YUYV and V4L2_PIX_FMT_RGB24 (checked in v4l2_camera.cpp).
constexpr std::uint32_t kFourccYuyv = fourcc('Y', 'U', 'Y', 'V');
constexpr std::uint32_t kFourccRgb24 = fourcc('R', 'G', 'B', '3');

inline std::string fourcc_text(std::uint32_t code) {
  std::string s(4, ' ');
  for (std::size_t i = 0; i < 4; ++i) {
    const auto ch = static_cast<char>((code >> (8U * i)) & 0xFFU);
    s[i] = (ch >= 32 && ch < 127) ? ch : '?';
  }
  return s;
}

/// Picks the fourcc to request from the @p count formats the device offers, or 0 when none fits.
inline std::uint32_t choose_fourcc(FormatRequest request, const std::uint32_t* offered,
                                   std::size_t count) {
  const auto has = [&](std::uint32_t code) {
    for (std::size_t i = 0; i < count; ++i)
      if (offered[i] == code) return true;
    return false;
  };
  switch (request) {
    case FormatRequest::kYuyv:
      return has(kFourccYuyv) ? kFourccYuyv : 0U;
    case FormatRequest::kRgb24:
      return has(kFourccRgb24) ? kFourccRgb24 : 0U;
    case FormatRequest::kAuto:
      if (has(kFourccYuyv)) return kFourccYuyv;
      if (has(kFourccRgb24)) return kFourccRgb24;
      return 0U;
  }
  return 0U;
}

inline hal::PixelFormat pixel_format_of(std::uint32_t code) {
  return code == kFourccYuyv ? hal::PixelFormat::kYuyv : hal::PixelFormat::kRgb24;
}

/// The smallest stride a frame of @p width_px needs in @p format.
inline std::uint32_t min_stride_bytes(hal::PixelFormat format, std::uint32_t width_px) {
  return format == hal::PixelFormat::kYuyv ? width_px * 2U : width_px * 3U;
}

/// Checks what the device agreed to (VIDIOC_S_FMT answers with what it will really deliver).
/// Returns an empty string when it fits the request, else the reason.
inline std::string check_negotiated(std::uint32_t want_fourcc, std::uint32_t want_width_px,
                                    std::uint32_t want_height_px, std::uint32_t got_fourcc,
                                    std::uint32_t got_width_px, std::uint32_t got_height_px,
                                    std::uint32_t got_stride_bytes, std::uint32_t got_image_bytes) {
  if (got_fourcc != want_fourcc) {
    return "asked for " + fourcc_text(want_fourcc) + ", the device gives " +
           fourcc_text(got_fourcc);
  }
  if (got_width_px != want_width_px || got_height_px != want_height_px) {
    return "asked for " + std::to_string(want_width_px) + "x" + std::to_string(want_height_px) +
           ", the device gives " + std::to_string(got_width_px) + "x" +
           std::to_string(got_height_px) + " (set camera.width/height to a size it supports)";
  }
  const hal::PixelFormat f = pixel_format_of(got_fourcc);
  if (got_stride_bytes < min_stride_bytes(f, got_width_px)) {
    return "the device reports " + std::to_string(got_stride_bytes) + " bytes a row, fewer than " +
           std::to_string(min_stride_bytes(f, got_width_px));
  }
  if (static_cast<std::uint64_t>(got_image_bytes) <
      static_cast<std::uint64_t>(got_stride_bytes) * got_height_px) {
    return "the device reports an image of " + std::to_string(got_image_bytes) +
           " bytes, fewer than rows x stride";
  }
  return {};
}

}  // namespace harmoloc::drivers
