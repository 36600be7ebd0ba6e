#include "harmoloc/sim_host/label_offset.hpp"

#include "harmoloc/algorithms/odometry.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace harmoloc::sim_host {
namespace {

struct Track {
  std::vector<double> t_s, x_m, y_m;
  // Dead-reckoned position at @p t (linear between samples); false outside the track.
  bool at(double t, double& x, double& y) const {
    if (t < t_s.front() || t > t_s.back()) return false;
    const auto it = std::upper_bound(t_s.begin(), t_s.end(), t);
    const std::size_t b =
        it == t_s.end() ? t_s.size() - 1 : static_cast<std::size_t>(it - t_s.begin());
    const std::size_t a = b > 0 ? b - 1 : 0;
    const double span = t_s[b] - t_s[a];
    const double w = span > 0.0 ? (t - t_s[a]) / span : 0.0;
    x = x_m[a] + w * (x_m[b] - x_m[a]);
    y = y_m[a] + w * (y_m[b] - y_m[a]);
    return true;
  }
};

Track dead_reckon(const OdometryTrack& odo) {
  Track tr;
  const std::size_t n = odo.timestamp_ns.size();
  tr.t_s.reserve(n);
  tr.x_m.reserve(n);
  tr.y_m.reserve(n);
  const std::uint64_t t0 = odo.timestamp_ns.front();
  algorithms::Pose2 pose;
  for (std::size_t i = 0; i < n; ++i) {
    if (i > 0) {
      pose = algorithms::apply_arc(
          pose,
          algorithms::odometry_from_ticks(odo.geometry, odo.left_ticks[i] - odo.left_ticks[i - 1],
                                          odo.right_ticks[i] - odo.right_ticks[i - 1]));
    }
    // Seconds after the first sample (the labels are converted the same way).
    tr.t_s.push_back(static_cast<double>(odo.timestamp_ns[i] - t0) * 1e-9);
    tr.x_m.push_back(pose.x_m);
    tr.y_m.push_back(pose.y_m);
  }
  return tr;
}

}  // namespace

LabelOffsetEstimate estimate_label_offset(const OdometryTrack& odometry,
                                          const std::vector<dataset::StampedPose>& labels,
                                          double max_offset_s) {
  LabelOffsetEstimate e;
  if (odometry.empty()) {
    e.why_not = "the run has no wheel odometry to compare the labels with";
    return e;
  }
  if (labels.size() < 4) {
    e.why_not = "fewer than 4 labels";
    return e;
  }
  const Track track = dead_reckon(odometry);
  const std::uint64_t t0 = odometry.timestamp_ns.front();
  const double t0_s =
      static_cast<double>(t0 / 1000000000ULL) + static_cast<double>(t0 % 1000000000ULL) * 1e-9;
  std::vector<double> t;
  for (const dataset::StampedPose& l : labels) t.push_back(l.t_s - t0_s);

  // The label pairs compared: consecutive labels up to four apart (longer chords span the
  // turnarounds and speed changes that show the offset).
  struct Pair {
    std::size_t a, b;
    double label_m;
  };
  std::vector<Pair> pairs;
  for (std::size_t gap = 1; gap <= 4; ++gap) {
    for (std::size_t a = 0; a + gap < labels.size(); ++a) {
      const std::size_t b = a + gap;
      pairs.push_back(Pair{a, b,
                           std::hypot(labels[b].pose.x_m - labels[a].pose.x_m,
                                      labels[b].pose.y_m - labels[a].pose.y_m)});
    }
  }
  // The odometry's distance between a pair's shifted times (negative: outside the odometry).
  const auto chord = [&](const Pair& p, double offset) {
    double xa, ya, xb, yb;
    if (!track.at(t[p.a] + offset, xa, ya) || !track.at(t[p.b] + offset, xb, yb)) return -1.0;
    return std::hypot(xb - xa, yb - ya);
  };
  // Mean squared misfit at an offset, over the pairs that stay within the odometry.
  const auto misfit = [&](double offset, std::size_t& used) {
    double sum = 0.0;
    used = 0;
    for (const Pair& p : pairs) {
      const double c = chord(p, offset);
      if (c < 0.0) continue;
      sum += (c - p.label_m) * (c - p.label_m);
      ++used;
    }
    return used > 0 ? sum / static_cast<double>(used) : std::numeric_limits<double>::infinity();
  };
  constexpr double kStep = 0.005;
  const int steps = static_cast<int>(std::lround(max_offset_s / kStep));
  std::vector<double> cost(static_cast<std::size_t>(2 * steps + 1));
  std::size_t min_used = std::numeric_limits<std::size_t>::max(), used = 0;
  for (int k = -steps; k <= steps; ++k) {
    cost[static_cast<std::size_t>(k + steps)] = misfit(k * kStep, used);
    min_used = std::min(min_used, used);
  }
  if (min_used < 8) {
    e.why_not = "too few labels stay within the run's odometry when shifted";
    return e;
  }
  const auto best =
      static_cast<std::size_t>(std::min_element(cost.begin(), cost.end()) - cost.begin());
  e.offset_s = (static_cast<double>(best) - steps) * kStep;
  e.rms_at_best_m = std::sqrt(cost[best]);
  e.rms_at_zero_m = std::sqrt(cost[static_cast<std::size_t>(steps)]);
  double away = std::numeric_limits<double>::infinity();
  const auto far = static_cast<std::size_t>(std::lround(0.2 / kStep));
  for (std::size_t k = 0; k < cost.size(); ++k) {
    if (k + far <= best || k >= best + far) away = std::min(away, cost[k]);
  }
  e.contrast = std::sqrt(away / std::max(cost[best], 1e-12));
  if (best == 0 || best + 1 == cost.size()) {
    char why[120];
    std::snprintf(why, sizeof why, "the best offset is at the edge of the search (+-%.1f s)",
                  max_offset_s);
    e.why_not = why;
    return e;
  }
  // Its standard error as a least-squares estimate: the misfit's spread over how fast the
  // chords change with the offset (Gauss-Newton, one parameter).
  double slope2 = 0.0, rss = 0.0;
  std::size_t n = 0;
  for (const Pair& p : pairs) {
    const double c = chord(p, e.offset_s), lo = chord(p, e.offset_s - kStep),
                 hi = chord(p, e.offset_s + kStep);
    if (c < 0.0 || lo < 0.0 || hi < 0.0) continue;
    const double d = (hi - lo) / (2.0 * kStep);
    slope2 += d * d;
    rss += (c - p.label_m) * (c - p.label_m);
    ++n;
  }
  e.standard_error_s = n > 1 && slope2 > 0.0 ? std::sqrt(rss / static_cast<double>(n - 1) / slope2)
                                             : std::numeric_limits<double>::infinity();
  if (!(e.standard_error_s <= 0.05)) {
    char why[240];
    std::snprintf(why, sizeof why,
                  "the run does not show it clearly (best %+.3f s, +-%.3f s; the robot's speed "
                  "barely changes between labels)",
                  e.offset_s, e.standard_error_s);
    e.why_not = why;
    return e;
  }
  e.found = true;
  return e;
}

}  // namespace harmoloc::sim_host
