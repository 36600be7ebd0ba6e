#include "harmoloc/sim_host/colour_windows.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <sstream>
#include <stdexcept>

#include <toml++/toml.h>

#include "colour_windows_parts.hpp"

namespace harmoloc::sim_host::colours {

namespace alg = algorithms;

using namespace detail;  // the pieces of colour_windows_parts.hpp

// ---------------------------------------------------------------------------------------------

AutoResult propose_automatic(FrameSource& frames, const AutoOptions& opt) {
  AutoResult result;
  const std::size_t n = frames.size();
  if (n == 0) throw std::runtime_error("the recording has no frames");
  std::vector<std::size_t> sample;
  const std::size_t m = std::min(n, std::max<std::size_t>(opt.sample_frames, 1));
  for (std::size_t k = 0; k < m; ++k) sample.push_back(m == 1 ? 0 : k * (n - 1) / (m - 1));
  result.frames_sampled = m;
  const alg::BoardClassifier cls;
  RgbImage img;
  HsvPlanes hsv;
  const auto candidate = [&](std::size_t i) {
    return hsv.s[i] >= opt.saturation_floor && hsv.v[i] >= opt.value_floor;
  };

  // Pass 1: which saturated hues the run holds.
  std::array<double, kHueSteps> hist{};
  for (std::size_t k = 0; k < m; ++k) {
    if (opt.progress) opt.progress(k, 2 * m, "hues");
    frames.read(sample[k], img);
    to_hsv(img, cls, hsv);
    for (std::size_t i = 0; i < hsv.h.size(); ++i)
      if (candidate(i)) hist[hsv.h[i]] += 1.0;
  }
  std::vector<int> peaks;
  const std::vector<int> owner = hue_basins(hist, peaks);
  const std::size_t clusters = peaks.size();

  // Pass 2: per cluster and frame its blobs; the board candidates' pixels and the background's.
  std::vector<PixelStats> stats(clusters);
  SatByHue background(kHueSteps);
  std::vector<std::vector<double>> blob_area(clusters, std::vector<double>(m, 0.0));
  std::vector<double> all_px(clusters, 0.0), blob_px(clusters, 0.0);
  std::vector<int> label;
  std::vector<std::uint32_t> size_of;
  double frame_px = 1.0;
  for (std::size_t k = 0; k < m; ++k) {
    if (opt.progress) opt.progress(m + k, 2 * m, "blobs");
    frames.read(sample[k], img);
    to_hsv(img, cls, hsv);
    const std::size_t px = hsv.h.size();
    frame_px = static_cast<double>(px);
    const auto min_blob = static_cast<std::uint32_t>(std::ceil(opt.min_blob_share * frame_px));
    label.assign(px, -1);
    for (std::size_t i = 0; i < px; ++i)
      if (candidate(i)) label[i] = owner[hsv.h[i]];
    component_sizes(label, img.width_px, img.height_px, size_of);
    std::vector<std::uint8_t> in_blob(px, 0);
    for (std::size_t i = 0; i < px; ++i) {
      if (label[i] < 0) continue;
      const auto c = static_cast<std::size_t>(label[i]);
      all_px[c] += 1.0;
      if (size_of[i] < min_blob) continue;
      in_blob[i] = 1;
      blob_px[c] += 1.0;
      blob_area[c][k] += 1.0;
      stats[c].board_sat_by_hue[hsv.h[i]][hsv.s[i]] += 1.0;
      stats[c].board_value[hsv.v[i]] += 1.0;
    }
    const std::vector<std::uint8_t> near = dilate(in_blob, img.width_px, img.height_px, 2);
    for (std::size_t i = 0; i < px; ++i) {
      if (near[i] == 0 && hsv.v[i] >= 30) background[hsv.h[i]][hsv.s[i]] += 1.0;
    }
  }
  if (opt.progress) opt.progress(2 * m, 2 * m, "blobs");

  for (std::size_t c = 0; c < clusters; ++c) {
    HueCluster hc;
    hc.peak_h8 = peaks[c];
    hc.range = owned_range(owner, static_cast<int>(c), peaks[c]);
    hc.pixels = all_px[c];
    hc.blob_share = all_px[c] > 0.0 ? blob_px[c] / all_px[c] : 0.0;
    std::size_t seen = 0;
    for (const double a : blob_area[c]) seen += a > 0.0 ? 1 : 0;
    hc.frames_seen = static_cast<double>(seen) / static_cast<double>(m);
    const double p90 = quantile(blob_area[c], 0.9), p10 = quantile(blob_area[c], 0.1);
    hc.area_variation = p90 > 0.0 ? (p90 - p10) / p90 : 0.0;
    hc.median_area_share = quantile(blob_area[c], 0.5) / frame_px;
    char why[200];
    if (hc.blob_share < opt.min_blob_fraction) {
      std::snprintf(why, sizeof why, "scattered: %.0f%% of its pixels in blobs (< %.0f%%)",
                    100.0 * hc.blob_share, 100.0 * opt.min_blob_fraction);
    } else if (hc.frames_seen < opt.min_frames_seen) {
      std::snprintf(why, sizeof why, "rare: a blob in %.1f%% of the frames (< %.0f%%)",
                    100.0 * hc.frames_seen, 100.0 * opt.min_frames_seen);
    } else if (hc.area_variation < opt.min_area_variation) {
      std::snprintf(why, sizeof why,
                    "constant: its area changes by %.0f%% along the run (< %.0f%%): background",
                    100.0 * hc.area_variation, 100.0 * opt.min_area_variation);
    } else if (hc.median_area_share > 0.3) {
      std::snprintf(why, sizeof why, "too large: %.0f%% of the frame in half the frames",
                    100.0 * hc.median_area_share);
    } else {
      hc.is_board = true;
      std::snprintf(why, sizeof why,
                    "board: %.0f%% in blobs, in %.0f%% of the frames, area "
                    "varies %.0f%%",
                    100.0 * hc.blob_share, 100.0 * hc.frames_seen, 100.0 * hc.area_variation);
    }
    hc.verdict = why;
    result.clusters.push_back(hc);
  }

  // Rank: the boards first, then by how many blob pixels they hold over the run.
  std::vector<std::size_t> order(clusters);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    if (result.clusters[a].is_board != result.clusters[b].is_board)
      return result.clusters[a].is_board;
    return blob_px[a] > blob_px[b];
  });
  std::size_t want = 0;
  if (opt.boards > 0) {
    want = std::min(static_cast<std::size_t>(opt.boards), clusters);
  } else {
    for (const auto& hc : result.clusters) want += hc.is_board ? 1 : 0;
  }
  want = std::min(want, alg::kMaxBoards);
  std::vector<std::size_t> chosen(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(want));
  // Rejected clusters are background: their blob pixels count against a board's window.
  for (std::size_t c = 0; c < clusters; ++c) {
    if (std::find(chosen.begin(), chosen.end(), c) != chosen.end()) continue;
    result.clusters[c].is_board = false;
    for (int h = 0; h < kHueSteps; ++h)
      for (int s = 0; s < 256; ++s)
        background[static_cast<std::size_t>(h)][static_cast<std::size_t>(s)] +=
            stats[c].board_sat_by_hue[static_cast<std::size_t>(h)][static_cast<std::size_t>(s)];
  }
  for (const std::size_t c : chosen) result.clusters[c].is_board = true;
  std::sort(chosen.begin(), chosen.end(),
            [&](std::size_t a, std::size_t b) { return peaks[a] < peaks[b]; });
  for (const std::size_t c : chosen) {
    std::vector<int> others;
    for (std::size_t o = 0; o < clusters; ++o) {
      // A neighbour worth keeping off: a colour with a real share of the saturated pixels.
      if (o != c && all_px[o] >= 0.002 * all_px[c]) others.push_back(peaks[o]);
    }
    result.boards.push_back(window_from(stats[c], background, others));
  }
  name_uniquely(result.boards);
  return result;
}

