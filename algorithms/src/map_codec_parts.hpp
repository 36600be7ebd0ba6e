#pragma once
/// @file What the pieces of the map codec (map_codec_*.cpp) share: the calibration entry ids, the
/// magic, the byte reader and the range checks. Private to algorithms/src.

#include <cmath>
#include <cstdint>
#include <cstring>

#include "harmoloc/algorithms/map_codec.hpp"

namespace harmoloc::algorithms::map_codec_detail {

// Calibration entry ids (version 4).
constexpr std::uint32_t kCalibrationFixRmseX = 1;
constexpr std::uint32_t kCalibrationFixRmseY = 2;
constexpr std::uint32_t kCalibrationPassSpread = 3;
constexpr std::uint32_t kCalibrationLocalLinearRidge = 4;
constexpr std::uint32_t kCalibrationLeftWheelScale = 5;
constexpr std::uint32_t kCalibrationRightWheelScale = 6;
constexpr std::uint32_t kCalibrationTrackScale = 7;
constexpr std::uint32_t kCalibrationPassHeadingSpread = 8;
constexpr float kMinOdometryScale = 0.5F, kMaxOdometryScale = 2.0F;

inline constexpr std::uint8_t kMagic[8] = {'H', 'A', 'R', 'M', 'O', 'M', 'A', 'P'};

class Reader {
 public:
  Reader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  bool u8(std::uint8_t& v, const char* what) {
    if (!need(1, what)) return false;
    v = data_[pos_++];
    return true;
  }
  bool u16(std::uint16_t& v, const char* what) {
    if (!need(2, what)) return false;
    v = static_cast<std::uint16_t>(data_[pos_] | (data_[pos_ + 1] << 8));
    pos_ += 2;
    return true;
  }
  bool u32(std::uint32_t& v, const char* what) {
    if (!need(4, what)) return false;
    v = 0;
    for (int i = 0; i < 4; ++i) v |= static_cast<std::uint32_t>(data_[pos_ + i]) << (8 * i);
    pos_ += 4;
    return true;
  }
  bool f32(float& v, const char* what) {
    std::uint32_t u = 0;
    if (!u32(u, what)) return false;
    std::memcpy(&v, &u, 4);
    return true;
  }
  bool need(std::size_t n, const char* what) {
    if (size_ - pos_ < n) {
      error = MapError{what, pos_};
      return false;
    }
    return true;
  }
  std::size_t pos() const { return pos_; }
  MapError error;

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

inline bool finite_positive(float v) {
  return std::isfinite(v) && v > 0.0F;
}

inline bool finite_in(float v, float lo, float hi) {
  return v >= lo && v <= hi;  // false for NaN
}

// The forward map section (version 3; tiled from version 5); map_codec_read_forward.cpp.
MapError decode_forward(Reader& r, std::uint32_t version, std::uint32_t boards, ForwardMap& f);

}  // namespace harmoloc::algorithms::map_codec_detail
