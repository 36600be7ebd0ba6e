#include "harmoloc/algorithms/bearing_calibration.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "harmoloc/algorithms/column_gain.hpp"
#include "harmoloc/algorithms/forward_map.hpp"

namespace harmoloc::algorithms {

namespace {

struct Ray {
  double x_m, y_m, yaw_rad;
  double t;  ///< the centroid's column offset from the centre, in frame widths
};

struct Law {
  double a1, a3;
  double angle(double t) const { return (a1 + a3 * t * t) * t; }
};

struct Fit {
  bool placed = false;
  double x_m = 0.0, y_m = 0.0;
  double sse = 0.0;  ///< sum of squared angular residuals
};

// The board's place under @p law: the point nearest to all its rays in the least-squares sense,
// first unweighted, then with each ray weighted by the inverse square of its range (so that the
// residual minimised is an angle, not a distance); then the angular residuals. A board behind
// the camera on most rays, or rays too parallel to meet, is not placed.
Fit triangulate(const std::vector<Ray>& rays, const Law& law, double min_spread_rad) {
  Fit fit;
  if (rays.size() < 2) return fit;
  double lo = 0.0, hi = 0.0;
  const double theta0 = rays.front().yaw_rad - law.angle(rays.front().t);
  for (const Ray& r : rays) {
    const double d = wrap_angle_rad(r.yaw_rad - law.angle(r.t) - theta0);
    lo = std::min(lo, d);
    hi = std::max(hi, d);
  }
  if (hi - lo < min_spread_rad) return fit;
  double bx = 0.0, by = 0.0;
  for (int pass = 0; pass < 2; ++pass) {
    double a00 = 0.0, a01 = 0.0, a11 = 0.0, c0 = 0.0, c1 = 0.0;
    for (const Ray& r : rays) {
      const double theta = r.yaw_rad - law.angle(r.t);
      const double nx = std::sin(theta), ny = -std::cos(theta);
      double w = 1.0;
      if (pass == 1) {
        const double range2 = (bx - r.x_m) * (bx - r.x_m) + (by - r.y_m) * (by - r.y_m);
        w = 1.0 / std::max(range2, 0.01);
      }
      const double np = nx * r.x_m + ny * r.y_m;
      a00 += w * nx * nx;
      a01 += w * nx * ny;
      a11 += w * ny * ny;
      c0 += w * nx * np;
      c1 += w * ny * np;
    }
    const double det = a00 * a11 - a01 * a01;
    if (!(det > 1e-12 * (a00 + a11) * (a00 + a11))) return fit;
    bx = (a11 * c0 - a01 * c1) / det;
    by = (a00 * c1 - a01 * c0) / det;
  }
  std::size_t behind = 0;
  for (const Ray& r : rays) {
    const double e =
        wrap_angle_rad(std::atan2(by - r.y_m, bx - r.x_m) - (r.yaw_rad - law.angle(r.t)));
    if (std::fabs(e) > 0.5 * kPi) ++behind;
    fit.sse += e * e;
  }
  if (2 * behind > rays.size() || !std::isfinite(bx) || !std::isfinite(by)) return Fit{};
  fit.placed = true;
  fit.x_m = bx;
  fit.y_m = by;
  return fit;
}

// At most @p n rays, evenly spread over the run: enough to rank laws on the search grid.
std::vector<Ray> thin(const std::vector<Ray>& rays, std::size_t n) {
  if (rays.size() <= n) return rays;
  std::vector<Ray> out;
  out.reserve(n);
  for (std::size_t i = 0; i < n; ++i) out.push_back(rays[i * rays.size() / n]);
  return out;
}

// Total squared angular residual of every board under @p law; a board that cannot be placed
// costs what its rays would at a quarter of a radian each, so no law wins by losing boards.
double cost(const std::vector<std::vector<Ray>>& boards, const Law& law, double min_spread) {
  double total = 0.0;
  for (const std::vector<Ray>& rays : boards) {
    if (rays.empty()) continue;
    const Fit f = triangulate(rays, law, min_spread);
    const double unplaced = 0.0625 * static_cast<double>(rays.size());
    total += f.placed ? std::min(f.sse, unplaced) : unplaced;
  }
  return total;
}

}  // namespace

double BearingCalibration::angle_rad(double u_px, std::uint32_t width_px) const {
  if (width_px == 0) return 0.0;
  return Law{a1_rad, a3_rad}.angle(column_offset(u_px, width_px));
}

BearingCalibration calibrate_bearings(const std::vector<BearingFrame>& frames,
                                      const BearingCalibrationOptions& options) {
  BearingCalibration out;
  std::size_t boards = 0;
  for (const BearingFrame& f : frames) boards = std::max(boards, f.areas.count);
  out.boards = boards;
  out.placements.assign(boards, BoardPlacement{});
  std::vector<std::vector<Ray>> rays(boards);
  for (const BearingFrame& f : frames) {
    const AreaVector& a = f.areas;
    if (!a.columns_measured()) continue;
    for (std::size_t k = 0; k < a.count; ++k) {
      // The firmware's rule (enough pixels, none on the frame's sides), so that the law is
      // learnt from the same centroids the filter will weigh.
      if (!gives_bearing(a, k)) continue;
      rays[k].push_back(Ray{f.pose.x_m, f.pose.y_m, f.pose.yaw_rad, column_offset(a, k)});
    }
  }
  // Boards with too few frames take no part (an empty ray list).
  std::vector<std::vector<Ray>> sparse(boards);
  std::size_t candidates = 0;
  for (std::size_t k = 0; k < boards; ++k) {
    if (rays[k].size() < options.min_frames) {
      rays[k].clear();
      continue;
    }
    sparse[k] = thin(rays[k], 200);
    ++candidates;
  }
  if (candidates < 2) return out;

  // Coarse grid: half field of view 10..75 degrees by 1, a3 / a1 from -0.5 to 1.5 by 0.1; then
  // a finer grid a tenth of the step around the best.
  const double deg = kPi / 180.0;
  auto law_of = [](double half_fov_rad, double ratio) {
    // half_fov = a1 / 2 + a3 / 8 with a3 = ratio * a1.
    const double a1 = half_fov_rad / (0.5 + 0.125 * ratio);
    return Law{a1, ratio * a1};
  };
  double best_fov = 0.0, best_ratio = 0.0, best = std::numeric_limits<double>::infinity();
  for (int f = 10; f <= 75; ++f) {
    for (int r = -5; r <= 15; ++r) {
      const double c = cost(sparse, law_of(f * deg, 0.1 * r), options.min_ray_spread_rad);
      if (c < best) {
        best = c;
        best_fov = f * deg;
        best_ratio = 0.1 * r;
      }
    }
  }
  const double fov0 = best_fov, ratio0 = best_ratio;
  for (int f = -10; f <= 10; ++f) {
    for (int r = -10; r <= 10; ++r) {
      const double fov = fov0 + 0.1 * f * deg, ratio = ratio0 + 0.01 * r;
      const double c = cost(sparse, law_of(fov, ratio), options.min_ray_spread_rad);
      if (c < best) {
        best = c;
        best_fov = fov;
        best_ratio = ratio;
      }
    }
  }
  const Law law = law_of(best_fov, best_ratio);
  out.a1_rad = law.a1;
  out.a3_rad = law.a3;
  double sse = 0.0;
  std::size_t placed = 0;
  for (std::size_t k = 0; k < boards; ++k) {
    if (rays[k].empty()) continue;
    const Fit fit = triangulate(rays[k], law, options.min_ray_spread_rad);
    if (!fit.placed) continue;
    BoardPlacement& p = out.placements[k];
    p.placed = true;
    p.x_m = fit.x_m;
    p.y_m = fit.y_m;
    p.frames = rays[k].size();
    p.rms_residual_rad = std::sqrt(fit.sse / static_cast<double>(p.frames));
    sse += fit.sse;
    out.rays += p.frames;
    ++placed;
  }
  out.ok = placed >= 2;
  out.rms_residual_rad = out.rays > 0 ? std::sqrt(sse / static_cast<double>(out.rays)) : 0.0;
  return out;
}

}  // namespace harmoloc::algorithms
