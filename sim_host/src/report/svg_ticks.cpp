#include "harmoloc/sim_host/svg_ticks.hpp"

#include <algorithm>
#include <cmath>

#include "format.hpp"

namespace harmoloc::sim_host::svg {

double nice_step(double range, int target) {
  if (!(range > 0.0) || !std::isfinite(range)) return 1.0;
  const double raw = range / target;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  const double norm = raw / magnitude;
  const double nice = norm < 1.5 ? 1.0 : norm < 3.0 ? 2.0 : norm < 7.0 ? 5.0 : 10.0;
  return nice * magnitude;
}

double covering_step(double range, double max_intervals, double magnitude_intervals) {
  const double step =
      std::pow(10.0, std::floor(std::log10(range <= 0 ? 1.0 : range / magnitude_intervals)));
  for (const double f : {1.0, 2.0, 5.0, 10.0}) {
    if (f * step * max_intervals >= range) return f * step;
  }
  return step;
}

int decimals_for(double step) {
  const int d = static_cast<int>(-std::floor(std::log10(step) + 1e-9));
  return std::clamp(d, 0, 6);
}

std::vector<double> ticks_in(double lo, double hi, double step) {
  std::vector<double> out;
  const double first = std::ceil(lo / step - 1e-9) * step;
  for (double v = first; v <= hi + step * 1e-9 && out.size() < 200; v += step) {
    out.push_back(std::fabs(v) < step * 1e-9 ? 0.0 : v);
  }
  return out;
}

std::vector<Tick> make_ticks(const Scale& scale, double step, double divisor) {
  std::vector<Tick> out;
  const int decimals = decimals_for(step / divisor);
  for (const double v :
       ticks_in(std::min(scale.v0, scale.v1), std::max(scale.v0, scale.v1), step)) {
    out.push_back({scale(v), report_text::format("%.*f", decimals, v / divisor)});
  }
  return out;
}

}  // namespace harmoloc::sim_host::svg
