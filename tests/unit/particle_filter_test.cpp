// Fixed-capacity particle filter (Guo & Li 2013): determinism, the motion noise model, the fix
// update, low-variance resampling, the estimate (weighted mean, circular yaw mean, covariance)
// and convergence on a known trajectory from a uniform heading.
#include "harmoloc/algorithms/particle_filter.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <tuple>
#include <vector>

#include "harmoloc/algorithms/geometry.hpp"
#include "harmoloc/algorithms/odometry.hpp"
#include "harmoloc/algorithms/random.hpp"

namespace ha = harmoloc::algorithms;
using ha::kPi;

namespace {

std::unique_ptr<ha::ParticleFilter> make_filter(std::size_t n, std::uint64_t seed,
                                                const ha::MotionNoise& noise = ha::MotionNoise{}) {
  auto pf = std::make_unique<ha::ParticleFilter>();
  pf->configure(n, seed, noise);
  return pf;
}

bool same_bits(double a, double b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

// Weighted mean and covariance from the accessors, written out here.
void reference_estimate(const ha::ParticleFilter& pf, double mean[3], double cov[9]) {
  double sw = 0.0, sx = 0.0, sy = 0.0, ss = 0.0, sc = 0.0;
  for (std::size_t i = 0; i < pf.size(); ++i) {
    const double w = pf.weight(i);
    sw += w;
    sx += w * pf.particle(i).x_m;
    sy += w * pf.particle(i).y_m;
    ss += w * std::sin(pf.particle(i).yaw_rad);
    sc += w * std::cos(pf.particle(i).yaw_rad);
  }
  mean[0] = sx / sw;
  mean[1] = sy / sw;
  mean[2] = std::atan2(ss, sc);
  for (int k = 0; k < 9; ++k) cov[k] = 0.0;
  for (std::size_t i = 0; i < pf.size(); ++i) {
    const double w = pf.weight(i) / sw;
    const double d[3] = {pf.particle(i).x_m - mean[0], pf.particle(i).y_m - mean[1],
                         std::remainder(pf.particle(i).yaw_rad - mean[2], 2.0 * kPi)};
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) cov[r * 3 + c] += w * d[r] * d[c];
    }
  }
}

void expect_estimate_matches_reference(const ha::ParticleFilter& pf) {
  double mean[3], cov[9];
  reference_estimate(pf, mean, cov);
  const ha::PoseEstimate e = pf.estimate();
  EXPECT_NEAR(e.mean.x_m, mean[0], 1e-12);
  EXPECT_NEAR(e.mean.y_m, mean[1], 1e-12);
  EXPECT_NEAR(std::remainder(e.mean.yaw_rad - mean[2], 2.0 * kPi), 0.0, 1e-12);
  for (int k = 0; k < 9; ++k)
    EXPECT_NEAR(e.covariance.m[k], cov[k], 1e-12) << "covariance element " << k;
  // Symmetric.
  EXPECT_NEAR(e.covariance(0, 1), e.covariance(1, 0), 1e-15);
  EXPECT_NEAR(e.covariance(0, 2), e.covariance(2, 0), 1e-15);
  EXPECT_NEAR(e.covariance(1, 2), e.covariance(2, 1), 1e-15);
}

}  // namespace

TEST(ParticleFilter, ConfigureClampsTheCount) {
  auto pf = make_filter(0, 1);
  EXPECT_EQ(pf->size(), 1U);
  pf->configure(100000, 1, ha::MotionNoise{});
  EXPECT_EQ(pf->size(), ha::ParticleFilter::kMaxParticles);
  pf->configure(300, 1, ha::MotionNoise{});
  EXPECT_EQ(pf->size(), 300U);
  EXPECT_FALSE(pf->initialized());
  pf->initialize(ha::Pose2{}, 0.1, 0.1, false);
  EXPECT_TRUE(pf->initialized());
}

