#pragma once
/// @file What the pieces of the forward map's training (forward_map_training*.cpp) share: a frame
/// with its position, and the fit of the grid to such frames. Private to sim_host/src.

#include <cstddef>
#include <vector>

#include "harmoloc/sim_host/forward_map_training.hpp"

namespace harmoloc::sim_host::forward_map_training_detail {

using algorithms::ForwardMap;
using algorithms::kMaxBoards;

struct Positioned {
  double x_m, y_m, yaw_rad, t_s;
  bool has_yaw;
  const std::vector<float>* features;
  double travel_m;  // < 0: unknown (then passes are told apart by time)
  // Per board, the world bearing the frame saw it at (NaN: none); nullptr: no bearings.
  const float* bearing_rad = nullptr;
  // Per board, its angular half-width in the frame (radians, where bearing_rad holds one).
  const float* half_width_rad = nullptr;
};

// forward_map_training_fit.cpp
// Fits the grid to frames that already have a position (shared by both ways of placing them).
// With @p law (a1, a3 and the optical axis under the law, ForwardMap::visibility_axis_rad;
// nullptr: none) and frames' bearing_rad, also the boards' bearings;
// @p board_places: where each board stands (x, y per board, NaN: not placed; nullptr: none).
ForwardMapReport fit_grid(std::vector<Positioned>& frames, std::size_t board_count,
                          const ForwardMapOptions& opt, algorithms::ForwardMap& out,
                          ForwardMapReport report, const double* law = nullptr,
                          const double* board_places = nullptr);

}  // namespace harmoloc::sim_host::forward_map_training_detail
