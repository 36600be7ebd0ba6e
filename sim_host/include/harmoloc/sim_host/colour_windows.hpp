#pragma once
/// @file Choosing the boards' colour windows from a recording (harmoloc-colours, docs/colours.md):
/// automatically, from the saturated colour clusters that are compact blobs and change area
/// along the run, or guided, from a rectangle around each board in one frame. Every pixel is
/// converted with the firmware's own HSV (algorithms::BoardClassifier, OpenCV's 8-bit scale:
/// H 0..179 in 2-degree steps), and every window is proposed in those steps, so a window means
/// exactly what the firmware will count.

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "harmoloc/algorithms/segmentation.hpp"
#include "harmoloc/sim_host/colour_frames.hpp"

namespace harmoloc::sim_host::colours {

/// Hue in the firmware's 8-bit steps (0..179, 2 degrees each).
constexpr int kHueSteps = 180;

/// A hue window in 8-bit steps, both ends inside; lo > hi wraps through 0.
struct HueRange {
  int lo_h8 = 0;
  int hi_h8 = 0;
  bool contains(int h8) const {
    return lo_h8 <= hi_h8 ? h8 >= lo_h8 && h8 <= hi_h8 : h8 >= lo_h8 || h8 <= hi_h8;
  }
  int width_h8() const { return (hi_h8 - lo_h8 + kHueSteps) % kHueSteps + 1; }
};

/// The firmware's window for @p hue and the given saturation and value bounds: degrees are the
/// steps' own (2 x step), so the firmware's ceil(min / 2) .. floor(max / 2) gives the same steps
/// back, and a range that wraps gives min > max degrees.
algorithms::ColourThreshold to_threshold(const HueRange& hue, std::uint8_t saturation_min,
                                         std::uint8_t value_min, std::uint8_t value_max = 255);
/// The steps the firmware takes for @p threshold's hue (docs/segmentation.md).
HueRange hue_steps_of(const algorithms::ColourThreshold& threshold);

/// Circular distance between two hues, in steps (0..90).
int hue_distance_h8(int a_h8, int b_h8);
/// A colour's everyday name by hue (red, orange, ...), for board names.
std::string hue_name(int hue_h8);

/// One saturated colour cluster of the run: a peak of the hue histogram of saturated pixels.
struct HueCluster {
  HueRange range;            ///< from valley to valley of the smoothed histogram
  int peak_h8 = 0;           ///< the histogram's maximum
  double pixels = 0.0;       ///< saturated pixels of this hue over the sampled frames
  double blob_share = 0.0;   ///< share of those pixels in blobs (connected, at least kMinBlobShare)
  double frames_seen = 0.0;  ///< share of the sampled frames with a blob of this colour
  double area_variation = 0.0;     ///< (90th - 10th percentile) / 90th percentile of its blob area
  double median_area_share = 0.0;  ///< median blob area over the sampled frames, share of frame
  bool is_board = false;
  std::string verdict;  ///< why it is, or is not, taken for a board
};

/// A proposed board: its name and the firmware window, with what the window was built from.
struct ProposedBoard {
  std::string name;
  algorithms::ColourThreshold window;
  int hue_centre_h8 = 0;
  std::uint8_t board_saturation_low = 0;  ///< 2nd percentile of the board's pixels
  /// The background near its hue: the saturation that all but 0.01% of the frame stays below.
  std::uint8_t background_saturation_high = 0;
  std::uint8_t board_value_low = 0;  ///< 1st percentile of the board's pixels
};

/// Progress on a long pass: (done, total, what).
using Progress = std::function<void(std::size_t, std::size_t, const char*)>;

struct AutoOptions {
  int boards = 0;                      ///< 0: as many as pass the tests below (at most 8)
  std::size_t sample_frames = 150;     ///< frames looked at, evenly spread over the run
  std::uint8_t saturation_floor = 80;  ///< a pixel below this is not a candidate board pixel
  std::uint8_t value_floor = 50;       ///< below this noise moves the hue too much to trust
  /// A blob: a connected set of a cluster's pixels of at least this share of the frame.
  double min_blob_share = 0.0004;
  double min_blob_fraction = 0.6;   ///< of a cluster's pixels in blobs, for a board
  double min_frames_seen = 0.05;    ///< of the sampled frames showing it, for a board
  double min_area_variation = 0.3;  ///< a board's area changes along the run
  Progress progress;
};

struct AutoResult {
  std::vector<HueCluster> clusters;   ///< every cluster found, boards and others
  std::vector<ProposedBoard> boards;  ///< in hue order
  std::size_t frames_sampled = 0;
};

/// Automatic mode: the clusters of the run and a window per board.
AutoResult propose_automatic(FrameSource& frames, const AutoOptions& options);

/// Guided mode: a board's name and its rectangle in one frame.
struct GuidedRect {
  std::string name;
  int x = 0, y = 0, w = 0, h = 0;
};
/// Parses NAME:x,y,w,h (pixels). Throws std::invalid_argument with what is wrong.
GuidedRect parse_rect(const std::string& text);

/// Guided mode: each board's window from the pixels inside its rectangle against those outside
/// every rectangle. Throws std::runtime_error when a rectangle leaves the frame or holds no
/// saturated colour.
std::vector<ProposedBoard> propose_guided(const RgbImage& frame,
                                          const std::vector<GuidedRect>& rects,
                                          const AutoOptions& options);

/// The boards' areas along a whole run, as the firmware counts them, and how much their masks
/// overlap.
struct RunAreas {
  std::size_t boards = 0;
  std::size_t frame_px = 0;
  std::vector<std::uint64_t> timestamp_ns;
  std::vector<std::vector<std::uint32_t>> area_px;  ///< [board][frame]
  /// [a][b]: pixels in both a's and b's windows, summed over the run.
  std::vector<std::vector<std::uint64_t>> overlap_px;
  std::vector<std::uint64_t> total_px;  ///< [board]: its pixels summed over the run
};
/// Every frame (or every @p step-th), segmented with the firmware's colour table.
RunAreas measure_run(FrameSource& frames, const algorithms::ThresholdSet& windows,
                     std::size_t step = 1, const Progress& progress = {});

/// One line each: a window whose area is far above a board's in most frames (background), an
/// area that is nearly constant over the run, boards whose masks overlap, a board never seen.
std::vector<std::string> window_warnings(const RunAreas& areas,
                                         const std::vector<std::string>& names);

/// The `[[board]]` tables of @p boards as TOML (toml++). With @p base_config the other sections
/// of that config are kept and its boards replaced (a robot owner's own harmoloc.toml).
std::string boards_toml(const std::vector<ProposedBoard>& boards,
                        const std::string& base_config_text = "");

/// The ThresholdSet of @p boards, in order.
algorithms::ThresholdSet threshold_set_of(const std::vector<ProposedBoard>& boards);

}  // namespace harmoloc::sim_host::colours