TEST(ParticleFilter, SameSeedSameParticlesBitForBit) {
  auto run = [](std::uint64_t seed) {
    auto pf = make_filter(500, seed);
    pf->initialize(ha::Pose2{1.0, 2.0, 0.3}, 0.2, 0.5, true);
    for (int k = 0; k < 20; ++k) {
      pf->predict(ha::OdometryDelta{0.05, 0.01 * k});
      pf->update_position(1.0 + 0.04 * k, 2.0 + 0.01 * k, 0.05, 0.05);
      pf->resample_if_needed(0.5);
      if (k % 7 == 3) pf->diffuse(0.01, 0.02);
    }
    return pf;
  };
  const auto a = run(42), b = run(42), c = run(43);
  bool any_difference = false;
  for (std::size_t i = 0; i < a->size(); ++i) {
    ASSERT_TRUE(same_bits(a->particle(i).x_m, b->particle(i).x_m)) << i;
    ASSERT_TRUE(same_bits(a->particle(i).y_m, b->particle(i).y_m)) << i;
    ASSERT_TRUE(same_bits(a->particle(i).yaw_rad, b->particle(i).yaw_rad)) << i;
    ASSERT_TRUE(same_bits(a->weight(i), b->weight(i))) << i;
    any_difference = any_difference || !same_bits(a->particle(i).x_m, c->particle(i).x_m);
  }
  EXPECT_TRUE(any_difference) << "another seed gave the same particles";
  const ha::PoseEstimate ea = a->estimate(), eb = b->estimate();
  EXPECT_TRUE(same_bits(ea.mean.x_m, eb.mean.x_m));
  EXPECT_TRUE(same_bits(ea.mean.yaw_rad, eb.mean.yaw_rad));
  EXPECT_TRUE(same_bits(ea.covariance(0, 0), eb.covariance(0, 0)));
}

TEST(ParticleFilter, InitializeSpreadsAsAsked) {
  auto pf = make_filter(4000, 7);
  pf->initialize(ha::Pose2{1.0, -2.0, 0.5}, 0.2, 0.1, false);
  const ha::PoseEstimate e = pf->estimate();
  EXPECT_NEAR(e.mean.x_m, 1.0, 0.015);
  EXPECT_NEAR(e.mean.y_m, -2.0, 0.015);
  EXPECT_NEAR(e.mean.yaw_rad, 0.5, 0.008);
  EXPECT_NEAR(e.covariance(0, 0), 0.04, 0.04 * 0.1);
  EXPECT_NEAR(e.covariance(1, 1), 0.04, 0.04 * 0.1);
  EXPECT_NEAR(e.covariance(2, 2), 0.01, 0.01 * 0.1);
  EXPECT_NEAR(e.covariance(0, 1), 0.0, 0.003);
  EXPECT_NEAR(e.covariance(0, 2), 0.0, 0.0015);
  EXPECT_NEAR(e.effective_particles, 4000.0, 1e-6);
  for (std::size_t i = 0; i < pf->size(); ++i) ASSERT_DOUBLE_EQ(pf->weight(i), 1.0 / 4000.0);
  expect_estimate_matches_reference(*pf);

  // Uniform yaw: every particle's yaw in [-pi, pi), spread over the whole circle.
  pf->initialize(ha::Pose2{}, 0.1, 0.0, true);
  int quadrant[4] = {0, 0, 0, 0};
  for (std::size_t i = 0; i < pf->size(); ++i) {
    const double yaw = pf->particle(i).yaw_rad;
    ASSERT_GE(yaw, -kPi);
    ASSERT_LT(yaw, kPi);
    ++quadrant[static_cast<int>((yaw + kPi) / (kPi / 2.0)) % 4];
  }
  for (int q : quadrant) EXPECT_NEAR(q, 1000, 120);
}

TEST(ParticleFilter, InitializeBetweenSharesTheCloudByHalves) {
  auto pf = make_filter(4000, 7);
  pf->initialize_between(ha::Pose2{1.0, -2.0, 0.5}, ha::Pose2{1.3, -2.0, 0.7}, 0.02, 0.05, false);
  int near_a = 0, near_b = 0;
  double yaw_a = 0.0, yaw_b = 0.0;
  for (std::size_t i = 0; i < pf->size(); ++i) {
    const auto& q = pf->particle(i);
    ASSERT_NEAR(q.y_m, -2.0, 0.15);
    if (std::fabs(q.x_m - 1.0) < 0.1) {
      ++near_a;
      yaw_a += q.yaw_rad;
    } else if (std::fabs(q.x_m - 1.3) < 0.1) {
      ++near_b;
      yaw_b += q.yaw_rad;
    }
    ASSERT_DOUBLE_EQ(pf->weight(i), 1.0 / 4000.0);
  }
  EXPECT_EQ(near_a, 2000);
  EXPECT_EQ(near_b, 2000);
  EXPECT_NEAR(yaw_a / near_a, 0.5, 0.005);  // each half with its centre's heading
  EXPECT_NEAR(yaw_b / near_b, 0.7, 0.005);
  const ha::PoseEstimate e = pf->estimate();
  EXPECT_NEAR(e.mean.x_m, 1.15, 0.005);
}

