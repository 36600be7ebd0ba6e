// The area's gain by column (algorithms/column_gain.hpp): its value and bounds, the fit that finds
// a known gain again from pairs of frames at one place, the fits it refuses, and the harmonic
// features it is removed from (the columns keep the plain areas).
#include "harmoloc/algorithms/column_gain.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>

#include "harmoloc/algorithms/harmonic_model.hpp"
#include "harmoloc/algorithms/random.hpp"

namespace ha = harmoloc::algorithms;

namespace {

constexpr std::uint32_t kWidth = 640;

// Board @p b of @p a seen whole with @p pixels at @p t frame widths from the centre.
void put_board(ha::AreaVector& a, std::size_t b, std::uint32_t pixels, double t) {
  a.width_px = kWidth;
  a.count = std::max(a.count, b + 1);
  a.pixels[b] = pixels;
  const double column = t * kWidth + 0.5 * (kWidth - 1.0);
  a.column_sum[b] = static_cast<std::uint64_t>(std::llround(column * pixels));
  a.side_pixels[b] = 0;
}

// Pairs of frames of three boards, each board at two random columns with its area at each the
// true gain's, times 1 + @p noise (uniform).
ha::ColumnGainFit fit_pairs(const ha::ColumnGain& truth, int pairs, double noise,
                            std::uint64_t seed) {
  ha::Pcg32 rng(seed);
  ha::ColumnGainFit fit;
  for (int p = 0; p < pairs; ++p) {
    ha::AreaVector first, second;
    for (std::size_t b = 0; b < 3; ++b) {
      const double area = rng.uniform(2000.0, 20000.0);
      const double t1 = rng.uniform(-0.45, 0.45), t2 = rng.uniform(-0.45, 0.45);
      put_board(
          first, b,
          static_cast<std::uint32_t>(area * truth.at(t1) * (1.0 + rng.uniform(-noise, noise))), t1);
      put_board(
          second, b,
          static_cast<std::uint32_t>(area * truth.at(t2) * (1.0 + rng.uniform(-noise, noise))), t2);
    }
    fit.add_pair(first, second, 3);
  }
  return fit;
}

}  // namespace

TEST(ColumnGain, ValueOffsetAndExtent) {
  const ha::ColumnGain none;
  EXPECT_FALSE(none.present());
  EXPECT_EQ(none.at(0.4), 1.0);
  const ha::ColumnGain g{2.0F, -6.0F};
  EXPECT_TRUE(g.present());
  EXPECT_EQ(g.at(0.0), 1.0);
  EXPECT_DOUBLE_EQ(g.at(0.5), std::exp(2.0 * 0.25 - 6.0 * 0.0625));
  EXPECT_DOUBLE_EQ(g.at(-0.3), g.at(0.3));
  // log G = 2 s - 6 s^2 (s = t^2) peaks inside the frame, at s = 1/6.
  EXPECT_NEAR(ha::column_gain_log_extent(2.0, -6.0), 1.0 / 6.0, 1e-12);
  EXPECT_NEAR(ha::column_gain_log_extent(-2.0, 0.0), 0.5, 1e-12);
  EXPECT_TRUE(ha::column_gain_in_range(4.0 * std::log(4.0), 0.0));
  EXPECT_FALSE(ha::column_gain_in_range(4.0 * std::log(4.0) * 1.01, 0.0));
  EXPECT_FALSE(ha::column_gain_in_range(24.0, -96.0));  // 1 at the side, 4.48 at t^2 = 1/8
  EXPECT_FALSE(ha::column_gain_in_range(std::nan(""), 0.0));

  ha::AreaVector a;
  put_board(a, 0, 400, 0.25);
  put_board(a, 1, 400, -0.45);
  EXPECT_NEAR(ha::column_offset(a, 0), 0.25, 1e-9);
  EXPECT_NEAR(ha::column_offset(a, 1), -0.45, 1e-9);
  EXPECT_NEAR(ha::remove_column_gain(g, a, 0, 3.0F), 3.0 / g.at(0.25), 1e-6);
  EXPECT_EQ(ha::remove_column_gain(none, a, 0, 3.0F), 3.0F);
  EXPECT_EQ(ha::remove_column_gain(g, a, 2, 3.0F), 3.0F) << "no pixels";
  a.width_px = 0;
  EXPECT_EQ(ha::remove_column_gain(g, a, 0, 3.0F), 3.0F) << "columns not measured";
}

