// The check of the harmonic fix's boards (fix_board_check.hpp): a board that drags the fix away
// from the estimate, and only that, is left out of the fix; a kidnap leaves every board trusted.
#include "harmoloc/algorithms/fix_board_check.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>

namespace ha = harmoloc::algorithms;

namespace {

// Three boards whose areas change along a 2 m route on x (y = 0): one sample a centimetre.
double area(std::size_t board, double x) {
  switch (board) {
    case 0:
      return 1.0 + 0.5 * x;
    case 1:
      return 2.0 - 0.4 * x;
    default:
      return 0.5 + 0.3 * x * x;
  }
}

std::unique_ptr<ha::HarmonicModel> route_model() {
  auto m = std::make_unique<ha::HarmonicModel>();
  m->feature_count = 3;
  m->board_index = {0, 1, 2, 0, 0, 0, 0, 0};
  m->feature_weight.fill(1.0F);
  m->area_scale = 1.0F;
  m->sigma_x = m->sigma_y = 2.0e4F;
  m->max_nearest_distance = 1.0F;
  m->max_dissimilarity = 1.0F;
  m->sample_count = 201;
  for (std::size_t i = 0; i < m->sample_count; ++i) {
    const double x = 0.01 * static_cast<double>(i);
    for (std::size_t b = 0; b < 3; ++b) m->sample(i)[b] = static_cast<float>(area(b, x));
    m->target_x_m[i] = static_cast<float>(x);
    m->target_y_m[i] = 0.0F;
  }
  return m;
}

// What the camera shows at @p x, board @p moved showing what it would at @p x + @p shift.
std::array<float, ha::HarmonicModel::kMaxFeatures> seen(double x, int moved = -1,
                                                        double shift = 0.0) {
  std::array<float, ha::HarmonicModel::kMaxFeatures> f{};
  for (std::size_t b = 0; b < 3; ++b)
    f[b] = static_cast<float>(area(b, static_cast<int>(b) == moved ? x + shift : x));
  return f;
}

constexpr ha::FeatureMask kAll = {true, true, true, true, true, true, true, true};

}  // namespace

TEST(FixBoardCheck, ParamsFollowTheFixError) {
  const ha::FixCheckParams p = ha::fix_check_params(0.03, 0.04);
  EXPECT_NEAR(p.far_m, 0.15, 1e-12);
  EXPECT_NEAR(p.near_m, 0.075, 1e-12);
  EXPECT_NEAR(ha::fix_check_params(0.001, 0.0).far_m, 0.03, 1e-12) << "floors";
  EXPECT_EQ(ha::fix_check_params(0.0, 0.0).near_m, 0.0) << "no calibration: no check";
}

TEST(FixBoardCheck, AMovedBoardIsLeftOutOfTheFix) {
  const auto model = route_model();
  const ha::FixCheckParams p{0.09, 0.045, 30};
  // Board 1 shows what it would 60 cm further on; the robot is at 1.0 and the filter knows it.
  const auto f = seen(1.0, 1, 0.6);
  const ha::HarmonicFix plain = ha::harmonic_query(*model, f, kAll);
  ASSERT_GT(std::fabs(plain.x_m - 1.0), 0.09) << "the plain fix is dragged";
  ha::FixBoardCheck check;
  ha::HarmonicFix fix;
  for (int frame = 0; frame < 3; ++frame) fix = check.fix(*model, f, kAll, 1.0, 0.0, p);
  EXPECT_TRUE(check.suspect(1));
  EXPECT_FALSE(check.suspect(0));
  EXPECT_FALSE(check.suspect(2));
  EXPECT_EQ(check.suspicions(), 1U);
  EXPECT_NEAR(fix.x_m, 1.0, 0.02);
  // It stays out while it disagrees, and is trusted again once it agrees (put back).
  for (int frame = 0; frame < 60; ++frame) fix = check.fix(*model, f, kAll, 1.0, 0.0, p);
  EXPECT_TRUE(check.suspect(1));
  for (int frame = 0; frame < 3; ++frame) fix = check.fix(*model, seen(1.0), kAll, 1.0, 0.0, p);
  EXPECT_FALSE(check.suspect(1));
  // A reset trusts every board again.
  for (int frame = 0; frame < 3; ++frame) check.fix(*model, f, kAll, 1.0, 0.0, p);
  ASSERT_TRUE(check.suspect(1));
  check.reset();
  EXPECT_FALSE(check.suspect(1));
}

TEST(FixBoardCheck, AKidnapLeavesEveryBoardTrusted) {
  const auto model = route_model();
  const ha::FixCheckParams p{0.09, 0.045, 30};
  ha::FixBoardCheck check;
  ha::HarmonicFix fix;
  // Carried to 1.5 while the estimate is still at 1.0: every board agrees on 1.5.
  for (int frame = 0; frame < 9; ++frame) fix = check.fix(*model, seen(1.5), kAll, 1.0, 0.0, p);
  for (std::size_t k = 0; k < 3; ++k) EXPECT_FALSE(check.suspect(k)) << k;
  EXPECT_EQ(check.suspicions(), 0U);
  EXPECT_NEAR(fix.x_m, 1.5, 0.02);
}

TEST(FixBoardCheck, NoCheckWithoutTheCalibrationOrWithTwoBoards) {
  const auto model = route_model();
  const auto f = seen(1.0, 1, 0.4);
  ha::FixBoardCheck check;
  for (int frame = 0; frame < 6; ++frame)
    check.fix(*model, f, kAll, 1.0, 0.0, ha::FixCheckParams{});
  EXPECT_FALSE(check.suspect(1)) << "no calibration";
  ha::FeatureMask two = kAll;
  two[2] = false;  // the filter already distrusts board 2: two remain, none is left out
  const ha::FixCheckParams p{0.09, 0.045, 30};
  ha::HarmonicFix fix;
  for (int frame = 0; frame < 6; ++frame) fix = check.fix(*model, f, two, 1.0, 0.0, p);
  EXPECT_FALSE(check.suspect(1));
  const ha::HarmonicFix plain = ha::harmonic_query(*model, f, two);
  EXPECT_EQ(fix.x_m, plain.x_m);
}