TEST(ParticleFilter, InitializeBetweenSpreadsEachCentreByItsOwnSigma) {
  auto pf = make_filter(4000, 7);
  // A searched pose 1 cm wide and a fix 20 cm wide, 2 m apart: the halves do not mix.
  pf->initialize_between(ha::Pose2{0.0, 0.0, 0.0}, 0.01, ha::Pose2{2.0, 0.0, 0.0}, 0.20, 0.0,
                         false);
  double sum_a = 0.0, sum_b = 0.0;
  int n_a = 0, n_b = 0;
  for (std::size_t i = 0; i < pf->size(); ++i) {
    const auto& q = pf->particle(i);
    if (q.x_m < 1.0) {
      sum_a += q.y_m * q.y_m;
      ++n_a;
    } else {
      sum_b += q.y_m * q.y_m;
      ++n_b;
    }
  }
  ASSERT_EQ(n_a, 2000);
  ASSERT_EQ(n_b, 2000);
  EXPECT_NEAR(std::sqrt(sum_a / n_a), 0.01, 0.001);
  EXPECT_NEAR(std::sqrt(sum_b / n_b), 0.20, 0.015);
}

TEST(ParticleFilter, PointInitialisationHasZeroCovariance) {
  auto pf = make_filter(64, 3);
  pf->initialize(ha::Pose2{0.5, 0.25, -1.0}, 0.0, 0.0, false);
  const ha::PoseEstimate e = pf->estimate();
  EXPECT_DOUBLE_EQ(e.mean.x_m, 0.5);
  EXPECT_DOUBLE_EQ(e.mean.y_m, 0.25);
  EXPECT_NEAR(e.mean.yaw_rad, -1.0, 1e-12);
  for (double v : e.covariance.m) EXPECT_NEAR(v, 0.0, 1e-24);
}

TEST(ParticleFilter, CircularMeanAcrossPlusMinusPi) {
  for (double centre : {kPi - 0.01, -kPi + 0.003, kPi - 1e-9}) {
    auto pf = make_filter(2000, 11);
    pf->initialize(ha::Pose2{0.0, 0.0, centre}, 0.01, 0.05, false);
    // Particles lie on both sides of the +-pi cut.
    int positive = 0;
    for (std::size_t i = 0; i < pf->size(); ++i) positive += pf->particle(i).yaw_rad > 0.0 ? 1 : 0;
    EXPECT_GT(positive, 100);
    EXPECT_LT(positive, 1900);
    const ha::PoseEstimate e = pf->estimate();
    EXPECT_NEAR(std::remainder(e.mean.yaw_rad - centre, 2.0 * kPi), 0.0, 0.006) << centre;
    // The yaw variance is that of the spread (0.05^2), not of a linear mean across the cut.
    EXPECT_NEAR(e.covariance(2, 2), 0.0025, 0.0025 * 0.12) << centre;
    expect_estimate_matches_reference(*pf);
  }
}

TEST(ParticleFilter, UpdateWeightsAreGaussianPlusOutlierFloor) {
  auto pf = make_filter(300, 5);
  pf->initialize(ha::Pose2{0.0, 0.0, 0.0}, 0.3, 0.1, false);
  const double fx = 0.1, fy = -0.05, sigma = 0.2, outlier = 0.05;
  std::vector<double> expected(pf->size());
  double sum = 0.0;
  for (std::size_t i = 0; i < pf->size(); ++i) {
    const double dx = pf->particle(i).x_m - fx, dy = pf->particle(i).y_m - fy;
    expected[i] =
        (1.0 - outlier) * std::exp(-(dx * dx + dy * dy) / (2.0 * sigma * sigma)) + outlier;
    sum += expected[i];
  }
  pf->update_position(fx, fy, sigma, outlier);
  for (std::size_t i = 0; i < pf->size(); ++i)
    ASSERT_NEAR(pf->weight(i), expected[i] / sum, 1e-12) << i;
  expect_estimate_matches_reference(*pf);
  double sum_sq = 0.0;
  for (std::size_t i = 0; i < pf->size(); ++i) sum_sq += pf->weight(i) * pf->weight(i);
  EXPECT_NEAR(pf->estimate().effective_particles, 1.0 / sum_sq, 1e-9);
}