// A stretch at the side (projection) and a squeeze (a barrel lens, vignetting) are both found
// again to within 1% over the frame, from noisy areas.
TEST(ColumnGain, FitFindsAKnownGainAgain) {
  for (const ha::ColumnGain truth :
       {ha::ColumnGain{1.2F, 1.5F}, ha::ColumnGain{-0.8F, -4.0F}, ha::ColumnGain{2.8F, -21.0F}}) {
    const ha::ColumnGainFit fit = fit_pairs(truth, 2000, 0.05, 11);
    EXPECT_EQ(fit.pairs(), 2000U);
    EXPECT_EQ(fit.observations(), 6000U);
    ha::ColumnGain g;
    ASSERT_TRUE(fit.solve(50, g));
    for (double t : {0.1, 0.25, 0.4, 0.5})
      EXPECT_NEAR(g.at(t) / truth.at(t), 1.0, 0.01) << truth.c2 << " " << truth.c4 << " t " << t;
  }
}

// Boards that are cut by the side or too small give no observation; too few observations, every
// board at one column (a singular fit) or a gain beyond a factor of 4 give none.
TEST(ColumnGain, FitRefusesWhatItCannotMeasure) {
  ha::ColumnGain g{1.0F, 1.0F};
  EXPECT_FALSE(fit_pairs(ha::ColumnGain{1.0F, 0.0F}, 16, 0.0, 3).solve(50, g));  // 48
  EXPECT_FALSE(g.present()) << "a refused fit leaves the plain areas";
  EXPECT_TRUE(fit_pairs(ha::ColumnGain{1.0F, 0.0F}, 17, 0.0, 3).solve(50, g));  // 51

  ha::ColumnGainFit still;
  for (int p = 0; p < 100; ++p) {
    ha::AreaVector a, b;
    put_board(a, 0, 5000, 0.2);
    put_board(b, 0, 5200, 0.2);
    still.add_pair(a, b, 1);
  }
  EXPECT_FALSE(still.solve(50, g)) << "every board at one column";

  ha::ColumnGainFit cut;
  ha::AreaVector a, b;
  put_board(a, 0, 5000, 0.45);
  put_board(b, 0, 5000, 0.0);
  put_board(a, 1, 20, 0.1);  // below kBearingMinPixels
  put_board(b, 1, 20, -0.1);
  a.side_pixels[0] = 3;  // board 0 cut by the side
  cut.add_pair(a, b, 2);
  EXPECT_EQ(cut.pairs(), 1U);
  EXPECT_EQ(cut.observations(), 0U);

  EXPECT_FALSE(fit_pairs(ha::ColumnGain{8.0F, 0.0F}, 500, 0.0, 5).solve(50, g)) << "G(0.5) = 7.4";
}

// The harmonic features have the gain removed where the frame measured columns; the column
// features come from the plain areas, the same with and without the gain.
TEST(ColumnGain, RemovedFromTheHarmonicFeaturesOnly) {
  auto model = std::make_unique<ha::HarmonicModel>();
  model->feature_count = 2;
  model->board_index = {1, 0};
  model->area_scale = 0.01F;
  ha::AreaVector a;
  put_board(a, 0, 1000, -0.4);
  put_board(a, 1, 3000, 0.1);
  std::array<float, ha::HarmonicModel::kMaxFeatures> plain{}, gained{};
  std::array<float, ha::HarmonicModel::kMaxFeatures> plain_columns{}, gained_columns{};
  ha::areas_to_features(*model, a, plain);
  ASSERT_TRUE(ha::areas_to_columns(*model, a, plain_columns));
  model->column_gain = ha::ColumnGain{1.5F, -2.0F};
  ha::areas_to_features(*model, a, gained);
  ASSERT_TRUE(ha::areas_to_columns(*model, a, gained_columns));
  EXPECT_FLOAT_EQ(plain[0], 30.0F);
  EXPECT_FLOAT_EQ(plain[1], 10.0F);
  EXPECT_NEAR(gained[0], 30.0 / model->column_gain.at(0.1), 1e-4);
  EXPECT_NEAR(gained[1], 10.0 / model->column_gain.at(-0.4), 1e-4);
  EXPECT_EQ(gained_columns, plain_columns);
  // Without columns measured, plain areas.
  a.width_px = 0;
  ha::areas_to_features(*model, a, gained);
  EXPECT_EQ(gained, plain);
}
