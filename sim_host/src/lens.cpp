#include "harmoloc/sim_host/lens.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "harmoloc/algorithms/geometry.hpp"

namespace harmoloc::sim_host {

namespace {

constexpr int kNewtonIterations = 50;
constexpr double kRadialTolerance = 1e-12;
constexpr double kForwardTolerance = 1e-9;  // an accepted 2-D inverse maps back this close
// The monotonic region is searched up to this radius (84 degrees off the axis).
constexpr double kSearchRadius = 10.0;

}  // namespace

LensModel::LensModel(double k1, double k2, double k3, double p1, double p2)
    : k1_(k1), k2_(k2), k3_(k3), p1_(p1), p2_(p2) {
  if (k2_ == 0.0 && k3_ == 0.0) {
    // Wu & Qin's model in closed form (the simulator's arithmetic before the polynomial model).
    if (k1_ < 0.0) {
      r_max_ = 1.0 / std::sqrt(-3.0 * k1_);
      rd_max_ = r_max_ * (1.0 + k1_ * r_max_ * r_max_);
    }
    return;
  }
  // The first radius where the slope reaches 0: scanned, then bisected.
  constexpr int kScan = 20000;
  double lo = 0.0;
  for (int i = 1; i <= kScan; ++i) {
    const double r = kSearchRadius * i / kScan;
    if (radial_slope(r) <= 0.0) {
      double hi = r;
      for (int k = 0; k < 100; ++k) {
        const double mid = 0.5 * (lo + hi);
        (radial_slope(mid) > 0.0 ? lo : hi) = mid;
      }
      r_max_ = lo;
      const double r2 = lo * lo;
      rd_max_ = lo * (1.0 + k1_ * lo * lo + r2 * r2 * (k2_ + k3_ * r2));
      return;
    }
    lo = r;
  }
}

double LensModel::radial_slope(double r) const {
  const double r2 = r * r, r4 = r2 * r2;
  return 1.0 + 3.0 * k1_ * r * r + r4 * (5.0 * k2_ + 7.0 * k3_ * r2);
}

void LensModel::distort(double x, double y, double& xd, double& yd) const {
  const double r2 = x * x + y * y;
  const double radial = 1.0 + k1_ * r2 + r2 * r2 * (k2_ + k3_ * r2);
  xd = x * radial + 2.0 * p1_ * x * y + p2_ * (r2 + 2.0 * x * x);
  yd = y * radial + p1_ * (r2 + 2.0 * y * y) + 2.0 * p2_ * x * y;
}

// Solves r (1 + k1 r^2 + k2 r^4 + k3 r^6) = rd on [0, r_max) by Newton's method (bisection when
// it does not settle). With k2 = k3 = 0 the arithmetic is exactly the simulator's before the
// polynomial model, so Wu & Qin's scenes trace the same rays.
bool LensModel::undistort_radius(double rd, double& r_out) const {
  if (rd == 0.0) {
    r_out = 0.0;
    return true;
  }
  if (rd >= rd_max_) return false;
  const auto f = [this, rd](double r) {
    const double r2 = r * r, r4 = r2 * r2;
    return r * (1.0 + k1_ * r * r + r4 * (k2_ + k3_ * r2)) - rd;
  };
  double r = rd;
  bool settled = false;
  for (int i = 0; i < kNewtonIterations; ++i) {
    const double next = r - f(r) / radial_slope(r);
    if (std::fabs(next - r) < kRadialTolerance) {
      r = next;
      settled = true;
      break;
    }
    r = std::min(std::max(next, 0.0), r_max_);
  }
  if (!settled || !(std::fabs(f(r)) <= kForwardTolerance)) {
    if (r_max_ >= kNoLimit) return false;
    double lo = 0.0, hi = r_max_;
    for (int k = 0; k < 200 && hi - lo > kRadialTolerance; ++k) {
      const double mid = 0.5 * (lo + hi);
      (f(mid) < 0.0 ? lo : hi) = mid;
    }
    r = 0.5 * (lo + hi);
  }
  r_out = r;
  return true;
}

bool LensModel::undistort(double xd, double yd, double& x, double& y) const {
  const double rd = std::hypot(xd, yd);
  double ru = 0.0;
  const bool radial_ok = undistort_radius(rd, ru);
  if (radial_only()) {
    const double s = rd > 0.0 ? ru / rd : 1.0;
    x = xd * s;
    y = yd * s;
    return radial_ok;
  }
  // Tangential terms move a point by at most 3 (|p1| + |p2|) r^2 <= that at r_max: beyond the
  // radial image circle by more than that, there is no preimage.
  if (!radial_ok && r_max_ < kNoLimit &&
      rd > rd_max_ + 3.0 * (std::fabs(p1_) + std::fabs(p2_)) * r_max_ * r_max_ + 1e-9)
    return false;
  // 2-D Newton on F(x, y) = distort(x, y) - (xd, yd), from the radial solution (or the
  // distorted point itself beyond the radial image circle), with step halving.
  double s = radial_ok && rd > 0.0 ? ru / rd : 1.0;
  x = xd * s;
  y = yd * s;
  const auto residual = [&](double px, double py, double& ex, double& ey) {
    double fx = 0.0, fy = 0.0;
    distort(px, py, fx, fy);
    ex = fx - xd;
    ey = fy - yd;
    return std::hypot(ex, ey);
  };
  const auto jacobian = [&](double px, double py, double j[4]) {
    const double r2 = px * px + py * py;
    const double radial = 1.0 + k1_ * r2 + r2 * r2 * (k2_ + k3_ * r2);
    const double dradial = k1_ + 2.0 * k2_ * r2 + 3.0 * k3_ * r2 * r2;  // d radial / d r^2
    j[0] = radial + 2.0 * px * px * dradial + 2.0 * p1_ * py + 6.0 * p2_ * px;
    j[1] = 2.0 * px * py * dradial + 2.0 * p1_ * px + 2.0 * p2_ * py;
    j[2] = j[1];
    j[3] = radial + 2.0 * py * py * dradial + 6.0 * p1_ * py + 2.0 * p2_ * px;
  };
  double ex = 0.0, ey = 0.0;
  double err = residual(x, y, ex, ey);
  for (int i = 0; i < kNewtonIterations && err > 1e-15; ++i) {
    double j[4];
    jacobian(x, y, j);
    const double det = j[0] * j[3] - j[1] * j[2];
    if (!(std::fabs(det) > 1e-300)) break;
    const double dx = (j[3] * ex - j[1] * ey) / det, dy = (j[0] * ey - j[2] * ex) / det;
    double step = 1.0;
    bool improved = false;
    for (int h = 0; h < 20 && !improved; ++h, step *= 0.5) {
      double nx = x - step * dx, ny = y - step * dy, nex = 0.0, ney = 0.0;
      const double nerr = residual(nx, ny, nex, ney);
      if (nerr < err) {
        x = nx;
        y = ny;
        ex = nex;
        ey = ney;
        err = nerr;
        improved = true;
      }
    }
    if (!improved) break;  // stuck: no preimage near here
  }
  if (!(err <= kForwardTolerance)) return false;
  if (!(std::hypot(x, y) < r_max_)) return false;
  double j[4];
  jacobian(x, y, j);
  return j[0] * j[3] - j[1] * j[2] > 0.0;
}

Intrinsics intrinsics_of(const CameraSpec& c) {
  Intrinsics in{};
  in.focal_px = 0.5 * c.width_px / std::tan(0.5 * c.horizontal_fov_deg * algorithms::kPi / 180.0);
  in.cx_px = 0.5 * c.width_px - 0.5 + c.principal_offset_x_px;
  in.cy_px = 0.5 * c.height_px - 0.5 + c.principal_offset_y_px;
  return in;
}

CameraFrame camera_frame_of(const CameraSpec& c, const algorithms::Pose2& robot) {
  using algorithms::kPi;
  CameraFrame f{};
  const double psi = robot.yaw_rad + c.mount_yaw_deg * kPi / 180.0;
  const double pitch = c.pitch_deg * kPi / 180.0;
  f.origin[0] = robot.x_m + c.forward_offset_m * std::cos(robot.yaw_rad);
  f.origin[1] = robot.y_m + c.forward_offset_m * std::sin(robot.yaw_rad);
  f.origin[2] = c.height_m;
  f.forward[0] = std::cos(psi) * std::cos(pitch);
  f.forward[1] = std::sin(psi) * std::cos(pitch);
  f.forward[2] = std::sin(pitch);
  f.right[0] = std::sin(psi);
  f.right[1] = -std::cos(psi);
  f.right[2] = 0.0;
  // down = forward x right
  f.down[0] = f.forward[1] * f.right[2] - f.forward[2] * f.right[1];
  f.down[1] = f.forward[2] * f.right[0] - f.forward[0] * f.right[2];
  f.down[2] = f.forward[0] * f.right[1] - f.forward[1] * f.right[0];
  return f;
}

bool project_point(const CameraSpec& camera, const LensModel& lens, const CameraFrame& f,
                   const double p[3], double& u, double& v) {
  const double w[3] = {p[0] - f.origin[0], p[1] - f.origin[1], p[2] - f.origin[2]};
  const double z = w[0] * f.forward[0] + w[1] * f.forward[1] + w[2] * f.forward[2];
  if (!(z > 0.01)) return false;
  const double x = (w[0] * f.right[0] + w[1] * f.right[1] + w[2] * f.right[2]) / z;
  const double y = (w[0] * f.down[0] + w[1] * f.down[1] + w[2] * f.down[2]) / z;
  if (!(std::hypot(x, y) < lens.max_radius())) return false;
  double xd = 0.0, yd = 0.0;
  lens.distort(x, y, xd, yd);
  const Intrinsics in = intrinsics_of(camera);
  u = in.focal_px * xd + in.cx_px;
  v = in.focal_px * yd + in.cy_px;
  return true;
}

ColumnLaw column_law_of(const CameraSpec& camera, const std::vector<double>& rows) {
  ColumnLaw law;
  const LensModel lens(camera);
  const Intrinsics in = intrinsics_of(camera);
  const CameraFrame f = camera_frame_of(camera, algorithms::Pose2{0.0, 0.0, 0.0});
  const double w = static_cast<double>(camera.width_px), h = static_cast<double>(camera.height_px);
  Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
  Eigen::Vector3d atb = Eigen::Vector3d::Zero();
  std::size_t n = 0;
  const std::vector<double> middle{0.35, 0.5, 0.65};
  for (const double row : rows.empty() ? middle : rows) {
    if (!(row >= 0.0 && row <= 1.0)) continue;
    const double v = row * (h - 1.0);
    for (int k = -32; k <= 32; ++k) {
      const double t = k / 64.0;
      const double u = 0.5 * (w - 1.0) + t * w;
      double x = 0.0, y = 0.0;
      if (!lens.undistort((u - in.cx_px) / in.focal_px, (v - in.cy_px) / in.focal_px, x, y))
        continue;
      double ray[3];
      for (int i = 0; i < 3; ++i) ray[i] = f.right[i] * x + f.down[i] * y + f.forward[i];
      const double angle = -std::atan2(ray[1], ray[0]);  // positive to the right
      const Eigen::Vector3d basis(1.0, t, t * t * t);
      ata += basis * basis.transpose();
      atb += basis * angle;
      ++n;
    }
  }
  if (n < 20) return law;
  const Eigen::Vector3d c = ata.ldlt().solve(atb);
  if (!c.allFinite() || !(c[1] > 0.0)) return law;
  law.ok = true;
  law.axis_rad = c[0];
  law.optical_axis_rad = -std::atan2(f.forward[1], f.forward[0]) - c[0];
  law.a1_rad = c[1];
  law.a3_rad = c[2];
  return law;
}

}  // namespace harmoloc::sim_host