TEST(ParticleFilter, FixFarFromEveryParticleDoesNotProduceNaN) {
  auto pf = make_filter(100, 5);
  pf->initialize(ha::Pose2{0.0, 0.0, 0.0}, 0.01, 0.01, false);
  pf->update_position(100.0, 100.0, 0.01, 0.0);  // every weight underflows to 0
  for (std::size_t i = 0; i < pf->size(); ++i) ASSERT_DOUBLE_EQ(pf->weight(i), 0.01);
  const ha::PoseEstimate e = pf->estimate();
  EXPECT_TRUE(std::isfinite(e.mean.x_m));
  EXPECT_NEAR(e.mean.x_m, 0.0, 0.01);
  // With an outlier floor, a wild fix leaves the weights (nearly) equal.
  pf->update_position(100.0, 100.0, 0.01, 0.05);
  EXPECT_NEAR(pf->estimate().effective_particles, 100.0, 1e-6);
}

// A second hypothesis beside the cloud: count particles drawn around it share the weight given,
// so the published mean hardly moves; evidence for it over a few frames carries the cloud there,
// and evidence against it leaves the cloud where it was.
TEST(ParticleFilter, ReplaceSomeAddsAWeakSecondHypothesisThatEvidenceCanCarry) {
  const ha::Pose2 here{0.0, 0.0, 0.0}, there{2.0, 1.0, 1.0};
  const auto near_there = [&](const ha::ParticleFilter& pf, std::size_t i) {
    return std::hypot(pf.particle(i).x_m - there.x_m, pf.particle(i).y_m - there.y_m) < 0.1;
  };
  for (const bool evidence_for_it : {true, false}) {
    auto pf = make_filter(1024, 9);
    pf->initialize(here, 0.02, 0.01, false);
    pf->replace_some(there, 0.02, 0.02, 32, 1e-3);
    std::size_t moved = 0;
    double moved_weight = 0.0, total = 0.0;
    for (std::size_t i = 0; i < pf->size(); ++i) {
      total += pf->weight(i);
      if (!near_there(*pf, i)) continue;
      ++moved;
      moved_weight += pf->weight(i);
      EXPECT_NEAR(pf->particle(i).yaw_rad, there.yaw_rad, 0.1);
    }
    EXPECT_EQ(moved, 32U);
    EXPECT_NEAR(moved_weight, 1e-3, 1e-12);
    EXPECT_NEAR(total, 1.0, 1e-12);
    // 0.1% of the weight 2.2 m away moves the mean by about 2 mm.
    EXPECT_LT(std::hypot(pf->estimate().mean.x_m, pf->estimate().mean.y_m), 0.01);
    expect_estimate_matches_reference(*pf);
    const ha::Pose2 seen = evidence_for_it ? there : here;
    for (int frame = 0; frame < 5; ++frame) pf->update_position(seen.x_m, seen.y_m, 0.3, 0.0);
    const ha::Pose2 mean = pf->estimate().mean;
    EXPECT_LT(std::hypot(mean.x_m - seen.x_m, mean.y_m - seen.y_m), 0.1) << evidence_for_it;
  }
}

TEST(ParticleFilter, ReplaceSomeRefusesWhatItCannotDo) {
  auto pf = make_filter(64, 3);
  pf->replace_some(ha::Pose2{1.0, 1.0, 0.0}, 0.01, 0.01, 8, 0.5);  // not initialised
  EXPECT_FALSE(pf->initialized());
  pf->initialize(ha::Pose2{0.0, 0.0, 0.0}, 0.01, 0.01, false);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const double w : {0.0, 1.0, -0.5, 2.0, nan}) {
    pf->replace_some(ha::Pose2{1.0, 1.0, 0.0}, 0.01, 0.01, 8, w);
    for (std::size_t i = 0; i < pf->size(); ++i) ASSERT_LT(std::fabs(pf->particle(i).x_m), 0.1);
  }
  // More than the cloud: all but one move, and the one left keeps the rest of the weight.
  pf->replace_some(ha::Pose2{1.0, 1.0, 0.0}, 0.01, 0.01, 1000, 0.25);
  std::size_t stayed = 0;
  for (std::size_t i = 0; i < pf->size(); ++i) {
    if (std::fabs(pf->particle(i).x_m) < 0.1) {
      ++stayed;
      EXPECT_NEAR(pf->weight(i), 0.75, 1e-12);
    }
  }
  EXPECT_EQ(stayed, 1U);
}

