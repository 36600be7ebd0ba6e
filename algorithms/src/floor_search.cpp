#include "harmoloc/algorithms/floor_search.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "harmoloc/algorithms/geometry.hpp"

namespace harmoloc::algorithms {

namespace {

std::size_t boards_of(const ForwardMap& map, const BoardFeatures& observed) {
  return std::min<std::size_t>({map.board_count, observed.count, kMaxBoards});
}

// Whether board @p b takes part: modelled and not left out.
bool counts(const ForwardMap& map, std::size_t b, std::uint32_t leave_out) {
  return map.sigma[b] > 0.0F && ((leave_out >> b) & 1U) == 0U;
}

// A bearing of board @p b observed this frame that the map weighs.
bool bearing_counts(const ForwardMap& map, const BoardFeatures& observed, std::size_t b,
                    std::uint32_t leave_out) {
  return counts(map, b, leave_out) && ((observed.angle_mask >> b) & 1U) != 0U &&
         map.bearing_sigma_rad[b] > 0.0F;
}

// A board's robust likelihood exp(-r^2 / 2) + c; the fit is the log of their product (at least
// c^16 = 1e-32 for eight boards' areas and bearings: no underflow).
double robust(double r, double c) {
  return std::exp(-0.5 * r * r) + c;
}

// The observed boards' world bearings at a camera place (ForwardMap::kNoBearing: none there, or
// the board gives none this frame).
using Bearings = std::array<float, kMaxBoards>;

void read_bearings(const ForwardMap& map, const BoardFeatures& observed, const GridPoint& at,
                   std::uint32_t leave_out, Bearings& phi) {
  phi.fill(ForwardMap::kNoBearing);
  for (std::size_t b = 0; b < boards_of(map, observed); ++b) {
    if (bearing_counts(map, observed, b, leave_out) && !expected_bearing(map, at, b, phi[b]))
      phi[b] = ForwardMap::kNoBearing;
  }
}

// floor_fit with the heading as the map reads it and the bearings at the pose's camera place
// already read.
double fit(const ForwardMap& map, const BoardFeatures& observed, double x_m, double y_m,
           const SeenHeading& heading, const Bearings& phi, const BoardModelParams& params,
           std::uint32_t leave_out) {
  const auto yaw_rad = static_cast<double>(heading.yaw_rad);
  std::array<float, kMaxBoards> expected{};
  expected_at_pose(map, locate(map, x_m, y_m), x_m, y_m, heading, expected.data());
  const double c = params.outlier_floor;
  double product = 1.0;
  for (std::size_t b = 0; b < boards_of(map, observed); ++b) {
    if (!counts(map, b, leave_out)) continue;
    const double cut = cut_width(observed, params, b);
    if (!(cut > 0.0)) continue;
    // The trained noise itself, as board_preference weighs two places against each other.
    product *= robust((static_cast<double>(observed.value[b]) - static_cast<double>(expected[b])) /
                          (cut * static_cast<double>(map.sigma[b])),
                      c);
    if (phi[b] == ForwardMap::kNoBearing) continue;
    const double d = wrap_angle_rad(yaw_rad - static_cast<double>(observed.angle_rad[b]) -
                                    static_cast<double>(phi[b]));
    product *= robust(d / static_cast<double>(map.bearing_sigma_rad[b]), c);
  }
  return std::log(product);
}

// The pose whose camera stands at (@p cx_m, @p cy_m), where the observed boards' world bearings
// are @p phi: the heading they give (each board's world bearing plus its image angle, weighed by
// its trained spread; averaged as offsets from the first board's, which needs no trigonometry),
// then its fit. Invalid when no board has a bearing there. The heading's cosine and sine serve
// both the axle's place and the fit.
FloorPose pose_from(const ForwardMap& map, const BoardFeatures& observed, double cx_m, double cy_m,
                    const Bearings& phi, const BoardModelParams& params, std::uint32_t leave_out) {
  FloorPose pose;
  double first = 0.0, offset = 0.0, weight = 0.0;
  for (std::size_t b = 0; b < boards_of(map, observed); ++b) {
    if (phi[b] == ForwardMap::kNoBearing) continue;
    const double yaw = static_cast<double>(phi[b]) + static_cast<double>(observed.angle_rad[b]);
    const double s = static_cast<double>(map.bearing_sigma_rad[b]);
    if (weight == 0.0) first = yaw;
    offset += wrap_angle_rad(yaw - first) / (s * s);
    weight += 1.0 / (s * s);
  }
  if (!(weight > 0.0)) return pose;
  const SeenHeading heading = seen_heading(first + offset / weight);
  pose.yaw_rad = static_cast<double>(heading.yaw_rad);
  // (cx, cy) is the camera's place where the map's bearings are seen from it.
  const auto d = static_cast<double>(map.bearing_camera_forward_m);
  pose.x_m = cx_m - d * static_cast<double>(heading.cos_yaw);
  pose.y_m = cy_m - d * static_cast<double>(heading.sin_yaw);
  pose.nats = fit(map, observed, pose.x_m, pose.y_m, heading, phi, params, leave_out);
  pose.valid = true;
  return pose;
}

}  // namespace

bool floor_search_possible(const ForwardMap& map) {
  return map.present() && map.has_bearings;
}

double floor_fit(const ForwardMap& map, const BoardFeatures& observed, double x_m, double y_m,
                 double yaw_rad, const BoardModelParams& params, std::uint32_t leave_out) {
  if (!map.present()) return 0.0;
  Bearings phi;
  phi.fill(ForwardMap::kNoBearing);
  if (map.has_bearings && observed.angle_mask != 0U)
    read_bearings(map, observed, bearing_point(map, x_m, y_m, std::cos(yaw_rad), std::sin(yaw_rad)),
                  leave_out, phi);
  return fit(map, observed, x_m, y_m, seen_heading(yaw_rad), phi, params, leave_out);
}

FloorPose floor_pose_seen_from(const ForwardMap& map, const BoardFeatures& observed, double cx_m,
                               double cy_m, const BoardModelParams& params,
                               std::uint32_t leave_out) {
  if (!floor_search_possible(map) || observed.angle_mask == 0U) return FloorPose{};
  const GridPoint at = locate(map, cx_m, cy_m);
  if (at.outside_m > 0.0F) return FloorPose{};
  // The pose's camera stands here, so these are the bearings its fit reads too.
  Bearings phi;
  read_bearings(map, observed, at, leave_out, phi);
  return pose_from(map, observed, cx_m, cy_m, phi, params, leave_out);
}

void FloorSearch::reset() {
  cursor_ = 0;
  best_ = FloorPose{};
  last_ = FloorPose{};
}

bool FloorSearch::step(const ForwardMap& map, const BoardFeatures& observed,
                       const BoardModelParams& params, std::uint32_t leave_out, std::size_t places,
                       std::uint32_t stride) {
  if (!floor_search_possible(map)) return false;
  stride = std::max<std::uint32_t>(stride, 1U);
  const std::uint64_t columns = (map.columns + stride - 1U) / stride;
  const std::uint64_t rows = (map.rows + stride - 1U) / stride;
  const std::uint64_t total = columns * rows;
  if (cursor_ >= total) cursor_ = 0;  // another map or stride since the last call
  const auto x0 = static_cast<double>(map.origin_x_m), y0 = static_cast<double>(map.origin_y_m);
  const auto cell = static_cast<double>(map.cell_m);
  // The boards whose bearings this frame's search weighs: the same at every place.
  std::uint32_t bearing_boards = 0;
  for (std::size_t b = 0; b < boards_of(map, observed); ++b)
    if (bearing_counts(map, observed, b, leave_out)) bearing_boards |= 1U << b;
  for (std::size_t n = 0; n < places; ++n) {
    const auto c = static_cast<std::uint32_t>(cursor_ % columns) * stride;
    const auto r = static_cast<std::uint32_t>(cursor_ / columns) * stride;
    const std::size_t at = map.index(c, r);
    if (at != ForwardMap::kVoidCell && bearing_boards != 0U) {
      // On a cell the bearings are the cell's own (no corners to weigh).
      Bearings phi;
      phi.fill(ForwardMap::kNoBearing);
      for (std::uint32_t mask = bearing_boards; mask != 0U; mask &= mask - 1U) {
        const auto b = static_cast<std::size_t>(__builtin_ctz(mask));
        phi[b] = map.bearing_rad[at * kMaxBoards + b];
      }
      best_ = better_of(
          best_, pose_from(map, observed, x0 + cell * c, y0 + cell * r, phi, params, leave_out));
    }
    if (++cursor_ == total) {
      last_ = best_;
      best_ = FloorPose{};
      cursor_ = 0;
      return true;
    }
  }
  return false;
}

FloorPose FloorSearch::refine(const ForwardMap& map, const BoardFeatures& observed,
                              const FloorPose& around, double radius_m,
                              const BoardModelParams& params, std::uint32_t leave_out, int levels) {
  FloorPose best;
  if (!around.valid) return best;
  const auto d = static_cast<double>(map.bearing_camera_forward_m);
  double cx = around.x_m + d * std::cos(around.yaw_rad);
  double cy = around.y_m + d * std::sin(around.yaw_rad);
  double step = radius_m / 2.0;
  for (int j = -2; j <= 2; ++j) {
    for (int i = -2; i <= 2; ++i) {
      best = better_of(best, floor_pose_seen_from(map, observed, cx + i * step, cy + j * step,
                                                  params, leave_out));
    }
  }
  // Each further level: the eight places around the best at half the step (the best lies
  // within half a step of the optimum the coarser grid can see).
  for (int level = 1; level < levels && best.valid; ++level) {
    cx = best.x_m + d * std::cos(best.yaw_rad);
    cy = best.y_m + d * std::sin(best.yaw_rad);
    step *= 0.5;
    for (int j = -1; j <= 1; ++j) {
      for (int i = -1; i <= 1; ++i) {
        if (i == 0 && j == 0) continue;
        best = better_of(best, floor_pose_seen_from(map, observed, cx + i * step, cy + j * step,
                                                    params, leave_out));
      }
    }
  }
  return best;
}

}  // namespace harmoloc::algorithms
