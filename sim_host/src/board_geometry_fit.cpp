#include "harmoloc/sim_host/board_geometry_fit.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "board_sighting_residuals.hpp"
#include "harmoloc/sim_host/board_projection.hpp"
#include "robust_least_squares.hpp"

namespace harmoloc::sim_host {

namespace {

// Central difference steps: metres, log size, radians.
const std::vector<double> kSteps(detail::kBoardParams, 1e-4);

}  // namespace

BoardFitOptions for_frame(BoardFitOptions options, std::uint32_t width_px,
                          std::uint32_t height_px) {
  if (width_px == 0 || height_px == 0) return options;
  const double linear = static_cast<double>(width_px) / kBoardFitReferenceWidthPx;
  const double area = static_cast<double>(width_px) * static_cast<double>(height_px) /
                      (static_cast<double>(kBoardFitReferenceWidthPx) * kBoardFitReferenceHeightPx);
  options.centroid_scale_px *= linear;
  options.sqrt_area_scale *= std::sqrt(area);
  options.min_area_px *= area;
  return options;
}

std::vector<BoardSighting> usable_sightings(const std::vector<BoardSighting>& all,
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

BoardSpec start_board_geometry(const CameraSpec& camera, const LensModel& lens,
                               const std::vector<BoardSighting>& sightings, double x_m, double y_m,
                               const BoardSpec& like, const BoardFitOptions& options) {
  const std::vector<BoardSighting> used = usable_sightings(sightings, options);
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
  const std::vector<BoardSighting> used = usable_sightings(sightings, options);
  fit.sightings_used = used.size();
  if (used.size() < options.min_sightings) return fit;
  detail::RobustSolution best;
  const bool aspect = detail::has_aspect_residual(options);
  auto f = [&](const Eigen::VectorXd& p, Eigen::VectorXd& r) {
    detail::board_residuals(camera, lens, detail::board_from_params(p.data(), start), used, options,
                            r);
    if (!aspect) return;
    r.conservativeResize(r.size() + 1);
    r[r.size() - 1] = detail::aspect_residual(p.data(), options);
  };
  const auto jac = [&f](const Eigen::VectorXd& p, Eigen::Index rows, Eigen::MatrixXd& j) {
    detail::central_differences(f, p, kSteps, rows, j);
  };
  for (double turn_deg : {0.0, 40.0, -40.0, 80.0, -80.0}) {
    if (turn_deg != 0.0 && !options.other_facings) continue;
    BoardSpec s = start;
    s.facing_yaw_rad += turn_deg * algorithms::kPi / 180.0;
    const detail::RobustSolution sol = detail::robust_least_squares(
        f, jac, detail::board_params(s), options.huber, options.max_iterations);
    if (sol.cost < best.cost) best = sol;
  }
  if (!std::isfinite(best.cost)) return fit;
  fit.board = detail::board_from_params(best.p.data(), start);
  Eigen::VectorXd r;
  detail::board_residuals(camera, lens, fit.board, used, options, r);
  detail::ResidualSpread spread;
  spread.add(r, options.huber);
  fit.rms_sqrt_area = spread.rms(0, options.sqrt_area_scale);
  fit.rms_column_px = spread.rms(1, options.centroid_scale_px);
  fit.rms_row_px = spread.rms(2, options.centroid_scale_px);
  fit.outlier_share = static_cast<double>(spread.outliers) / static_cast<double>(used.size());
  fit.ok = best.converged && fit.outlier_share < 0.5;
  return fit;
}

}  // namespace harmoloc::sim_host