TEST(ParticleFilter, ResamplingIsLowVarianceAndEqualisesWeights) {
  const std::size_t n = 400;
  auto pf = make_filter(n, 21);
  pf->initialize(ha::Pose2{0.0, 0.0, 0.0}, 0.5, 0.3, false);
  // Nothing to do while the weights are equal.
  EXPECT_FALSE(pf->resample_if_needed(0.5));
  pf->update_position(0.3, -0.2, 0.25, 0.0);
  std::map<std::tuple<double, double, double>, double> before;
  for (std::size_t i = 0; i < n; ++i) {
    before[{pf->particle(i).x_m, pf->particle(i).y_m, pf->particle(i).yaw_rad}] = pf->weight(i);
  }
  ASSERT_EQ(before.size(), n);
  const double n_eff = pf->estimate().effective_particles;
  ASSERT_LT(n_eff, 0.9 * static_cast<double>(n));
  EXPECT_FALSE(
      pf->resample_if_needed(n_eff / static_cast<double>(n) - 0.01));  // above the threshold
  EXPECT_TRUE(pf->resample_if_needed(1.0));
  EXPECT_EQ(pf->size(), n);
  std::map<std::tuple<double, double, double>, int> copies;
  for (std::size_t i = 0; i < n; ++i) {
    ASSERT_DOUBLE_EQ(pf->weight(i), 1.0 / static_cast<double>(n));
    const auto key =
        std::make_tuple(pf->particle(i).x_m, pf->particle(i).y_m, pf->particle(i).yaw_rad);
    ASSERT_EQ(before.count(key), 1U)
        << "resampled particle " << i << " is not one of the originals";
    ++copies[key];
  }
  // Systematic resampling: every particle gets floor(N w) or ceil(N w) copies.
  for (const auto& [key, w] : before) {
    const auto it = copies.find(key);
    const int c = it == copies.end() ? 0 : it->second;
    EXPECT_LT(std::fabs(c - static_cast<double>(n) * w), 1.0 + 1e-9)
        << "weight " << w << " copies " << c;
  }
  EXPECT_NEAR(pf->estimate().effective_particles, static_cast<double>(n), 1e-6);
}

TEST(ParticleFilter, PredictFollowsTheArcWithTheDocumentedNoise) {
  ha::MotionNoise noise;  // alpha1..4 = 0.02, 0.02, 0.02, 0.002
  auto pf = make_filter(4000, 9, noise);
  pf->initialize(ha::Pose2{1.0, 1.0, kPi / 2.0}, 0.0, 0.0, false);
  pf->predict(ha::OdometryDelta{1.0, 0.0});
  const ha::PoseEstimate e = pf->estimate();
  // Mean moves 1 m along +y.
  EXPECT_NEAR(e.mean.x_m, 1.0, 0.01);
  EXPECT_NEAR(e.mean.y_m, 2.0, 0.01);
  EXPECT_NEAR(e.mean.yaw_rad, kPi / 2.0, 0.01);
  // Yaw variance alpha2 d^2 = 0.02; distance variance alpha3 d^2 = 0.02 (along y); the sideways
  // spread of an arc of length 1 with yaw error e is e/2: variance 0.02 / 4.
  EXPECT_NEAR(e.covariance(2, 2), 0.02, 0.02 * 0.12);
  EXPECT_NEAR(e.covariance(1, 1), 0.02, 0.02 * 0.12);
  EXPECT_NEAR(e.covariance(0, 0), 0.005, 0.005 * 0.15);
  // Standing still: the floors keep a little diffusion going.
  pf->initialize(ha::Pose2{}, 0.0, 0.0, false);
  pf->predict(ha::OdometryDelta{0.0, 0.0});
  const ha::PoseEstimate still = pf->estimate();
  EXPECT_NEAR(std::sqrt(still.covariance(2, 2)), noise.min_yaw_sigma_rad,
              0.1 * noise.min_yaw_sigma_rad);
  EXPECT_NEAR(std::sqrt(still.covariance(0, 0)), noise.min_distance_sigma_m,
              0.1 * noise.min_distance_sigma_m);
}

