// The nearby pose test (algorithms/nearby_pose_test.hpp): the boards' likelihood of one pose as
// the filter weighs it, and the sequential test that draws particles at a nearby pose only
// when the boards keep preferring it.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <memory>

#include "harmoloc/algorithms/board_observation.hpp"
#include "harmoloc/algorithms/geometry.hpp"
#include "harmoloc/algorithms/nearby_pose_test.hpp"
#include "harmoloc/algorithms/particle_filter.hpp"
#include "synthetic_floor.hpp"

namespace ha = harmoloc::algorithms;
using harmoloc::test_floor::make_floor;
using harmoloc::test_floor::seen;

namespace {

// The filter's board update of one frame, as the cycle makes it (the estimate's assessment).
ha::BoardUpdate update_for(const ha::ForwardMap& map, const ha::BoardFeatures& o,
                           const ha::Pose2& estimate, const ha::BoardModelParams& params) {
  ha::BoardReliability reliability;
  reliability.reset(params);
  ha::BoardUpdate u;
  reliability.assess(map, o, estimate, params, u);
  return u;
}

}  // namespace

TEST(NearbyPoseTest, BoardLikelihoodIsTheWeightAParticleGets) {
  const auto map = make_floor();
  ha::BoardModelParams params;
  const ha::BoardFeatures o = seen(1.3, 0.9, 0.6);
  ha::BoardUpdate u = update_for(*map, o, ha::Pose2{1.3, 0.9, 0.6}, params);
  u.inv_tempering = 1.0;  // the weight itself, untempered
  ha::ParticleFilter filter;
  filter.configure(64, 3, ha::MotionNoise{});
  filter.initialize(ha::Pose2{1.3, 0.9, 0.6}, 0.1, 0.2, false);
  const double before_0 = filter.weight(0), before_1 = filter.weight(1);
  filter.update_boards(u);
  const auto pose = [&](std::size_t i) {
    const ha::ParticleFilter::Particle& p = filter.particle(i);
    return ha::Pose2{p.x_m, p.y_m, p.yaw_rad};
  };
  const double l0 = ha::ParticleFilter::board_likelihood(u, pose(0));
  const double l1 = ha::ParticleFilter::board_likelihood(u, pose(1));
  ASSERT_GT(l0, 0.0);
  ASSERT_GT(l1, 0.0);
  // The weights are normalised: their ratio is the likelihoods' ratio.
  EXPECT_NEAR((filter.weight(0) / before_0) / (filter.weight(1) / before_1), l0 / l1,
              1e-5 * l0 / l1);
  // The truth fits better than a place 15 cm off.
  EXPECT_GT(ha::ParticleFilter::board_likelihood(u, ha::Pose2{1.3, 0.9, 0.6}),
            ha::ParticleFilter::board_likelihood(u, ha::Pose2{1.45, 0.9, 0.6}));
}

// The best of 3 x 3 places in the filter's model: the one nearest the robot, its fit the log of
// the likelihood there, never worse than the centre's. The floor kidnap test weighs the floor
// search's place against the estimate with it.
TEST(NearbyPoseTest, BestModelFitNearIsTheGridPlaceNearestTheRobot) {
  const auto map = make_floor();
  ha::BoardModelParams params;
  const ha::Pose2 robot{1.3, 0.9, 0.6};
  const ha::BoardFeatures o = seen(robot.x_m, robot.y_m, robot.yaw_rad);
  const ha::BoardUpdate u = update_for(*map, o, robot, params);
  double nats = 0.0;
  const ha::Pose2 around{1.34, 0.86, 0.6};  // 4 cm off in x and y: the grid's corner is the robot
  const ha::Pose2 best = ha::best_model_fit_near(u, around, 0.04, nats);
  EXPECT_NEAR(best.x_m, robot.x_m, 1e-9);
  EXPECT_NEAR(best.y_m, robot.y_m, 1e-9);
  EXPECT_DOUBLE_EQ(best.yaw_rad, around.yaw_rad);
  EXPECT_NEAR(nats, std::log(ha::ParticleFilter::board_likelihood(u, best)), 1e-12);
  EXPECT_GT(nats, std::log(ha::ParticleFilter::board_likelihood(u, around)));
  // Far from the robot the best of the grid still fits worse than the robot's place.
  double far_nats = 0.0;
  ha::best_model_fit_near(u, ha::Pose2{1.8, 0.9, 0.6}, 0.02, far_nats);
  EXPECT_LT(far_nats, nats);
  EXPECT_TRUE(std::isfinite(far_nats));
}

