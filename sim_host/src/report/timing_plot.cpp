#include "harmoloc/sim_host/report.hpp"

#include <algorithm>
#include <cmath>

#include "plot_kit.hpp"

namespace harmoloc::sim_host {

std::string timing_svg(const RunStats& stats) {
  const double width = 860.0;
  const Area area{80.0, 100.0, width - 80.0 - 30.0, 260.0};
  Canvas svg(width, area.bottom() + 90.0);
  const StageTiming* cycle = stats.stage("cycle");
  const std::uint64_t total = stats.cycle_histogram ? stats.cycle_histogram->total() : 0;
  svg.text(width / 2.0, 26.0,
           format("Whole-cycle compute time (%llu cycles)", static_cast<unsigned long long>(total)),
           "middle", 17.0, kTextColour, " font-weight=\"bold\"");
  std::string subtitle = "budget " + budget(stats.budget_us) + " per cycle";
  if (cycle != nullptr && std::isfinite(cycle->p99_us)) {
    subtitle +=
        format(": p99 uses %.1f%% of it, max %.1f%%", cycle->p99_us / stats.budget_us * 100.0,
               cycle->max_us / stats.budget_us * 100.0);
  }
  if (stats.overruns) {
    subtitle += format(";  %llu overrun%s", static_cast<unsigned long long>(*stats.overruns),
                       *stats.overruns == 1 ? "" : "s");
  }
  svg.text(width / 2.0, 48.0, subtitle, "middle", 13.0, kMutedColour);

  if (!stats.cycle_histogram || total == stats.cycle_histogram->overflow()) {
    svg.rect(area.left, area.top, area.width, area.height, "none",
             format(" stroke=\"%s\"", kAxisColour));
    svg.text(area.left + area.width / 2.0, area.top + area.height / 2.0,
             "no cycle histogram in the stats", "middle", 14.0, kMutedColour);
    return svg.finish();
  }
  const CycleHistogram& h = *stats.cycle_histogram;
  const std::size_t n = h.upper_us.size();
  const auto lower = [&](std::size_t b) { return b == 0 ? 0.0 : h.upper_us[b - 1]; };
  std::size_t first = n, last = 0;
  for (std::size_t b = 0; b < n; ++b) {
    if (h.counts[b] > 0) {
      first = std::min(first, b);
      last = b;
    }
  }
  // Shown buckets: the occupied range and one empty bucket either side; from 0 when that is close.
  std::size_t b0 = first > 0 ? first - 1 : 0;
  const std::size_t b1 = std::min(last + 1, n - 1);
  if (lower(b0) < 0.35 * h.upper_us[b1]) b0 = 0;
  const double v0 = lower(b0), v1 = h.upper_us[b1];
  bool uniform = true;
  const double w0 = h.upper_us[b1] - lower(b1);
  for (std::size_t b = b0; b <= b1; ++b) {
    uniform = uniform && std::fabs((h.upper_us[b] - lower(b)) - w0) <= 1e-6 * w0;
  }
  const std::size_t shown = b1 - b0 + 1;
  // x: linear when the buckets are even; otherwise each bucket gets the same width.
  const auto x_of = [&](double us) {
    us = std::clamp(us, v0, v1);
    if (uniform) return area.left + (us - v0) / (v1 - v0) * area.width;
    std::size_t b = b0;
    while (b < b1 && us > h.upper_us[b]) ++b;
    const double frac = (us - lower(b)) / (h.upper_us[b] - lower(b));
    return area.left +
           (static_cast<double>(b - b0) + frac) / static_cast<double>(shown) * area.width;
  };
  const bool in_ms = v1 >= 2000.0;
  const double divisor = in_ms ? 1000.0 : 1.0;
  std::vector<Tick> x_ticks;
  if (uniform) {
    const Scale sx{v0, v1, area.left, area.right()};
    x_ticks = make_ticks(sx, nice_step(v1 - v0, 8), divisor);
  } else {
    const std::size_t every = (shown + 9) / 10;
    for (std::size_t b = b0; b <= b1 + 1; b += every) {
      const double v = b == 0 ? 0.0 : h.upper_us[b - 1];
      x_ticks.push_back({x_of(v), format("%g", v / divisor)});
    }
  }
  std::uint64_t peak = 0;
  for (std::size_t b = b0; b <= b1; ++b) peak = std::max(peak, h.counts[b]);
  const double y_step = nice_step(static_cast<double>(peak) * 1.08, 5);
  const double y_top =
      std::max(y_step, std::ceil(static_cast<double>(peak) * 1.08 / y_step - 1e-9) * y_step);
  const Scale sy{0.0, y_top, area.bottom(), area.top};
  std::vector<Tick> y_ticks;
  for (const double v : ticks_in(0.0, y_top, std::max(1.0, y_step))) {
    y_ticks.push_back({sy(v), format("%.0f", v)});
  }
  draw_axes(svg, area, x_ticks, y_ticks, in_ms ? "cycle time (ms)" : "cycle time (µs)", "cycles",
            false);
  svg.raw("<g class=\"bars\">\n");
  for (std::size_t b = b0; b <= b1; ++b) {
    if (h.counts[b] == 0) continue;
    const double xa = x_of(lower(b)), xb = x_of(h.upper_us[b]);
    const double hpx = std::max(1.0, area.bottom() - sy(static_cast<double>(h.counts[b])));
    const double gap = xb - xa > 4.0 ? 0.5 : 0.0;
    svg.rect(xa + gap, area.bottom() - hpx, xb - xa - 2.0 * gap, hpx, "#6b9bd1",
             " stroke=\"#3f6fa8\" stroke-width=\"0.5\"");
  }
  svg.raw("</g>\n");

  // Median and p99 markers, labels on separate rows so that they never collide.
  if (cycle != nullptr) {
    struct Marker {
      double us;
      const char* colour;
      std::string label;
      double row;
    };
    const Marker markers[] = {
        {cycle->median_us, kMedianColour, "median " + duration(cycle->median_us, true), 0.0},
        {cycle->p99_us, kP99Colour, "p99 " + duration(cycle->p99_us, true), 1.0},
    };
    for (const Marker& m : markers) {
      if (!std::isfinite(m.us)) continue;
      const double x = x_of(m.us);
      const double baseline = area.top - 22.0 + 16.0 * m.row;
      svg.line(x, baseline - 10.0, x, area.bottom(), m.colour, 1.8, " stroke-dasharray=\"6,3\"");
      const double w = text_width(m.label, 12.0);
      const bool right_side = x + 6.0 + w < area.right();
      svg.text(right_side ? x + 5.0 : x - 5.0, baseline, m.label, right_side ? "start" : "end",
               12.0, m.colour, " font-weight=\"bold\"");
    }
  }
  std::string caption;
  std::uint64_t hidden_above = h.overflow();
  for (std::size_t b = b1 + 1; b < n; ++b) hidden_above += h.counts[b];
  caption = format("%zu buckets shown, %s to %s", shown,
                   v0 > 0.0 ? duration(v0, true).c_str() : "0", duration(v1, true).c_str());
  if (!uniform) caption += ", uneven buckets drawn at equal width";
  if (hidden_above > 0) {
    caption +=
        format(";  %llu cycle%s above %s not drawn", static_cast<unsigned long long>(hidden_above),
               hidden_above == 1 ? "" : "s", duration(v1, true).c_str());
  }
  if (cycle != nullptr) caption += ";  max " + duration(cycle->max_us, true);
  svg.text(width / 2.0, area.bottom() + 66.0, caption, "middle", 11.5, kMutedColour);
  return svg.finish();
}

}  // namespace harmoloc::sim_host