TEST(ParticleFilter, ConvergesOnAKnownTrajectoryFromUniformHeading) {
  auto pf = make_filter(2000, 2024);
  ha::Pcg32 fix_noise(77);
  ha::Pose2 truth{0.0, 0.0, 0.6};
  pf->initialize(ha::Pose2{0.05, -0.04, 0.0}, 0.15, 0.0, true);
  auto step = [&](const ha::OdometryDelta& d) {
    truth = ha::apply_arc(truth, d);
    pf->predict(d);
    pf->update_position(truth.x_m + 0.03 * fix_noise.normal(),
                        truth.y_m + 0.03 * fix_noise.normal(), 0.04, 0.05);
    pf->resample_if_needed(0.5);
  };
  for (int k = 0; k < 60; ++k) step(ha::OdometryDelta{0.05, 0.0});  // 3 m straight
  ha::PoseEstimate e = pf->estimate();
  EXPECT_LT(std::hypot(e.mean.x_m - truth.x_m, e.mean.y_m - truth.y_m), 0.05);
  EXPECT_LT(std::fabs(ha::wrap_angle_rad(e.mean.yaw_rad - truth.yaw_rad)), 5.0 * kPi / 180.0);
  for (int k = 0; k < 40; ++k) step(ha::OdometryDelta{0.05, 0.02});  // 2 m of arc, 0.8 rad
  e = pf->estimate();
  EXPECT_LT(std::hypot(e.mean.x_m - truth.x_m, e.mean.y_m - truth.y_m), 0.05)
      << "estimate " << e.mean.x_m << "," << e.mean.y_m << " truth " << truth.x_m << ","
      << truth.y_m;
  EXPECT_LT(std::fabs(ha::wrap_angle_rad(e.mean.yaw_rad - truth.yaw_rad)), 5.0 * kPi / 180.0)
      << "estimate yaw " << e.mean.yaw_rad << " truth " << truth.yaw_rad;
  // And it is confident about it.
  EXPECT_LT(std::sqrt(e.covariance(0, 0) + e.covariance(1, 1)), 0.06);
  EXPECT_LT(std::sqrt(e.covariance(2, 2)), 0.1);
}

// KLD-sampling (Fox 2003): the count it asks for, written out from the paper's eq. 12.
TEST(ParticleFilterKld, RequiredCountIsFoxsBound) {
  ha::KldSampling kld;
  EXPECT_EQ(kld.required(0), 1.0);
  EXPECT_EQ(kld.required(1), 1.0);
  // k = 100 bins, epsilon 0.05, z 2.326: 99 / 0.1 * (1 - 2/891 + sqrt(2/891) * 2.326)^3.
  const double a = 2.0 / 891.0;
  EXPECT_NEAR(kld.required(100), 990.0 * std::pow(1.0 - a + std::sqrt(a) * 2.326, 3.0), 1e-9);
  EXPECT_NEAR(kld.required(100), 1346.5, 0.5);
  double before = 0.0;
  for (std::size_t k = 2; k < 5000; k += 37) {
    EXPECT_GT(kld.required(k), before) << k;
    before = kld.required(k);
  }
}

namespace {

ha::KldSampling kld_on() {
  ha::KldSampling kld;
  kld.enabled = true;
  kld.min_particles = 100;
  return kld;
}

// Weights the cloud by a sharp fix at (x, y) and resamples (always: the weights are uneven).
bool weigh_and_resample(ha::ParticleFilter& pf, double x, double y, double sigma_m) {
  pf.update_position(x, y, sigma_m, 0.0);
  return pf.resample_if_needed(1.0);
}

}  // namespace

TEST(ParticleFilterKld, ConvergedCloudShrinksToTheMinimumAndStaysOnTheFix) {
  auto pf = make_filter(2048, 7);
  pf->set_kld_sampling(kld_on());
  pf->initialize(ha::Pose2{1.025, 2.025, 0.3}, 0.004, 0.01, false);  // inside one 5 cm bin
  ASSERT_TRUE(weigh_and_resample(*pf, 1.025, 2.025, 0.01));
  EXPECT_EQ(pf->size(), 100U);
  EXPECT_EQ(pf->capacity(), 2048U);
  double sum = 0.0;
  for (std::size_t i = 0; i < pf->size(); ++i) sum += pf->weight(i);
  EXPECT_NEAR(sum, 1.0, 1e-12);
  const ha::PoseEstimate e = pf->estimate();
  EXPECT_NEAR(e.mean.x_m, 1.025, 0.003);
  EXPECT_NEAR(e.mean.y_m, 2.025, 0.003);
  // Astride bin borders (four bins): Fox's bound for k = 4, above the minimum.
  pf->initialize(ha::Pose2{1.0, 2.0, 0.3}, 0.004, 0.01, false);
  ASSERT_TRUE(weigh_and_resample(*pf, 1.0, 2.0, 0.01));
  EXPECT_EQ(pf->size(), static_cast<std::size_t>(std::ceil(kld_on().required(4))));
  expect_estimate_matches_reference(*pf);
}

