#include "harmoloc/algorithms/frame_information.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace harmoloc::algorithms {

namespace {

/// What the map expects a robot at one pose to see: every board's feature and, for the boards
/// of the bearing mask, the image angle (bit b of angle_mask: the map holds one there).
struct Look {
  std::array<float, kMaxBoards> feature{};
  std::array<double, kMaxBoards> angle_rad{};
  std::uint32_t angle_mask = 0;
};

Look look_at(const ForwardMap& map, double x_m, double y_m, double yaw_rad,
             std::uint32_t bearing_boards) {
  Look l;
  const SeenHeading heading = seen_heading(yaw_rad);
  expected_at_pose(map, locate(map, x_m, y_m), x_m, y_m, heading, l.feature.data());
  if (bearing_boards == 0U) return l;
  const double cos_yaw = std::cos(yaw_rad), sin_yaw = std::sin(yaw_rad);
  const GridPoint at = bearing_point(map, x_m, y_m, cos_yaw, sin_yaw);
  CameraOnce camera(map.projection, x_m, y_m, cos_yaw, sin_yaw);
  for (std::uint32_t mask = bearing_boards; mask != 0U; mask &= mask - 1U) {
    const auto b = static_cast<std::size_t>(__builtin_ctz(mask));
    if (map.projection.points[b] != 0U) {
      float angle = 0.0F;
      if (!projected_image_angle(map, camera.get(), b, angle)) continue;
      l.angle_rad[b] = static_cast<double>(angle);
    } else {
      // Under the law a board at world bearing phi shows at image angle yaw - phi.
      float phi = 0.0F;
      if (!expected_bearing(map, at, b, phi)) continue;
      l.angle_rad[b] = wrap_angle_rad(yaw_rad - static_cast<double>(phi));
    }
    l.angle_mask |= 1U << b;
  }
  return l;
}

}  // namespace

FrameInformation frame_information(const ForwardMap& map, const BoardFeatures& observed,
                                   const Pose2& at, const BoardModelParams& params,
                                   std::uint32_t leave_out) {
  FrameInformation out;
  if (!map.present()) return out;
  const std::size_t boards = std::min<std::size_t>({map.board_count, observed.count, kMaxBoards});
  std::uint32_t area_boards = 0, bearing_boards = 0;
  for (std::size_t b = 0; b < boards; ++b) {
    if (!(map.sigma[b] > 0.0F) || ((leave_out >> b) & 1U) != 0U) continue;
    if (cut_width(observed, params, b) > 0.0) area_boards |= 1U << b;
    if (params.bearings && map.has_bearings && ((observed.angle_mask >> b) & 1U) != 0U &&
        weighed_bearing_sigma_rad(map, b) > 0.0F)
      bearing_boards |= 1U << b;
  }
  // Over a cell's width the grid's bilinear mean changes as one straight line: the difference
  // is its slope there, not the step from one cell's to the next's.
  const double step[3] = {std::max(0.01, 0.5 * static_cast<double>(map.cell_m)),
                          std::max(0.01, 0.5 * static_cast<double>(map.cell_m)), 0.02};
  // The gradients, one axis at a time: per board, of its feature and of its image angle.
  std::array<std::array<double, 3>, kMaxBoards> feature_gradient{}, angle_gradient{};
  std::uint32_t angles = bearing_boards;
  for (std::size_t k = 0; k < 3; ++k) {
    double d[3] = {0.0, 0.0, 0.0};
    d[k] = step[k];
    const Look hi = look_at(map, at.x_m + d[0], at.y_m + d[1], at.yaw_rad + d[2], bearing_boards);
    const Look lo = look_at(map, at.x_m - d[0], at.y_m - d[1], at.yaw_rad - d[2], bearing_boards);
    angles &= hi.angle_mask & lo.angle_mask;
    for (std::size_t b = 0; b < boards; ++b) {
      feature_gradient[b][k] =
          (static_cast<double>(hi.feature[b]) - static_cast<double>(lo.feature[b])) /
          (2.0 * step[k]);
      angle_gradient[b][k] = wrap_angle_rad(hi.angle_rad[b] - lo.angle_rad[b]) / (2.0 * step[k]);
    }
  }
  double* j = out.information;
  const auto add = [j](const std::array<double, 3>& g, double sigma) {
    const double w = 1.0 / (sigma * sigma);
    for (std::size_t r = 0; r < 3; ++r)
      for (std::size_t c = 0; c < 3; ++c) j[3 * r + c] += w * g[r] * g[c];
  };
  for (std::size_t b = 0; b < boards; ++b) {
    if (((area_boards >> b) & 1U) != 0U) {
      add(feature_gradient[b],
          cut_width(observed, params, b) * static_cast<double>(weighed_area_sigma(map, b)));
      out.boards |= 1U << b;
    }
    if (((angles >> b) & 1U) != 0U) {
      add(angle_gradient[b], static_cast<double>(weighed_bearing_sigma_rad(map, b)));
      out.boards |= 1U << b;
    }
  }
  // The position's information with the heading free: the Schur complement of the heading's.
  double a = j[0], bxy = j[1], c = j[4];
  if (j[8] > 0.0) {
    a -= j[2] * j[2] / j[8];
    bxy -= j[2] * j[5] / j[8];
    c -= j[5] * j[5] / j[8];
  }
  const double mean = 0.5 * (a + c), half = 0.5 * (a - c);
  const double weakest = mean - std::sqrt(half * half + bxy * bxy);
  // Relative to the strongest, below rounding: no information along that direction.
  if (weakest > 1e-12 * std::max(1.0, mean)) out.weak_sigma_m = 1.0 / std::sqrt(weakest);
  // The eigenvector of the smallest eigenvalue of [[a, b], [b, c]].
  out.weak_axis_rad = 0.5 * std::atan2(-2.0 * bxy, -(a - c));
  return out;
}

}  // namespace harmoloc::algorithms
