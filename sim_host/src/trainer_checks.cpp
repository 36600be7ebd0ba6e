#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "harmoloc/sim_host/trainer.hpp"
#include "trainer_parts.hpp"

namespace harmoloc::sim_host {

namespace trainer_detail {

void check_labels(const std::vector<dataset::StampedPose>& labels) {
  char msg[320];
  for (std::size_t l = 0; l < labels.size(); ++l) {
    const dataset::StampedPose& s = labels[l];
    if (!std::isfinite(s.t_s) || !std::isfinite(s.pose.x_m) || !std::isfinite(s.pose.y_m) ||
        std::fabs(s.pose.x_m) > 1e4 || std::fabs(s.pose.y_m) > 1e4) {
      std::snprintf(msg, sizeof msg,
                    "label %zu of %zu (t = %.3f s): (%g, %g) is not a place on a floor", l + 1,
                    labels.size(), s.t_s, s.pose.x_m, s.pose.y_m);
      throw std::runtime_error(msg);
    }
    if (l > 0 && !(s.t_s > labels[l - 1].t_s)) {
      std::snprintf(msg, sizeof msg, "label %zu of %zu (t = %.3f s): labels must be in time order",
                    l + 1, labels.size(), s.t_s);
      throw std::runtime_error(msg);
    }
  }
  // A ground robot does not cover metres in a moment: a label far from both its neighbours, more
  // than 5 m/s could explain, is mistyped (units, a swapped coordinate) or misdated.
  const auto jump = [&](std::size_t a, std::size_t b) {
    const double d = std::hypot(labels[a].pose.x_m - labels[b].pose.x_m,
                                labels[a].pose.y_m - labels[b].pose.y_m);
    return d > 0.5 + 5.0 * std::fabs(labels[a].t_s - labels[b].t_s) ? d : 0.0;
  };
  for (std::size_t l = 0; l < labels.size(); ++l) {
    const double before = l > 0 ? jump(l, l - 1) : -1.0;
    const double after = l + 1 < labels.size() ? jump(l, l + 1) : -1.0;
    if (before != 0.0 && after != 0.0 && (before > 0.0 || after > 0.0)) {
      std::snprintf(msg, sizeof msg,
                    "label %zu of %zu (t = %.3f s, x %g, y %g) is %.3g m from its neighbours: "
                    "check its position, units and time",
                    l + 1, labels.size(), labels[l].t_s, labels[l].pose.x_m, labels[l].pose.y_m,
                    std::max(before, after));
      throw std::runtime_error(msg);
    }
  }
}

std::vector<int> candidate_boards(const std::vector<int>& chosen, std::size_t boards) {
  std::vector<int> candidates = chosen;
  if (candidates.empty()) {
    for (std::size_t k = 0; k < boards; ++k) candidates.push_back(static_cast<int>(k));
  }
  for (int b : candidates) {
    if (b < 0 || static_cast<std::size_t>(b) >= boards) {
      throw std::runtime_error("board " + std::to_string(b + 1) + " is not among the " +
                               std::to_string(boards) + " configured boards");
    }
  }
  return candidates;
}

}  // namespace trainer_detail

void check_trained_map(const TrainReport& report, const std::vector<dataset::StampedPose>& labels,
                       const algorithms::MapFile& map, const TrainOptions& opt) {
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  for (const dataset::StampedPose& l : labels) {
    x0 = std::min(x0, l.pose.x_m);
    y0 = std::min(y0, l.pose.y_m);
    x1 = std::max(x1, l.pose.x_m);
    y1 = std::max(y1, l.pose.y_m);
  }
  const double extent = std::hypot(x1 - x0, y1 - y0);
  char msg[320];
  // The map's coordinates must lie where the labels are (a little beyond, for the stretch the
  // odometry carries past the first and last label).
  const double margin = std::max(opt.max_extrapolation_m, 0.1 * extent);
  const algorithms::HarmonicModel& m = map.model;
  for (std::size_t i = 0; i < m.sample_count; ++i) {
    const double x = m.target_x_m[i], y = m.target_y_m[i];
    if (!(x >= x0 - margin && x <= x1 + margin && y >= y0 - margin && y <= y1 + margin)) {
      std::snprintf(msg, sizeof msg,
                    "the trained map puts a sample at (%.3g, %.3g) m, outside the labelled region "
                    "(%.3g..%.3g, %.3g..%.3g) m: the labels do not fit the run (check their units "
                    "and times)",
                    x, y, x0, x1, y0, y1);
      throw std::runtime_error(msg);
    }
  }
  // A cross-validated error of a quarter of the labelled region is no map of it.
  const double cv = std::hypot(report.x.cv_rmse_m, report.y.cv_rmse_m);
  if (!std::isfinite(cv) || cv > std::max(0.25 * extent, 0.05)) {
    std::snprintf(msg, sizeof msg,
                  "cross-validated error %.3g m is absurd for labels spanning %.3g m: the boards "
                  "do not tell places apart (check the colour windows, the labels' units and "
                  "times)",
                  cv, extent);
    throw std::runtime_error(msg);
  }
}

}  // namespace harmoloc::sim_host
