// Bearing calibration (algorithms/bearing_calibration.hpp): from the poses of a run and each
// board's centroid column alone, the column-to-angle law and the boards' places are found again
// on synthetic runs with a known lens, and frames or boards that cannot be trusted are left out.
#include "harmoloc/algorithms/bearing_calibration.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "harmoloc/algorithms/random.hpp"

namespace ha = harmoloc::algorithms;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr std::uint32_t kWidth = 640;

struct Board {
  double x_m, y_m;
};

// The true law, inverted by Newton's method: the column at which angle @p a is seen.
double column_of(double a1, double a3, double a) {
  double t = a / a1;
  for (int i = 0; i < 30; ++i) t -= ((a1 + a3 * t * t) * t - a) / (a1 + 3.0 * a3 * t * t);
  return t * kWidth + 0.5 * (kWidth - 1.0);
}

// A run along a gently curving line with a wandering heading past boards on both sides; each
// frame sees the boards inside the field of view, their centroid columns with @p noise_px.
std::vector<ha::BearingFrame> make_run(const std::vector<Board>& boards, double a1, double a3,
                                       double noise_px, std::uint64_t seed) {
  ha::Pcg32 rng(seed);
  std::vector<ha::BearingFrame> frames;
  const double half_fov = 0.5 * a1 + 0.125 * a3;
  for (int i = 0; i < 1500; ++i) {
    const double s = 0.004 * i;  // 6 m
    ha::BearingFrame f;
    f.pose = {s, 0.3 * std::sin(0.5 * s), 0.15 * std::cos(0.5 * s) + 0.2 * std::sin(1.7 * s)};
    f.areas.count = boards.size();
    f.areas.width_px = kWidth;
    for (std::size_t k = 0; k < boards.size(); ++k) {
      const double bearing = std::atan2(boards[k].y_m - f.pose.y_m, boards[k].x_m - f.pose.x_m);
      const double a = ha::wrap_angle_rad(f.pose.yaw_rad - bearing);  // to the right: positive
      if (std::fabs(a) > 0.95 * half_fov) continue;
      const double u = column_of(a1, a3, a) + noise_px * rng.normal();
      f.areas.pixels[k] = 400;
      f.areas.column_sum[k] = static_cast<std::uint64_t>(std::llround(u * 400.0));
    }
    frames.push_back(f);
  }
  return frames;
}

const std::vector<Board> kBoards{{3.0, 2.5}, {5.5, 2.0}, {8.0, -2.2}, {4.0, -3.0}, {9.0, 1.0}};

void expect_law(const ha::BearingCalibration& c, double a1, double a3, double tol_deg) {
  for (double t = -0.45; t <= 0.45; t += 0.05) {
    const double u = t * kWidth + 0.5 * (kWidth - 1.0);
    EXPECT_NEAR(c.angle_rad(u, kWidth) * 180.0 / kPi, ((a1 + a3 * t * t) * t) * 180.0 / kPi,
                tol_deg)
        << "t " << t;
  }
}

}  // namespace

TEST(BearingCalibration, FindsThePinholeLawAndTheBoards) {
  for (const double half_fov_deg : {25.0, 40.0}) {
    const double half = half_fov_deg * kPi / 180.0;
    const double a1 = 2.0 * std::atan(std::tan(half)) / 1.0;  // a pinhole's angle is nearly linear
    const double a3 = -0.1 * a1;
    const auto frames = make_run(kBoards, a1, a3, 0.0, 1);
    const ha::BearingCalibration c = ha::calibrate_bearings(frames);
    ASSERT_TRUE(c.ok);
    expect_law(c, a1, a3, 0.3);
    for (std::size_t k = 0; k < kBoards.size(); ++k) {
      if (!c.placements[k].placed) continue;
      EXPECT_NEAR(c.placements[k].x_m, kBoards[k].x_m, 0.05) << k << " fov " << half_fov_deg;
      EXPECT_NEAR(c.placements[k].y_m, kBoards[k].y_m, 0.05) << k << " fov " << half_fov_deg;
    }
    EXPECT_LT(c.rms_residual_rad, 0.2 * kPi / 180.0);
  }
}

TEST(BearingCalibration, FindsABarrelLawThroughCentroidNoise) {
  const double a1 = 1.1, a3 = 0.8 * a1;  // barrel: the edges of the frame hold more angle
  const auto frames = make_run(kBoards, a1, a3, 1.0, 2);
  const ha::BearingCalibration c = ha::calibrate_bearings(frames);
  ASSERT_TRUE(c.ok);
  expect_law(c, a1, a3, 0.5);
  std::size_t placed = 0;
  for (std::size_t k = 0; k < kBoards.size(); ++k) {
    if (!c.placements[k].placed) continue;
    ++placed;
    EXPECT_NEAR(
        std::hypot(c.placements[k].x_m - kBoards[k].x_m, c.placements[k].y_m - kBoards[k].y_m), 0.0,
        0.10)
        << k;
  }
  EXPECT_GE(placed, 4U);
  // The residual is the centroid noise as an angle: 1 px of 640 is about 0.1 degree here.
  EXPECT_LT(c.rms_residual_rad, 0.3 * kPi / 180.0);
}

TEST(BearingCalibration, LeavesOutCutBlobsSmallBlobsAndUnmeasuredFrames) {
  const double a1 = 1.0, a3 = 0.2;
  auto frames = make_run(kBoards, a1, a3, 0.0, 3);
  // Corrupt every third frame's centroids in three ways the calibration must ignore.
  for (std::size_t i = 0; i < frames.size(); i += 3) {
    ha::AreaVector& a = frames[i].areas;
    for (std::size_t k = 0; k < a.count; ++k) a.column_sum[k] = 0;  // all at the left edge
    if (i % 9 == 0)
      a.width_px = 0;  // not measured
    else if (i % 9 == 3)
      a.side_pixels.fill(1);  // cut by the side
    else
      a.pixels.fill(10);  // too small to trust
  }
  const ha::BearingCalibration c = ha::calibrate_bearings(frames);
  ASSERT_TRUE(c.ok);
  expect_law(c, a1, a3, 0.3);
}

TEST(BearingCalibration, NotOkWithoutTwoBoardsToPlace) {
  const auto one = make_run({{3.0, 2.5}}, 1.0, 0.2, 0.0, 4);
  EXPECT_FALSE(ha::calibrate_bearings(one).ok);
  EXPECT_FALSE(ha::calibrate_bearings({}).ok);
  std::vector<ha::BearingFrame> unmeasured = make_run(kBoards, 1.0, 0.2, 0.0, 5);
  for (auto& f : unmeasured) f.areas.width_px = 0;
  EXPECT_FALSE(ha::calibrate_bearings(unmeasured).ok);
}
