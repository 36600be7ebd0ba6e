#include "harmoloc/sim_host/relative_error.hpp"

#include <algorithm>
#include <cmath>

#include "harmoloc/sim_host/trajectory_evaluation.hpp"

namespace harmoloc::sim_host {

namespace {

/// Times within this of delta count as reaching it: 30 Hz stamps are not exact in binary.
constexpr double kTimeSlack_s = 1e-9;

/// Translation of a^-1 b, i.e. b's position seen from a's frame.
void relative_translation(const algorithms::Pose2& a, const algorithms::Pose2& b, double& x_m,
                          double& y_m) {
  const double dx = b.x_m - a.x_m, dy = b.y_m - a.y_m;
  const double c = std::cos(a.yaw_rad), s = std::sin(a.yaw_rad);
  x_m = c * dx + s * dy;
  y_m = -s * dx + c * dy;
}

std::vector<std::size_t> anchors(const std::vector<PosePair>& poses, double delta, DeltaUnit unit) {
  std::vector<std::size_t> ids;
  if (unit == DeltaUnit::kSeconds) {
    ids.push_back(0);
    for (std::size_t i = 1; i < poses.size(); ++i) {
      if (poses[i].t_s - poses[ids.back()].t_s >= delta - kTimeSlack_s) ids.push_back(i);
    }
    return ids;
  }
  double path_m = 0.0;
  for (std::size_t i = 1; i < poses.size(); ++i) {
    path_m += std::hypot(poses[i].estimate.x_m - poses[i - 1].estimate.x_m,
                         poses[i].estimate.y_m - poses[i - 1].estimate.y_m);
    if (path_m >= delta) {
      ids.push_back(i);
      path_m = 0.0;
    }
  }
  return ids;
}

}  // namespace

std::vector<PosePair> pair_with_truth(const std::vector<dataset::StampedPose>& truth,
                                      const std::vector<dataset::StampedPose>& estimate,
                                      double from_s) {
  std::vector<PosePair> out;
  for (const dataset::StampedPose& e : estimate) {
    PosePair p;
    if (e.t_s < from_s || !dataset::interpolate(truth, e.t_s, p.truth)) continue;
    p.t_s = e.t_s;
    p.estimate = e.pose;
    out.push_back(p);
  }
  return out;
}

RelativeErrors relative_errors(const std::vector<PosePair>& poses, double delta, DeltaUnit unit) {
  RelativeErrors out;
  out.delta = delta;
  out.unit = unit;
  if (poses.size() < 2 || !(delta > 0.0)) return out;
  const std::vector<std::size_t> ids = anchors(poses, delta, unit);
  std::vector<double> errors;
  double sum_m = 0.0, sum2_m2 = 0.0;
  for (std::size_t k = 0; k + 1 < ids.size(); ++k) {
    const PosePair& a = poses[ids[k]];
    const PosePair& b = poses[ids[k + 1]];
    double qx, qy, px, py;
    relative_translation(a.truth, b.truth, qx, qy);
    relative_translation(a.estimate, b.estimate, px, py);
    // E = Q_rel^-1 P_rel: its translation is R(Q_rel)^T (p - q), whose length is |p - q|.
    const double e = std::hypot(px - qx, py - qy);
    out.samples.push_back({a.t_s, b.t_s, e});
    errors.push_back(e);
    sum_m += e;
    sum2_m2 += e * e;
    out.max_m = std::max(out.max_m, e);
  }
  out.pairs = errors.size();
  if (out.pairs == 0) return out;
  const double n = static_cast<double>(out.pairs);
  out.rmse_m = std::sqrt(sum2_m2 / n);
  out.mean_m = sum_m / n;
  out.median_m = percentile(std::move(errors), 50.0);
  return out;
}

}  // namespace harmoloc::sim_host
