#include <array>
#include <sstream>
#include <stdexcept>
#include <string>

#include "colour_windows_parts.hpp"

namespace harmoloc::sim_host::colours {

namespace alg = algorithms;

using namespace detail;  // the pieces of colour_windows_parts.hpp

GuidedRect parse_rect(const std::string& text) {
  const auto colon = text.rfind(':');
  if (colon == std::string::npos || colon == 0)
    throw std::invalid_argument("'" + text + "' is not NAME:x,y,w,h");
  GuidedRect r;
  r.name = text.substr(0, colon);
  std::array<int, 4> v{};
  std::stringstream ss(text.substr(colon + 1));
  std::string item;
  std::size_t k = 0;
  while (std::getline(ss, item, ',')) {
    std::size_t used = 0;
    int x = 0;
    try {
      x = std::stoi(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (k >= 4 || used != item.size() || item.empty() || x < 0)
      throw std::invalid_argument("'" + text + "' is not NAME:x,y,w,h (whole pixels, >= 0)");
    v[k++] = x;
  }
  if (k != 4) throw std::invalid_argument("'" + text + "' is not NAME:x,y,w,h");
  if (v[2] == 0 || v[3] == 0) throw std::invalid_argument("'" + text + "': empty rectangle");
  r.x = v[0];
  r.y = v[1];
  r.w = v[2];
  r.h = v[3];
  return r;
}

std::vector<ProposedBoard> propose_guided(const RgbImage& frame,
                                          const std::vector<GuidedRect>& rects,
                                          const AutoOptions& opt) {
  const alg::BoardClassifier cls;
  HsvPlanes hsv;
  to_hsv(frame, cls, hsv);
  const std::size_t px = hsv.h.size();
  std::vector<int> inside(px, -1);
  for (std::size_t r = 0; r < rects.size(); ++r) {
    const GuidedRect& g = rects[r];
    if (g.x + g.w > static_cast<int>(frame.width_px) ||
        g.y + g.h > static_cast<int>(frame.height_px))
      throw std::runtime_error("rectangle '" + g.name + "' leaves the " +
                               std::to_string(frame.width_px) + "x" +
                               std::to_string(frame.height_px) + " frame");
    for (int y = g.y; y < g.y + g.h; ++y)
      for (int x = g.x; x < g.x + g.w; ++x)
        inside[static_cast<std::size_t>(y) * frame.width_px + static_cast<std::size_t>(x)] =
            static_cast<int>(r);
  }
  // Each rectangle's dominant saturated hue is its board; the rest of the rectangle (the wall
  // around a board) is neither board nor background.
  std::vector<PixelStats> stats(rects.size());
  std::vector<int> peaks;
  for (std::size_t r = 0; r < rects.size(); ++r) {
    std::array<double, kHueSteps> hist{};
    for (std::size_t i = 0; i < px; ++i)
      if (inside[i] == static_cast<int>(r) && hsv.s[i] >= opt.saturation_floor &&
          hsv.v[i] >= opt.value_floor)
        hist[hsv.h[i]] += 1.0;
    std::vector<int> basin_peaks;
    const std::vector<int> owner = hue_basins(hist, basin_peaks);
    if (basin_peaks.empty())
      throw std::runtime_error("rectangle '" + rects[r].name +
                               "' holds no saturated colour (saturation >= " +
                               std::to_string(opt.saturation_floor) + ")");
    int best = 0;
    double best_px = -1.0;
    for (std::size_t b = 0; b < basin_peaks.size(); ++b) {
      double sum = 0.0;
      for (int h = 0; h < kHueSteps; ++h)
        sum += owner[static_cast<std::size_t>(h)] == static_cast<int>(b)
                   ? hist[static_cast<std::size_t>(h)]
                   : 0.0;
      if (sum > best_px) {
        best_px = sum;
        best = static_cast<int>(b);
      }
    }
    peaks.push_back(basin_peaks[static_cast<std::size_t>(best)]);
    for (std::size_t i = 0; i < px; ++i) {
      if (inside[i] != static_cast<int>(r) || hsv.s[i] < opt.saturation_floor ||
          hsv.v[i] < opt.value_floor || owner[hsv.h[i]] != best)
        continue;
      stats[r].board_sat_by_hue[hsv.h[i]][hsv.s[i]] += 1.0;
      stats[r].board_value[hsv.v[i]] += 1.0;
    }
  }
  SatByHue background(kHueSteps);
  for (std::size_t i = 0; i < px; ++i)
    if (inside[i] < 0 && hsv.v[i] >= 30) background[hsv.h[i]][hsv.s[i]] += 1.0;
  std::vector<ProposedBoard> out;
  for (std::size_t r = 0; r < rects.size(); ++r) {
    std::vector<int> others;
    for (std::size_t o = 0; o < rects.size(); ++o)
      if (o != r) others.push_back(peaks[o]);
    ProposedBoard b = window_from(stats[r], background, others);
    b.name = rects[r].name;
    out.push_back(b);
  }
  return out;
}

}  // namespace harmoloc::sim_host::colours
