#include "harmoloc/sim_host/scenario.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "scenario_parts.hpp"

namespace harmoloc::sim_host {

using scenario_detail::kDeg;

void hsv_of(const Rgb& c, double& hue_deg, double& saturation, double& value) {
  const double r = c.r, g = c.g, b = c.b;
  const double hi = std::max({r, g, b}), lo = std::min({r, g, b});
  value = hi;
  saturation = hi > 0.0 ? 255.0 * (hi - lo) / hi : 0.0;
  hue_deg = 0.0;
  if (hi > lo) {
    if (hi == r)
      hue_deg = 60.0 * (g - b) / (hi - lo);
    else if (hi == g)
      hue_deg = 120.0 + 60.0 * (b - r) / (hi - lo);
    else
      hue_deg = 240.0 + 60.0 * (r - g) / (hi - lo);
    if (hue_deg < 0.0) hue_deg += 360.0;
  }
}

double light_gain_at(const Scenario& s, double t_s) {
  const LightingSpec& l = s.lighting;
  double gain = s.camera.light_gain;
  if (l.drift_amplitude != 0.0) {
    gain *= 1.0 + l.drift_amplitude * std::sin(2.0 * algorithms::kPi * t_s / l.drift_period_s +
                                               l.drift_phase_deg * kDeg);
  }
  double step = 1.0;
  for (const auto& st : l.steps) {
    if (st[0] <= t_s) step = st[1];
  }
  return gain * step;
}

std::string describe_events(const Scenario& s) {
  std::string out;
  const auto add = [&out](std::size_t n, const char* what) {
    if (n == 0) return;
    out += (out.empty() ? "" : ", ") + std::to_string(n) + " " + what + (n == 1 ? "" : "s");
  };
  add(static_cast<std::size_t>(std::max(0, s.kidnaps.count)), "kidnap");
  add(s.board_moves.size(), "board move");
  add(s.occluders.size(), "occluder");
  return out.empty() ? "no events" : out;
}

}  // namespace harmoloc::sim_host
