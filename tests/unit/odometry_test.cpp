// Differential-drive odometry: counter wrap, ticks to motion, and the exact circular arc.
#include "harmoloc/algorithms/odometry.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

#include "harmoloc/algorithms/geometry.hpp"

namespace ha = harmoloc::algorithms;
using ha::kPi;

namespace {

void expect_pose_near(const ha::Pose2& got, double x, double y, double yaw, double tol) {
  EXPECT_NEAR(got.x_m, x, tol);
  EXPECT_NEAR(got.y_m, y, tol);
  EXPECT_NEAR(ha::wrap_angle_rad(got.yaw_rad - yaw), 0.0, tol)
      << "yaw " << got.yaw_rad << " vs " << yaw;
}

}  // namespace

TEST(WrapAngle, Range) {
  EXPECT_DOUBLE_EQ(ha::wrap_angle_rad(0.0), 0.0);
  EXPECT_NEAR(ha::wrap_angle_rad(3.0 * kPi / 2.0), -kPi / 2.0, 1e-12);
  EXPECT_NEAR(ha::wrap_angle_rad(-3.0 * kPi / 2.0), kPi / 2.0, 1e-12);
  EXPECT_NEAR(ha::wrap_angle_rad(kPi), -kPi, 1e-12);  // [-pi, pi)
  EXPECT_NEAR(ha::wrap_angle_rad(-kPi), -kPi, 1e-12);
  EXPECT_NEAR(ha::wrap_angle_rad(20.0 * kPi + 0.25), 0.25, 1e-9);
  for (double a = -50.0; a < 50.0; a += 0.37) {
    const double w = ha::wrap_angle_rad(a);
    EXPECT_GE(w, -kPi);
    EXPECT_LT(w, kPi);
    EXPECT_NEAR(std::remainder(w - a, 2.0 * kPi), 0.0, 1e-9);
  }
}

TEST(WrappedDelta, SixteenBitsBothDirections) {
  EXPECT_EQ(ha::wrapped_delta(65530, 5, 16), 11);
  EXPECT_EQ(ha::wrapped_delta(5, 65530, 16), -11);
  EXPECT_EQ(ha::wrapped_delta(100, 250, 16), 150);
  EXPECT_EQ(ha::wrapped_delta(250, 100, 16), -150);
  EXPECT_EQ(ha::wrapped_delta(0, 32767, 16), 32767);
  EXPECT_EQ(ha::wrapped_delta(0, 32768, 16), -32768);  // range is [-2^15, 2^15)
  // Bits above the counter width are ignored; a sign-extended int16 on the wire is the same.
  EXPECT_EQ(ha::wrapped_delta(0xFFFFFFFDU, 2U, 16), 5);  // -3 -> 2
  EXPECT_EQ(ha::wrapped_delta(0x0001FFFFU, 0x00000001U, 16), 2);
}

TEST(WrappedDelta, ThirtyTwoBitsBothDirections) {
  EXPECT_EQ(ha::wrapped_delta(0xFFFFFFF0U, 0x10U, 32), 32);
  EXPECT_EQ(ha::wrapped_delta(0x10U, 0xFFFFFFF0U, 32), -32);
  EXPECT_EQ(ha::wrapped_delta(0x7FFFFFFFU, 0x80000000U, 32), 1);  // signed overflow on the wire
  EXPECT_EQ(ha::wrapped_delta(0x80000000U, 0x7FFFFFFFU, 32), -1);
  EXPECT_EQ(ha::wrapped_delta(0U, 0x7FFFFFFFU, 32), 2147483647LL);
  EXPECT_EQ(ha::wrapped_delta(0U, 0x80000000U, 32), -2147483648LL);
  EXPECT_EQ(ha::wrapped_delta(123456789U, 123456789U, 32), 0);
}

TEST(WrappedDelta, EightAndTwelveBits) {
  EXPECT_EQ(ha::wrapped_delta(250, 4, 8), 10);
  EXPECT_EQ(ha::wrapped_delta(4, 250, 8), -10);
  EXPECT_EQ(ha::wrapped_delta(0, 127, 8), 127);
  EXPECT_EQ(ha::wrapped_delta(0, 128, 8), -128);
  EXPECT_EQ(ha::wrapped_delta(4090, 5, 12), 11);
  EXPECT_EQ(ha::wrapped_delta(5, 4090, 12), -11);
  EXPECT_EQ(ha::wrapped_delta(0, 2047, 12), 2047);
  EXPECT_EQ(ha::wrapped_delta(0, 2048, 12), -2048);
  EXPECT_EQ(ha::wrapped_delta(1, 0, 1), -1);  // 1-bit: [-1, 1)
}

