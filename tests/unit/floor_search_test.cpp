// The search over a whole floor map (algorithms/floor_search.hpp): the heading from the boards'
// bearings at each place, the pose from the boards' fit, a slice of the grid a cycle.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <memory>

#include "harmoloc/algorithms/board_observation.hpp"
#include "harmoloc/algorithms/floor_search.hpp"
#include "harmoloc/algorithms/geometry.hpp"
#include "synthetic_floor.hpp"

namespace ha = harmoloc::algorithms;
using harmoloc::test_floor::make_floor;
using harmoloc::test_floor::seen;

TEST(FloorSearch, FindsThePoseAndHeadingOverTheWholeFloorFromOneFrame) {
  const auto map = make_floor();
  const ha::BoardModelParams params;
  const double x = 2.13, y = 0.71, yaw = 1.0;
  const ha::BoardFeatures o = seen(x, y, yaw);
  ASSERT_GE(__builtin_popcount(o.angle_mask), 2);
  ha::FloorSearch search;
  // A stride of 4 cells: 38 x 26 places, 256 a step: the fourth step completes the pass.
  int steps = 0;
  while (!search.step(*map, o, params, 0U, 256, 4)) ASSERT_LE(++steps, 3);
  EXPECT_EQ(steps, 3);
  const ha::FloorPose& pass = search.last_pass();
  ASSERT_TRUE(pass.valid);
  EXPECT_LT(std::hypot(pass.x_m - x, pass.y_m - y), 0.06);
  EXPECT_LT(std::fabs(ha::wrap_angle_rad(pass.yaw_rad - yaw)), 0.02);
  // Refined on the frame (a stride's reach), twice: within a centimetre and a half-degree.
  ha::FloorPose fine = ha::FloorSearch::refine(*map, o, pass, 0.08, params, 0U);
  fine = ha::FloorSearch::refine(*map, o, fine, 0.02, params, 0U);
  ASSERT_TRUE(fine.valid);
  EXPECT_LT(std::hypot(fine.x_m - x, fine.y_m - y), 0.01);
  EXPECT_LT(std::fabs(ha::wrap_angle_rad(fine.yaw_rad - yaw)), 0.01);
  EXPECT_GE(fine.nats, pass.nats);
  // The same in one call: three levels (steps of 4, 2 and 1 cm) come as close as two calls,
  // with 41 places against 50; one level alone stays a grid step off.
  const ha::FloorPose leveled = ha::FloorSearch::refine(*map, o, pass, 0.08, params, 0U, 3);
  ASSERT_TRUE(leveled.valid);
  EXPECT_LT(std::hypot(leveled.x_m - x, leveled.y_m - y), 0.01);
  const ha::FloorPose one = ha::FloorSearch::refine(*map, o, pass, 0.08, params, 0U);
  EXPECT_GE(leveled.nats, one.nats);
  EXPECT_GT(std::hypot(one.x_m - x, one.y_m - y), 0.01);
  // The fit prefers the truth to a place half a metre off, and to the truth turned (its two
  // bearings then each at the robust floor, ln 0.01).
  const double at_truth = ha::floor_fit(*map, o, x, y, yaw, params, 0U);
  EXPECT_GT(at_truth, ha::floor_fit(*map, o, x - 0.5, y + 0.3, yaw, params, 0U) + 10.0);
  EXPECT_GT(at_truth, ha::floor_fit(*map, o, x, y, yaw + 0.3, params, 0U) + 8.0);
}

TEST(FloorSearch, AMovedBoardLeftOutDoesNotMislead) {
  const auto map = make_floor();
  const ha::BoardModelParams params;
  const double x = 1.2, y = 1.1, yaw = 0.8;
  ha::BoardFeatures o = seen(x, y, yaw);
  ASSERT_EQ(o.angle_mask, 0b0110U);
  // Board 2 moved: it shows twice its area, and its bearing turned 0.3 rad.
  o.value[2] *= 2.0F;
  o.angle_rad[2] += 0.3F;
  ha::FloorSearch search;
  while (!search.step(*map, o, params, 1U << 2, 4096, 2)) {
  }
  const ha::FloorPose fine =
      ha::FloorSearch::refine(*map, o, search.last_pass(), 0.04, params, 1U << 2);
  ASSERT_TRUE(fine.valid);
  EXPECT_LT(std::hypot(fine.x_m - x, fine.y_m - y), 0.03);
  EXPECT_LT(std::fabs(ha::wrap_angle_rad(fine.yaw_rad - yaw)), 0.02);
}

