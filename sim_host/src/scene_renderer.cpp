#include "harmoloc/sim_host/scene_renderer.hpp"

#include "harmoloc/sim_host/board_projection.hpp"

#include <algorithm>
#include <cmath>

#include "scene_renderer_parts.hpp"

namespace harmoloc::sim_host {

using algorithms::kPi;
using namespace scene_renderer_detail;

namespace {

// Acklam's rational approximation of the standard normal quantile, refined by one Halley step on
// erfc: accurate to about 1e-15, computed once per renderer.
double normal_quantile(double p) {
  static const double a[] = {-3.969683028665376e+01, 2.209460984245205e+02,  -2.759285104469687e+02,
                             1.383577518672690e+02,  -3.066479806614716e+01, 2.506628277459239e+00};
  static const double b[] = {-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02,
                             6.680131188771972e+01, -1.328068155288572e+01};
  static const double c[] = {-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e+00,
                             -2.549732539343734e+00, 4.374664141464968e+00,  2.938163982698783e+00};
  static const double d[] = {7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00,
                             3.754408661907416e+00};
  double x = 0.0;
  if (p < 0.02425) {
    const double q = std::sqrt(-2.0 * std::log(p));
    x = (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
        ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1.0);
  } else if (p > 1.0 - 0.02425) {
    const double q = std::sqrt(-2.0 * std::log(1.0 - p));
    x = -(((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
        ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1.0);
  } else {
    const double q = p - 0.5, r = q * q;
    x = (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
        (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1.0);
  }
  const double e = 0.5 * std::erfc(-x / std::sqrt(2.0)) - p;
  const double u = e * std::sqrt(2.0 * kPi) * std::exp(0.5 * x * x);
  return x - u / (1.0 + 0.5 * x * u);
}

}  // namespace

SceneRenderer::SceneRenderer(const Scenario& scenario) : scenario_(scenario) {
  const CameraSpec& c = scenario.camera;
  intrinsics_ = intrinsics_of(c);
  const LensModel lens(c);
  const double f = intrinsics_.focal_px, cx = intrinsics_.cx_px, cy = intrinsics_.cy_px;
  const std::size_t pixels = static_cast<std::size_t>(c.width_px) * c.height_px;
  rays_.resize(pixels);
  valid_.assign(pixels, 0);
  vignette_.assign(pixels, 1.0F);
  for (std::uint32_t v = 0; v < c.height_px; ++v) {
    for (std::uint32_t u = 0; u < c.width_px; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * c.width_px + u;
      const double xd = (u - cx) / f, yd = (v - cy) / f;
      Ray& ray = rays_[i];
      const bool valid = lens.undistort(xd, yd, ray.x, ray.y);
      valid_[i] = valid ? 1 : 0;
      if (!valid) continue;
      ++valid_pixels_;
      if (c.vignetting > 0.0) {
        const double cos2 = 1.0 / (1.0 + ray.x * ray.x + ray.y * ray.y);
        vignette_[i] = static_cast<float>(1.0 - c.vignetting * (1.0 - cos2 * cos2));
      }
    }
  }
  // Tiles and the cones of their rays.
  for (std::uint32_t v0 = 0; v0 < c.height_px; v0 += kTile) {
    for (std::uint32_t u0 = 0; u0 < c.width_px; u0 += kTile) {
      Tile t{};
      t.u0 = u0;
      t.v0 = v0;
      t.u1 = std::min(u0 + kTile, c.width_px);
      t.v1 = std::min(v0 + kTile, c.height_px);
      double sum[3] = {0.0, 0.0, 0.0};
      for (std::uint32_t v = t.v0; v < t.v1; ++v) {
        for (std::uint32_t u = t.u0; u < t.u1; ++u) {
          const std::size_t i = static_cast<std::size_t>(v) * c.width_px + u;
          if (!valid_[i]) continue;
          const double n = std::sqrt(rays_[i].x * rays_[i].x + rays_[i].y * rays_[i].y + 1.0);
          sum[0] += rays_[i].x / n;
          sum[1] += rays_[i].y / n;
          sum[2] += 1.0 / n;
          t.any_valid = true;
        }
      }
      if (t.any_valid) {
        const double n = std::sqrt(sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]);
        for (int k = 0; k < 3; ++k) t.axis[k] = sum[k] / n;
        double min_dot = 1.0;
        for (std::uint32_t v = t.v0; v < t.v1; ++v) {
          for (std::uint32_t u = t.u0; u < t.u1; ++u) {
            const std::size_t i = static_cast<std::size_t>(v) * c.width_px + u;
            if (!valid_[i]) continue;
            const double rn = std::sqrt(rays_[i].x * rays_[i].x + rays_[i].y * rays_[i].y + 1.0);
            const double dot = (t.axis[0] * rays_[i].x + t.axis[1] * rays_[i].y + t.axis[2]) / rn;
            min_dot = std::min(min_dot, dot);
          }
        }
        // A little wider than the widest ray, so that rounding can never cull a hit.
        const double half = std::acos(std::clamp(min_dot, -1.0, 1.0)) + 1e-6;
        t.cos_half = half < 0.5 * kPi ? std::cos(half) : -2.0;  // -2: the tile takes everything
        t.sin_half = std::sin(std::min(half, 0.5 * kPi));
      }
      tiles_.push_back(t);
    }
  }
  // Noise: quantiles at (k + 0.5) / N, scaled to unit variance (the table's own), times sigma.
  if (c.pixel_noise > 0.0) {
    std::vector<double> z(kNoiseEntries);
    double var = 0.0;
    for (std::size_t k = 0; k < kNoiseEntries; ++k) {
      z[k] = normal_quantile((static_cast<double>(k) + 0.5) / static_cast<double>(kNoiseEntries));
      var += z[k] * z[k];
    }
    const double s = c.pixel_noise / std::sqrt(var / static_cast<double>(kNoiseEntries));
    noise_.resize(kNoiseEntries);
    for (std::size_t k = 0; k < kNoiseEntries; ++k) noise_[k] = static_cast<float>(z[k] * s);
  }
  set_time(0.0);
}

void SceneRenderer::set_time(double t_s) {
  time_s_ = t_s;
  gain_ = light_gain_at(scenario_, t_s);
  boards_ = scenario_.boards;
  for (const BoardMoveSpec& m : scenario_.board_moves) {
    if (m.at_s > t_s) continue;
    for (BoardSpec& b : boards_) {
      if (b.name != m.board) continue;
      b.centre_x_m += m.offset_m[0];
      b.centre_y_m += m.offset_m[1];
      b.centre_z_m += m.offset_m[2];
      b.facing_yaw_rad += m.turn_deg * kPi / 180.0;
    }
  }
  cylinders_.clear();
  for (const OccluderSpec& o : scenario_.occluders) {
    if (o.path.empty() || t_s < o.path.front()[0] || t_s > o.path.back()[0]) continue;
    std::size_t k = 1;
    while (k < o.path.size() && o.path[k][0] < t_s) ++k;
    double x = o.path.front()[1], y = o.path.front()[2];
    if (k < o.path.size()) {
      const auto& a = o.path[k - 1];
      const auto& b = o.path[k];
      const double u = (t_s - a[0]) / (b[0] - a[0]);
      x = a[1] + u * (b[1] - a[1]);
      y = a[2] + u * (b[2] - a[2]);
    }
    cylinders_.push_back(PlacedCylinder{x, y, o.radius_m, o.height_m, o.colour});
  }
  occluders_present_ = cylinders_.size();
  // The boards' geometry (board_axes).
  placed_.clear();
  for (const BoardSpec& b : boards_) {
    PlacedBoard p{};
    const BoardAxes axes = board_axes(b);
    for (int k = 0; k < 3; ++k) {
      p.c[k] = axes.centre[k];
      p.n[k] = axes.normal[k];
      p.u[k] = axes.width_dir[k];
      p.v[k] = axes.height_dir[k];
    }
    p.half_w = 0.5 * b.width_m;
    p.half_h = 0.5 * b.height_m;
    p.shape = b.shape;
    p.colour = b.colour;
    placed_.push_back(p);
    if (b.stand) {
      const double bottom = b.centre_z_m - 0.5 * b.height_m * std::fabs(axes.height_dir[2]);
      if (bottom > 0.0) {
        cylinders_.push_back(
            PlacedCylinder{b.centre_x_m, b.centre_y_m, kStandRadius_m, bottom, kStandColour});
      }
    }
  }
  // Bounding spheres for the culling.
  spheres_.clear();
  const Scenario& s = scenario_;
  if (s.desk.present) {
    const double hx = 0.5 * (s.desk.x_m[1] - s.desk.x_m[0]);
    const double hy = 0.5 * (s.room.y_m[1] - s.desk.front_y_m), hz = 0.5 * s.desk.height_m;
    spheres_.push_back(Sphere{{s.desk.x_m[0] + hx, s.desk.front_y_m + hy, hz},
                              std::sqrt(hx * hx + hy * hy + hz * hz),
                              kDesk});
  }
  for (std::size_t i = 0; i < placed_.size(); ++i) {
    const PlacedBoard& p = placed_[i];
    spheres_.push_back(Sphere{{p.c[0], p.c[1], p.c[2]},
                              std::sqrt(p.half_w * p.half_w + p.half_h * p.half_h),
                              static_cast<std::uint16_t>(kBoard0 + i)});
  }
  const auto cylinder0 = static_cast<std::uint16_t>(kBoard0 + placed_.size());
  for (std::size_t i = 0; i < cylinders_.size(); ++i) {
    const PlacedCylinder& c = cylinders_[i];
    // Stacked spheres, each around a slice no taller than the cylinder's diameter.
    const int slices =
        std::clamp(static_cast<int>(std::ceil(c.height_m / (2.0 * c.radius_m))), 1, 16);
    const double half = 0.5 * c.height_m / slices;
    for (int k = 0; k < slices; ++k) {
      spheres_.push_back(Sphere{{c.x_m, c.y_m, (2 * k + 1) * half},
                                std::sqrt(c.radius_m * c.radius_m + half * half),
                                static_cast<std::uint16_t>(cylinder0 + i)});
    }
  }
}

}  // namespace harmoloc::sim_host