TEST(WrappedDelta, RandomAgainstModularArithmetic) {
  std::uint64_t state = 0x12345;
  for (int i = 0; i < 10000; ++i) {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    const auto bits = static_cast<std::uint8_t>(1 + (state >> 59) % 32);  // 1..32
    const auto prev = static_cast<std::uint32_t>(state >> 16);
    const std::int64_t half = std::int64_t{1} << (bits - 1);
    const std::int64_t true_delta =
        static_cast<std::int64_t>((state >> 8) % static_cast<std::uint64_t>(2 * half)) - half;
    const std::uint64_t mod = std::uint64_t{1} << bits;
    const auto cur = static_cast<std::uint32_t>(
        (static_cast<std::uint64_t>(prev) + static_cast<std::uint64_t>(true_delta)) & (mod - 1U));
    ASSERT_EQ(ha::wrapped_delta(prev & static_cast<std::uint32_t>(mod - 1U), cur, bits), true_delta)
        << "bits " << int{bits} << " prev " << prev;
  }
}

TEST(OdometryFromTicks, StraightSpinAndDirections) {
  ha::DiffDriveGeometry g;
  g.wheel_radius_m = 0.05;
  g.track_m = 0.30;
  g.ticks_per_rev = 4096.0;
  const double circumference = 2.0 * kPi * 0.05;

  ha::OdometryDelta d = ha::odometry_from_ticks(g, 4096, 4096);  // one turn of each wheel
  EXPECT_NEAR(d.distance_m, circumference, 1e-12);
  EXPECT_NEAR(d.yaw_rad, 0.0, 1e-15);

  d = ha::odometry_from_ticks(g, -2048, -2048);  // half a turn backwards
  EXPECT_NEAR(d.distance_m, -0.5 * circumference, 1e-12);
  EXPECT_NEAR(d.yaw_rad, 0.0, 1e-15);

  // Spin in place to the left: right wheel forward a quarter turn, left backward.
  d = ha::odometry_from_ticks(g, -1024, 1024);
  EXPECT_NEAR(d.distance_m, 0.0, 1e-15);
  EXPECT_NEAR(d.yaw_rad, 2.0 * (0.25 * circumference) / 0.30, 1e-12);  // = pi/6
  EXPECT_NEAR(d.yaw_rad, kPi / 6.0, 1e-12);
  d = ha::odometry_from_ticks(g, 1024, -1024);
  EXPECT_NEAR(d.yaw_rad, -kPi / 6.0, 1e-12);

  // Only the right wheel turns: pivot about the left wheel, yaw positive (left turn).
  d = ha::odometry_from_ticks(g, 0, 4096);
  EXPECT_NEAR(d.distance_m, 0.5 * circumference, 1e-12);
  EXPECT_NEAR(d.yaw_rad, circumference / 0.30, 1e-12);

  // A left wheel that counts down going forward.
  ha::DiffDriveGeometry flipped = g;
  flipped.left_direction = -1;
  d = ha::odometry_from_ticks(flipped, -4096, 4096);
  EXPECT_NEAR(d.distance_m, circumference, 1e-12);
  EXPECT_NEAR(d.yaw_rad, 0.0, 1e-15);
  flipped.left_direction = 1;
  flipped.right_direction = -1;
  d = ha::odometry_from_ticks(flipped, 4096, -4096);
  EXPECT_NEAR(d.distance_m, circumference, 1e-12);
  flipped.left_direction = -1;
  d = ha::odometry_from_ticks(flipped, -4096, -4096);  // both count down going forward
  EXPECT_NEAR(d.distance_m, circumference, 1e-12);
  EXPECT_NEAR(d.yaw_rad, 0.0, 1e-15);
  d = ha::odometry_from_ticks(flipped, 1024, -1024);  // spin to the left
  EXPECT_NEAR(d.distance_m, 0.0, 1e-15);
  EXPECT_NEAR(d.yaw_rad, kPi / 6.0, 1e-12);
}

