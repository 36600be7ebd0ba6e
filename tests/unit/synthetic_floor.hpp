#pragma once
/// @file A synthetic floor map for the floor tests (the floor search, the nearby pose test): 3 x
/// 2 m of 2 cm cells from (0, 0), four boards around it. Each board's feature falls with the
/// square of the distance from the axle's place; its bearing is seen from the camera's place
/// 10 cm ahead (as the trainer stores them).

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <memory>

#include "harmoloc/algorithms/board_observation.hpp"
#include "harmoloc/algorithms/forward_map.hpp"
#include "harmoloc/algorithms/geometry.hpp"

namespace harmoloc::test_floor {

namespace ha = harmoloc::algorithms;

constexpr double kCameraForward = 0.1;
constexpr double kHalfView = 1.0;  // the image angle within which a board gives a bearing
constexpr std::array<double, 8> kBoards = {-0.5, 1.0, 1.5, 2.5, 3.5, 1.0, 1.5, -0.5};  // x, y

inline double feature(std::size_t b, double x, double y) {
  const double dx = kBoards[2 * b] - x, dy = kBoards[2 * b + 1] - y;
  return 4.0 / (dx * dx + dy * dy);
}

inline double world_bearing(std::size_t b, double x, double y) {
  return std::atan2(kBoards[2 * b + 1] - y, kBoards[2 * b] - x);
}

inline std::unique_ptr<ha::ForwardMap> make_floor(bool bearings = true) {
  auto f = std::make_unique<ha::ForwardMap>();
  EXPECT_TRUE(ha::lay_out_grid(*f, 151, 101));
  f->cell_m = 0.02F;
  f->board_count = 4;
  f->has_bearings = bearings;
  f->bearing_a1_rad = 2.0F;
  f->bearing_camera_forward_m = static_cast<float>(kCameraForward);
  for (std::size_t b = 0; b < 4; ++b) {
    f->sigma[b] = 0.02F;
    f->bearing_sigma_rad[b] = 0.01F;
  }
  for (std::uint32_t r = 0; r < f->rows; ++r) {
    for (std::uint32_t c = 0; c < f->columns; ++c) {
      const std::size_t at = f->index(c, r);
      const double x = 0.02 * c, y = 0.02 * r;
      for (std::size_t b = 0; b < 4; ++b) {
        f->expected[at * ha::kMaxBoards + b] = static_cast<float>(feature(b, x, y));
        f->bearing_rad[at * ha::kMaxBoards + b] = static_cast<float>(world_bearing(b, x, y));
      }
    }
  }
  return f;
}

/// What a robot at (x, y) facing yaw sees: every board's feature (off by @p noise[b]), and the
/// image angle of those within kHalfView of the axis.
inline ha::BoardFeatures seen(double x, double y, double yaw,
                              const std::array<double, 4>& noise = {}) {
  ha::BoardFeatures o;
  o.count = 4;
  const double cx = x + kCameraForward * std::cos(yaw), cy = y + kCameraForward * std::sin(yaw);
  for (std::size_t b = 0; b < 4; ++b) {
    o.value[b] = static_cast<float>(feature(b, x, y) + noise[b]);
    const double a = ha::wrap_angle_rad(yaw - world_bearing(b, cx, cy));
    if (std::fabs(a) >= kHalfView) continue;
    o.angle_rad[b] = static_cast<float>(a);
    o.angle_mask |= 1U << b;
  }
  return o;
}

}  // namespace harmoloc::test_floor