TEST(FloorSearch, ACutBoardsAreaIsWeighedAsWideAsConfigured) {
  const auto map = make_floor();
  const double x = 1.2, y = 1.1, yaw = 0.8;
  const ha::BoardFeatures whole = seen(x, y, yaw);
  std::size_t b = 0;
  while (b < whole.count && !(whole.value[b] > 0.0F)) ++b;
  ASSERT_LT(b, whole.count);
  // The frame's side cuts the board: it shows twice its trained noise less than the map expects
  // and gives no bearing.
  ASSERT_GT(whole.value[b], 2.0F * map->sigma[b]);
  ha::BoardFeatures cut = whole;
  cut.value[b] -= 2.0F * map->sigma[b];
  cut.angle_mask &= ~(1U << b);
  cut.cut_mask = 1U << b;
  ha::BoardModelParams as_whole, wider, none;
  wider.cut_board_width = 3.0;
  none.cut_board_width = 0.0;
  const double reference = ha::floor_fit(*map, whole, x, y, yaw, as_whole, 0U);
  const double at_one = ha::floor_fit(*map, cut, x, y, yaw, as_whole, 0U);
  const double at_three = ha::floor_fit(*map, cut, x, y, yaw, wider, 0U);
  const double left_out = ha::floor_fit(*map, cut, x, y, yaw, none, 0U);
  EXPECT_LT(at_one, at_three);
  EXPECT_LT(at_three, left_out);
  // Left out, the frame fits as the whole frame without that board's area and bearing: each a
  // perfect fit's ln(1 + c) at most.
  EXPECT_NEAR(left_out, reference, 2.0 * std::log(1.0 + as_whole.outlier_floor) + 1e-6);
  // The same weighs a particle: the board is not used at all with 0.
  ha::BoardReliability reliability;
  reliability.reset(none);
  ha::BoardUpdate update;
  reliability.assess(*map, cut, ha::Pose2{x, y, yaw}, none, update, 0.0);
  EXPECT_FALSE(update.use[b]);
  reliability.assess(*map, cut, ha::Pose2{x, y, yaw}, wider, update, 0.0);
  EXPECT_TRUE(update.use[b]);
}

TEST(FloorSearch, BoardFeaturesMarkTheBoardsTheFramesSideCuts) {
  ha::AreaVector a;
  a.count = 3;
  a.width_px = 320;
  a.pixels = {400, 300, 0};
  a.side_pixels = {0, 12, 0};
  const ha::BoardFeatures f = ha::board_features(1.0F, a);
  EXPECT_EQ(f.cut_mask, 1U << 1);
}

TEST(FloorSearch, StepsAreBoundedAndNothingWithoutBearings) {
  const auto map = make_floor();
  const ha::BoardModelParams params;
  ha::FloorSearch search;
  const ha::BoardFeatures o = seen(1.0, 1.0, 0.0);
  // 151 x 101 places at stride 1, ten a step: 1525 steps without completing, the 1526th does.
  for (int i = 0; i < 1525; ++i) ASSERT_FALSE(search.step(*map, o, params, 0U, 10, 1));
  EXPECT_FALSE(search.last_pass().valid);
  EXPECT_TRUE(search.step(*map, o, params, 0U, 10, 1));
  EXPECT_TRUE(search.last_pass().valid);
  search.reset();
  EXPECT_FALSE(search.last_pass().valid);

  // No board gives a bearing: no heading, no pose.
  ha::BoardFeatures blind = o;
  blind.angle_mask = 0;
  EXPECT_FALSE(ha::floor_pose_seen_from(*map, blind, 1.0, 1.0, params, 0U).valid);
  // Every bearing's board left out: the same.
  EXPECT_FALSE(ha::floor_pose_seen_from(*map, o, 1.0, 1.0, params, 0xFFU).valid);
  // Off the grid: none.
  EXPECT_FALSE(ha::floor_pose_seen_from(*map, o, -1.0, 1.0, params, 0U).valid);
  // A map without bearings: the search cannot run.
  const auto plain = make_floor(false);
  EXPECT_FALSE(ha::floor_search_possible(*plain));
  EXPECT_FALSE(search.step(*plain, o, params, 0U, 1000000, 1));
  EXPECT_FALSE(ha::FloorSearch::refine(*plain, o, ha::FloorPose{}, 0.1, params, 0U).valid);
}