TEST(ApplyArc, QuarterCircleOfRadiusOne) {
  const ha::Pose2 end =
      ha::apply_arc(ha::Pose2{0.0, 0.0, 0.0}, ha::OdometryDelta{kPi / 2.0, kPi / 2.0});
  expect_pose_near(end, 1.0, 1.0, kPi / 2.0, 1e-12);
  // The same to the right, backwards along the arc, and from a rotated and shifted start.
  expect_pose_near(ha::apply_arc(ha::Pose2{0, 0, 0}, ha::OdometryDelta{kPi / 2.0, -kPi / 2.0}), 1.0,
                   -1.0, -kPi / 2.0, 1e-12);
  expect_pose_near(ha::apply_arc(ha::Pose2{0, 0, 0}, ha::OdometryDelta{-kPi / 2.0, kPi / 2.0}),
                   -1.0, -1.0, kPi / 2.0, 1e-12);
  // Start (2, 3) heading +y, left quarter circle of radius 0.5: centre (1.5, 3), end (1.5, 3.5)
  // heading -x.
  expect_pose_near(
      ha::apply_arc(ha::Pose2{2.0, 3.0, kPi / 2.0}, ha::OdometryDelta{kPi / 4.0, kPi / 2.0}), 1.5,
      3.5, kPi, 1e-12);
}

TEST(ApplyArc, StraightFullCircleAndContinuityAtZeroYaw) {
  expect_pose_near(ha::apply_arc(ha::Pose2{1.0, 2.0, kPi / 6.0}, ha::OdometryDelta{2.0, 0.0}),
                   1.0 + std::sqrt(3.0), 2.0 + 1.0, kPi / 6.0, 1e-12);
  // A whole circle comes back to the start.
  expect_pose_near(
      ha::apply_arc(ha::Pose2{0.3, -0.2, 1.0}, ha::OdometryDelta{2.0 * kPi * 0.7, 2.0 * kPi}), 0.3,
      -0.2, 1.0, 1e-12);
  // Pure rotation does not move.
  expect_pose_near(ha::apply_arc(ha::Pose2{0.3, -0.2, 1.0}, ha::OdometryDelta{0.0, 0.4}), 0.3, -0.2,
                   1.4, 1e-15);
  // Tiny yaw: the arc formula and the straight-line branch agree (no jump at the switch-over).
  for (double yaw : {1e-12, 1e-10, 1e-9, 2e-9, 1e-8, 1e-7}) {
    const ha::Pose2 a = ha::apply_arc(ha::Pose2{0, 0, 0.7}, ha::OdometryDelta{0.5, yaw});
    // Exact chord: length 2 r sin(yaw/2) along the mid heading.
    const double r = 0.5 / yaw;
    const double chord = 2.0 * r * std::sin(0.5 * yaw);
    // 1 um: the arc formula loses a few digits to cancellation at huge radii, nothing more.
    EXPECT_NEAR(a.x_m, chord * std::cos(0.7 + 0.5 * yaw), 1e-6) << yaw;
    EXPECT_NEAR(a.y_m, chord * std::sin(0.7 + 0.5 * yaw), 1e-6) << yaw;
  }
}

TEST(ApplyArc, ManySmallStepsEqualOneBigStep) {
  const ha::Pose2 start{0.4, -1.1, 2.9};  // near +pi: the yaw wraps on the way
  for (const ha::OdometryDelta big :
       {ha::OdometryDelta{3.0, 1.2}, ha::OdometryDelta{-1.5, -4.0}, ha::OdometryDelta{2.0, 0.0}}) {
    const ha::Pose2 once = ha::apply_arc(start, big);
    ha::Pose2 stepped = start;
    const int n = 1000;
    for (int i = 0; i < n; ++i) {
      stepped = ha::apply_arc(stepped, ha::OdometryDelta{big.distance_m / n, big.yaw_rad / n});
      ASSERT_GE(stepped.yaw_rad, -kPi);
      ASSERT_LT(stepped.yaw_rad, kPi);
    }
    expect_pose_near(stepped, once.x_m, once.y_m, once.yaw_rad, 1e-9);
  }
}

TEST(ApplyArc, TicksToArcMatchWheelPaths) {
  // Constant wheel speeds: the left and right wheels run on concentric circles about the same
  // centre. Compute the end pose from the wheel paths directly.
  ha::DiffDriveGeometry g;
  g.wheel_radius_m = 0.04;
  g.track_m = 0.25;
  g.ticks_per_rev = 1000.0;
  const std::int64_t left = 3000, right = 5000;
  const double sl = left * 2.0 * kPi * 0.04 / 1000.0, sr = right * 2.0 * kPi * 0.04 / 1000.0;
  const double yaw = (sr - sl) / 0.25;
  const double r_centre =
      0.25 * (sl + sr) / (2.0 * (sr - sl));  // turning radius of the axle centre
  // Start at origin heading +x; the centre of rotation is (0, r_centre).
  const double x = r_centre * std::sin(yaw), y = r_centre * (1.0 - std::cos(yaw));
  const ha::Pose2 end = ha::apply_arc(ha::Pose2{}, ha::odometry_from_ticks(g, left, right));
  expect_pose_near(end, x, y, yaw, 1e-12);
}
