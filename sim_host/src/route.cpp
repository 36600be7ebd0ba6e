#include "harmoloc/sim_host/route.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace harmoloc::sim_host {

using algorithms::kPi;
using algorithms::Pose2;
using algorithms::wrap_angle_rad;

namespace {

struct Polyline {
  std::vector<double> x, y, s;  // s: cumulative arc length
  double length() const { return s.back(); }
  void at(double si, double& px, double& py, double& tx, double& ty) const {
    si = std::clamp(si, 0.0, length());
    const auto it = std::upper_bound(s.begin(), s.end(), si);
    std::size_t k = static_cast<std::size_t>(std::max<std::ptrdiff_t>(1, it - s.begin()));
    if (k >= s.size()) k = s.size() - 1;
    const double seg = s[k] - s[k - 1];
    const double u = seg > 0.0 ? (si - s[k - 1]) / seg : 0.0;
    px = x[k - 1] + u * (x[k] - x[k - 1]);
    py = y[k - 1] + u * (y[k] - y[k - 1]);
    tx = (x[k] - x[k - 1]) / seg;
    ty = (y[k] - y[k - 1]) / seg;
  }
};

// Catmull-Rom through the waypoints (end points repeated), densely sampled.
Polyline make_path(const std::vector<std::array<double, 2>>& w) {
  if (w.size() < 2) throw std::runtime_error("a route needs at least 2 waypoints");
  Polyline p;
  const std::size_t n = w.size();
  auto pt = [&](std::ptrdiff_t i) {
    return w[static_cast<std::size_t>(
        std::clamp<std::ptrdiff_t>(i, 0, static_cast<std::ptrdiff_t>(n) - 1))];
  };
  constexpr int kSteps = 400;
  for (std::size_t i = 0; i + 1 < n; ++i) {
    const auto p0 = pt(static_cast<std::ptrdiff_t>(i) - 1), p1 = pt(static_cast<std::ptrdiff_t>(i)),
               p2 = pt(static_cast<std::ptrdiff_t>(i) + 1),
               p3 = pt(static_cast<std::ptrdiff_t>(i) + 2);
    for (int k = (i == 0 ? 0 : 1); k <= kSteps; ++k) {
      const double t = static_cast<double>(k) / kSteps, t2 = t * t, t3 = t2 * t;
      double c[2];
      for (int d = 0; d < 2; ++d) {
        c[d] = 0.5 * (2 * p1[d] + (-p0[d] + p2[d]) * t +
                      (2 * p0[d] - 5 * p1[d] + 4 * p2[d] - p3[d]) * t2 +
                      (-p0[d] + 3 * p1[d] - 3 * p2[d] + p3[d]) * t3);
      }
      p.x.push_back(c[0]);
      p.y.push_back(c[1]);
    }
  }
  p.s.assign(p.x.size(), 0.0);
  for (std::size_t k = 1; k < p.x.size(); ++k)
    p.s[k] = p.s[k - 1] + std::hypot(p.x[k] - p.x[k - 1], p.y[k] - p.y[k - 1]);
  return p;
}

// Distance covered after time t on a leg of length L with a trapezoidal speed profile.
double leg_distance(double t, double length, double v, double a, double& duration) {
  double t_acc = v / a;
  double d_acc = 0.5 * a * t_acc * t_acc;
  if (2.0 * d_acc > length) {  // triangle: never reaches cruise speed
    t_acc = std::sqrt(length / a);
    d_acc = 0.5 * length;
    v = a * t_acc;
  }
  const double t_cruise = (length - 2.0 * d_acc) / v;
  duration = 2.0 * t_acc + t_cruise;
  if (t <= 0.0) return 0.0;
  if (t < t_acc) return 0.5 * a * t * t;
  if (t < t_acc + t_cruise) return d_acc + v * (t - t_acc);
  if (t < duration) {
    const double r = duration - t;
    return length - 0.5 * a * r * r;
  }
  return length;
}

}  // namespace

