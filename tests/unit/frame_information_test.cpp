// How tightly one frame pins the pose down (algorithms/frame_information.hpp): the boards'
// Fisher information about (x, y, yaw) and the position spread it leaves with the heading free.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>

#include "harmoloc/algorithms/board_observation.hpp"
#include "harmoloc/algorithms/frame_information.hpp"
#include "harmoloc/algorithms/geometry.hpp"
#include "synthetic_floor.hpp"

namespace ha = harmoloc::algorithms;
using harmoloc::test_floor::kBoards;
using harmoloc::test_floor::kCameraForward;
using harmoloc::test_floor::make_floor;
using harmoloc::test_floor::seen;

namespace {

// The synthetic floor's information at a pose, from its closed form: feature 4 / r^2 from the
// axle, image angle yaw - atan2 from the camera 10 cm ahead; sigma 0.02 and 0.01 rad.
std::array<double, 9> information_by_hand(double x, double y, double yaw, std::uint32_t areas,
                                          std::uint32_t bearings) {
  std::array<double, 9> j{};
  const auto add = [&j](const double(&g)[3], double sigma) {
    for (std::size_t r = 0; r < 3; ++r)
      for (std::size_t c = 0; c < 3; ++c) j[3 * r + c] += g[r] * g[c] / (sigma * sigma);
  };
  const double cx = x + kCameraForward * std::cos(yaw), cy = y + kCameraForward * std::sin(yaw);
  for (std::size_t b = 0; b < 4; ++b) {
    if (((areas >> b) & 1U) != 0U) {
      const double dx = kBoards[2 * b] - x, dy = kBoards[2 * b + 1] - y;
      const double r4 = (dx * dx + dy * dy) * (dx * dx + dy * dy);
      const double g[3] = {8.0 * dx / r4, 8.0 * dy / r4, 0.0};
      add(g, 0.02);
    }
    if (((bearings >> b) & 1U) != 0U) {
      const double X = kBoards[2 * b] - cx, Y = kBoards[2 * b + 1] - cy;
      const double r2 = X * X + Y * Y;
      // d atan2(Y, X) / d(cx, cy) = (Y, -X) / r^2; the camera moves with the heading.
      const double dcx = Y / r2, dcy = -X / r2;
      const double g[3] = {
          -dcx, -dcy,
          1.0 - (dcx * -kCameraForward * std::sin(yaw) + dcy * kCameraForward * std::cos(yaw))};
      add(g, 0.01);
    }
  }
  return j;
}

}  // namespace

TEST(FrameInformation, MatchesTheClosedFormOnTheSyntheticFloor) {
  const auto map = make_floor();
  const ha::BoardModelParams params;
  const double x = 1.6, y = 0.9, yaw = 0.8;
  const ha::BoardFeatures o = seen(x, y, yaw);
  ASSERT_GE(__builtin_popcount(o.angle_mask), 2);
  const ha::FrameInformation info = ha::frame_information(*map, o, ha::Pose2{x, y, yaw}, params);
  const std::array<double, 9> j = information_by_hand(x, y, yaw, 0b1111U, o.angle_mask);
  for (std::size_t k = 0; k < 9; ++k) {
    const double scale = std::sqrt(j[4 * (k / 3)] * j[4 * (k % 3)]);
    EXPECT_NEAR(info.information[k], j[k], 0.03 * scale) << "entry " << k;
  }
  EXPECT_EQ(info.boards, 0b1111U);
  // The weak sigma from the closed form: the Schur complement's smallest eigenvalue.
  const double a = j[0] - j[2] * j[2] / j[8], b = j[1] - j[2] * j[5] / j[8],
               c = j[4] - j[5] * j[5] / j[8];
  const double weakest = 0.5 * (a + c) - std::sqrt(0.25 * (a - c) * (a - c) + b * b);
  EXPECT_NEAR(info.weak_sigma_m, 1.0 / std::sqrt(weakest), 0.03 / std::sqrt(weakest));
  // Four boards round the robot, two of them with a bearing: about a centimetre (1.2).
  EXPECT_LT(info.weak_sigma_m, 0.015);
}

TEST(FrameInformation, OneBoardLeavesTheDirectionAcrossItOpen) {
  const auto map = make_floor();
  const ha::BoardModelParams params;
  const double x = 1.6, y = 0.9, yaw = 0.8;
  const ha::BoardFeatures o = seen(x, y, yaw);
  // Only board 1 (at 1.5, 2.5) counts: its area says how far, its bearing the heading.
  ASSERT_NE(o.angle_mask & 0b0010U, 0U);
  const ha::FrameInformation info =
      ha::frame_information(*map, o, ha::Pose2{x, y, yaw}, params, 0b1101U);
  EXPECT_EQ(info.boards, 0b0010U);
  EXPECT_FALSE(std::isfinite(info.weak_sigma_m));
  // The open direction is across the line of sight (modulo a half turn).
  const double sight = std::atan2(kBoards[3] - y, kBoards[2] - x);
  const double off = ha::wrap_angle_rad(2.0 * (info.weak_axis_rad - sight - 0.5 * ha::kPi));
  EXPECT_LT(std::fabs(off), 0.1);
  // Boards 1 and 2 (at 3.5, 1.0) pin it down again.
  const ha::FrameInformation two =
      ha::frame_information(*map, o, ha::Pose2{x, y, yaw}, params, 0b1001U);
  EXPECT_TRUE(std::isfinite(two.weak_sigma_m));
  EXPECT_LT(two.weak_sigma_m, 0.1);
}

TEST(FrameInformation, NothingObservedOrNoMapFixesNothing) {
  const auto map = make_floor();
  const ha::BoardModelParams params;
  const ha::BoardFeatures none;
  EXPECT_FALSE(std::isfinite(
      ha::frame_information(*map, none, ha::Pose2{1.0, 1.0, 0.0}, params).weak_sigma_m));
  const ha::ForwardMap absent;
  EXPECT_FALSE(std::isfinite(
      ha::frame_information(absent, seen(1.0, 1.0, 0.0), ha::Pose2{1.0, 1.0, 0.0}, params)
          .weak_sigma_m));
}
