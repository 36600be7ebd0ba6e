#include "harmoloc/sim_host/forward_map_geometry.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>

#include "harmoloc/algorithms/geometry.hpp"
#include "harmoloc/sim_host/board_projection.hpp"

namespace harmoloc::sim_host {

namespace {

using algorithms::ForwardMap;
using algorithms::kMaxBoards;

// What a camera at a map place sees of a board when turned to face it: the cell's entries.
struct CellView {
  float bearing_rad = 0.0F;
  float feature = 0.0F;  // on the optical axis (visibility_gain taken out)
  float half_width_rad = 0.0F;
  bool cut = false;  // the frame's border cuts the board even facing it
};

class GeometryView {
 public:
  GeometryView(const CameraSpec& camera, const ForwardMap& map, float area_scale)
      : camera_(camera),
        lens_(camera),
        map_(map),
        area_scale_(static_cast<double>(area_scale)),
        forward_m_(static_cast<double>(map.bearing_camera_forward_m)),
        width_px_(static_cast<double>(camera.width_px)) {}

  double area_scale() const { return area_scale_; }
  // Where the map's angle gain is centred (ForwardMap::visibility_axis_rad).
  double axis_rad() const { return static_cast<double>(map_.visibility_axis_rad); }

  // The image angle of a centroid column under the map's law (forward_map.hpp).
  double angle_rad(double u_px) const {
    const double t = (u_px - 0.5 * (width_px_ - 1.0)) / width_px_;
    return static_cast<double>(map_.bearing_a1_rad) * t +
           static_cast<double>(map_.bearing_a3_rad) * t * t * t;
  }

  // The camera at the map's bearing place (@p x_m, @p y_m) turned towards @p board's centre: a
  // board whose face looks away shows nothing (its back is not its colour).
  // @p gain: the angle gain the feature is taken back to the axis by (centred on the map's
  // visibility_axis_rad).
  CellView from(const BoardSpec& board, double x_m, double y_m, float gain) const {
    const double dx = board.centre_x_m - x_m, dy = board.centre_y_m - y_m;
    const double yaw = std::atan2(dy, dx);
    CellView v;
    v.bearing_rad = static_cast<float>(yaw);
    const BoardAxes axes = board_axes(board);
    const double dz = board.centre_z_m - camera_.height_m;
    if (-(dx * axes.normal[0] + dy * axes.normal[1] + dz * axes.normal[2]) <= 0.0) return v;
    const algorithms::Pose2 robot{x_m - forward_m_ * std::cos(yaw),
                                  y_m - forward_m_ * std::sin(yaw), yaw};
    const BoardImage image = project_board(camera_, lens_, board, robot);
    if (!(image.area_px > 0.0)) return v;
    v.cut = image.cut;
    const double angle = angle_rad(image.centroid_u_px);
    v.bearing_rad = static_cast<float>(algorithms::wrap_angle_rad(yaw - angle));
    v.feature =
        static_cast<float>(image.area_px * area_scale_ /
                           static_cast<double>(algorithms::angle_gain(
                               gain, static_cast<float>(angle) - map_.visibility_axis_rad)));
    // As the trainer measures a frame's (trainer_on_areas.cpp): a board about as wide as high
    // spans the square root of its pixels in columns.
    v.half_width_rad =
        static_cast<float>(0.5 * std::fabs(static_cast<double>(map_.bearing_a1_rad)) *
                           std::sqrt(image.area_px) / width_px_);
    return v;
  }

