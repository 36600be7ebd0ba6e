#include "harmoloc/sim_host/board_geometry_fit.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "harmoloc/sim_host/board_projection.hpp"

namespace harmoloc::sim_host {

namespace {

constexpr std::size_t kParams = 6;  // centre x, y, z; log width, log height; facing yaw
using Params = Eigen::Matrix<double, kParams, 1>;

Params params_of(const BoardSpec& b) {
  Params p;
  p << b.centre_x_m, b.centre_y_m, b.centre_z_m, std::log(b.width_m), std::log(b.height_m),
      b.facing_yaw_rad;
  return p;
}

BoardSpec board_of(const Params& p, const BoardSpec& like) {
  BoardSpec b = like;
  b.centre_x_m = p[0];
  b.centre_y_m = p[1];
  b.centre_z_m = p[2];
  b.width_m = std::exp(p[3]);
  b.height_m = std::exp(p[4]);
  b.facing_yaw_rad = std::remainder(p[5], 2.0 * algorithms::kPi);
  return b;
}

// The sightings the fit uses: enough pixels, at most options.max_sightings evenly spaced.
std::vector<BoardSighting> usable(const std::vector<BoardSighting>& all,
                                  const BoardFitOptions& options) {
  std::vector<BoardSighting> kept;
  for (const BoardSighting& s : all) {
    if (s.area_px >= options.min_area_px) kept.push_back(s);
  }
  if (kept.size() <= options.max_sightings) return kept;
  std::vector<BoardSighting> thinned;
  thinned.reserve(options.max_sightings);
  for (std::size_t i = 0; i < options.max_sightings; ++i) {
    thinned.push_back(kept[i * kept.size() / options.max_sightings]);
  }
  return thinned;
}

// Scaled residuals of every sighting: sqrt(area), column, row (three a sighting). A board the
// model does not see where the frame showed it leaves its centroid residuals at 0 and lets the
// area's speak.
void residuals(const CameraSpec& camera, const LensModel& lens, const BoardSpec& board,
               const std::vector<BoardSighting>& sightings, const BoardFitOptions& o,
               Eigen::VectorXd& r) {
  r.resize(static_cast<Eigen::Index>(3 * sightings.size()));
  for (std::size_t i = 0; i < sightings.size(); ++i) {
    const BoardSighting& s = sightings[i];
    const BoardImage im = project_board(camera, lens, board, s.pose);
    const auto k = static_cast<Eigen::Index>(3 * i);
    r[k] = (std::sqrt(s.area_px) - std::sqrt(im.area_px)) / o.sqrt_area_scale;
    const bool seen = im.area_px > 0.0;
    r[k + 1] = seen ? (s.centroid_u_px - im.centroid_u_px) / o.centroid_scale_px : 0.0;
    r[k + 2] = seen ? (s.centroid_v_px - im.centroid_v_px) / o.centroid_scale_px : 0.0;
  }
}

double huber_weight(double r, double k) {
  const double a = std::fabs(r);
  return a <= k ? 1.0 : k / a;
}

double robust_cost(const Eigen::VectorXd& r, double k) {
  double c = 0.0;
  for (Eigen::Index i = 0; i < r.size(); ++i) {
    const double a = std::fabs(r[i]);
    c += a <= k ? 0.5 * a * a : k * (a - 0.5 * k);
  }
  return c;
}

struct Solution {
  Params p;
  double cost = std::numeric_limits<double>::infinity();
  bool converged = false;
};

// Levenberg-Marquardt on the Huber cost (weights recomputed each step), Jacobian by central
// differences.
Solution solve(const CameraSpec& camera, const LensModel& lens,
               const std::vector<BoardSighting>& sightings, const BoardSpec& like, Params p,
               const BoardFitOptions& o) {
  constexpr std::array<double, kParams> kStep = {1e-4, 1e-4, 1e-4, 1e-4, 1e-4, 1e-4};
  Eigen::VectorXd r, rp, rm;
  residuals(camera, lens, board_of(p, like), sightings, o, r);
  double cost = robust_cost(r, o.huber);
  double lambda = 1e-3;
  Solution best{p, cost, false};
  for (int it = 0; it < o.max_iterations; ++it) {
    Eigen::MatrixXd jac(r.size(), static_cast<Eigen::Index>(kParams));
    for (std::size_t j = 0; j < kParams; ++j) {
      Params a = p, b = p;
      a[static_cast<Eigen::Index>(j)] += kStep[j];
      b[static_cast<Eigen::Index>(j)] -= kStep[j];
      residuals(camera, lens, board_of(a, like), sightings, o, rp);
      residuals(camera, lens, board_of(b, like), sightings, o, rm);
      jac.col(static_cast<Eigen::Index>(j)) = (rp - rm) / (2.0 * kStep[j]);
    }
    Eigen::VectorXd w(r.size());
    for (Eigen::Index i = 0; i < r.size(); ++i) w[i] = huber_weight(r[i], o.huber);
    const Eigen::Matrix<double, kParams, kParams> jtj = jac.transpose() * w.asDiagonal() * jac;
    const Params jtr = jac.transpose() * w.asDiagonal() * r;
    bool stepped = false;
    for (int tries = 0; tries < 10 && !stepped; ++tries) {
      Eigen::Matrix<double, kParams, kParams> a = jtj;
      for (Eigen::Index d = 0; d < static_cast<Eigen::Index>(kParams); ++d) {
        a(d, d) += lambda * (jtj(d, d) + 1e-9);
      }
      // J is the residuals' Jacobian: the damped Gauss-Newton step is -(J^T W J + D)^-1 J^T W r.
      const Params step = -a.ldlt().solve(jtr);
      if (!step.allFinite()) break;
      const Params q = p + step;
      residuals(camera, lens, board_of(q, like), sightings, o, rp);
      const double c = robust_cost(rp, o.huber);
      if (c < cost) {
        const double gain = cost - c;
        p = q;
        r = rp;
        cost = c;
        lambda = std::max(lambda * 0.3, 1e-9);
        stepped = true;
        if (gain < 1e-7 * (1.0 + cost)) {
          best = {p, cost, true};
          return best;
        }
      } else {
        lambda *= 10.0;
      }
    }
    if (!stepped) {
      best = {p, cost, true};  // no step lowers the cost: a minimum
      return best;
    }
    best = {p, cost, false};
  }
  return best;
}

}  // namespace

BoardSpec start_board_geometry(const CameraSpec& camera, const LensModel& lens,
                               const std::vector<BoardSighting>& sightings, double x_m, double y_m,
                               const BoardSpec& like, const BoardFitOptions& options) {
  const std::vector<BoardSighting> used = usable(sightings, options);
  BoardSpec b = like;
  b.centre_x_m = x_m;
  b.centre_y_m = y_m;
  // Facing the mean of the places it was seen from.
  double mx = 0.0, my = 0.0;
  for (const BoardSighting& s : used) {
    mx += s.pose.x_m;
    my += s.pose.y_m;
  }
  if (!used.empty()) {
    mx /= static_cast<double>(used.size());
    my /= static_cast<double>(used.size());
    b.facing_yaw_rad = std::atan2(my - y_m, mx - x_m);
  }
  // The height whose centre projects nearest the centroid rows (every 2 cm up to 3 m).
  double best_z = like.centre_z_m, best_err = std::numeric_limits<double>::infinity();
  for (int i = 0; i <= 150; ++i) {
    const double z = 0.02 * i;
    const double point[3] = {x_m, y_m, z};
    double err = 0.0;
    std::size_t n = 0;
    for (const BoardSighting& s : used) {
      double u = 0.0, v = 0.0;
      if (!project_point(camera, lens, camera_frame_of(camera, s.pose), point, u, v)) continue;
      err += (v - s.centroid_v_px) * (v - s.centroid_v_px);
      ++n;
    }
    if (n > 0 && err / static_cast<double>(n) < best_err) {
      best_err = err / static_cast<double>(n);
      best_z = z;
    }
  }
  b.centre_z_m = best_z;
  // A square whose area at each range is what was seen, facing the camera: side
  // sqrt(area) * range / focal; the median over the sightings.
  const double focal = intrinsics_of(camera).focal_px;
  std::vector<double> sides;
  for (const BoardSighting& s : used) {
    const double range =
        std::hypot(std::hypot(s.pose.x_m - x_m, s.pose.y_m - y_m), best_z - camera.height_m);
    sides.push_back(std::sqrt(s.area_px) * range / focal);
  }
  if (!sides.empty()) {
    std::nth_element(sides.begin(), sides.begin() + static_cast<std::ptrdiff_t>(sides.size() / 2),
                     sides.end());
    b.width_m = b.height_m = std::clamp(sides[sides.size() / 2], 0.05, 3.0);
  }
  return b;
}

BoardFit fit_board_geometry(const CameraSpec& camera, const LensModel& lens,
                            const std::vector<BoardSighting>& sightings, const BoardSpec& start,
                            const BoardFitOptions& options) {
  BoardFit fit;
  fit.board = start;
  const std::vector<BoardSighting> used = usable(sightings, options);
  fit.sightings_used = used.size();
  if (used.size() < options.min_sightings) return fit;
  Solution best;
  for (double turn_deg : {0.0, 40.0, -40.0, 80.0, -80.0}) {
    BoardSpec s = start;
    s.facing_yaw_rad += turn_deg * algorithms::kPi / 180.0;
    const Solution sol = solve(camera, lens, used, start, params_of(s), options);
    if (sol.cost < best.cost) best = sol;
  }
  if (!std::isfinite(best.cost)) return fit;
  fit.board = board_of(best.p, start);
  Eigen::VectorXd r;
  residuals(camera, lens, fit.board, used, options, r);
  double sa = 0.0, su = 0.0, sv = 0.0;
  std::size_t na = 0, nu = 0, nv = 0, outliers = 0;
  for (std::size_t i = 0; i < used.size(); ++i) {
    const auto k = static_cast<Eigen::Index>(3 * i);
    const double ra = r[k], ru = r[k + 1], rv = r[k + 2];
    if (std::fabs(ra) > options.huber || std::fabs(ru) > options.huber ||
        std::fabs(rv) > options.huber) {
      ++outliers;
    }
    if (std::fabs(ra) <= options.huber) {
      sa += ra * ra;
      ++na;
    }
    if (std::fabs(ru) <= options.huber) {
      su += ru * ru;
      ++nu;
    }
    if (std::fabs(rv) <= options.huber) {
      sv += rv * rv;
      ++nv;
    }
  }
  fit.rms_sqrt_area =
      na > 0 ? options.sqrt_area_scale * std::sqrt(sa / static_cast<double>(na)) : 0.0;
  fit.rms_column_px =
      nu > 0 ? options.centroid_scale_px * std::sqrt(su / static_cast<double>(nu)) : 0.0;
  fit.rms_row_px =
      nv > 0 ? options.centroid_scale_px * std::sqrt(sv / static_cast<double>(nv)) : 0.0;
  fit.outlier_share = static_cast<double>(outliers) / static_cast<double>(used.size());
  fit.ok = best.converged && fit.outlier_share < 0.5;
  return fit;
}

}  // namespace harmoloc::sim_host
