#include <algorithm>
#include <array>
#include <cstdio>

#include "colour_windows_parts.hpp"

namespace harmoloc::sim_host::colours {

namespace alg = algorithms;

using detail::quantile;

RunAreas measure_run(FrameSource& frames, const alg::ThresholdSet& windows, std::size_t step,
                     const Progress& progress) {
  RunAreas out;
  out.boards = windows.count;
  out.area_px.assign(windows.count, {});
  out.overlap_px.assign(windows.count, std::vector<std::uint64_t>(windows.count, 0));
  out.total_px.assign(windows.count, 0);
  std::vector<std::uint8_t> storage(alg::ColourTable::kStorageBytes);
  alg::ColourTable table;
  table.build(alg::BoardClassifier(windows), storage.data());
  RgbImage img;
  step = std::max<std::size_t>(step, 1);
  const std::size_t n = frames.size();
  for (std::size_t f = 0; f < n; f += step) {
    if (progress) progress(f, n, "areas");
    frames.read(f, img);
    const std::size_t px = static_cast<std::size_t>(img.width_px) * img.height_px;
    out.frame_px = px;
    std::array<std::uint32_t, 256> by_mask{};
    for (std::size_t i = 0; i < px; ++i)
      ++by_mask[table.classify(img.rgb[3 * i], img.rgb[3 * i + 1], img.rgb[3 * i + 2])];
    out.timestamp_ns.push_back(frames.timestamp_ns(f));
    for (std::size_t b = 0; b < windows.count; ++b) out.area_px[b].push_back(0);
    for (unsigned mask = 1; mask < 256; ++mask) {
      const std::uint32_t count = by_mask[mask];
      if (count == 0) continue;
      for (std::size_t a = 0; a < windows.count; ++a) {
        if ((mask & (1U << a)) == 0) continue;
        out.area_px[a].back() += count;
        out.total_px[a] += count;
        for (std::size_t b = a + 1; b < windows.count; ++b) {
          if ((mask & (1U << b)) == 0) continue;
          out.overlap_px[a][b] += count;
          out.overlap_px[b][a] += count;
        }
      }
    }
  }
  if (progress) progress(n, n, "areas");
  return out;
}

std::vector<std::string> window_warnings(const RunAreas& r, const std::vector<std::string>& names) {
  std::vector<std::string> out;
  const double frame_px = static_cast<double>(std::max<std::size_t>(r.frame_px, 1));
  std::vector<double> median(r.boards), p10(r.boards), p90(r.boards);
  for (std::size_t b = 0; b < r.boards; ++b) {
    const std::vector<double> a(r.area_px[b].begin(), r.area_px[b].end());
    median[b] = quantile(a, 0.5);
    p10[b] = quantile(a, 0.1);
    p90[b] = quantile(a, 0.9);
  }
  char line[400];
  for (std::size_t b = 0; b < r.boards; ++b) {
    const char* name = names[b].c_str();
    if (r.total_px[b] == 0) {
      std::snprintf(
          line, sizeof line,
          "board '%s': no pixel in its window in any frame (wrong colour, or not in view)", name);
      out.emplace_back(line);
      continue;
    }
    // What a board looks like here: the other boards' typical area when in view.
    std::vector<double> others;
    for (std::size_t o = 0; o < r.boards; ++o)
      if (o != b && p90[o] > 0.0) others.push_back(p90[o]);
    const double typical = others.empty() ? 0.0 : quantile(others, 0.5);
    const double share = median[b] / frame_px;
    if (share > 0.25 || (typical > 0.0 && median[b] > 3.0 * typical && share > 0.02)) {
      std::snprintf(line, sizeof line,
                    "board '%s' catches background: %.1f%% of the frame in half the frames "
                    "(%.0f px; the other boards at most %.0f px in most frames)",
                    name, 100.0 * share, median[b], typical);
      out.emplace_back(line);
    }
    if (p10[b] > 0.0 && p90[b] > 0.0 && (p90[b] - p10[b]) / p90[b] < 0.15) {
      std::snprintf(line, sizeof line,
                    "board '%s' has a nearly constant area (%.0f..%.0f px in 80%% of the frames): "
                    "it tells no places apart (background, or part of the robot in view)",
                    name, p10[b], p90[b]);
      out.emplace_back(line);
    }
  }
  for (std::size_t a = 0; a < r.boards; ++a) {
    for (std::size_t b = a + 1; b < r.boards; ++b) {
      const double smaller =
          static_cast<double>(std::max<std::uint64_t>(std::min(r.total_px[a], r.total_px[b]), 1));
      const double shared = static_cast<double>(r.overlap_px[a][b]);
      if (shared > 0.02 * smaller) {
        std::snprintf(line, sizeof line,
                      "boards '%s' and '%s' overlap: %.1f%% of the smaller one's pixels are in "
                      "both windows",
                      names[a].c_str(), names[b].c_str(), 100.0 * shared / smaller);
        out.emplace_back(line);
      }
    }
  }
  return out;
}

}  // namespace harmoloc::sim_host::colours
