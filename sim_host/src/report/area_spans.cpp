// What the report takes from an area log: the periods the filter distrusted each board (runs of
// frames with its bit set) and each board's area over the ground truth's time span.
#include <algorithm>

#include "harmoloc/sim_host/report.hpp"

namespace harmoloc::sim_host {

std::vector<TimeSpan> distrusted_spans(const dataset::AreaLog& log, std::size_t board) {
  std::vector<TimeSpan> spans;
  const std::size_t n = std::min(log.timestamp_ns.size(), log.distrusted_mask.size());
  if (!log.has_distrust || board >= 32) return spans;
  const auto t_s = [&](std::size_t i) { return static_cast<double>(log.timestamp_ns[i]) * 1e-9; };
  const auto frame_end = [&](std::size_t i) {
    if (i + 1 < n) return t_s(i + 1);
    return i > 0 ? t_s(i) + (t_s(i) - t_s(i - 1)) : t_s(i);
  };
  for (std::size_t i = 0; i < n; ++i) {
    if ((log.distrusted_mask[i] >> board & 1U) == 0U) continue;
    if (!spans.empty() && i > 0 && (log.distrusted_mask[i - 1] >> board & 1U) != 0U) {
      spans.back().end_s = frame_end(i);
    } else {
      spans.push_back({t_s(i), frame_end(i)});
    }
  }
  return spans;
}

std::vector<BoardAreaSummary> board_area_summary(const Report& report) {
  std::vector<BoardAreaSummary> out;
  if (!report.areas) return out;
  const dataset::AreaLog& log = *report.areas;
  const double from_s = report.truth.front().t_s, to_s = report.truth.back().t_s;
  const double frame_px =
      static_cast<double>(log.image_width_px) * static_cast<double>(log.image_height_px);
  for (std::size_t b = 0; b < log.board_names.size(); ++b) {
    BoardAreaSummary s;
    s.name = log.board_names[b];
    double sum = 0.0;
    for (std::size_t i = 0; i < log.areas.size(); ++i) {
      const double t = static_cast<double>(log.timestamp_ns[i]) * 1e-9;
      if (t < from_s || t > to_s) continue;
      const double percent = 100.0 * static_cast<double>(log.areas[i].pixels[b]) / frame_px;
      s.min_percent = s.frames == 0 ? percent : std::min(s.min_percent, percent);
      s.max_percent = s.frames == 0 ? percent : std::max(s.max_percent, percent);
      sum += percent;
      ++s.frames;
    }
    if (s.frames > 0) s.mean_percent = sum / static_cast<double>(s.frames);
    for (const TimeSpan& span : distrusted_spans(log, b)) {
      s.distrusted_s += std::max(0.0, std::min(span.end_s, to_s) - std::max(span.start_s, from_s));
    }
    out.push_back(std::move(s));
  }
  return out;
}

}  // namespace harmoloc::sim_host
