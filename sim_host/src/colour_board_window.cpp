#include <algorithm>
#include <cmath>
#include <map>

#include "colour_windows_parts.hpp"

namespace harmoloc::sim_host::colours::detail {

namespace {

// Percentile of a histogram (share 0..1 of its total), as a bin index.
template <typename Hist>
int hist_percentile(const Hist& hist, double share) {
  double total = 0.0;
  for (const auto c : hist) total += static_cast<double>(c);
  if (total <= 0.0) return 0;
  const double want = share * total;
  double sum = 0.0;
  for (std::size_t i = 0; i < hist.size(); ++i) {
    sum += static_cast<double>(hist[i]);
    if (sum >= want) return static_cast<int>(i);
  }
  return static_cast<int>(hist.size()) - 1;
}

}  // namespace

// A window around a board's pixels: the hue steps they cover plus a margin, kept off the
// neighbouring colours' peaks (half the gap less 2 steps, as a careful user would); the
// saturation minimum 45% of the way from the background's most saturated pixels of that hue to
// the board's least saturated; the value minimum well below the board's darkest.
ProposedBoard window_from(const PixelStats& board, const SatByHue& background,
                          const std::vector<int>& neighbour_peaks_h8) {
  std::array<double, kHueSteps> hue_hist{};
  std::array<double, 256> sat_hist{};
  for (int h = 0; h < kHueSteps; ++h) {
    for (int s = 0; s < 256; ++s) {
      const double c =
          board.board_sat_by_hue[static_cast<std::size_t>(h)][static_cast<std::size_t>(s)];
      hue_hist[static_cast<std::size_t>(h)] += c;
      sat_hist[static_cast<std::size_t>(s)] += c;
    }
  }
  const int peak =
      static_cast<int>(std::max_element(hue_hist.begin(), hue_hist.end()) - hue_hist.begin());
  // Unwrap around the peak so that reds through 0 are one interval.
  std::array<double, kHueSteps> unwrapped{};
  for (int d = -kHueSteps / 2; d < kHueSteps / 2; ++d)
    unwrapped[static_cast<std::size_t>(d + kHueSteps / 2)] =
        hue_hist[static_cast<std::size_t>(wrap_h8(peak + d))];
  const int p_lo = hist_percentile(unwrapped, 0.005) - kHueSteps / 2;
  const int p_mid = hist_percentile(unwrapped, 0.5) - kHueSteps / 2;
  const int p_hi = hist_percentile(unwrapped, 0.995) - kHueSteps / 2;
  const int centre = wrap_h8(peak + p_mid);

  // 8..10 steps (16..20 degrees) each side, as far as the neighbours allow.
  constexpr int kPreferredHalf = 10, kMinHalf = 2, kMargin = 2;
  int left = std::max(p_mid - p_lo + kMargin, kPreferredHalf);
  int right = std::max(p_hi - p_mid + kMargin, kPreferredHalf);
  for (const int n : neighbour_peaks_h8) {
    const int d_right = wrap_h8(n - centre), d_left = wrap_h8(centre - n);
    if (d_right == 0) continue;
    if (d_right <= kHueSteps / 2) right = std::min(right, d_right / 2 - kMargin);
    if (d_left <= kHueSteps / 2) left = std::min(left, d_left / 2 - kMargin);
  }
  left = std::max(left, kMinHalf);
  right = std::max(right, kMinHalf);
  const HueRange hue{wrap_h8(centre - left), wrap_h8(centre + right)};

  ProposedBoard out;
  out.hue_centre_h8 = centre;
  out.board_saturation_low = static_cast<std::uint8_t>(hist_percentile(sat_hist, 0.02));
  // The background of the board's hue, and of hues a little beyond the window: light and noise
  // move a pale colour's hue more than a saturated one's.
  constexpr int kBackgroundMargin = 5;
  const HueRange near_hue{wrap_h8(hue.lo_h8 - kBackgroundMargin),
                          wrap_h8(hue.hi_h8 + kBackgroundMargin)};
  std::array<double, 256> bg_sat{};
  double bg_total = 0.0;
  for (int h = 0; h < kHueSteps; ++h) {
    const bool near = near_hue.contains(h);
    for (int s = 0; s < 256; ++s) {
      const double c = background[static_cast<std::size_t>(h)][static_cast<std::size_t>(s)];
      bg_total += c;
      if (near) bg_sat[static_cast<std::size_t>(s)] += c;
    }
  }
  // Its most saturated pixels, all but what may leak: 0.01% of the frame (scattered noise pixels
  // cannot be kept out without losing the board's own).
  int bg_high = 0;
  double above = 0.0;
  for (int s = 255; s >= 0; --s) {
    above += bg_sat[static_cast<std::size_t>(s)];
    if (above > 1e-4 * bg_total) {
      bg_high = s;
      break;
    }
  }
  out.background_saturation_high = static_cast<std::uint8_t>(bg_high);
  const int board_low = out.board_saturation_low;
  const int s_min = board_low > bg_high
                        ? bg_high + static_cast<int>(std::lround(0.45 * (board_low - bg_high)))
                        : board_low;
  out.board_value_low = static_cast<std::uint8_t>(hist_percentile(board.board_value, 0.01));
  // Well below the board's darkest in the recording: a dimmer day must not lose its pixels,
  // and dark pixels whose hue noise could reach the window are below saturation_min anyway.
  const int v_min = std::max(30, static_cast<int>(0.4 * out.board_value_low));
  out.window = to_threshold(hue, static_cast<std::uint8_t>(std::clamp(s_min, 1, 255)),
                            static_cast<std::uint8_t>(std::min(v_min, 255)));
  out.name = hue_name(centre);
  return out;
}

void name_uniquely(std::vector<ProposedBoard>& boards) {
  std::map<std::string, int> count;
  for (const auto& b : boards) ++count[b.name];
  std::map<std::string, int> seen;
  for (auto& b : boards) {
    if (count[b.name] > 1) b.name += "-" + std::to_string(++seen[b.name]);
  }
}

}  // namespace harmoloc::sim_host::colours::detail