TEST(ParticleFilterKld, LostCloudKeepsTheCapacityAndEveryReseedStartsFull) {
  auto pf = make_filter(2048, 7);
  pf->set_kld_sampling(kld_on());
  pf->initialize_uniform(0.0, 0.0, 4.0, 4.0);  // thousands of bins
  ASSERT_TRUE(weigh_and_resample(*pf, 2.0, 2.0, 1.0));
  EXPECT_EQ(pf->size(), 2048U);
  // Converge, then re-seed: the new cloud has every particle again.
  pf->initialize(ha::Pose2{1.025, 1.025, 0.0}, 0.004, 0.01, false);
  ASSERT_TRUE(weigh_and_resample(*pf, 1.025, 1.025, 0.01));
  ASSERT_EQ(pf->size(), 100U);
  pf->initialize(ha::Pose2{3.0, 3.0, 0.0}, 0.5, 1.0, true);
  EXPECT_EQ(pf->size(), 2048U);
  // A cloud that spreads again (odometry lost) grows back at the next resampling.
  pf->initialize(ha::Pose2{1.025, 1.025, 0.0}, 0.004, 0.01, false);
  ASSERT_TRUE(weigh_and_resample(*pf, 1.025, 1.025, 0.01));
  ASSERT_EQ(pf->size(), 100U);
  pf->diffuse(0.5, 1.0);
  ASSERT_TRUE(weigh_and_resample(*pf, 1.0, 1.0, 2.0));
  EXPECT_GT(pf->size(), 100U);
}

TEST(ParticleFilterKld, TheCountGrowsWithTheBinsTheCloudOccupies) {
  std::size_t before = 0;
  for (const double spread_m : {0.01, 0.04, 0.1}) {
    auto pf = make_filter(4096, 11);
    pf->set_kld_sampling(kld_on());
    pf->initialize(ha::Pose2{0.0, 0.0, 0.0}, spread_m, 0.05, false);
    ASSERT_TRUE(weigh_and_resample(*pf, 0.0, 0.0, 10.0 * spread_m));
    EXPECT_GT(pf->size(), before) << spread_m;
    before = pf->size();
  }
  EXPECT_LT(before, 4096U);
}

// With a minimum at the capacity the count never changes, and the draw is the one without it.
TEST(ParticleFilterKld, AtTheCapacityTheSameParticlesBitForBit) {
  auto a = make_filter(512, 3);
  auto b = make_filter(512, 3);
  ha::KldSampling full = kld_on();
  full.min_particles = 512;
  b->set_kld_sampling(full);
  for (auto* pf : {a.get(), b.get()}) {
    pf->initialize(ha::Pose2{0.0, 0.0, 0.0}, 0.004, 0.01, false);
    weigh_and_resample(*pf, 0.001, 0.0, 0.01);
  }
  ASSERT_EQ(a->size(), 512U);
  ASSERT_EQ(b->size(), 512U);
  for (std::size_t i = 0; i < 512; ++i) {
    EXPECT_TRUE(same_bits(a->particle(i).x_m, b->particle(i).x_m)) << i;
    EXPECT_TRUE(same_bits(a->weight(i), b->weight(i))) << i;
  }
}

// A particle far out or not a number (it should never be one) does not stop the count.
TEST(ParticleFilterKld, ParticlesFarOutOrNotANumberShareAnEdgeBin) {
  auto pf = make_filter(256, 5);
  pf->set_kld_sampling(kld_on());
  pf->initialize(ha::Pose2{0.0, 0.0, 0.0}, 0.004, 0.01, false);
  pf->shift(1.0e300, std::numeric_limits<double>::quiet_NaN(), 0.0);
  pf->update_position(0.0, 0.0, 0.01, 0.0);  // every weight ruled out: uniform again
  EXPECT_TRUE(pf->resample_if_needed(1.1));  // forced
  EXPECT_GE(pf->size(), 100U);
  EXPECT_LE(pf->size(), 256U);
}