std::vector<MotionSample> simulate_motion(const Scenario& scenario, double step_s,
                                          algorithms::Pcg32& rng, RouteStats* stats) {
  const RouteSpec& r = scenario.route;
  const Polyline path = make_path(r.waypoints_m);
  const double length = path.length();
  double leg_s = 0.0;
  leg_distance(0.0, length, r.speed_mps, r.acceleration_mps2, leg_s);
  const double lap_s = 2.0 * (r.pause_s + leg_s);
  const double total_s = r.laps * lap_s + r.pause_s;

  // Smooth sideways wander as a function of distance travelled (so a stopped robot stays put).
  double amp[3], wavelength[3], phase[3];
  for (int k = 0; k < 3; ++k) {
    amp[k] = r.wander_m * rng.uniform(0.3, 0.6);
    wavelength[k] = rng.uniform(1.0, 2.5);
    phase[k] = rng.uniform(0.0, 2.0 * kPi);
  }
  auto wander = [&](double travelled) {
    double w = 0.0;
    for (int k = 0; k < 3; ++k)
      w += amp[k] * std::sin(2.0 * kPi * travelled / wavelength[k] + phase[k]);
    return w;
  };

  auto position = [&](double s_m, double travelled_m, double& x, double& y) {
    double px, py, tx, ty;
    path.at(s_m, px, py, tx, ty);
    const double w = wander(travelled_m);
    x = px - ty * w;
    y = py + tx * w;
  };

  const auto count = static_cast<std::size_t>(std::ceil(total_s / step_s)) + 1;
  std::vector<MotionSample> out(count);
  double travelled = 0.0, last_s = 0.0;
  double heading = 0.0;
  {
    double px, py, tx, ty;
    path.at(0.0, px, py, tx, ty);
    heading = std::atan2(ty, tx);
  }
  constexpr double kProbe_m = 0.005;
  for (std::size_t i = 0; i < count; ++i) {
    const double t = static_cast<double>(i) * step_s;
    const double in_lap = std::fmod(t, lap_s);
    const bool done = t >= r.laps * lap_s;
    double s = 0.0;
    int dir = 0;
    if (done || in_lap < r.pause_s) {
      s = 0.0;
    } else if (in_lap < r.pause_s + leg_s) {
      s = leg_distance(in_lap - r.pause_s, length, r.speed_mps, r.acceleration_mps2, leg_s);
      dir = 1;
    } else if (in_lap < 2.0 * r.pause_s + leg_s) {
      s = length;
    } else {
      s = length - leg_distance(in_lap - 2.0 * r.pause_s - leg_s, length, r.speed_mps,
                                r.acceleration_mps2, leg_s);
      dir = -1;
    }
    travelled += std::fabs(s - last_s);
    last_s = s;
    double x, y;
    position(s, travelled, x, y);
    if (dir != 0) {
      // Heading follows the direction of motion, probed a few mm ahead and behind along the route
      // (reversed when backing up); held while stopped.
      double xf, yf, xb, yb;
      position(s + dir * kProbe_m, travelled + kProbe_m, xf, yf);
      position(s - dir * kProbe_m, travelled - kProbe_m, xb, yb);
      heading = std::atan2(yf - yb, xf - xb) + (dir < 0 ? kPi : 0.0);
    }
    out[i].t_s = t;
    out[i].pose = Pose2{x, y, wrap_angle_rad(heading)};
  }
  // Wheel travel from the pose increments (standard differential drive).
  const double half_track = 0.5 * scenario.robot.track_m;
  double mean_sin = 0.0, mean_cos = 0.0;
  for (std::size_t i = 0; i < count; ++i) {
    mean_sin += std::sin(out[i].pose.yaw_rad);
    mean_cos += std::cos(out[i].pose.yaw_rad);
    if (i == 0) {
      out[i].left_m = out[i].right_m = 0.0;
      continue;
    }
    const Pose2& p0 = out[i - 1].pose;
    const Pose2& p1 = out[i].pose;
    const double dyaw = wrap_angle_rad(p1.yaw_rad - p0.yaw_rad);
    const double mid = p0.yaw_rad + 0.5 * dyaw;
    const double ds = (p1.x_m - p0.x_m) * std::cos(mid) + (p1.y_m - p0.y_m) * std::sin(mid);
    out[i].left_m = out[i - 1].left_m + ds - dyaw * half_track;
    out[i].right_m = out[i - 1].right_m + ds + dyaw * half_track;
  }
  if (stats != nullptr) {
    stats->length_m = length;
    stats->duration_s = total_s;
    const double mean = std::atan2(mean_sin, mean_cos);
    double worst = 0.0;
    for (const MotionSample& m : out)
      worst = std::max(worst, std::fabs(wrap_angle_rad(m.pose.yaw_rad - mean)));
    stats->max_heading_offset_deg = worst * 180.0 / kPi;
  }
  return out;
}

}  // namespace harmoloc::sim_host
