// The wheel odometry calibrated from a labelled training run (odometry_calibration.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "harmoloc/algorithms/odometry_calibration.hpp"
#include "harmoloc/algorithms/random.hpp"

namespace harmoloc::algorithms {
namespace {

struct Robot {
  double left_error = 0.0;  // the left encoder counts this much more than the wheel travels
  double right_error = 0.0;
  double track_m = 0.2;  // the true track (the configured one is 0.2)
  bool turns = true;     // a loop; otherwise a straight line forth and back
};

struct LabelledRun {
  std::vector<OdometrySample> odometry;
  std::vector<PlacementLabel> labels;
  DiffDriveGeometry configured;
};

// 100 Hz encoders with 1% slip, labels every 0.5 s with 3 mm noise and no heading.
LabelledRun make_run(const Robot& robot, std::uint64_t seed) {
  LabelledRun run;
  run.configured.wheel_radius_m = 0.05;
  run.configured.track_m = 0.2;
  run.configured.ticks_per_rev = 2048;
  Pcg32 rng(seed, 7);
  const double dt = 0.01, m_per_tick = 2.0 * kPi * 0.05 / 2048.0;
  Pose2 p{2.0, 1.0, 0.0};
  double left = 0.0, right = 0.0;
  for (int i = 0; i <= 9000; ++i) {  // 90 s
    const double t = i * dt;
    run.odometry.push_back(OdometrySample{t, static_cast<std::int64_t>(std::floor(left)),
                                          static_cast<std::int64_t>(std::floor(right))});
    if (i % 50 == 10) {
      run.labels.push_back(PlacementLabel{t, p.x_m + 0.003 * rng.normal(),
                                          p.y_m + 0.003 * rng.normal(), 0.0, false});
    }
    // A loop of two straights and two half circles, or a straight line forth and back.
    double v = 0.15, w = 0.0;
    if (robot.turns) {
      const double phase = std::fmod(t, 30.0);
      w = (phase > 10.0 && phase < 15.0) || phase > 25.0 ? kPi / 5.0 : 0.0;
    } else {
      v = std::fmod(t, 30.0) < 15.0 ? 0.15 : -0.15;
    }
    const OdometryDelta d{v * dt, w * dt};
    const double dl = d.distance_m - 0.5 * d.yaw_rad * robot.track_m;
    const double dr = d.distance_m + 0.5 * d.yaw_rad * robot.track_m;
    left += dl * (1.0 + robot.left_error + 0.01 * rng.normal()) / m_per_tick;
    right += dr * (1.0 + robot.right_error + 0.01 * rng.normal()) / m_per_tick;
    p = apply_arc(p, d);
  }
  return run;
}

TEST(OdometryCalibration, RecoversUnequalWheelsAndTheTrack) {
  Robot robot;
  robot.left_error = 0.006;
  robot.right_error = -0.004;
  robot.track_m = 0.206;
  const LabelledRun run = make_run(robot, 1);
  const OdometryCalibration c = calibrate_odometry(run.odometry, run.configured, run.labels);
  ASSERT_TRUE(c.used);
  std::printf("scales %.5f %.5f %.5f misfit %.4f -> %.4f over %d stretches\n", c.scale.left,
              c.scale.right, c.scale.track, c.misfit_before_m, c.misfit_after_m, c.stretches);
  EXPECT_GT(c.stretches, 10);
  // Within 0.15% (3 mm over 2 m, the labels' own noise) of the truth; configured is 0.5% off.
  EXPECT_NEAR(c.scale.left, 1.0 / 1.006, 0.0015);
  EXPECT_NEAR(c.scale.right, 1.0 / 0.996, 0.0015);
  EXPECT_NEAR(c.scale.track, 1.03, 0.005);
  // The stretches fit their labels to the labels' own noise once calibrated.
  EXPECT_GT(c.misfit_before_m, 0.0075);
  EXPECT_LT(c.misfit_after_m, 0.005);
}

TEST(OdometryCalibration, ExactWheelsStayAsConfigured) {
  const LabelledRun run = make_run(Robot{}, 2);
  const OdometryCalibration c = calibrate_odometry(run.odometry, run.configured, run.labels);
  ASSERT_TRUE(c.used);
  EXPECT_NEAR(c.scale.left, 1.0, 0.001);
  EXPECT_NEAR(c.scale.right, 1.0, 0.001);
  EXPECT_NEAR(c.scale.track, 1.0, 0.005);
  EXPECT_LE(c.misfit_after_m, c.misfit_before_m);
}

TEST(OdometryCalibration, WithoutTurnsTheTrackKeepsItsConfiguredValue) {
  Robot robot;
  robot.turns = false;
  robot.left_error = 0.01;
  robot.right_error = 0.01;
  robot.track_m = 0.25;  // not observable on a straight line
  const LabelledRun run = make_run(robot, 3);
  const OdometryCalibration c = calibrate_odometry(run.odometry, run.configured, run.labels);
  ASSERT_TRUE(c.used);
  EXPECT_NEAR(c.scale.left, 1.0 / 1.01, 0.002);
  EXPECT_NEAR(c.scale.right, 1.0 / 1.01, 0.002);
  EXPECT_NEAR(c.scale.track, 1.0, 0.01);
}

TEST(OdometryCalibration, TooFewLabelsSayNothing) {
  LabelledRun run = make_run(Robot{}, 4);
  run.labels.resize(3);
  const OdometryCalibration c = calibrate_odometry(run.odometry, run.configured, run.labels);
  EXPECT_FALSE(c.used);
  EXPECT_EQ(c.scale.left, 1.0);
  EXPECT_EQ(c.scale.track, 1.0);
}

TEST(OdometryCalibration, CalibratedGeometryScalesEachWheelAndTheTrack) {
  DiffDriveGeometry g;
  g.wheel_radius_m = 0.05;
  g.track_m = 0.3;
  g.ticks_per_rev = 1000;
  const DiffDriveGeometry c = calibrated(g, OdometryScale{0.99, 1.02, 1.1});
  const OdometryDelta d = odometry_from_ticks(c, 1000, 1000);
  const double turn = 2.0 * kPi * 0.05;
  EXPECT_NEAR(d.distance_m, 0.5 * (0.99 + 1.02) * turn, 1e-12);
  EXPECT_NEAR(d.yaw_rad, (1.02 - 0.99) * turn / 0.33, 1e-12);
}

}  // namespace
}  // namespace harmoloc::algorithms
