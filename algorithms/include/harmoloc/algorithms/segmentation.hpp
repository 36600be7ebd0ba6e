#pragma once
/// @file Threshold area segmentation of coloured landmark boards (seed 000): each board is a
/// range of hue with minimum saturation and a value window; its "area" is the number of pixels
/// of the raw, distorted frame inside that range. Do not undistort: the distortion is what makes
/// area depend on lateral position.

#include <array>
#include <cstddef>
#include <cstdint>

namespace harmoloc::algorithms {

constexpr std::size_t kMaxBoards = 8;

/// Colour window of one board, in HSV with H in degrees [0, 360) and S, V in [0, 255].
/// If hue_min_deg > hue_max_deg the window wraps through 0 (reds).
struct ColourThreshold {
  float hue_min_deg = 0.0F;
  float hue_max_deg = 0.0F;
  std::uint8_t saturation_min = 0;
  std::uint8_t value_min = 0;
  std::uint8_t value_max = 255;
};

struct ThresholdSet {
  std::array<ColourThreshold, kMaxBoards> boards{};
  std::size_t count = 0;
};

bool operator==(const ColourThreshold& a, const ColourThreshold& b);
bool operator==(const ThresholdSet& a, const ThresholdSet& b);

/// Pixel counts per board.
struct AreaVector {
  std::array<std::uint32_t, kMaxBoards> pixels{};
  std::size_t count = 0;
};

/// HSV of one 8-bit RGB pixel: H degrees [0, 360), S and V in [0, 255].
struct Hsv {
  float hue_deg;
  float saturation;
  float value;
};
Hsv rgb_to_hsv(std::uint8_t r, std::uint8_t g, std::uint8_t b);

bool in_threshold(const ColourThreshold& t, const Hsv& hsv);

/// Counts board pixels in an RGB24 image (3 bytes a pixel). No allocation.
void segment_rgb24(const std::uint8_t* data, std::uint32_t width_px, std::uint32_t height_px,
                   std::uint32_t stride_bytes, const ThresholdSet& thresholds, AreaVector& areas);

/// Counts board pixels in a YUYV image (BT.601 limited range), each pixel with its own luma and
/// the chroma it shares with its neighbour. No allocation.
void segment_yuyv(const std::uint8_t* data, std::uint32_t width_px, std::uint32_t height_px,
                  std::uint32_t stride_bytes, const ThresholdSet& thresholds, AreaVector& areas);

}  // namespace harmoloc::algorithms
