// The per-sample fix errors over the forward map's cells (fix_error_grid.hpp): each cell holds
// the error of the sample nearest its centre, as the pass over every sample names it, and the
// fix term is as wide as the error where the fix lands.
#include "harmoloc/algorithms/fix_error_grid.hpp"

#include "harmoloc/algorithms/map_codec.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <memory>
#include <random>
#include <vector>

namespace ha = harmoloc::algorithms;

namespace {

// A 3 m x 1.5 m grid of 2 cm cells with some tiles not stored (every third along the top rows).
void lay_out(ha::ForwardMap& f) {
  const std::uint32_t columns = 150, rows = 75;
  const std::uint32_t tc = (columns + 7) / 8, tr = (rows + 7) / 8;
  std::vector<std::uint8_t> stored(static_cast<std::size_t>(tc) * tr, 1);
  for (std::uint32_t c = 0; c < tc; c += 3) stored[(tr - 1) * tc + c] = 0;
  ASSERT_TRUE(ha::lay_out_grid(f, columns, rows, stored.data()));
  f.origin_x_m = -0.2F;
  f.origin_y_m = 0.1F;
  f.cell_m = 0.02F;
  f.board_count = 1;
}

}  // namespace

TEST(FixErrorGrid, EachCellHoldsTheErrorOfTheSampleNearestItsCentre) {
  auto map = std::make_unique<ha::MapFile>();
  lay_out(map->forward);
  ha::HarmonicModel& m = map->model;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> x(-0.5F, 3.2F), y(0.0F, 1.7F), e(0.001F, 0.3F);
  m.sample_count = 700;
  for (std::size_t i = 0; i < m.sample_count; ++i) {
    m.target_x_m[i] = x(rng);
    m.target_y_m[i] = y(rng);
    m.fix_error_m[i] = e(rng);
  }
  // Ties: two samples at one place, the lower index names the error.
  m.target_x_m[11] = m.target_x_m[10];
  m.target_y_m[11] = m.target_y_m[10];
  auto grid = std::make_unique<ha::FixErrorGrid>();
  grid->build(m, map->forward);
  ASSERT_FALSE(grid->empty());
  const ha::ForwardMap& f = map->forward;
  std::size_t checked = 0;
  for (std::uint32_t r = 0; r < f.rows; ++r) {
    for (std::uint32_t c = 0; c < f.columns; ++c) {
      const double cx = f.origin_x_m + static_cast<float>(c) * f.cell_m;
      const double cy = f.origin_y_m + static_cast<float>(r) * f.cell_m;
      if (!f.stored(c, r)) continue;
      // A little off the centre, towards the cell's own side of its neighbours.
      ASSERT_EQ(grid->at(f, cx + 0.004, cy + 0.003), ha::fix_error_near(m, cx, cy))
          << c << " " << r;
      ++checked;
    }
  }
  EXPECT_GT(checked, 9000U);
  // Where no tile is stored (the top row's first tile: cells 0-7 of rows 72-74) nothing was
  // trained; the error reads 0 and the run's own width applies.
  EXPECT_EQ(grid->at(f, f.origin_x_m + 3 * f.cell_m, f.origin_y_m + 74 * f.cell_m), 0.0F);
}

TEST(FixErrorGrid, EmptyWithoutErrorsOrWithoutAForwardMap) {
  auto map = std::make_unique<ha::MapFile>();
  lay_out(map->forward);
  ha::HarmonicModel& m = map->model;
  m.sample_count = 2;
  m.target_x_m[1] = 1.0F;
  EXPECT_FALSE(ha::has_fix_errors(m));
  auto grid = std::make_unique<ha::FixErrorGrid>();
  grid->build(m, map->forward);
  EXPECT_TRUE(grid->empty());
  EXPECT_EQ(grid->at(map->forward, 1.0, 0.5), 0.0F);
  m.fix_error_m[1] = 0.2F;
  EXPECT_TRUE(ha::has_fix_errors(m));
  grid->build(m, map->forward);
  EXPECT_FALSE(grid->empty());
  EXPECT_FLOAT_EQ(grid->at(map->forward, 0.9, 0.5), 0.2F);
  EXPECT_EQ(grid->at(map->forward, 0.1, 0.5), 0.0F);  // nearest sample 0, which has none
  // Errors beyond the sample count do not count.
  m.fix_error_m[1] = 0.0F;
  m.fix_error_m[2] = 0.5F;
  EXPECT_FALSE(ha::has_fix_errors(m));
  auto no_grid = std::make_unique<ha::MapFile>();
  grid->build(m, no_grid->forward);
  EXPECT_TRUE(grid->empty());
}

// As wide as the run's fix error (already tempered), or the error where the fix lands tempered
// alike where that is wider.
TEST(FixErrorGrid, TheFixTermWidensWhereTheMapSaysSo) {
  const double tempering = 40.0, base = 0.03 * std::sqrt(tempering);
  EXPECT_DOUBLE_EQ(ha::fix_term_sigma_m(base, tempering, 0.01F), base);
  EXPECT_NEAR(ha::fix_term_sigma_m(base, tempering, 0.15F), 0.15 * std::sqrt(tempering), 1e-6);
  EXPECT_DOUBLE_EQ(ha::fix_term_sigma_m(base, tempering, 0.0F), base);  // none in the map
  EXPECT_DOUBLE_EQ(ha::fix_term_sigma_m(base, 1.0, 0.05F), base);
}
