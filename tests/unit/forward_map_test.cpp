// Where a position falls on the forward map's grid (forward_map.hpp): locate() and the cell
// that stands for a place in the per-cell values (route heading, heading coverage, fix error):
// the heaviest stored corner, the first on a tie, none when no corner is stored.
#include "harmoloc/algorithms/forward_map.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <memory>

namespace ha = harmoloc::algorithms;

TEST(NearestStoredCell, TheHeaviestStoredCornerOrNone) {
  constexpr std::uint32_t kVoid = static_cast<std::uint32_t>(ha::ForwardMap::kVoidCell);
  ha::GridPoint point{{10, 11, 12, 13}, {0.1F, 0.2F, 0.6F, 0.1F}, 0.0F};
  EXPECT_EQ(ha::nearest_stored_cell(point), 12U);
  point.index[2] = kVoid;  // the heaviest is not stored: the next heaviest stands for it
  EXPECT_EQ(ha::nearest_stored_cell(point), 11U);
  point.weight[3] = 0.2F;  // a tie goes to the first corner
  EXPECT_EQ(ha::nearest_stored_cell(point), 11U);
  point.index[0] = point.index[1] = point.index[3] = kVoid;
  EXPECT_EQ(ha::nearest_stored_cell(point), ha::ForwardMap::kVoidCell);
}

// On a laid-out grid: a place near a stored cell's centre is that cell; a place near an unstored
// tile's cell is the stored neighbour across the tile's edge; a place inside an unstored tile,
// away from every stored cell, is no cell.
TEST(NearestStoredCell, OnAGridWithAnUnstoredTile) {
  auto map = std::make_unique<ha::ForwardMap>();
  // 16 x 8 cells of 2 cm from (1 m, 2 m): two tiles side by side, the right one not stored.
  const std::uint8_t stored[2] = {1, 0};
  ASSERT_TRUE(ha::lay_out_grid(*map, 16, 8, stored));
  map->origin_x_m = 1.0F;
  map->origin_y_m = 2.0F;
  map->cell_m = 0.02F;
  const ha::ForwardMap& f = *map;

  const double cell_m = f.cell_m;
  const auto cell_at = [&](double x_m, double y_m) {
    return ha::nearest_stored_cell(ha::locate(f, x_m, y_m));
  };
  EXPECT_EQ(cell_at(1.0 + 3 * cell_m + 0.004, 2.0 + 5 * cell_m - 0.004), f.index(3, 5));
  // Cell 8 (the unstored tile's first column) is nearer, cell 7 is the stored one.
  EXPECT_EQ(cell_at(1.0 + 7 * cell_m + 0.015, 2.0 + 2 * cell_m), f.index(7, 2));
  EXPECT_EQ(cell_at(1.0 + 12 * cell_m, 2.0 + 4 * cell_m), ha::ForwardMap::kVoidCell);
  // Beyond the border the place is clamped to the border cells.
  const ha::GridPoint outside = ha::locate(f, 0.5, 2.0 + 1 * cell_m);
  EXPECT_GT(outside.outside_m, 0.4F);
  EXPECT_EQ(ha::nearest_stored_cell(outside), f.index(0, 1));
}
