// The health timeline: which mode the firmware was in when (from the link's STATUSTEXTs), with
// the quality it sent in each ODOMETRY below, so that an error peak can be matched with a lost
// camera or encoder.
#include <algorithm>
#include <array>
#include <cmath>

#include "harmoloc/sim_host/report.hpp"
#include "plot_kit.hpp"

namespace harmoloc::sim_host {

namespace {

using firmware::Health;

constexpr std::array<Health, 5> kHealths = {Health::kNominal, Health::kOdometryOnly,
                                            Health::kVisionOnly, Health::kInvalid,
                                            Health::kNotInitialized};

const char* health_colour(Health h) {
  switch (h) {
    case Health::kNominal:
      return "#2ca02c";
    case Health::kOdometryOnly:
      return "#ff7f0e";
    case Health::kVisionOnly:
      return "#9467bd";
    case Health::kInvalid:
      return "#d62728";
    case Health::kNotInitialized:
      break;
  }
  return "#bbbbbb";
}

}  // namespace

std::string health_svg(const Report& report) {
  const double t0 = report.truth.front().t_s;
  const double duration_s = std::max(report.truth.back().t_s - t0, 1e-3);
  const double width = 860.0, left = 110.0, right = 30.0;
  const Area strip{left, 84.0, width - left - right, 34.0};
  const Area quality{left, strip.bottom() + 40.0, width - left - right, 120.0};
  Canvas svg(width, quality.bottom() + 80.0);
  svg.text(width / 2.0, 26.0, "Health over time (from the link)", "middle", 17.0, kTextColour,
           " font-weight=\"bold\"");

  std::array<double, kHealths.size()> time_s{};
  if (report.link) {
    for (const HealthSpan& span : report.link->health) {
      for (std::size_t i = 0; i < kHealths.size(); ++i) {
        if (kHealths[i] == span.health) time_s[i] += span.end_s - span.start_s;
      }
    }
  }
  double total_s = 0.0;
  for (const double t : time_s) total_s += t;
  std::vector<LegendItem> legend;
  for (std::size_t i = 0; i < kHealths.size(); ++i) {
    if (time_s[i] <= 0.0 && kHealths[i] != Health::kNominal) continue;
    legend.push_back({LegendItem::Kind::kBox, health_colour(kHealths[i]),
                      format("%s %.1f%%", health_label(kHealths[i]),
                             total_s > 0.0 ? 100.0 * time_s[i] / total_s : 0.0)});
  }
  const double legend_w = draw_legend(svg, 0, 0, legend, false);
  draw_legend(svg, (width - legend_w) / 2.0, 56.0, legend);

  const Scale sx{0.0, duration_s, strip.left, strip.right()};
  svg.rect(strip.left, strip.top, strip.width, strip.height, "#f7f7f7",
           format(" stroke=\"%s\"", kAxisColour));
  svg.text(strip.left - 8.0, strip.top + strip.height / 2.0 + 4.0, "health", "end", 12.0);
  svg.raw(clip_path("health-strip", strip));
  svg.raw("<g class=\"health\" clip-path=\"url(#health-strip)\">\n");
  if (report.link) {
    for (const HealthSpan& span : report.link->health) {
      const double xa = sx(span.start_s - t0), xb = sx(span.end_s - t0);
      // A one-cycle span still shows as a sliver.
      svg.rect(xa, strip.top, std::max(xb - xa, 1.0), strip.height, health_colour(span.health),
               format(" data-health=\"%s\"", health_label(span.health)));
    }
  }
  svg.raw("</g>\n");

  const Scale sy{0.0, 100.0, quality.bottom(), quality.top};
  draw_axes(svg, quality, make_ticks(sx, nice_step(duration_s, 10)), make_ticks(sy, 25.0),
            "time since start of ground truth (s)", "quality");
  svg.text(quality.left + 6.0, quality.top - 8.0,
           "ODOMETRY quality (100 at 0 spread, 0 at 10 cm; -1 invalid, drawn at 0)", "start", 12.0,
           kTextColour, " font-weight=\"bold\"");
  std::vector<std::pair<double, double>> points;
  if (report.link) {
    for (const LinkPose& p : report.link->poses) {
      points.emplace_back(sx(p.t_s - t0), sy(std::max(p.quality, 0)));
    }
  }
  svg.raw(clip_path("health-quality", quality));
  svg.raw("<g clip-path=\"url(#health-quality)\">\n");
  svg.polyline(points, kEstimateColour, 1.2, "quality");
  svg.raw("</g>\n");

  std::size_t changes = 0;
  if (report.link && !report.link->health.empty()) changes = report.link->health.size() - 1;
  draw_caption(svg, quality.bottom() + 62.0,
               {format("%zu health change%s over %zu poses on the link; a change is placed at "
                       "the first pose after its STATUSTEXT",
                       changes, changes == 1 ? "" : "s",
                       report.link ? report.link->poses.size() : std::size_t{0})});
  return svg.finish();
}

}  // namespace harmoloc::sim_host
