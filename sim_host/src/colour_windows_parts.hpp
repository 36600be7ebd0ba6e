#pragma once
/// @file What the pieces of the colour-window proposer share (private to sim_host/src/): the
/// firmware's HSV of a frame, its blobs and quantiles (colour_image_stats.cpp), the hue circle's
/// clusters (colour_hue_clusters.cpp) and one board's window from its pixels
/// (colour_board_window.cpp). The public side is harmoloc/sim_host/colour_windows.hpp.

#include <array>
#include <cstdint>
#include <vector>

#include "harmoloc/algorithms/segmentation.hpp"
#include "harmoloc/sim_host/colour_windows.hpp"

namespace harmoloc::sim_host::colours::detail {

// colour_image_stats.cpp

// The firmware's HSV of a frame, three planes.
struct HsvPlanes {
  std::vector<std::uint8_t> h, s, v;
};

void to_hsv(const RgbImage& img, const algorithms::BoardClassifier& cls, HsvPlanes& out);
void component_sizes(const std::vector<int>& label, std::uint32_t width, std::uint32_t height,
                     std::vector<std::uint32_t>& size_of);
std::vector<std::uint8_t> dilate(const std::vector<std::uint8_t>& mask, std::uint32_t width,
                                 std::uint32_t height, int radius);
double quantile(std::vector<double> v, double q);

// colour_hue_clusters.cpp

int wrap_h8(int h8);
std::vector<int> hue_basins(const std::array<double, kHueSteps>& hist, std::vector<int>& peaks);
HueRange owned_range(const std::vector<int>& owner, int id, int peak);

// colour_board_window.cpp

// A board's pixels by hue and saturation, and by value: what its window is built from.
struct PixelStats {
  std::vector<std::array<double, 256>> board_sat_by_hue =
      std::vector<std::array<double, 256>>(kHueSteps);
  std::array<double, 256> board_value{};
};

using SatByHue = std::vector<std::array<double, 256>>;

ProposedBoard window_from(const PixelStats& board, const SatByHue& background,
                          const std::vector<int>& neighbour_peaks_h8);
void name_uniquely(std::vector<ProposedBoard>& boards);

}  // namespace harmoloc::sim_host::colours::detail
