#pragma once
/// @file The colour tool's preview (docs/colours.md): PNG images of the frames with each board's
/// mask, and an HTML page with the frames, the masks overlaid and each board's area along the
/// run.

#include <cstdint>
#include <string>
#include <vector>

#include "harmoloc/sim_host/colour_windows.hpp"

namespace harmoloc::sim_host::colours {

/// An 8-bit PNG (@p channels 1, 3 or 4, rows packed), compressed with zlib.
std::vector<std::uint8_t> encode_png(std::uint32_t width_px, std::uint32_t height_px, int channels,
                                     const std::vector<std::uint8_t>& pixels);
void write_png(const std::string& path, std::uint32_t width_px, std::uint32_t height_px,
               int channels, const std::vector<std::uint8_t>& pixels);

/// Board @p board's mask of @p frame as RGBA: its pixels in a colour that stands out from the
/// board's own (the opposite hue), the rest transparent. Pixels counted by the firmware's own
/// classification of @p windows.
std::vector<std::uint8_t> mask_rgba(const RgbImage& frame, const algorithms::ThresholdSet& windows,
                                    std::size_t board);

struct PreviewInput {
  std::string title;  ///< the recording
  std::vector<ProposedBoard> boards;
  RunAreas areas;
  std::vector<std::string> warnings;
  std::vector<HueCluster> clusters;  ///< automatic mode: every cluster and its verdict
};

/// Writes DIR/index.html, DIR/frame-*.png and DIR/mask-*.png: for each board the frame where its
/// area is largest, and the frame where most boards show, each with the masks overlaid. Returns
/// the page's path.
std::string write_preview(const std::string& dir, FrameSource& frames, const PreviewInput& input);

}  // namespace harmoloc::sim_host::colours
