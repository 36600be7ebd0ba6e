// sim_host::estimate_label_offset: the clock offset between an external reference's labels and
// the robot's wheel odometry, from the distances between labels (harmoloc-train --label-offset
// auto). Synthetic runs: a robot that drives, stops and turns shows the offset; one at constant
// speed on a straight line cannot, and the estimator must say so instead of guessing.
#include "harmoloc/sim_host/label_offset.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

namespace hs = harmoloc::sim_host;
namespace hd = harmoloc::dataset;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr std::uint64_t kT0 = 1767225600000000000ULL;

struct SyntheticRun {
  hs::OdometryTrack odometry;
  std::vector<hd::StampedPose> truth;  // the true pose at every odometry sample
};

// 60 s at 100 Hz; the wheel speeds (m/s) at time t come from @p wheels.
template <typename Wheels>
SyntheticRun drive(Wheels wheels) {
  SyntheticRun r;
  hs::OdometryTrack& o = r.odometry;
  o.geometry.wheel_radius_m = 0.05;
  o.geometry.track_m = 0.3;
  o.geometry.ticks_per_rev = 4096;
  const double per_tick = 2.0 * kPi * 0.05 / 4096.0;
  double x = 0.5, y = 0.5, yaw = 0.3, left_m = 0.0, right_m = 0.0;
  for (int i = 0; i <= 6000; ++i) {
    const double t = i * 0.01;
    if (i > 0) {
      double vl = 0.0, vr = 0.0;
      wheels(t, vl, vr);
      const double dl = vl * 0.01, dr = vr * 0.01, ds = 0.5 * (dl + dr), dyaw = (dr - dl) / 0.3;
      x += ds * std::cos(yaw + 0.5 * dyaw);
      y += ds * std::sin(yaw + 0.5 * dyaw);
      yaw += dyaw;
      left_m += dl;
      right_m += dr;
    }
    o.timestamp_ns.push_back(kT0 + static_cast<std::uint64_t>(i) * 10'000'000ULL);
    o.left_ticks.push_back(std::llround(left_m / per_tick));
    o.right_ticks.push_back(std::llround(right_m / per_tick));
    r.truth.push_back(hd::StampedPose{static_cast<double>(kT0 / 1000000000ULL) + t,
                                      harmoloc::algorithms::Pose2{x, y, yaw}});
  }
  return r;
}

// Labels every @p every samples (from the second second on), their times moved by @p shift_s as
// a reference whose clock runs that far ahead would stamp them; 3 mm of deterministic noise.
std::vector<hd::StampedPose> labels_of(const SyntheticRun& r, int every, double shift_s) {
  std::vector<hd::StampedPose> out;
  std::uint32_t s = 7;
  for (std::size_t i = 200; i + 200 < r.truth.size(); i += static_cast<std::size_t>(every)) {
    hd::StampedPose l = r.truth[i];
    s = s * 1664525U + 1013904223U;
    l.pose.x_m += 0.003 * ((s >> 8) % 2001 / 1000.0 - 1.0);
    s = s * 1664525U + 1013904223U;
    l.pose.y_m += 0.003 * ((s >> 8) % 2001 / 1000.0 - 1.0);
    l.t_s += shift_s;
    out.push_back(l);
  }
  return out;
}

// Drives 3 s, stops 1 s, turns on the spot, drives on: speed changes every few seconds.
void stop_and_go(double t, double& vl, double& vr) {
  const double phase = std::fmod(t, 6.0);
  if (phase < 3.0) {
    vl = vr = 0.2;
  } else if (phase < 4.0) {
    vl = vr = 0.0;
  } else if (phase < 5.0) {
    vl = -0.1;
    vr = 0.1;
  } else {
    vl = 0.15;
    vr = 0.25;
  }
}

TEST(LabelOffset, FindsTheOffsetOfAReferenceAheadOrBehind) {
  const SyntheticRun run = drive(stop_and_go);
  for (const double shift : {0.0, 0.35, -0.8, 1.5}) {
    const hs::LabelOffsetEstimate e =
        hs::estimate_label_offset(run.odometry, labels_of(run, 170, shift));
    ASSERT_TRUE(e.found) << "shift " << shift << ": " << e.why_not;
    EXPECT_NEAR(e.offset_s, -shift, 0.02) << "shift " << shift;
    EXPECT_LE(e.standard_error_s, 0.05);
    EXPECT_LT(e.rms_at_best_m, 0.01);
    if (shift != 0.0) {
      EXPECT_GT(e.rms_at_zero_m, 2.0 * e.rms_at_best_m);
    }
  }
}

TEST(LabelOffset, ConstantSpeedOnAStraightLineCannotShowIt) {
  const SyntheticRun run = drive([](double, double& vl, double& vr) { vl = vr = 0.1; });
  const hs::LabelOffsetEstimate e =
      hs::estimate_label_offset(run.odometry, labels_of(run, 170, 0.4));
  EXPECT_FALSE(e.found) << "estimated " << e.offset_s << " s +- " << e.standard_error_s;
  EXPECT_NE(e.why_not.find("does not show it"), std::string::npos) << e.why_not;
}

TEST(LabelOffset, AnOffsetBeyondTheSearchIsNotGuessed) {
  const SyntheticRun run = drive(stop_and_go);
  const hs::LabelOffsetEstimate e =
      hs::estimate_label_offset(run.odometry, labels_of(run, 170, 2.6), 2.0);
  EXPECT_FALSE(e.found);
}

TEST(LabelOffset, NeedsOdometryAndLabels) {
  const SyntheticRun run = drive(stop_and_go);
  EXPECT_FALSE(hs::estimate_label_offset(hs::OdometryTrack{}, labels_of(run, 170, 0.0)).found);
  EXPECT_FALSE(hs::estimate_label_offset(run.odometry, {}).found);
}

}  // namespace
