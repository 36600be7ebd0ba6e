#include "harmoloc/sim_host/report.hpp"

#include <algorithm>
#include <cmath>

#include "histogram_edges.hpp"
#include "plot_kit.hpp"

namespace harmoloc::sim_host {

namespace {

std::size_t occupied_buckets(const CycleHistogram& h, std::size_t first, std::size_t last) {
  std::size_t n = 0;
  for (std::size_t b = first; b <= last; ++b) n += h.counts[b] > 0;
  return n;
}

}  // namespace

std::string timing_svg(const RunStats& stats) {
  const double width = 860.0;
  const Area area{80.0, 100.0, width - 80.0 - 30.0, 260.0};
  const StageTiming* cycle = stats.stage("cycle");
  const std::uint64_t total = stats.cycle_histogram ? stats.cycle_histogram->total() : 0;
  // The budget joins the bars' axis when it is near enough not to squeeze them; otherwise a
  // second panel below shows the bars against it.
  double occupied_hi = 0.0;
  if (stats.cycle_histogram) {
    const CycleHistogram& ch = *stats.cycle_histogram;
    for (std::size_t b = 0; b < ch.upper_us.size(); ++b) {
      if (ch.counts[b] > 0) occupied_hi = ch.upper_us[b];
    }
  }
  const bool budget_in_view = stats.budget_us <= 1.5 * occupied_hi;
  Canvas svg(width, area.bottom() + 90.0 + (budget_in_view || occupied_hi == 0.0 ? 0.0 : 150.0));
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
  // True bucket edges (histogram_edges.hpp): the firmware lists only non-empty buckets.
  const std::vector<double> lower_us = bucket_lower_us(h);
  std::size_t first = n, last = 0;
  for (std::size_t b = 0; b < n; ++b) {
    if (h.counts[b] > 0) {
      first = std::min(first, b);
      last = b;
    }
  }
  // Shown: the occupied range with a little room, from 0 when that is close, and the budget.
  const double occupied_lo = lower_us[first];
  const double room = 0.04 * (occupied_hi - occupied_lo);
  double v0 = std::max(0.0, occupied_lo - room);
  if (v0 < 0.35 * occupied_hi) v0 = 0.0;
  double v1 = occupied_hi + room;
  if (budget_in_view) v1 = std::max(v1, stats.budget_us * 1.04);
  // Uneven widths: bar height is a density (cycles per the narrowest shown width), so that a
  // wide bucket's area, not its height, counts its cycles.
  double narrowest = 0.0, widest = 0.0;
  for (std::size_t b = first; b <= last; ++b) {
    if (h.counts[b] == 0) continue;
    const double w = h.upper_us[b] - lower_us[b];
    narrowest = narrowest == 0.0 ? w : std::min(narrowest, w);
    widest = std::max(widest, w);
  }
  const bool uniform = widest - narrowest <= 1e-6 * widest;
  const auto height_of = [&](std::size_t b) {
    const double c = static_cast<double>(h.counts[b]);
    return uniform ? c : c * narrowest / (h.upper_us[b] - lower_us[b]);
  };
  const Scale sx{v0, v1, area.left, area.right()};
  const auto x_of = [&](double us) { return sx(std::clamp(us, v0, v1)); };
  const bool in_ms = v1 >= 2000.0;
  const double divisor = in_ms ? 1000.0 : 1.0;
  const std::vector<Tick> x_ticks = make_ticks(sx, nice_step(v1 - v0, 8), divisor);
  double peak = 0.0;
  for (std::size_t b = first; b <= last; ++b) peak = std::max(peak, height_of(b));
  const double y_step = nice_step(peak * 1.08, 5);
  const double y_top = std::max(y_step, std::ceil(peak * 1.08 / y_step - 1e-9) * y_step);
  const Scale sy{0.0, y_top, area.bottom(), area.top};
  std::vector<Tick> y_ticks;
  const int y_decimals = uniform ? 0 : svg::decimals_for(y_step);
  for (const double v : ticks_in(0.0, y_top, uniform ? std::max(1.0, y_step) : y_step)) {
    y_ticks.push_back({sy(v), format("%.*f", y_decimals, v)});
  }
  const std::string y_title =
      uniform ? std::string("cycles") : "cycles per " + duration(narrowest, true);
  draw_axes(svg, area, x_ticks, y_ticks, in_ms ? "cycle time (ms)" : "cycle time (µs)", y_title,
            false);
  const auto draw_bars = [&](const Scale& bx, const Scale& by, const Area& a) {
    for (std::size_t b = first; b <= last; ++b) {
      if (h.counts[b] == 0) continue;
      const double xa = bx(std::clamp(lower_us[b], bx.v0, bx.v1));
      const double xb = bx(std::clamp(h.upper_us[b], bx.v0, bx.v1));
      const double hpx = std::max(1.0, a.bottom() - by(height_of(b)));
      const double gap = xb - xa > 4.0 ? 0.5 : 0.0;
      // At least a pixel: a bucket narrower than that is still seen.
      svg.rect(xa + gap, a.bottom() - hpx, std::max(xb - xa - 2.0 * gap, 1.0), hpx, "#6b9bd1",
               " stroke=\"#3f6fa8\" stroke-width=\"0.5\"");
    }
  };
  svg.raw("<g class=\"bars\">\n");
  draw_bars(sx, sy, area);
  svg.raw("</g>\n");
  const auto budget_line = [&](double x, const Area& a) {
    svg.line(x, a.top - 4.0, x, a.bottom(), kP99Colour, 2.0, " class=\"budget\"");
    const std::string label = "budget " + budget(stats.budget_us);
    const bool right_side = x + 6.0 + text_width(label, 12.0) < a.right();
    svg.text(right_side ? x + 5.0 : x - 5.0, a.top + 12.0, label, right_side ? "start" : "end",
             12.0, kP99Colour, " font-weight=\"bold\"");
  };
  if (budget_in_view) budget_line(x_of(stats.budget_us), area);

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
  for (std::size_t b = last + 1; b < n; ++b) hidden_above += h.counts[b];
  caption = format("%zu occupied buckets, %s to %s", occupied_buckets(h, first, last),
                   occupied_lo > 0.0 ? duration(occupied_lo, true).c_str() : "0",
                   duration(occupied_hi, true).c_str());
  caption += uniform ? ", drawn at their true widths"
                     : ", uneven buckets drawn at their true widths (height: cycles per " +
                           duration(narrowest, true) + ")";
  if (hidden_above > 0) {
    caption +=
        format(";  %llu cycle%s above %s not drawn", static_cast<unsigned long long>(hidden_above),
               hidden_above == 1 ? "" : "s", duration(occupied_hi, true).c_str());
  }
  if (cycle != nullptr) caption += ";  max " + duration(cycle->max_us, true);
  svg.text(width / 2.0, area.bottom() + 66.0, caption, "middle", 11.5, kMutedColour);

  // The budget far off the bars: a second, narrow panel from 0 to the budget shows the headroom.
  if (!budget_in_view) {
    const Area whole{area.left, area.bottom() + 110.0, area.width, 70.0};
    const double w1 = std::max(stats.budget_us, occupied_hi) * 1.04;
    const Scale wx{0.0, w1, whole.left, whole.right()};
    const Scale wy{0.0, y_top, whole.bottom(), whole.top};
    draw_axes(svg, whole, make_ticks(wx, nice_step(w1, 8), w1 >= 2000.0 ? 1000.0 : 1.0), {},
              w1 >= 2000.0 ? "cycle time (ms)" : "cycle time (µs)", "", false);
    svg.text(whole.left + 6.0, whole.top - 8.0, "the same cycles against the budget", "start", 12.0,
             kTextColour, " font-weight=\"bold\"");
    svg.raw("<g class=\"bars-budget\">\n");
    draw_bars(wx, wy, whole);
    svg.raw("</g>\n");
    budget_line(wx(stats.budget_us), whole);
  }
  return svg.finish();
}

}  // namespace harmoloc::sim_host
