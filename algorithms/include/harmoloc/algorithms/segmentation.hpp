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

/// OpenCV's 8-bit HSV of one RGB pixel: H in 0..179 (2 degrees a step), S and V in 0..255.
/// Bit-exact with cv::cvtColor(COLOR_RGB2HSV) (the unit tests check all 2^24 colours).
struct Hsv8 {
  std::uint8_t h, s, v;
};

/// A ThresholdSet compiled at start-up into per-channel class masks. Each board's window is a
/// box in (H, S, V), so a pixel's boards are hue[H] & sat[S] & val[V]: three lookups, no
/// per-board loop, no floating point. Degrees map onto OpenCV's 2-degree steps as
/// H in [ceil(min/2), floor(max/2)] (documented in docs/segmentation.md).
class BoardClassifier {
 public:
  BoardClassifier();
  explicit BoardClassifier(const ThresholdSet& thresholds) : BoardClassifier() {
    build(thresholds);
  }
  void build(const ThresholdSet& thresholds);
  std::size_t board_count() const { return boards_; }

  Hsv8 to_hsv(std::uint8_t r, std::uint8_t g, std::uint8_t b) const {
    const int vmax = r > g ? (r > b ? r : b) : (g > b ? g : b);
    const int vmin = r < g ? (r < b ? r : b) : (g < b ? g : b);
    const int diff = vmax - vmin;
    const int vr = vmax == r ? -1 : 0;
    const int vg = vmax == g ? -1 : 0;
    const int s = (diff * sdiv_[static_cast<std::size_t>(vmax)] + (1 << (kShift - 1))) >> kShift;
    int h = (vr & (g - b)) + (~vr & ((vg & (b - r + 2 * diff)) + ((~vg) & (r - g + 4 * diff))));
    h = (h * hdiv_[static_cast<std::size_t>(diff)] + (1 << (kShift - 1))) >> kShift;
    h += h < 0 ? 180 : 0;
    return Hsv8{static_cast<std::uint8_t>(h), static_cast<std::uint8_t>(s),
                static_cast<std::uint8_t>(vmax)};
  }
  /// Bit k set: the pixel is inside board k's window.
  std::uint8_t classify(std::uint8_t r, std::uint8_t g, std::uint8_t b) const {
    const Hsv8 p = to_hsv(r, g, b);
    return static_cast<std::uint8_t>(hue_[p.h] & sat_[p.s] & val_[p.v]);
  }

 private:
  static constexpr int kShift = 12;
  std::array<std::int32_t, 256> sdiv_{};
  std::array<std::int32_t, 256> hdiv_{};
  std::array<std::uint8_t, 256> hue_{};
  std::array<std::uint8_t, 256> sat_{};
  std::array<std::uint8_t, 256> val_{};
  std::size_t boards_ = 0;
};

/// Every 24-bit RGB colour's board mask, tabulated once at start-up from a BoardClassifier:
/// one load a pixel instead of the HSV arithmetic, with identical results. The 16 MiB of storage
/// belong to the caller (reserved at start-up); images of a few dominant colours touch only a
/// few hundred cache lines of it.
class ColourTable {
 public:
  static constexpr std::size_t kEntries = std::size_t{1} << 24;

  /// Fills @p storage (kEntries bytes) and uses it from now on.
  void build(const BoardClassifier& classifier, std::uint8_t* storage);
  bool ready() const { return table_ != nullptr; }
  std::size_t board_count() const { return boards_; }
  std::uint8_t classify(std::uint8_t r, std::uint8_t g, std::uint8_t b) const {
    return table_[(static_cast<std::size_t>(r) << 16U) | (static_cast<std::size_t>(g) << 8U) | b];
  }

 private:
  const std::uint8_t* table_ = nullptr;
  std::size_t boards_ = 0;
};

/// Counts board pixels in an RGB24 image (3 bytes a pixel): one pass, no allocation.
void segment_rgb24(const std::uint8_t* data, std::uint32_t width_px, std::uint32_t height_px,
                   std::uint32_t stride_bytes, const BoardClassifier& classifier,
                   AreaVector& areas);
void segment_rgb24(const std::uint8_t* data, std::uint32_t width_px, std::uint32_t height_px,
                   std::uint32_t stride_bytes, const ColourTable& table, AreaVector& areas);

/// Counts board pixels in a YUYV image (BT.601 limited range, decoded exactly as OpenCV's
/// COLOR_YUV2RGB_YUYV, each pixel with its own luma and the chroma it shares with its
/// neighbour): one pass, no allocation. YUYV comes in pixel pairs: @p width_px must be even
/// (the metadata and the V4L2 driver ensure it), else the last pair's chroma lies past the row.
void segment_yuyv(const std::uint8_t* data, std::uint32_t width_px, std::uint32_t height_px,
                  std::uint32_t stride_bytes, const BoardClassifier& classifier, AreaVector& areas);
void segment_yuyv(const std::uint8_t* data, std::uint32_t width_px, std::uint32_t height_px,
                  std::uint32_t stride_bytes, const ColourTable& table, AreaVector& areas);

/// Convenience for host code and tests: compiles @p thresholds on the stack first.
void segment_rgb24(const std::uint8_t* data, std::uint32_t width_px, std::uint32_t height_px,
                   std::uint32_t stride_bytes, const ThresholdSet& thresholds, AreaVector& areas);
void segment_yuyv(const std::uint8_t* data, std::uint32_t width_px, std::uint32_t height_px,
                  std::uint32_t stride_bytes, const ThresholdSet& thresholds, AreaVector& areas);

}  // namespace harmoloc::algorithms
