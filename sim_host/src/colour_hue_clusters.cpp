#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <utility>

#include "colour_windows_parts.hpp"

namespace harmoloc::sim_host::colours {

namespace alg = algorithms;

namespace detail {

int wrap_h8(int h8) {
  return ((h8 % kHueSteps) + kHueSteps) % kHueSteps;
}

// Hue clusters of a histogram of saturated pixels: every step climbs to its local maximum
// (watershed on a circle), then neighbouring basins merge while the saddle between them is more
// than half the lower peak (one colour's hue spread, not two colours). Returns a cluster id
// per step (-1: no pixels).
std::vector<int> hue_basins(const std::array<double, kHueSteps>& hist, std::vector<int>& peaks) {
  std::array<double, kHueSteps> sm{};
  const std::array<double, 5> kernel{1.0, 2.0, 3.0, 2.0, 1.0};
  for (int h = 0; h < kHueSteps; ++h) {
    for (int d = -2; d <= 2; ++d)
      sm[static_cast<std::size_t>(h)] +=
          kernel[static_cast<std::size_t>(d + 2)] * hist[static_cast<std::size_t>(wrap_h8(h + d))];
  }
  const double top = *std::max_element(sm.begin(), sm.end());
  std::vector<int> owner(kHueSteps, -1);
  if (top <= 0.0) return owner;
  // Steps far below every peak are noise, not part of any colour.
  const double floor = top * 1e-4;
  std::vector<int> peak_of(kHueSteps, -1);
  for (int h = 0; h < kHueSteps; ++h) {
    if (sm[static_cast<std::size_t>(h)] <= floor) continue;
    // Climb to the local maximum; a plateau stops the climb where it starts, and its steps'
    // basins merge below (their saddle is their peak).
    int p = h;
    for (int guard = 0; guard < kHueSteps; ++guard) {
      const int l = wrap_h8(p - 1), r = wrap_h8(p + 1);
      const double here = sm[static_cast<std::size_t>(p)];
      if (sm[static_cast<std::size_t>(r)] > here &&
          sm[static_cast<std::size_t>(r)] >= sm[static_cast<std::size_t>(l)])
        p = r;
      else if (sm[static_cast<std::size_t>(l)] > here)
        p = l;
      else
        break;
    }
    peak_of[static_cast<std::size_t>(h)] = p;
  }
  // Basins by peak; merge across high saddles.
  std::map<int, int> id_of_peak;
  for (int h = 0; h < kHueSteps; ++h) {
    const int p = peak_of[static_cast<std::size_t>(h)];
    if (p >= 0 && id_of_peak.count(p) == 0) {
      const int id = static_cast<int>(id_of_peak.size());
      id_of_peak[p] = id;
    }
  }
  std::vector<int> parent(id_of_peak.size());
  std::iota(parent.begin(), parent.end(), 0);
  std::vector<double> height(id_of_peak.size());
  std::vector<int> peak_step(id_of_peak.size());
  for (const auto& [p, id] : id_of_peak) {
    height[static_cast<std::size_t>(id)] = sm[static_cast<std::size_t>(p)];
    peak_step[static_cast<std::size_t>(id)] = p;
  }
  const auto find = [&](int a) {
    while (parent[static_cast<std::size_t>(a)] != a) a = parent[static_cast<std::size_t>(a)];
    return a;
  };
  for (bool merged = true; merged;) {
    merged = false;
    for (int h = 0; h < kHueSteps; ++h) {
      const int pa = peak_of[static_cast<std::size_t>(h)];
      const int pb = peak_of[static_cast<std::size_t>(wrap_h8(h + 1))];
      if (pa < 0 || pb < 0) continue;
      const int a = find(id_of_peak[pa]), b = find(id_of_peak[pb]);
      if (a == b) continue;
      const double saddle =
          std::min(sm[static_cast<std::size_t>(h)], sm[static_cast<std::size_t>(wrap_h8(h + 1))]);
      const double lower =
          std::min(height[static_cast<std::size_t>(a)], height[static_cast<std::size_t>(b)]);
      if (saddle > 0.5 * lower) {
        const int keep =
            height[static_cast<std::size_t>(a)] >= height[static_cast<std::size_t>(b)] ? a : b;
        const int gone = keep == a ? b : a;
        parent[static_cast<std::size_t>(gone)] = keep;
        merged = true;
      }
    }
  }
  std::map<int, int> cluster_of_root;
  for (int h = 0; h < kHueSteps; ++h) {
    const int p = peak_of[static_cast<std::size_t>(h)];
    if (p < 0) continue;
    const int root = find(id_of_peak[p]);
    if (cluster_of_root.count(root) == 0) {
      const int id = static_cast<int>(cluster_of_root.size());
      cluster_of_root[root] = id;
      peaks.push_back(peak_step[static_cast<std::size_t>(root)]);
    }
    owner[static_cast<std::size_t>(h)] = cluster_of_root[root];
  }
  return owner;
}

// The contiguous circular range of the steps owned by @p id, around @p peak.
HueRange owned_range(const std::vector<int>& owner, int id, int peak) {
  int lo = peak, hi = peak;
  for (int k = 0; k < kHueSteps / 2 && owner[static_cast<std::size_t>(wrap_h8(lo - 1))] == id; ++k)
    lo = wrap_h8(lo - 1);
  for (int k = 0; k < kHueSteps / 2 && owner[static_cast<std::size_t>(wrap_h8(hi + 1))] == id; ++k)
    hi = wrap_h8(hi + 1);
  return HueRange{lo, hi};
}

}  // namespace detail

using detail::wrap_h8;

alg::ColourThreshold to_threshold(const HueRange& hue, std::uint8_t saturation_min,
                                  std::uint8_t value_min, std::uint8_t value_max) {
  alg::ColourThreshold t;
  t.hue_min_deg = static_cast<float>(2 * hue.lo_h8);
  t.hue_max_deg = static_cast<float>(2 * hue.hi_h8);
  t.saturation_min = saturation_min;
  t.value_min = value_min;
  t.value_max = value_max;
  return t;
}

HueRange hue_steps_of(const alg::ColourThreshold& t) {
  return HueRange{wrap_h8(static_cast<int>(std::ceil(t.hue_min_deg / 2.0F))),
                  wrap_h8(static_cast<int>(std::floor(t.hue_max_deg / 2.0F)))};
}

int hue_distance_h8(int a_h8, int b_h8) {
  const int d = wrap_h8(a_h8 - b_h8);
  return std::min(d, kHueSteps - d);
}

std::string hue_name(int hue_h8) {
  // The simulator's names (docs/scenarios.md), by the degrees they start at.
  static const std::array<std::pair<int, const char*>, 12> kNames{{{0, "red"},
                                                                   {15, "orange"},
                                                                   {45, "yellow"},
                                                                   {70, "lime"},
                                                                   {95, "green"},
                                                                   {155, "cyan"},
                                                                   {190, "azure"},
                                                                   {215, "blue"},
                                                                   {255, "violet"},
                                                                   {285, "magenta"},
                                                                   {320, "pink"},
                                                                   {345, "red"}}};
  const int deg = 2 * wrap_h8(hue_h8);
  const char* name = "red";
  for (const auto& [from, n] : kNames)
    if (deg >= from) name = n;
  return name;
}

}  // namespace harmoloc::sim_host::colours
