// The training run's frames placed by odometry between the labels (route_placement.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "harmoloc/algorithms/random.hpp"
#include "harmoloc/algorithms/route_placement.hpp"

namespace harmoloc::algorithms {
namespace {

struct SimRun {
  std::vector<double> t;
  std::vector<Pose2> truth;
  std::vector<OdometrySample> odometry;
  DiffDriveGeometry geometry;
};

// A robot driving an S-curve forth (forward) and back (reversing), 100 Hz encoders with 1% slip
// and a 0.4% radius error on one wheel, frames at 30 Hz.
SimRun make_run(std::uint64_t seed) {
  SimRun run;
  run.geometry.wheel_radius_m = 0.05;
  run.geometry.track_m = 0.3;
  run.geometry.ticks_per_rev = 2048;
  Pcg32 rng(seed, 7);
  const double dt = 0.01;
  Pose2 p{1.0, 0.5, 0.3};
  double left = 0.0, right = 0.0;
  const double m_per_tick = 2.0 * kPi * 0.05 / 2048.0;
  const int steps = 6000;  // 60 s
  std::vector<Pose2> poses;
  std::vector<double> times;
  for (int i = 0; i <= steps; ++i) {
    const double t = i * dt;
    times.push_back(t);
    poses.push_back(p);
    run.odometry.push_back(OdometrySample{t, static_cast<std::int64_t>(std::floor(left)),
                                          static_cast<std::int64_t>(std::floor(right))});
    const double v = t < 30.0 ? 0.12 : -0.12;
    const double w = 0.25 * std::sin(t * 0.4);
    const OdometryDelta d{v * dt, (t < 30.0 ? w : -w) * dt};
    const double dl = d.distance_m - 0.5 * d.yaw_rad * 0.3,
                 dr = d.distance_m + 0.5 * d.yaw_rad * 0.3;
    left += dl * (1.004 + 0.01 * rng.normal()) / m_per_tick;
    right += dr * (1.0 + 0.01 * rng.normal()) / m_per_tick;
    p = apply_arc(p, d);
  }
  for (int k = 0; k * (1.0 / 30.0) <= 60.0; ++k) {
    const double t = k / 30.0;
    run.t.push_back(t);
    run.truth.push_back(poses[static_cast<std::size_t>(std::llround(t / dt))]);
  }
  return run;
}

std::vector<PlacementLabel> labels_every(const SimRun& run, std::size_t every, bool with_yaw,
                                         std::uint64_t seed) {
  Pcg32 rng(seed, 9);
  std::vector<PlacementLabel> labels;
  for (std::size_t k = 5; k < run.t.size(); k += every) {
    PlacementLabel l;
    l.t_s = run.t[k];
    l.x_m = run.truth[k].x_m + 0.003 * rng.normal();
    l.y_m = run.truth[k].y_m + 0.003 * rng.normal();
    l.yaw_rad = with_yaw ? run.truth[k].yaw_rad : 0.0;
    l.has_yaw = with_yaw;
    labels.push_back(l);
  }
  return labels;
}

TEST(RoutePlacement, PlacesFramesBetweenSparseLabelsWithoutHeading) {
  const SimRun run = make_run(1);
  // One label every 3 s: 36 cm of travel between labels, no heading.
  const auto labels = labels_every(run, 90, false, 2);
  const PlacementResult r = place_by_odometry(run.t, run.odometry, run.geometry, labels);
  ASSERT_EQ(r.poses.size(), run.t.size());
  double se = 0.0, sh = 0.0, worst = 0.0;
  std::size_t n = 0;
  for (std::size_t k = 0; k < run.t.size(); ++k) {
    if (run.t[k] < labels.front().t_s || run.t[k] > labels.back().t_s) continue;
    const double e =
        std::hypot(r.poses[k].x_m - run.truth[k].x_m, r.poses[k].y_m - run.truth[k].y_m);
    se += e * e;
    worst = std::max(worst, e);
    const double h = wrap_angle_rad(r.poses[k].yaw_rad - run.truth[k].yaw_rad);
    sh += h * h;
    ++n;
  }
  std::printf("rmse %.5f worst %.5f heading %.3f deg iters %d\n",
              std::sqrt(se / static_cast<double>(n)), worst,
              std::sqrt(sh / static_cast<double>(n)) * 180.0 / kPi, r.gauss_newton_iterations);
  EXPECT_LT(std::sqrt(se / static_cast<double>(n)), 0.005);
  EXPECT_LT(worst, 0.015);
  EXPECT_LT(std::sqrt(sh / static_cast<double>(n)) * 180.0 / kPi, 1.5);
  // Dead reckoning alone over the minute is much worse: the labels did the work.
  for (std::size_t l = 1; l + 1 < labels.size(); ++l) EXPECT_LT(r.label_residual_m[l], 0.03);
  EXPECT_LT(r.travel_m.back(), 7.3);
  EXPECT_GT(r.travel_m.back(), 7.0);
}

TEST(RoutePlacement, HeadingLabelsAreUsedWhenPresent) {
  const SimRun run = make_run(3);
  const auto labels = labels_every(run, 90, true, 4);
  const PlacementResult r = place_by_odometry(run.t, run.odometry, run.geometry, labels);
  double sh = 0.0;
  for (std::size_t k = 0; k < run.t.size(); ++k) {
    const double h = wrap_angle_rad(r.poses[k].yaw_rad - run.truth[k].yaw_rad);
    sh += h * h;
  }
  EXPECT_LT(std::sqrt(sh / static_cast<double>(run.t.size())) * 180.0 / kPi, 1.5);
}

TEST(RoutePlacement, LeaveOneOutFindsAMisplacedLabel) {
  const SimRun run = make_run(5);
  auto labels = labels_every(run, 90, false, 6);
  labels[7].x_m += 0.30;  // a label typed 30 cm off
  const PlacementResult r = place_by_odometry(run.t, run.odometry, run.geometry, labels);
  std::size_t worst = 0;
  for (std::size_t l = 0; l < labels.size(); ++l)
    if (r.label_residual_m[l] > r.label_residual_m[worst]) worst = l;
  EXPECT_EQ(worst, 7U);
  EXPECT_GT(r.label_residual_m[7], 0.25);
}

TEST(RoutePlacement, UnwrapsSixteenBitCounters) {
  const std::vector<double> t{0.0, 0.1, 0.2, 0.3};
  const std::vector<std::uint32_t> left{65530, 65535, 4, 20}, right{10, 5, 65534, 65500};
  const auto u = unwrap_counters(t, left, right, 16);
  ASSERT_EQ(u.size(), 4U);
  EXPECT_EQ(u[3].left_ticks, 26);
  EXPECT_EQ(u[3].right_ticks, -46);
}

TEST(RoutePlacement, RejectsTooFewLabelsAndDisorderedOnes) {
  const SimRun run = make_run(7);
  auto labels = labels_every(run, 90, false, 8);
  EXPECT_THROW(place_by_odometry(run.t, run.odometry, run.geometry, {labels.front()}),
               std::invalid_argument);
  std::swap(labels[2], labels[3]);
  EXPECT_THROW(place_by_odometry(run.t, run.odometry, run.geometry, labels), std::invalid_argument);
  EXPECT_THROW(place_by_odometry(run.t, {}, run.geometry, labels), std::invalid_argument);
}

}  // namespace
}  // namespace harmoloc::algorithms