// ---------------------------------------------------------------------------------------------

alg::ThresholdSet threshold_set_of(const std::vector<ProposedBoard>& boards) {
  if (boards.size() > alg::kMaxBoards)
    throw std::runtime_error("more than " + std::to_string(alg::kMaxBoards) + " boards");
  alg::ThresholdSet set;
  for (const auto& b : boards) set.boards[set.count++] = b.window;
  return set;
}

std::string boards_toml(const std::vector<ProposedBoard>& boards, const std::string& base) {
  toml::table root;
  if (!base.empty()) {
    try {
      root = toml::parse(base);
    } catch (const toml::parse_error& e) {
      std::ostringstream where;
      where << "line " << e.source().begin.line << ": " << e.description();
      throw std::runtime_error(where.str());
    }
    root.erase("board");
  }
  toml::array list;
  for (const auto& b : boards) {
    const auto& w = b.window;
    toml::table t;
    t.insert("name", b.name);
    t.insert("hue_deg", toml::array{static_cast<std::int64_t>(std::lround(w.hue_min_deg)),
                                    static_cast<std::int64_t>(std::lround(w.hue_max_deg))});
    t.insert("saturation_min", static_cast<std::int64_t>(w.saturation_min));
    t.insert("value_min", static_cast<std::int64_t>(w.value_min));
    t.insert("value_max", static_cast<std::int64_t>(w.value_max));
    list.push_back(std::move(t));
  }
  root.insert("board", std::move(list));
  std::ostringstream o;
  o << "# Colour windows proposed by harmoloc-colours (docs/colours.md). Hue in degrees (min > "
       "max\n"
       "# wraps through 0), saturation and value 8-bit HSV, as the firmware segments them.\n";
  o << root << "\n";
  return o.str();
}

}  // namespace harmoloc::sim_host::colours
