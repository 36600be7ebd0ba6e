#include "harmoloc/algorithms/segmentation.hpp"

#include <algorithm>
#include <cmath>

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

// Pixels are tallied by their board mask (256 possible) and only expanded to per-board counts
// once per frame, so the per-pixel work does not grow with the number of boards.
void counts_from_masks(const std::array<std::uint32_t, 256>& by_mask, std::size_t boards,
                       AreaVector& areas) {
  areas.pixels.fill(0U);
  areas.count = boards;
  for (std::size_t mask = 1; mask < 256; ++mask) {
    if (by_mask[mask] == 0) continue;
    for (std::size_t k = 0; k < boards; ++k) {
      if ((mask >> k) & 1U) areas.pixels[k] += by_mask[mask];
    }
  }
}

inline std::uint8_t clamp_u8(int v) {
  return static_cast<std::uint8_t>(std::clamp(v, 0, 255));
}

}  // namespace

void ColourTable::build(const BoardClassifier& classifier, std::uint8_t* storage) {
  std::size_t i = 0;
  for (int r = 0; r < 256; ++r) {
    for (int g = 0; g < 256; ++g) {
      for (int b = 0; b < 256; ++b) {
        storage[i++] =
            classifier.classify(static_cast<std::uint8_t>(r), static_cast<std::uint8_t>(g),
                                static_cast<std::uint8_t>(b));
      }
    }
  }
  table_ = storage;
  boards_ = classifier.board_count();
}

namespace {

template <typename Classifier>
void segment_rgb24_with(const std::uint8_t* data, std::uint32_t width_px, std::uint32_t height_px,
                        std::uint32_t stride_bytes, const Classifier& classifier,
                        AreaVector& areas) {
  std::array<std::uint32_t, 256> by_mask{};
  for (std::uint32_t y = 0; y < height_px; ++y) {
    const std::uint8_t* p = data + static_cast<std::size_t>(y) * stride_bytes;
    for (std::uint32_t x = 0; x < width_px; ++x, p += 3)
      ++by_mask[classifier.classify(p[0], p[1], p[2])];
  }
  counts_from_masks(by_mask, classifier.board_count(), areas);
}

template <typename Classifier>
void segment_yuyv_with(const std::uint8_t* data, std::uint32_t width_px, std::uint32_t height_px,
                       std::uint32_t stride_bytes, const Classifier& classifier,
                       AreaVector& areas) {
  std::array<std::uint32_t, 256> by_mask{};
  for (std::uint32_t y = 0; y < height_px; ++y) {
    const std::uint8_t* row = data + static_cast<std::size_t>(y) * stride_bytes;
    for (std::uint32_t x = 0; x < width_px; x += 2U) {
      const std::uint8_t* p = row + 2U * x;
      // BT.601 limited range in OpenCV's 20-bit fixed point (as cvtColor(COLOR_YUV2RGB_YUYV)),
      // so areas equal the OpenCV reference exactly; the chroma terms are shared by the pair.
      const int du = p[1] - 128;
      const int dv = p[3] - 128;
      const int rv = (1 << 19) + 1673527 * dv;
      const int guv = (1 << 19) - 852492 * dv - 409993 * du;
      const int bu = (1 << 19) + 2116026 * du;
      for (std::uint32_t i = 0; i < 2U && x + i < width_px; ++i) {
        const int luma = std::max(0, p[i * 2U] - 16) * 1220542;
        ++by_mask[classifier.classify(clamp_u8((luma + rv) >> 20), clamp_u8((luma + guv) >> 20),
                                      clamp_u8((luma + bu) >> 20))];
      }
    }
  }
  counts_from_masks(by_mask, classifier.board_count(), areas);
}

}  // namespace

void segment_rgb24(const std::uint8_t* data, std::uint32_t width_px, std::uint32_t height_px,
                   std::uint32_t stride_bytes, const BoardClassifier& classifier,
                   AreaVector& areas) {
  segment_rgb24_with(data, width_px, height_px, stride_bytes, classifier, areas);
}

void segment_rgb24(const std::uint8_t* data, std::uint32_t width_px, std::uint32_t height_px,
                   std::uint32_t stride_bytes, const ColourTable& table, AreaVector& areas) {
  segment_rgb24_with(data, width_px, height_px, stride_bytes, table, areas);
}

void segment_yuyv(const std::uint8_t* data, std::uint32_t width_px, std::uint32_t height_px,
                  std::uint32_t stride_bytes, const BoardClassifier& classifier,
                  AreaVector& areas) {
  segment_yuyv_with(data, width_px, height_px, stride_bytes, classifier, areas);
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
