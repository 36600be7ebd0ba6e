#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "harmoloc/algorithms/route_placement.hpp"
#include "trainer_parts.hpp"

namespace harmoloc::sim_host::trainer_detail {

// Every frame placed by the odometry between the labels. Throws, naming the label, when a label
// lies far from where the odometry between its neighbours puts it.
algorithms::PlacementResult place_frames(const AreaSeries& run,
                                         const std::vector<dataset::StampedPose>& labels,
                                         const TrainOptions& opt, PlacementReport& report) {
  const std::uint64_t t0 = run.timestamp_ns.front();
  const auto rel = [t0](std::uint64_t t) {
    return t >= t0 ? static_cast<double>(t - t0) * 1e-9 : -static_cast<double>(t0 - t) * 1e-9;
  };
  const std::vector<algorithms::OdometrySample> odometry = run.odometry.relative_to(t0);
  const double odo_begin = odometry.front().t_s, odo_end = odometry.back().t_s;
  bool labels_have_yaw = false;
  for (const dataset::StampedPose& l : labels)
    labels_have_yaw = labels_have_yaw || l.pose.yaw_rad != 0.0;
  std::vector<algorithms::PlacementLabel> placement_labels;
  const double t0_s =
      static_cast<double>(t0 / 1000000000ULL) + static_cast<double>(t0 % 1000000000ULL) * 1e-9;
  for (std::size_t l = 0; l < labels.size(); ++l) {
    const dataset::StampedPose& s = labels[l];
    const double t = s.t_s - t0_s;
    char where[96];
    std::snprintf(where, sizeof where, "label %zu of %zu (t = %.3f s)", l + 1, labels.size(),
                  s.t_s);
    if (!std::isfinite(s.pose.x_m) || !std::isfinite(s.pose.y_m) || std::fabs(s.pose.x_m) > 1e4 ||
        std::fabs(s.pose.y_m) > 1e4) {
      throw std::runtime_error(std::string(where) + ": position is not a place on a floor");
    }
    if (t < odo_begin - 0.05 || t > odo_end + 0.05) {
      throw std::runtime_error(std::string(where) +
                               ": outside the run's wheel odometry (labels must be on the "
                               "robot's clock)");
    }
    if (!placement_labels.empty() && !(t > placement_labels.back().t_s)) {
      throw std::runtime_error(std::string(where) + ": labels must be in time order");
    }
    placement_labels.push_back(
        algorithms::PlacementLabel{t, s.pose.x_m, s.pose.y_m, s.pose.yaw_rad, labels_have_yaw});
  }
  std::vector<double> query;
  query.reserve(run.timestamp_ns.size());
  for (std::uint64_t t : run.timestamp_ns) query.push_back(rel(t));
  // The odometry measured against the labels first: the placement, and the firmware with the
  // map, use the wheels as they are, not as configured.
  report.odometry =
      algorithms::calibrate_odometry(odometry, run.odometry.geometry, placement_labels);
  const algorithms::OdometryScale& scale = report.odometry.scale;
  constexpr double kMaxScaleError = 0.2;
  for (const double v : {scale.left, scale.right, scale.track}) {
    if (std::fabs(v - 1.0) > kMaxScaleError) {
      char msg[320];
      std::snprintf(msg, sizeof msg,
                    "the labels and the wheel odometry disagree: they need the left wheel x %.3f, "
                    "the right x %.3f and the track x %.3f of the configured geometry (more than "
                    "%.0f%% off): check wheel_radius_m, track_m, ticks_per_rev and the wheel "
                    "directions, and that the labels are in metres on the robot's clock",
                    scale.left, scale.right, scale.track, 100.0 * kMaxScaleError);
      throw std::runtime_error(msg);
    }
  }
  algorithms::PlacementResult placed = algorithms::place_by_odometry(
      query, odometry, algorithms::calibrated(run.odometry.geometry, scale), placement_labels);

  // Labels that the odometry between their neighbours does not support.
  std::vector<double> residuals;
  for (double r : placed.label_residual_m) {
    if (r >= 0.0) residuals.push_back(r);
  }
  if (!residuals.empty()) {
    report.median_label_residual_m = quantile(residuals, 0.5);
    for (std::size_t l = 0; l < placed.label_residual_m.size(); ++l) {
      if (placed.label_residual_m[l] > report.worst_label_residual_m) {
        report.worst_label_residual_m = placed.label_residual_m[l];
        report.worst_label = static_cast<int>(l);
      }
    }
    if (report.worst_label_residual_m > opt.label_outlier_m &&
        report.worst_label_residual_m > opt.label_outlier_ratio * report.median_label_residual_m) {
      const dataset::StampedPose& bad = labels[static_cast<std::size_t>(report.worst_label)];
      char msg[320];
      std::snprintf(msg, sizeof msg,
                    "label %d of %zu (t = %.3f s, x %.3f, y %.3f) is %.1f cm from where the "
                    "wheel odometry between its neighbours puts the robot (median of the labels "
                    "%.1f cm): check its position, units and time",
                    report.worst_label + 1, labels.size(), bad.t_s, bad.pose.x_m, bad.pose.y_m,
                    100.0 * report.worst_label_residual_m, 100.0 * report.median_label_residual_m);
      throw std::runtime_error(msg);
    }
  }
  std::vector<double> spacing;
  for (std::size_t l = 1; l < placement_labels.size(); ++l) {
    const auto a = static_cast<std::size_t>(
        std::lower_bound(query.begin(), query.end(), placement_labels[l - 1].t_s) - query.begin());
    const auto b = static_cast<std::size_t>(
        std::lower_bound(query.begin(), query.end(), placement_labels[l].t_s) - query.begin());
    if (a < query.size() && b < query.size())
      spacing.push_back(placed.travel_m[b] - placed.travel_m[a]);
  }
  if (!spacing.empty()) report.label_spacing_m = quantile(spacing, 0.5);
  report.travel_m = placed.travel_m.empty() ? 0.0 : placed.travel_m.back();
  report.used = true;
  return placed;
}

}  // namespace harmoloc::sim_host::trainer_detail