TEST(NearbyPoseTest, DrawsAtTheRobotWhenTheEstimateIsOffAndNeverWhenItIsRight) {
  const auto map = make_floor();
  const ha::BoardModelParams params;
  const ha::NearbyPoseParams test;
  // The robot drives along x; the estimate is 12 cm off across its path.
  ha::NearbyPoseTest off;
  bool drew = false;
  ha::Pose2 at;
  int frames = 0;
  for (; frames < 60 && !drew; ++frames) {
    const double x = 0.8 + 0.01 * frames, y = 0.9, yaw = 0.3;
    const ha::Pose2 estimate{x, y + 0.12, yaw};
    const ha::BoardFeatures o = seen(x, y, yaw);
    drew = off.step(*map, o, update_for(*map, o, estimate, params), estimate, params, 0U, test, at);
    if (drew) {
      EXPECT_LT(std::hypot(at.x_m - x, at.y_m - y), 0.03);
    }
  }
  EXPECT_TRUE(drew) << "after " << frames << " frames";
  EXPECT_FALSE(off.holding());

  // The estimate right, the areas noisy (up to three times the boards' sigma): no draw in 600
  // frames, and never more than the bound summed.
  ha::NearbyPoseTest right;
  std::uint64_t state = 7;
  const auto noise = [&]() {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return (static_cast<double>(state >> 11) / 9007199254740992.0 - 0.5) * 0.12;
  };
  for (int k = 0; k < 600; ++k) {
    const double x = 0.6 + 0.002 * k, y = 1.0, yaw = -0.2;
    const ha::Pose2 estimate{x, y, yaw};
    const ha::BoardFeatures o = seen(x, y, yaw, {noise(), noise(), noise(), noise()});
    ASSERT_FALSE(
        right.step(*map, o, update_for(*map, o, estimate, params), estimate, params, 0U, test, at))
        << "frame " << k;
    ASSERT_LE(right.summed_nats(), test.bound_nats);
  }
}

TEST(NearbyPoseTest, DropsTheAlternativeAfterItsFramesAndWithoutAMap) {
  const auto map = make_floor();
  const ha::BoardModelParams params;
  ha::NearbyPoseParams test;
  test.bound_nats = 1e6;  // never decides: only the frame limit ends a test
  test.max_frames = 5;
  ha::NearbyPoseTest t;
  ha::Pose2 at;
  const ha::Pose2 estimate{1.0, 1.0, 0.0};
  const ha::BoardFeatures o = seen(1.0, 1.1, 0.0);
  const ha::BoardUpdate u = update_for(*map, o, estimate, params);
  for (int k = 0; k < 5; ++k) {
    EXPECT_FALSE(t.step(*map, o, u, estimate, params, 0U, test, at));
    EXPECT_EQ(t.holding(), k < 4) << "frame " << k;
  }
  // A board update without a map, or a map without bearings: nothing to test.
  ha::NearbyPoseTest none;
  EXPECT_FALSE(none.step(*map, o, ha::BoardUpdate{}, estimate, params, 0U, test, at));
  EXPECT_FALSE(none.holding());
  ha::ForwardMap plain;
  EXPECT_FALSE(none.step(plain, o, u, estimate, params, 0U, test, at));
  EXPECT_FALSE(none.holding());
}

TEST(NearbyPoseTest, TakesTheFloorSearchsPoseBeyondTheRefinementsReach) {
  const auto map = make_floor();
  const ha::BoardModelParams params;
  const ha::NearbyPoseParams test;
  // The estimate 40 cm off the robot, twice the refinement's radius (a re-seed that chose the
  // wrong start): without the search's pose the test cannot draw at the robot. Returns the
  // draw's distance from the robot (infinite: no draw in 60 frames).
  const auto run = [&](bool with_hint) {
    ha::NearbyPoseTest t;
    for (int frames = 0; frames < 60; ++frames) {
      const double x = 0.8 + 0.01 * frames, y = 0.9, yaw = 0.3;
      const ha::Pose2 estimate{x, y + 0.40, yaw};
      const ha::BoardFeatures o = seen(x, y, yaw);
      const ha::FloorPose hint =
          with_hint ? ha::FloorPose{x + 0.01, y - 0.01, yaw, 0.0, true} : ha::FloorPose{};
      ha::Pose2 at;
      if (t.step(*map, o, update_for(*map, o, estimate, params), estimate, params, 0U, test, at,
                 hint))
        return std::hypot(at.x_m - x, at.y_m - y);
    }
    return HUGE_VAL;
  };
  EXPECT_GT(run(false), 0.15);
  EXPECT_LT(run(true), 0.04);
}

