#include "harmoloc/algorithms/segmentation.hpp"

#include <algorithm>

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

Hsv rgb_to_hsv(std::uint8_t r, std::uint8_t g, std::uint8_t b) {
  const int max_c = std::max({r, g, b});
  const int min_c = std::min({r, g, b});
  const int delta = max_c - min_c;
  Hsv hsv{0.0F, 0.0F, static_cast<float>(max_c)};
  if (max_c == 0 || delta == 0) return hsv;
  hsv.saturation = 255.0F * static_cast<float>(delta) / static_cast<float>(max_c);
  const auto d = static_cast<float>(delta);
  float h = 0.0F;
  if (max_c == r) {
    h = 60.0F * static_cast<float>(g - b) / d;
  } else if (max_c == g) {
    h = 120.0F + 60.0F * static_cast<float>(b - r) / d;
  } else {
    h = 240.0F + 60.0F * static_cast<float>(r - g) / d;
  }
  if (h < 0.0F) h += 360.0F;
  hsv.hue_deg = h;
  return hsv;
}

bool in_threshold(const ColourThreshold& t, const Hsv& hsv) {
  if (hsv.saturation < static_cast<float>(t.saturation_min)) return false;
  if (hsv.value < static_cast<float>(t.value_min) || hsv.value > static_cast<float>(t.value_max)) {
    return false;
  }
  if (t.hue_min_deg <= t.hue_max_deg) {
    return hsv.hue_deg >= t.hue_min_deg && hsv.hue_deg <= t.hue_max_deg;
  }
  return hsv.hue_deg >= t.hue_min_deg || hsv.hue_deg <= t.hue_max_deg;
}

namespace {

inline void count_pixel(const ThresholdSet& thresholds, AreaVector& areas, std::uint8_t r,
                        std::uint8_t g, std::uint8_t b) {
  const Hsv hsv = rgb_to_hsv(r, g, b);
  for (std::size_t k = 0; k < thresholds.count; ++k) {
    areas.pixels[k] += in_threshold(thresholds.boards[k], hsv) ? 1U : 0U;
  }
}

inline std::uint8_t clamp_u8(int v) {
  return static_cast<std::uint8_t>(std::clamp(v, 0, 255));
}

}  // namespace

void segment_rgb24(const std::uint8_t* data, std::uint32_t width_px, std::uint32_t height_px,
                   std::uint32_t stride_bytes, const ThresholdSet& thresholds, AreaVector& areas) {
  areas.pixels.fill(0U);
  areas.count = thresholds.count;
  for (std::uint32_t y = 0; y < height_px; ++y) {
    const std::uint8_t* row = data + static_cast<std::size_t>(y) * stride_bytes;
    for (std::uint32_t x = 0; x < width_px; ++x) {
      const std::uint8_t* p = row + 3U * x;
      count_pixel(thresholds, areas, p[0], p[1], p[2]);
    }
  }
}

void segment_yuyv(const std::uint8_t* data, std::uint32_t width_px, std::uint32_t height_px,
                  std::uint32_t stride_bytes, const ThresholdSet& thresholds, AreaVector& areas) {
  areas.pixels.fill(0U);
  areas.count = thresholds.count;
  for (std::uint32_t y = 0; y < height_px; ++y) {
    const std::uint8_t* row = data + static_cast<std::size_t>(y) * stride_bytes;
    for (std::uint32_t x = 0; x + 1U < width_px + 1U; x += 2U) {
      const std::uint8_t* p = row + 2U * x;
      const int u = p[1] - 128;
      const int v = p[3] - 128;
      // BT.601 limited range, integer form (as the kernel's v4l2 helpers use).
      const int rv = 409 * v;
      const int guv = -100 * u - 208 * v;
      const int bu = 516 * u;
      for (int i = 0; i < 2 && x + static_cast<std::uint32_t>(i) < width_px; ++i) {
        const int c = 298 * (p[i * 2] - 16);
        count_pixel(thresholds, areas, clamp_u8((c + rv + 128) >> 8),
                    clamp_u8((c + guv + 128) >> 8), clamp_u8((c + bu + 128) >> 8));
      }
    }
  }
}

}  // namespace harmoloc::algorithms
