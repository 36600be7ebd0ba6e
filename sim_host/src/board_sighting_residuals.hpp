#pragma once
// What the geometry fits share (private to sim_host/src): a board's parameters, and the residuals
// they minimise: for each sighting of a board, sqrt(area) and the centroid's column and row,
// observed minus projected, each over its scale.
#include <Eigen/Dense>
#include <cmath>
#include <vector>

#include "harmoloc/sim_host/board_geometry_fit.hpp"
#include "harmoloc/sim_host/board_projection.hpp"

namespace harmoloc::sim_host::detail {

// A board's fitted parameters: centre x, y, z (m); log width, log height; facing yaw (rad).
constexpr int kBoardParams = 6;

inline Eigen::VectorXd board_params(const BoardSpec& b) {
  Eigen::VectorXd p(kBoardParams);
  p << b.centre_x_m, b.centre_y_m, b.centre_z_m, std::log(b.width_m), std::log(b.height_m),
      b.facing_yaw_rad;
  return p;
}

// The aspect residual of a board's parameters at @p p (BoardFitOptions::aspect_log_scale, when
// has_aspect_residual): linear in the log width and the log height.
inline double aspect_residual(const double* p, const BoardFitOptions& o) {
  return (p[3] - p[4]) / o.aspect_log_scale;
}
inline bool has_aspect_residual(const BoardFitOptions& o) {
  return o.aspect_log_scale > 0.0;
}

// @p like with the kBoardParams parameters at @p p.
inline BoardSpec board_from_params(const double* p, const BoardSpec& like) {
  BoardSpec b = like;
  b.centre_x_m = p[0];
  b.centre_y_m = p[1];
  b.centre_z_m = p[2];
  b.width_m = std::exp(p[3]);
  b.height_m = std::exp(p[4]);
  b.facing_yaw_rad = std::remainder(p[5], 2.0 * algorithms::kPi);
  return b;
}

// Three residuals a sighting into @p r from @p offset on (r is sized by the caller). A board the
// model does not see where the frame showed it leaves its centroid residuals at 0 and lets the
// area's speak.
inline void board_residuals(const CameraSpec& camera, const LensModel& lens, const BoardSpec& board,
                            const std::vector<BoardSighting>& sightings, const BoardFitOptions& o,
                            Eigen::VectorXd& r, Eigen::Index offset) {
  for (std::size_t i = 0; i < sightings.size(); ++i) {
    const BoardSighting& s = sightings[i];
    const BoardImage im = project_board(camera, lens, board, s.pose);
    const Eigen::Index k = offset + static_cast<Eigen::Index>(3 * i);
    r[k] = (std::sqrt(s.area_px) - std::sqrt(im.area_px)) / o.sqrt_area_scale;
    const bool seen = im.area_px > 0.0;
    r[k + 1] = seen ? (s.centroid_u_px - im.centroid_u_px) / o.centroid_scale_px : 0.0;
    r[k + 2] = seen ? (s.centroid_v_px - im.centroid_v_px) / o.centroid_scale_px : 0.0;
  }
}

// The same for one board alone: @p r resized to three a sighting.
inline void board_residuals(const CameraSpec& camera, const LensModel& lens, const BoardSpec& board,
                            const std::vector<BoardSighting>& sightings, const BoardFitOptions& o,
                            Eigen::VectorXd& r) {
  r.resize(static_cast<Eigen::Index>(3 * sightings.size()));
  board_residuals(camera, lens, board, sightings, o, r, 0);
}

// The spread of residuals from board_residuals: per kind (sqrt area, column, row) the root mean
// square over the residuals within Huber's threshold, and the sightings with any residual beyond.
struct ResidualSpread {
  double sum[3] = {0.0, 0.0, 0.0};
  std::size_t count[3] = {0, 0, 0};
  std::size_t sightings = 0, outliers = 0;

  void add(const Eigen::VectorXd& r, double huber) {
    for (Eigen::Index i = 0; i + 2 < r.size(); i += 3) {
      bool outlier = false;
      for (int k = 0; k < 3; ++k) {
        const double v = r[i + k];
        if (std::fabs(v) > huber) {
          outlier = true;
          continue;
        }
        sum[k] += v * v;
        ++count[k];
      }
      ++sightings;
      outliers += outlier ? 1U : 0U;
    }
  }
  // Unscaled: times the residual's scale.
  double rms(int k, double scale) const {
    return count[k] > 0 ? scale * std::sqrt(sum[k] / static_cast<double>(count[k])) : 0.0;
  }
};

}  // namespace harmoloc::sim_host::detail