 private:
  const CameraSpec& camera_;
  LensModel lens_;
  const ForwardMap& map_;
  double area_scale_;
  double forward_m_;
  double width_px_;
};

// The angle gain (ForwardMap::visibility_angle_gain) the geometry implies: over the placed
// frames' poses and the boards each sees whole (no edge of the frame cuts them, nor facing them),
// the least-squares slope
// (through 0) of a board's projected area at the frame's heading over its area turned to face
// it, less 1, against the square of its image angle (angle_gain's law, 1 + gain a^2). The lens's
// stretch towards the frame's edge alone, without the frames' noise. NaN with fewer than 50 such
// views.
double geometry_angle_gain(const SceneGeometryFit& fit, const std::vector<std::size_t>& boards,
                           const std::vector<PlacedFrame>& frames, const GeometryView& view,
                           double forward_m) {
  const LensModel lens(fit.camera);
  double xy = 0.0, xx = 0.0;
  std::size_t n = 0;
  for (const PlacedFrame& f : frames) {
    const double cx = f.pose.x_m + forward_m * std::cos(f.pose.yaw_rad);
    const double cy = f.pose.y_m + forward_m * std::sin(f.pose.yaw_rad);
    for (const std::size_t b : boards) {
      const BoardSpec& board = fit.boards[b].board;
      const BoardImage image = project_board(fit.camera, lens, board, f.pose);
      if (!(image.area_px >= 30.0) || image.cut) continue;
      const CellView facing = view.from(board, cx, cy, 0.0F);
      if (!(facing.feature > 0.0F) || facing.cut) continue;
      // From the optical axis (the map's visibility_axis_rad), where the gain is centred.
      const double a = view.angle_rad(image.centroid_u_px) - view.axis_rad();
      const double axis = static_cast<double>(facing.feature) / view.area_scale();
      xy += a * a * (image.area_px / axis - 1.0);
      xx += a * a * a * a;
      ++n;
    }
  }
  if (n < 50 || !(xx > 0.0)) return std::numeric_limits<double>::quiet_NaN();
  return std::clamp(xy / xx, -2.0, 2.0);
}

// The boards that keep the kernel's tables had their features taken back to the axis by the
// kernel's gain, and the map now holds the geometry's: each such board's features are scaled by
// the mean over the frames that saw it whole of the ratio of the two gains at the frame's image
// angle (what the kernel's mean over those frames would have been under the geometry's gain).
void rescale_kernel_boards(const std::vector<algorithms::AreaVector>& areas,
                           const std::vector<PlacedFrame>& frames, const GeometryView& view,
                           GeometryTablesReport& report, ForwardMap& map) {
  const auto old_gain = static_cast<float>(report.kernel_angle_gain);
  const float new_gain = map.visibility_angle_gain;
  if (old_gain == new_gain) return;
  for (std::size_t b = 0; b < report.from_geometry.size(); ++b) {
    if (report.from_geometry[b] || !(map.sigma[b] > 0.0F)) continue;
    double sum = 0.0;
    std::size_t n = 0;
    for (const PlacedFrame& f : frames) {
      const algorithms::AreaVector& a = areas[f.index];
      if (!algorithms::gives_bearing(a, b)) continue;
      const auto angle =
          static_cast<float>(view.angle_rad(a.centroid_column_px(b))) - map.visibility_axis_rad;
      sum += static_cast<double>(algorithms::angle_gain(old_gain, angle) /
                                 algorithms::angle_gain(new_gain, angle));
      ++n;
    }
    if (n == 0) continue;
    const auto factor = static_cast<float>(sum / static_cast<double>(n));
    for (std::size_t at = 0; at < map.stored_cells(); ++at) {
      if (map.bearing_rad[at * kMaxBoards + b] == ForwardMap::kNoBearing) continue;
      map.heading_terms[(at * kMaxBoards + b) * 2] *= factor;
    }
  }
}

double median_of(std::vector<double>& v) {
  if (v.empty()) return 0.0;
  auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

// A bearing's spread from its absolute misses (radians): 1.4826 times their median, at least 0.1
// degree; 0 with fewer than 20 misses.
double bearing_spread_of(std::vector<double>& abs_misses) {
  if (abs_misses.size() < 20) return 0.0;
  return std::max(1.4826 * median_of(abs_misses), 0.1 * algorithms::kPi / 180.0);
}

}  // namespace

GeometryTablesReport visibility_from_geometry(const SceneGeometryFit& fit,
                                              const std::vector<algorithms::AreaVector>& areas,
                                              const std::vector<PlacedFrame>& frames,
                                              float area_scale, ForwardMap& map,
                                              const GeometryTablesOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  GeometryTablesReport report;
  const std::size_t boards = map.board_count;
  report.from_geometry.assign(boards, 0);
  report.kernel_sigma.assign(boards, 0.0);
  report.geometry_sigma.assign(boards, 0.0);
  report.geometry_bearing_sigma_rad.assign(boards, 0.0);
  report.kernel_bearings.assign(boards, 0);
  report.kernel_bearing_sigma_rad.assign(boards, 0.0);
  for (std::size_t b = 0; b < boards; ++b) {
    report.kernel_sigma[b] = static_cast<double>(map.sigma[b]);
    report.kernel_bearing_sigma_rad[b] = static_cast<double>(map.bearing_sigma_rad[b]);
  }
  if (!ForwardMap::kHeadingTermStorage || !ForwardMap::kBearingStorage || !map.present() ||
      !map.has_visibility) {
    report.skipped = "the map has no visibility (a route map, or --no-visibility)";
    return report;
  }
  if (!fit.ok) {
    report.skipped = "the geometry fit did not converge";
    return report;
  }
  if (frames.empty()) {
    report.skipped = "the frames were not placed by odometry";
    return report;
  }
  std::vector<std::size_t> candidates;
  for (std::size_t b = 0; b < boards && b < fit.boards.size(); ++b)
    if (fit.boards[b].ok && map.sigma[b] > 0.0F) candidates.push_back(b);
  if (candidates.empty()) {
    report.skipped = "no board of the map was fitted";
    return report;
  }

  // The kernel tables, to put back for the boards the geometry does not predict better.
  const std::vector<float> old_bearing(map.bearing_rad.begin(), map.bearing_rad.end());
  const std::vector<float> old_terms(map.heading_terms.begin(), map.heading_terms.end());

  const GeometryView view(fit.camera, map, area_scale);
  report.kernel_angle_gain = static_cast<double>(map.visibility_angle_gain);
  report.geometry_angle_gain = geometry_angle_gain(
      fit, candidates, frames, view, static_cast<double>(map.bearing_camera_forward_m));
  // The geometry's own stretch towards the frame's edge: the kernel's gain is measured through
  // the frames' noise and the kernel's blur (on random scene 5: -0.22 against the projection's
  // 0.35). The boards that keep the kernel's tables are rescaled to it at the end.
  if (std::isfinite(report.geometry_angle_gain))
    map.visibility_angle_gain = static_cast<float>(report.geometry_angle_gain);
  const float gain = map.visibility_angle_gain;
  const double cell = static_cast<double>(map.cell_m);
  for (std::uint32_t r = 0; r < map.rows; ++r) {
    for (std::uint32_t c = 0; c < map.columns; ++c) {
      const std::size_t at = map.index(c, r);
      if (at == ForwardMap::kVoidCell) continue;
      const double x = static_cast<double>(map.origin_x_m) + c * cell;
      const double y = static_cast<double>(map.origin_y_m) + r * cell;
      for (const std::size_t b : candidates) {
        const CellView v = view.from(fit.boards[b].board, x, y, gain);
        map.bearing_rad[at * kMaxBoards + b] = v.bearing_rad;
        float* t = map.heading_terms.data() + (at * kMaxBoards + b) * 2;
        t[0] = v.feature;
        t[1] = v.half_width_rad;
      }
      ++report.cells;
    }
  }

  // Each candidate's areas and bearings as the firmware predicts them at the placed frames.
  std::vector<double> sq(boards, 0.0);
  std::vector<std::size_t> n(boards, 0);
  std::vector<std::vector<double>> bearing_residuals(boards);
  std::array<float, kMaxBoards> predicted{}, bearing{};
  for (const PlacedFrame& f : frames) {
    const algorithms::AreaVector& a = areas[f.index];
    const algorithms::SeenHeading heading = algorithms::seen_heading(f.pose.yaw_rad);
    const algorithms::GridPoint point = algorithms::locate(map, f.pose.x_m, f.pose.y_m);
    algorithms::expected_features(map, point, heading, predicted.data());
    algorithms::apply_visibility(
        map,
        algorithms::bearing_point(map, f.pose.x_m, f.pose.y_m, heading.cos_yaw, heading.sin_yaw),
        heading.yaw_rad, predicted.data(), bearing.data());
    for (const std::size_t b : candidates) {
      if (b >= a.count) continue;
      const double r = static_cast<double>(a.pixels[b]) * static_cast<double>(area_scale) -
                       static_cast<double>(predicted[b]);
      sq[b] += r * r;
      ++n[b];
      if (!algorithms::gives_bearing(a, b) || bearing[b] == ForwardMap::kNoBearing) continue;
      const double seen = f.pose.yaw_rad - view.angle_rad(a.centroid_column_px(b));
      bearing_residuals[b].push_back(
          std::fabs(algorithms::wrap_angle_rad(seen - static_cast<double>(bearing[b]))));
    }
  }

  for (const std::size_t b : candidates) {
    if (n[b] == 0) continue;
    report.geometry_sigma[b] = std::sqrt(sq[b] / static_cast<double>(n[b]));
    report.geometry_bearing_sigma_rad[b] = bearing_spread_of(bearing_residuals[b]);
    if (report.geometry_sigma[b] <= options.kernel_noise_ratio * report.kernel_sigma[b]) {
      report.from_geometry[b] = 1;
      map.sigma[b] = static_cast<float>(
          std::max(report.geometry_sigma[b], std::max(1e-2 * report.kernel_sigma[b], 1e-4)));
      report.applied = true;
      const double kernel_spread = static_cast<double>(map.bearing_sigma_rad[b]);
      if (kernel_spread > 0.0 && kernel_spread <= report.geometry_bearing_sigma_rad[b]) {
        // The kernel's bearings came closer to the frames' (the law's error at each image angle
        // averaged over the frames seen there): kept where it has one, and its spread.
        report.kernel_bearings[b] = 1;
        for (std::size_t at = 0; at < map.stored_cells(); ++at) {
          const std::size_t i = at * kMaxBoards + b;
          if (old_bearing[i] != ForwardMap::kNoBearing) map.bearing_rad[i] = old_bearing[i];
        }
      } else if (kernel_spread > 0.0 && report.geometry_bearing_sigma_rad[b] > 0.0 &&
                 report.geometry_bearing_sigma_rad[b] <= 1.0) {
        // At most 1 rad (the map format's bound), as the kernel's spread.
        map.bearing_sigma_rad[b] = static_cast<float>(report.geometry_bearing_sigma_rad[b]);
      }
    }
  }
  // The kernel tables back for the others.
  for (const std::size_t b : candidates) {
    if (report.from_geometry[b]) continue;
    for (std::size_t at = 0; at <= map.stored_cells(); ++at) {
      const std::size_t i = at * kMaxBoards + b;
      if (i >= old_bearing.size() || 2 * i + 1 >= old_terms.size()) break;
      map.bearing_rad[i] = old_bearing[i];
      map.heading_terms[2 * i] = old_terms[2 * i];
      map.heading_terms[2 * i + 1] = old_terms[2 * i + 1];
    }
  }
  if (!report.applied) {
    report.skipped = "the geometry predicted no board better than the kernel";
    map.visibility_angle_gain = static_cast<float>(report.kernel_angle_gain);
  } else {
    rescale_kernel_boards(areas, frames, view, report, map);
  }
  report.ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return report;
}

std::size_t project_bearings_from_geometry(const SceneGeometryFit& fit,
                                           const std::vector<char>& boards,
                                           algorithms::ForwardMap& map) {
  using algorithms::BearingProjection;
  map.projection = BearingProjection{};
  if (!fit.ok || !map.has_bearings) return 0;
  BearingProjection p;
  const CameraSpec& camera = fit.camera;
  // The robot at the map's origin facing +x: the camera's frame is then the robot's.
  const CameraFrame frame = camera_frame_of(camera, algorithms::Pose2{0.0, 0.0, 0.0});
  for (int k = 0; k < 3; ++k) {
    const auto i = static_cast<std::size_t>(k);
    p.origin_m[i] = static_cast<float>(frame.origin[k]);
    p.right[i] = static_cast<float>(frame.right[k]);
    p.down[i] = static_cast<float>(frame.down[k]);
    p.forward[i] = static_cast<float>(frame.forward[k]);
  }
  const Intrinsics in = intrinsics_of(camera);
  p.focal_px = static_cast<float>(in.focal_px);
  p.cx_px = static_cast<float>(in.cx_px);
  p.cy_px = static_cast<float>(in.cy_px);
  p.width_px = camera.width_px;
  p.height_px = camera.height_px;
  p.k1 = static_cast<float>(camera.k1);
  p.k2 = static_cast<float>(camera.k2);
  p.k3 = static_cast<float>(camera.k3);
  p.p1 = static_cast<float>(camera.p1);
  p.p2 = static_cast<float>(camera.p2);
  const double r_max = LensModel(camera).max_radius();
  p.max_radius2 = static_cast<float>(std::min(r_max * r_max, 1e16));
  std::size_t given = 0;
  for (std::size_t b = 0; b < boards.size() && b < map.board_count && b < fit.boards.size(); ++b) {
    if (!boards[b] || !fit.boards[b].ok || !(map.bearing_sigma_rad[b] > 0.0F)) continue;
    const BoardSpec& board = fit.boards[b].board;
    const BoardAxes axes = board_axes(board);
    const double hw = 0.5 * board.width_m, hh = 0.5 * board.height_m;
    // In the order project_board goes round the outline.
    std::array<std::array<double, 2>, BearingProjection::kMaxPoints> outline{};
    std::size_t n = 0;
    if (board.shape == BoardShape::kEllipse) {
      // An octagon round the ellipse with the ellipse's area (the inscribed one has 2 sqrt(2) /
      // pi of it): the projected areas need no correction for it.
      const double grow = std::sqrt(algorithms::kPi / (2.0 * std::sqrt(2.0)));
      for (; n < BearingProjection::kMaxPoints; ++n) {
        const double a = 2.0 * algorithms::kPi * static_cast<double>(n) /
                         static_cast<double>(BearingProjection::kMaxPoints);
        outline[n] = {grow * hw * std::cos(a), grow * hh * std::sin(a)};
      }
    } else {
      // The corners and the middle of each side: the lens bends the sides, and the projected
      // area follows most of the bend through the middle points.
      const double corner[5][2] = {{-hw, -hh}, {hw, -hh}, {hw, hh}, {-hw, hh}, {-hw, -hh}};
      for (int side = 0; side < 4; ++side) {
        outline[n++] = {corner[side][0], corner[side][1]};
        outline[n++] = {0.5 * (corner[side][0] + corner[side + 1][0]),
                        0.5 * (corner[side][1] + corner[side + 1][1])};
      }
    }
    for (std::size_t i = 0; i < n; ++i) {
      for (int k = 0; k < 3; ++k) {
        p.point_m(b, i, static_cast<std::size_t>(k)) =
            static_cast<float>(axes.centre[k] + outline[i][0] * axes.width_dir[k] +
                               outline[i][1] * axes.height_dir[k]);
      }
    }
    p.points[b] = static_cast<std::uint8_t>(n);
    ++given;
  }
  if (given > 0) map.projection = p;
  return given;
}

std::vector<double> projected_bearing_spread(const algorithms::ForwardMap& map,
                                             const std::vector<algorithms::AreaVector>& areas,
                                             const std::vector<PlacedFrame>& frames) {
  const std::size_t boards = map.board_count;
  std::vector<double> spread(boards, 0.0);
  if (!map.projection.present()) return spread;
  std::vector<std::vector<double>> residuals(boards);
  for (const PlacedFrame& f : frames) {
    if (f.index >= areas.size()) continue;
    const algorithms::AreaVector& a = areas[f.index];
    const algorithms::CameraAtPose camera = algorithms::camera_at_pose(
        map.projection, static_cast<float>(f.pose.x_m), static_cast<float>(f.pose.y_m),
        static_cast<float>(std::cos(f.pose.yaw_rad)), static_cast<float>(std::sin(f.pose.yaw_rad)));
    for (std::size_t b = 0; b < boards; ++b) {
      float measured = 0.0F, projected = 0.0F;
      if (map.projection.points[b] == 0U || !algorithms::board_image_angle(map, a, b, measured) ||
          !algorithms::projected_image_angle(map, camera, b, projected))
        continue;
      residuals[b].push_back(
          std::fabs(static_cast<double>(projected) - static_cast<double>(measured)));
    }
  }
  for (std::size_t b = 0; b < boards; ++b) spread[b] = bearing_spread_of(residuals[b]);
  return spread;
}

std::vector<double> project_areas_from_geometry(const std::vector<algorithms::AreaVector>& areas,
                                                const std::vector<PlacedFrame>& frames,
                                                float area_scale, ForwardMap& map) {
  const std::size_t boards = map.board_count;
  std::vector<double> noise(boards, 0.0);
  if (!map.projection.present()) return noise;
  // Each frame's projected areas at its placed pose (pixels; -1: no outline).
  std::vector<std::array<float, kMaxBoards>> projected(frames.size());
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const PlacedFrame& f = frames[k];
    const algorithms::CameraAtPose camera = algorithms::camera_at_pose(
        map.projection, static_cast<float>(f.pose.x_m), static_cast<float>(f.pose.y_m),
        static_cast<float>(std::cos(f.pose.yaw_rad)), static_cast<float>(std::sin(f.pose.yaw_rad)));
    projected[k].fill(-1.0F);
    for (std::size_t b = 0; b < boards; ++b) {
      float area_px = 0.0F;
      if (algorithms::projected_area_px(map.projection, camera, b, area_px))
        projected[k][b] = area_px;
    }
  }
  for (std::size_t b = 0; b < boards; ++b) {
    if (map.projection.points[b] == 0U || !(map.sigma[b] > 0.0F)) continue;
    double mp = 0.0, pp = 0.0;
    std::size_t whole = 0;
    for (std::size_t k = 0; k < frames.size(); ++k) {
      const algorithms::AreaVector& a = areas[frames[k].index];
      const double p = static_cast<double>(projected[k][b]);
      if (!algorithms::gives_bearing(a, b) || !(p > 0.0)) continue;
      mp += static_cast<double>(a.pixels[b]) * static_cast<double>(area_scale) * p;
      pp += p * p;
      ++whole;
    }
    if (whole < 20 || !(pp > 0.0)) continue;
    const double per_px = mp / pp;
    double sq = 0.0;
    std::size_t n = 0;
    for (std::size_t k = 0; k < frames.size(); ++k) {
      const algorithms::AreaVector& a = areas[frames[k].index];
      if (b >= a.count || projected[k][b] < 0.0F) continue;
      const double r = static_cast<double>(a.pixels[b]) * static_cast<double>(area_scale) -
                       per_px * static_cast<double>(projected[k][b]);
      sq += r * r;
      ++n;
    }
    if (n == 0) continue;
    noise[b] = std::sqrt(sq / static_cast<double>(n));
    const auto old_sigma = static_cast<double>(map.sigma[b]);
    if (noise[b] > old_sigma) continue;
    map.projection.area_per_px[b] = static_cast<float>(per_px);
    map.projection.area_sigma[b] =
        static_cast<float>(std::max(noise[b], std::max(1e-2 * old_sigma, 1e-4)));
  }
  return noise;
}

std::size_t drop_untaken_outlines(const std::vector<char>& served, ForwardMap& map) {
  algorithms::BearingProjection& p = map.projection;
  std::size_t dropped = 0;
  for (std::size_t b = 0; b < map.board_count; ++b) {
    if ((b < served.size() && served[b] != 0) || p.points[b] == 0U || p.area_per_px[b] > 0.0F)
      continue;
    p.points[b] = 0;
    p.sigma_rad[b] = 0.0F;
    p.area_sigma[b] = 0.0F;
    for (std::size_t i = 0; i < algorithms::BearingProjection::kMaxPoints; ++i)
      for (std::size_t d = 0; d < 3; ++d) p.point_m(b, i, d) = 0.0F;
    ++dropped;
  }
  if (!p.present()) p = algorithms::BearingProjection{};
  return dropped;
}

}  // namespace harmoloc::sim_host
