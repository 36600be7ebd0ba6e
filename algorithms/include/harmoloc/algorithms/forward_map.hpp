#pragma once
/// @file The forward map: from a position on the floor to the area each board should show there
/// (the inverse direction of the harmonic localizer), on a regular grid over the trained region.
/// The particle filter weighs every particle by how well each board's measured area fits what
/// the map expects at the particle's position, board by board, so that one occluded or moved
/// board can be recognised and ignored (board_observation.hpp). Learned by the trainer from the
/// training run; stored in the map file (docs/map-format.md). Fixed capacity.

#include <array>
#include <cstddef>
#include <cstdint>

#include "harmoloc/algorithms/segmentation.hpp"

namespace harmoloc::algorithms {

struct ForwardMap {
  static constexpr std::size_t kMaxCells = 4096;
  static constexpr std::size_t kMaxDimension = 256;  ///< columns and rows each

  /// Grid: cell (c, r) is centred on (origin_x_m + c cell_m, origin_y_m + r cell_m). Values
  /// between centres are bilinear; positions beyond the grid take the border value.
  std::uint32_t columns = 0;  ///< 0: the map has no forward model
  std::uint32_t rows = 0;
  float origin_x_m = 0.0F;
  float origin_y_m = 0.0F;
  float cell_m = 0.0F;
  /// One entry per board of the threshold set (features in the harmonic model's units,
  /// area_scale x pixels). A board with sigma 0 is not modelled (never seen in training).
  std::uint32_t board_count = 0;
  std::array<float, kMaxBoards> sigma{};
  /// Whether heading_rad holds the training run's heading (labels with orientation).
  bool has_heading = false;

  /// Expected feature of every board at each cell centre: [cell][board], kMaxBoards a cell.
  std::array<float, kMaxCells * kMaxBoards> expected{};
  /// Distance from the cell centre to the nearest position of the training run (metres): how
  /// far the map's knowledge is from this place.
  std::array<float, kMaxCells> route_distance_m{};
  /// The training run's heading near the cell (yaw, radians), where has_heading.
  std::array<float, kMaxCells> heading_rad{};

  bool present() const { return columns > 0 && rows > 0; }
  std::size_t cell_count() const { return static_cast<std::size_t>(columns) * rows; }
  float* cell(std::size_t c, std::size_t r) {
    return expected.data() + (r * columns + c) * kMaxBoards;
  }
  const float* cell(std::size_t c, std::size_t r) const {
    return expected.data() + (r * columns + c) * kMaxBoards;
  }
};

/// Where a position falls on the grid: the four surrounding cells and their bilinear weights.
struct GridPoint {
  std::uint32_t index[4];  ///< cell indices (row-major) of the corners
  float weight[4];         ///< bilinear weights, summing to 1
  float outside_m;         ///< how far the position lies beyond the grid's border cells (0 inside)
};

/// Locates (@p x_m, @p y_m) on @p map's grid (clamped to the border). @p map must be present().
GridPoint locate(const ForwardMap& map, double x_m, double y_m);

/// The expected features of all map.board_count boards at @p point.
void expected_features(const ForwardMap& map, const GridPoint& point, float* out);

/// The distance to the training run at @p point (metres; bilinear, plus the distance beyond the
/// grid for a position outside it).
float route_distance(const ForwardMap& map, const GridPoint& point);

/// The training run's heading at the cell nearest (@p x_m, @p y_m); 0 when !map.has_heading.
float route_heading(const ForwardMap& map, double x_m, double y_m);

}  // namespace harmoloc::algorithms
