// The Relative Pose Error (evo_rpe's translation part) on small trajectories whose answer is
// worked out by hand in each test's comment.
#include "harmoloc/sim_host/relative_error.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace hs = harmoloc::sim_host;
using harmoloc::algorithms::kPi;
using harmoloc::algorithms::Pose2;

namespace {

/// Poses every @p dt_s, truth = truth_of(k), estimate = estimate_of(k), k = 0..n.
template <typename Truth, typename Estimate>
std::vector<hs::PosePair> poses(int n, double dt_s, Truth truth_of, Estimate estimate_of) {
  std::vector<hs::PosePair> out;
  for (int k = 0; k <= n; ++k) out.push_back({k * dt_s, truth_of(k), estimate_of(k)});
  return out;
}

}  // namespace

// A constant offset is all absolute error and no drift: every relative motion agrees.
TEST(RelativeError, PureOffsetIsZero) {
  const auto p = poses(
      40, 0.25,
      [](int k) {
        return Pose2{0.1 * k, 0.02 * k * k, 0.05 * k};
      },
      [](int k) {
        return Pose2{0.1 * k + 0.3, 0.02 * k * k - 0.2, 0.05 * k};
      });
  for (const hs::DeltaUnit unit : {hs::DeltaUnit::kMetres, hs::DeltaUnit::kSeconds}) {
    const hs::RelativeErrors r = hs::relative_errors(p, 1.0, unit);
    EXPECT_GT(r.pairs, 3u);
    EXPECT_NEAR(r.rmse_m, 0.0, 1e-12);
    EXPECT_NEAR(r.max_m, 0.0, 1e-12);
  }
}

// The whole estimate turned by 90 degrees and moved (a rigid transform of the truth): the
// relative motions, seen from each pose's own frame, are the same, so the RPE is 0. Differences
// taken in the map frame would give sqrt(2) x the step instead.
TEST(RelativeError, RigidlyMovedTrajectoryIsZero) {
  const auto p = poses(
      12, 1.0,
      [](int k) {
        return Pose2{0.5 * k, 0.0, 0.0};
      },
      [](int k) {
        return Pose2{2.0, 1.0 + 0.5 * k, kPi / 2.0};
      });
  const hs::RelativeErrors r = hs::relative_errors(p, 1.0, hs::DeltaUnit::kMetres);
  EXPECT_EQ(r.pairs, 5u);
  EXPECT_NEAR(r.rmse_m, 0.0, 1e-12);
}

// Scale drift: the truth advances 0.25 m a pose, the estimate 0.5 m. Over 1 m of the estimate's
// path the anchors are poses 2, 4, 6, 8, 10 (evo's first anchor is where the path first reaches
// 1 m, not pose 0): four pairs, each with truth 0.5 m and estimate 1.0 m, error 0.5 m.
TEST(RelativeError, ScaleDriftOverDistance) {
  const auto p = poses(
      10, 0.5,
      [](int k) {
        return Pose2{0.25 * k, 0.0, 0.0};
      },
      [](int k) {
        return Pose2{0.5 * k, 0.0, 0.0};
      });
  const hs::RelativeErrors r = hs::relative_errors(p, 1.0, hs::DeltaUnit::kMetres);
  ASSERT_EQ(r.pairs, 4u);
  EXPECT_DOUBLE_EQ(r.samples.front().t_start_s, 1.0);  // pose 2
  EXPECT_DOUBLE_EQ(r.samples.front().t_end_s, 2.0);    // pose 4
  EXPECT_DOUBLE_EQ(r.rmse_m, 0.5);
  EXPECT_DOUBLE_EQ(r.median_m, 0.5);
  EXPECT_DOUBLE_EQ(r.max_m, 0.5);
}

// The same drift over 1 s: anchors every 2 poses from pose 0 (0, 2, ..., 10), five pairs with
// truth 0.5 m and estimate 1.0 m.
TEST(RelativeError, ScaleDriftOverTime) {
  const auto p = poses(
      10, 0.5,
      [](int k) {
        return Pose2{0.25 * k, 0.0, 0.0};
      },
      [](int k) {
        return Pose2{0.5 * k, 0.0, 0.0};
      });
  const hs::RelativeErrors r = hs::relative_errors(p, 1.0, hs::DeltaUnit::kSeconds);
  ASSERT_EQ(r.pairs, 5u);
  EXPECT_DOUBLE_EQ(r.samples.front().t_start_s, 0.0);
  EXPECT_DOUBLE_EQ(r.rmse_m, 0.5);
}