// After a re-seed the filter's model can be flat over 20 cm and more (random floor 21: two
// boards, both with a bearing, fitting the robot's place and one 24 cm off alike) while the
// map's tables tell the places apart. In the hint frames the test then weighs the search's pose
// against the estimate by the tables, each the best of the same 5 x 5 places around it.
TEST(NearbyPoseTest, WeighsTheSearchsPoseByTheTablesInTheHintFrames) {
  const auto map = make_floor();
  const ha::BoardModelParams params;
  ha::NearbyPoseParams test;
  test.hint_by_tables = true;
  // The estimate 30 cm off, beyond the refinement's reach; the search's pose 1 cm off the robot.
  // The filter's model flat: no board weighed. Returns the draw's distance from the robot
  // (infinite: no draw in 60 frames).
  const auto run = [&](const ha::NearbyPoseParams& p, bool evidence, int& frames) {
    ha::NearbyPoseTest t;
    for (frames = 1; frames <= 60; ++frames) {
      const double x = 0.8 + 0.01 * frames, y = 0.9, yaw = 0.3;
      const ha::Pose2 estimate{x, y + 0.30, yaw};
      const ha::BoardFeatures o = seen(x, y, yaw);
      ha::BoardUpdate flat = update_for(*map, o, estimate, params);
      flat.use = {};
      flat.bearing_mask = 0;
      flat.area_projection_mask = 0;
      flat.near_bearing_mask = 0;
      flat.near_area_mask = 0;
      const ha::FloorPose hint{x + 0.01, y - 0.01, yaw, 0.0, true};
      const ha::TablesEvidence tables =
          ha::tables_evidence(*map, o, hint, estimate, 2.0 * p.refine_step_m, params, 0U);
      EXPECT_TRUE(tables.searched.valid);
      EXPECT_TRUE(tables.estimate.valid);
      EXPECT_GT(tables.searched.nats, tables.estimate.nats + 5.0);
      ha::Pose2 at;
      if (t.step(*map, o, flat, estimate, params, 0U, p, at, hint, evidence ? &tables : nullptr))
        return std::hypot(at.x_m - x, at.y_m - y);
    }
    return HUGE_VAL;
  };
  int frames = 0;
  EXPECT_LT(run(test, true, frames), 0.03);
  EXPECT_LE(frames, 5);
  // Without the tables' evidence, or with the mode off, the flat model never draws.
  EXPECT_EQ(run(test, false, frames), HUGE_VAL);
  ha::NearbyPoseParams off = test;
  off.hint_by_tables = false;
  EXPECT_EQ(run(off, true, frames), HUGE_VAL);
}

// The tables can prefer a wrong place (random floor 27: a place 0.8 m off fitted them better
// than the robot's). Where the filter's model finds the search's pose ln 100 less likely than
// the estimate, the frame counts the model's log-ratio instead.
TEST(NearbyPoseTest, TheModelVetoesTablesThatPreferAPlaceItRulesOut) {
  const auto map = make_floor();
  const ha::BoardModelParams params;
  ha::NearbyPoseParams test;
  test.hint_by_tables = true;
  const auto draws = [&](const ha::NearbyPoseParams& p) {
    ha::NearbyPoseTest t;
    for (int frames = 0; frames < 60; ++frames) {
      const double x = 0.8 + 0.01 * frames, y = 0.9, yaw = 0.3;
      const ha::Pose2 estimate{x, y, yaw};  // right
      const ha::BoardFeatures o = seen(x, y, yaw);
      // Tables that put the robot 25 cm off, 5 nats a frame better than the estimate.
      ha::TablesEvidence tables;
      tables.searched = ha::FloorPose{x, y + 0.25, yaw, -0.5, true};
      tables.estimate = ha::FloorPose{x, y, yaw, -5.5, true};
      ha::Pose2 at;
      if (t.step(*map, o, update_for(*map, o, estimate, params), estimate, params, 0U, p, at,
                 tables.searched, &tables))
        return true;
      if (t.summed_nats() > 0.0) return true;  // a vetoed frame never adds
    }
    return false;
  };
  EXPECT_FALSE(draws(test));
  ha::NearbyPoseParams no_veto = test;
  no_veto.veto_nats = 1e9;
  EXPECT_TRUE(draws(no_veto));
}
