#include "harmoloc/sim_host/trajectory_evaluation.hpp"

#include <algorithm>
#include <cmath>

namespace harmoloc::sim_host {

namespace {
constexpr double kRadToDeg = 180.0 / algorithms::kPi;
}  // namespace

double percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const double rank = std::clamp(p, 0.0, 100.0) / 100.0 * static_cast<double>(values.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(rank));
  const std::size_t hi = std::min(lo + 1, values.size() - 1);
  const double frac = rank - static_cast<double>(lo);
  return values[lo] + frac * (values[hi] - values[lo]);
}

TrajectoryErrors evaluate(const std::vector<dataset::StampedPose>& truth,
                          const std::vector<dataset::StampedPose>& estimate,
                          const EvaluateOptions& options) {
  TrajectoryErrors out;
  out.skip_initial_s = options.skip_initial_s;
  if (truth.empty()) {
    out.outside_truth = estimate.size();
    return out;
  }
  const double from_s = truth.front().t_s + options.skip_initial_s;
  double sum_x2 = 0.0, sum_y2 = 0.0, sum_h2 = 0.0, sum_p = 0.0;
  std::vector<double> positions;
  for (const dataset::StampedPose& e : estimate) {
    algorithms::Pose2 reference;
    if (!dataset::interpolate(truth, e.t_s, reference)) {
      ++out.outside_truth;
      continue;
    }
    if (e.t_s < from_s) {
      ++out.skipped;
      continue;
    }
    ErrorSample s;
    s.t_s = e.t_s;
    s.dx_m = e.pose.x_m - reference.x_m;
    s.dy_m = e.pose.y_m - reference.y_m;
    s.position_m = std::hypot(s.dx_m, s.dy_m);
    s.heading_rad = algorithms::wrap_angle_rad(e.pose.yaw_rad - reference.yaw_rad);
    sum_x2 += s.dx_m * s.dx_m;
    sum_y2 += s.dy_m * s.dy_m;
    sum_h2 += s.heading_rad * s.heading_rad;
    sum_p += s.position_m;
    out.max_position_m = std::max(out.max_position_m, s.position_m);
    out.max_heading_deg = std::max(out.max_heading_deg, std::fabs(s.heading_rad) * kRadToDeg);
    positions.push_back(s.position_m);
    out.samples.push_back(s);
  }
  out.count = out.samples.size();
  if (out.count == 0) return out;
  const double n = static_cast<double>(out.count);
  const double mse_x = sum_x2 / n;
  const double mse_y = sum_y2 / n;
  out.rmse_x_m = std::sqrt(mse_x);
  out.rmse_y_m = std::sqrt(mse_y);
  out.rmse_position_m = std::sqrt(mse_x + mse_y);
  out.mse_x_cm2 = mse_x * 1e4;
  out.mse_y_cm2 = mse_y * 1e4;
  out.mean_position_m = sum_p / n;
  out.rmse_heading_deg = std::sqrt(sum_h2 / n) * kRadToDeg;
  out.p95_position_m = percentile(std::move(positions), 95.0);
  return out;
}

}  // namespace harmoloc::sim_host