// One jump of 0.3 m sideways between poses 4 and 5 (t = 2.0 and 2.5 s), otherwise exact. Pairs
// over 1 s: (0,2) (2,4) (4,6) (6,8) (8,10); only (4,6) spans the jump. Errors 0, 0, 0.3, 0, 0:
// RMSE sqrt(0.09 / 5) = 0.134164..., mean 0.06, median 0, max 0.3.
TEST(RelativeError, OneJumpGivesKnownStatistics) {
  const auto p = poses(
      10, 0.5,
      [](int k) {
        return Pose2{0.25 * k, 0.0, 0.0};
      },
      [](int k) {
        return Pose2{0.25 * k, k >= 5 ? 0.3 : 0.0, 0.0};
      });
  const hs::RelativeErrors r = hs::relative_errors(p, 1.0, hs::DeltaUnit::kSeconds);
  ASSERT_EQ(r.pairs, 5u);
  EXPECT_NEAR(r.rmse_m, std::sqrt(0.09 / 5.0), 1e-12);
  EXPECT_NEAR(r.mean_m, 0.06, 1e-12);
  EXPECT_NEAR(r.median_m, 0.0, 1e-12);
  EXPECT_NEAR(r.max_m, 0.3, 1e-12);
  EXPECT_NEAR(r.samples[2].error_m, 0.3, 1e-12);
  EXPECT_DOUBLE_EQ(r.samples[2].t_start_s, 2.0);
}

// A heading error at the pair's start turns the estimate's step: truth steps 1 m along x, the
// estimate starts each pair turned by 90 degrees but moves along the map's x too, so in its own
// frame it moved 1 m to its right, (0, -1): error |(0,-1) - (1,0)| = sqrt(2).
TEST(RelativeError, HeadingErrorTurnsTheStep) {
  const auto p = poses(
      4, 1.0,
      [](int k) {
        return Pose2{1.0 * k, 0.0, 0.0};
      },
      [](int k) {
        return Pose2{1.0 * k, 0.0, kPi / 2.0};
      });
  const hs::RelativeErrors r = hs::relative_errors(p, 1.0, hs::DeltaUnit::kSeconds);
  ASSERT_EQ(r.pairs, 4u);
  EXPECT_NEAR(r.rmse_m, std::sqrt(2.0), 1e-12);
}

// Too short or standing still: no pair, numbers 0 (the report prints n/a).
TEST(RelativeError, NoPairWhenTooShort) {
  const auto still = poses(
      10, 0.1,
      [](int) {
        return Pose2{1.0, 1.0, 0.0};
      },
      [](int) {
        return Pose2{1.0, 1.0, 0.0};
      });
  EXPECT_EQ(hs::relative_errors(still, 1.0, hs::DeltaUnit::kMetres).pairs, 0u);
  EXPECT_EQ(hs::relative_errors(still, 5.0, hs::DeltaUnit::kSeconds).pairs, 0u);
  EXPECT_EQ(hs::relative_errors({}, 1.0, hs::DeltaUnit::kSeconds).pairs, 0u);
}

// The pairing takes the estimate's poses inside the truth's span from the given time on.
TEST(RelativeError, PairingInterpolatesTruth) {
  using harmoloc::dataset::StampedPose;
  const std::vector<StampedPose> truth = {{0.0, Pose2{0.0, 0.0, 0.0}}, {2.0, Pose2{2.0, 0.0, 0.0}}};
  const std::vector<StampedPose> estimate = {
      {-1.0, Pose2{}}, {0.5, Pose2{0.6, 0.0, 0.0}}, {1.5, Pose2{1.4, 0.0, 0.0}}, {3.0, Pose2{}}};
  const std::vector<hs::PosePair> all = hs::pair_with_truth(truth, estimate, -1e9);
  ASSERT_EQ(all.size(), 2u);
  EXPECT_DOUBLE_EQ(all[0].truth.x_m, 0.5);
  EXPECT_DOUBLE_EQ(all[1].truth.x_m, 1.5);
  EXPECT_EQ(hs::pair_with_truth(truth, estimate, 1.0).size(), 1u);
}
