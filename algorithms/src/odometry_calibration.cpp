#include "harmoloc/algorithms/odometry_calibration.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>

namespace harmoloc::algorithms {

namespace {

// The run as tick increments between nodes (every encoder sample and every label time), and
// which node each label falls on.
struct Chain {
  std::vector<double> d_left, d_right;  // ticks from node k to k + 1
  std::vector<std::size_t> label_node;
};

Chain make_chain(const std::vector<OdometrySample>& odometry,
                 const std::vector<PlacementLabel>& labels) {
  std::vector<double> times;
  times.reserve(odometry.size() + labels.size());
  for (const OdometrySample& s : odometry) times.push_back(s.t_s);
  for (const PlacementLabel& l : labels) times.push_back(l.t_s);
  std::sort(times.begin(), times.end());
  times.erase(std::unique(times.begin(), times.end()), times.end());
  std::vector<double> left(times.size()), right(times.size());
  for (std::size_t k = 0; k < times.size(); ++k) ticks_at(odometry, times[k], left[k], right[k]);
  Chain c;
  for (std::size_t k = 0; k + 1 < times.size(); ++k) {
    c.d_left.push_back(left[k + 1] - left[k]);
    c.d_right.push_back(right[k + 1] - right[k]);
  }
  for (const PlacementLabel& l : labels) {
    c.label_node.push_back(static_cast<std::size_t>(
        std::lower_bound(times.begin(), times.end(), l.t_s) - times.begin()));
  }
  return c;
}

// Dead reckoning of the whole run with @p g, the pose at each label's node.
std::vector<Pose2> reckon(const Chain& c, const DiffDriveGeometry& g) {
  const double lm = left_metres_per_tick(g), rm = right_metres_per_tick(g);
  std::vector<Pose2> at_label(c.label_node.size());
  Pose2 p;
  std::size_t next = 0;
  for (std::size_t k = 0; next < c.label_node.size(); ++k) {
    while (next < c.label_node.size() && c.label_node[next] == k) at_label[next++] = p;
    if (k >= c.d_left.size()) break;
    const double l = c.d_left[k] * lm, r = c.d_right[k] * rm;
    p = apply_arc(p, OdometryDelta{0.5 * (l + r), (r - l) / g.track_m});
  }
  for (; next < c.label_node.size(); ++next) at_label[next] = p;
  return at_label;
}

struct Stretch {
  std::size_t first, last;  // label indices, inclusive
};

// Each stretch laid over its labels by the best rotation and shift; the misfits (metres), two
// per label, appended to @p out.
void misfits(const std::vector<Pose2>& dr, const std::vector<PlacementLabel>& labels,
             const std::vector<Stretch>& stretches, std::vector<double>& out) {
  out.clear();
  for (const Stretch& s : stretches) {
    double px = 0, py = 0, qx = 0, qy = 0;
    const auto n = static_cast<double>(s.last - s.first + 1);
    for (std::size_t l = s.first; l <= s.last; ++l) {
      px += dr[l].x_m;
      py += dr[l].y_m;
      qx += labels[l].x_m;
      qy += labels[l].y_m;
    }
    px /= n, py /= n, qx /= n, qy /= n;
    double sc = 0, ss = 0;
    for (std::size_t l = s.first; l <= s.last; ++l) {
      const double ax = dr[l].x_m - px, ay = dr[l].y_m - py;
      const double bx = labels[l].x_m - qx, by = labels[l].y_m - qy;
      sc += ax * bx + ay * by;
      ss += ax * by - ay * bx;
    }
    const double phi = std::atan2(ss, sc), c = std::cos(phi), sn = std::sin(phi);
    for (std::size_t l = s.first; l <= s.last; ++l) {
      const double ax = dr[l].x_m - px, ay = dr[l].y_m - py;
      out.push_back(qx + c * ax - sn * ay - labels[l].x_m);
      out.push_back(qy + sn * ax + c * ay - labels[l].y_m);
    }
  }
}

double rms(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x * x;
  return v.empty() ? 0.0 : std::sqrt(s / static_cast<double>(v.size()) * 2.0);
}

}  // namespace

OdometryCalibration calibrate_odometry(const std::vector<OdometrySample>& odometry,
                                       const DiffDriveGeometry& geometry,
                                       const std::vector<PlacementLabel>& labels,
                                       const CalibrationOptions& opt) {
  OdometryCalibration result;
  if (odometry.size() < 2 || labels.size() < static_cast<std::size_t>(opt.min_labels))
    return result;
  const Chain chain = make_chain(odometry, labels);

  // Stretches of about window_m of travel, each starting halfway along the one before.
  const std::vector<Pose2> nominal = reckon(chain, geometry);
  std::vector<double> travel(labels.size(), 0.0);
  {
    // Travel between labels from the nominal geometry's increments.
    const double lm = left_metres_per_tick(geometry), rm = right_metres_per_tick(geometry);
    std::size_t k = 0;
    double acc = 0.0;
    for (std::size_t l = 0; l < labels.size(); ++l) {
      for (; k < chain.label_node[l] && k < chain.d_left.size(); ++k)
        acc += std::fabs(0.5 * (chain.d_left[k] * lm + chain.d_right[k] * rm));
      travel[l] = acc;
    }
  }
  std::vector<Stretch> stretches;
  for (std::size_t a = 0; a + 1 < labels.size();) {
    std::size_t b = a + 1;
    while (b + 1 < labels.size() && travel[b] - travel[a] < opt.window_m) ++b;
    if (travel[b] - travel[a] < 0.5 * opt.window_m && !stretches.empty()) break;
    if (b - a + 1 >= static_cast<std::size_t>(opt.min_labels)) stretches.push_back({a, b});
    if (b + 1 >= labels.size()) break;
    std::size_t next = a + 1;
    while (next < b && travel[next] - travel[a] < 0.5 * opt.window_m) ++next;
    a = next;
  }
  result.stretches = static_cast<int>(stretches.size());
  if (stretches.empty()) return result;

  std::vector<double> r0, r1;
  misfits(nominal, labels, stretches, r0);
  result.misfit_before_m = rms(r0);

  // Gauss-Newton over (left, right, track), misfits in label sigmas, a prior at 1.
  Eigen::Vector3d p(1.0, 1.0, 1.0);
  const auto evaluate = [&](const Eigen::Vector3d& q, std::vector<double>& out) {
    misfits(reckon(chain, calibrated(geometry, OdometryScale{q(0), q(1), q(2)})), labels, stretches,
            out);
  };
  const double inv_label = 1.0 / opt.label_sigma_m;
  const double inv_prior = 1.0 / opt.prior_sigma;
  constexpr double kStep = 1e-5;
  std::vector<double> plus, minus;
  for (int it = 0; it < opt.iterations; ++it) {
    evaluate(p, r0);
    Eigen::MatrixXd jac(static_cast<Eigen::Index>(r0.size()), 3);
    for (int j = 0; j < 3; ++j) {
      Eigen::Vector3d a = p, b = p;
      a(j) += kStep;
      b(j) -= kStep;
      evaluate(a, plus);
      evaluate(b, minus);
      for (std::size_t i = 0; i < r0.size(); ++i)
        jac(static_cast<Eigen::Index>(i), j) = (plus[i] - minus[i]) / (2.0 * kStep) * inv_label;
    }
    const Eigen::Map<const Eigen::VectorXd> r(r0.data(), static_cast<Eigen::Index>(r0.size()));
    Eigen::Matrix3d h = jac.transpose() * jac;
    Eigen::Vector3d g = jac.transpose() * (r * inv_label);
    h.diagonal().array() += inv_prior * inv_prior;
    g += (p - Eigen::Vector3d::Ones()) * inv_prior * inv_prior;
    const Eigen::Vector3d delta = -h.ldlt().solve(g);
    if (!delta.allFinite()) break;
    p += delta;
    p = p.cwiseMax(0.5).cwiseMin(2.0);
    if (delta.cwiseAbs().maxCoeff() < 1e-7) break;
  }
  evaluate(p, r1);
  result.misfit_after_m = rms(r1);
  result.scale = OdometryScale{p(0), p(1), p(2)};
  result.used = true;
  return result;
}

}  // namespace harmoloc::algorithms
