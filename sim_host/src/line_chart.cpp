#include "harmoloc/sim_host/line_chart.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "harmoloc/sim_host/svg.hpp"
#include "harmoloc/sim_host/svg_ticks.hpp"

namespace harmoloc::sim_host {

std::string line_chart(const std::string& title, const std::string& x_label,
                       const std::string& y_label, const std::vector<double>& x,
                       const std::vector<Series>& series, double reference,
                       const std::string& reference_label, bool markers,
                       const std::vector<Span>& spans) {
  const double w = 640, h = 400, left = 70, right = 170, top = 40, bottom = 55;
  double y_max = reference > 0 ? reference * 1.15 : 0.0;
  for (const auto& s : series)
    for (double v : s.y) y_max = std::max(y_max, v);
  // The y axis is always five steps from zero, so the top is a round number too.
  y_max = svg::covering_step(y_max, 5.0) * 5.0;
  const double x_min = x.front(), x_max = x.back();
  const auto px = [&](double v) {
    return left + (w - left - right) * (x_max > x_min ? (v - x_min) / (x_max - x_min) : 0.5);
  };
  const auto py = [&](double v) { return top + (h - top - bottom) * (1.0 - v / y_max); };
  std::ostringstream o;
  o.precision(4);
  o << "<svg xmlns='http://www.w3.org/2000/svg' width='" << w << "' height='" << h
    << "' font-family='sans-serif' font-size='12'>\n<rect width='100%' height='100%' "
       "fill='white'/>\n<text x='"
    << w / 2 << "' y='20' text-anchor='middle' font-size='14'>" << svg::escape(title)
    << "</text>\n";
  for (const Span& sp : spans) {
    const double a = std::clamp(px(sp.from), left, w - right);
    const double b = std::clamp(px(sp.to), left, w - right);
    o << "<rect x='" << a << "' y='" << top << "' width='" << std::max(1.0, b - a) << "' height='"
      << h - top - bottom << "' fill='#f2e6c9'/>\n<text x='" << a + 3 << "' y='" << top + 12
      << "' fill='#8a6d2b'>" << svg::escape(sp.label) << "</text>\n";
  }
  for (int i = 0; i <= 5; ++i) {
    const double v = y_max * i / 5.0;
    o << "<line x1='" << left << "' x2='" << w - right << "' y1='" << py(v) << "' y2='" << py(v)
      << "' stroke='#ddd'/><text x='" << left - 6 << "' y='" << py(v) + 4 << "' text-anchor='end'>"
      << v << "</text>\n";
  }
  // x ticks: every value when there are few, else round steps over the range.
  std::vector<double> ticks = x;
  if (x.size() > 12) {
    ticks.clear();
    const double xs = svg::covering_step(x_max - x_min, 10.0, 8.0);
    for (double v = std::ceil(x_min / xs) * xs; v <= x_max; v += xs) ticks.push_back(v);
  }
  for (double v : ticks) {
    o << "<text x='" << px(v) << "' y='" << h - bottom + 16 << "' text-anchor='middle'>" << v
      << "</text>\n";
  }
  o << "<text x='" << (left + w - right) / 2 << "' y='" << h - 12 << "' text-anchor='middle'>"
    << svg::escape(x_label) << "</text>\n<text x='16' y='" << (top + h - bottom) / 2
    << "' text-anchor='middle' transform='rotate(-90 16 " << (top + h - bottom) / 2 << ")'>"
    << svg::escape(y_label) << "</text>\n";
  if (reference > 0) {
    o << "<line x1='" << left << "' x2='" << w - right << "' y1='" << py(reference) << "' y2='"
      << py(reference) << "' stroke='#999' stroke-dasharray='6 4'/>\n<text x='" << w - right + 8
      << "' y='" << py(reference) + 4 << "' fill='#666'>" << svg::escape(reference_label)
      << "</text>\n";
  }
  int row = 0;
  for (const auto& s : series) {
    o << "<polyline fill='none' stroke='" << s.colour << "' stroke-width='2' points='";
    for (std::size_t i = 0; i < x.size() && i < s.y.size(); ++i)
      o << px(x[i]) << "," << py(s.y[i]) << " ";
    o << "'/>\n";
    for (std::size_t i = 0; markers && i < x.size() && i < s.y.size(); ++i)
      o << "<circle cx='" << px(x[i]) << "' cy='" << py(s.y[i]) << "' r='3' fill='" << s.colour
        << "'/>\n";
    o << "<line x1='" << w - right + 8 << "' x2='" << w - right + 28 << "' y1='" << top + 20 * row
      << "' y2='" << top + 20 * row << "' stroke='" << s.colour << "' stroke-width='2'/><text x='"
      << w - right + 34 << "' y='" << top + 20 * row + 4 << "'>" << svg::escape(s.name)
      << "</text>\n";
    ++row;
  }
  o << "</svg>\n";
  return o.str();
}

}  // namespace harmoloc::sim_host
