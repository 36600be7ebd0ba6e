// Placing a random scene's boards where the camera sees them along the route.
#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <vector>

#include "harmoloc/algorithms/geometry.hpp"
#include "harmoloc/sim_host/board_projection.hpp"
#include "harmoloc/sim_host/lens.hpp"
#include "harmoloc/sim_host/random_scene.hpp"
#include "random_scene_parts.hpp"

namespace harmoloc::sim_host::random_scene_detail {

namespace {

constexpr double kWallGap_m = 0.02;  // a wall board's face stands this far off the wall

struct Wall {
  double x0, y0, x1, y1;  // along the wall
  double nx, ny;          // into the room
};

std::vector<Wall> walls_of(const RoomSpec& r) {
  return {{r.x_m[0], r.y_m[0], r.x_m[1], r.y_m[0], 0.0, 1.0},
          {r.x_m[0], r.y_m[1], r.x_m[1], r.y_m[1], 0.0, -1.0},
          {r.x_m[0], r.y_m[0], r.x_m[0], r.y_m[1], 1.0, 0.0},
          {r.x_m[1], r.y_m[0], r.x_m[1], r.y_m[1], -1.0, 0.0}};
}

// The area of polygon (x, y) clipped to the rectangle [0, w] x [0, h] (Sutherland-Hodgman).
double clipped_area(std::vector<std::array<double, 2>> poly, double w, double h) {
  const auto clip = [&poly](int axis, double bound, bool keep_below) {
    std::vector<std::array<double, 2>> out;
    const auto in = [&](const std::array<double, 2>& p) {
      return keep_below ? p[static_cast<std::size_t>(axis)] <= bound
                        : p[static_cast<std::size_t>(axis)] >= bound;
    };
    for (std::size_t i = 0; i < poly.size(); ++i) {
      const auto& a = poly[i];
      const auto& b = poly[(i + 1) % poly.size()];
      if (in(a)) out.push_back(a);
      if (in(a) != in(b)) {
        const auto ax = static_cast<std::size_t>(axis);
        const double t = (bound - a[ax]) / (b[ax] - a[ax]);
        out.push_back({a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])});
      }
    }
    poly = std::move(out);
  };
  clip(0, 0.0, false);
  clip(0, w, true);
  clip(1, 0.0, false);
  clip(1, h, true);
  double area = 0.0;
  for (std::size_t k = 0; k < poly.size(); ++k) {
    const auto& a = poly[k];
    const auto& b = poly[(k + 1) % poly.size()];
    area += a[0] * b[1] - b[0] * a[1];
  }
  return 0.5 * std::fabs(area);
}

// A board's approximate area (pixels) from the camera at @p f: its outline's corners projected
// through the lens, clipped to the frame; 0 unless it faces the camera and every corner projects.
// Coarser than project_board (board_projection.hpp), and kept so: the random scene family's
// boards are drawn with it, and another area would draw other scenes for the same seeds.
double approx_area(const Views& v, const CameraFrame& f, const BoardSpec& b) {
  const BoardAxes axes = board_axes(b);
  const double* n = axes.normal;
  const double* c = axes.centre;
  const double to_cam =
      (f.origin[0] - c[0]) * n[0] + (f.origin[1] - c[1]) * n[1] + (f.origin[2] - c[2]) * n[2];
  if (to_cam <= 0.05) return 0.0;
  const double* u = axes.width_dir;
  const double* w = axes.height_dir;
  const CameraSpec& cam = v.proxy.camera;
  std::vector<std::array<double, 2>> quad(4);
  const double su[4] = {-1, 1, 1, -1}, sv[4] = {-1, -1, 1, 1};
  for (std::size_t k = 0; k < 4; ++k) {
    double p[3];
    for (int i = 0; i < 3; ++i)
      p[i] = c[i] + su[k] * 0.5 * b.width_m * u[i] + sv[k] * 0.5 * b.height_m * w[i];
    if (!project_point(cam, v.lens, f, p, quad[k][0], quad[k][1])) return 0.0;
  }
  const double area = clipped_area(quad, cam.width_px, cam.height_px);
  return b.shape == BoardShape::kEllipse ? area * kPi / 4.0 : area;
}

double bounding_radius(const BoardSpec& b) {
  return 0.5 * std::hypot(b.width_m, b.height_m);
}

// A candidate board in view of place @p k: on the wall ahead, or on a stand in front of it.
std::optional<BoardSpec> candidate(Draw& d, const Scenario& s, const Views& v, std::size_t k,
                                   const std::vector<BoardSpec>& placed) {
  BoardSpec b{};
  b.width_m = q(d.u(0.15, 0.6), 1000.0);
  b.height_m = q(std::clamp(b.width_m * d.u(0.6, 1.6), 0.15, 0.6), 1000.0);
  b.shape = d.chance(0.4) ? BoardShape::kEllipse : BoardShape::kRectangle;
  const Pose2& place = v.places[k];
  const CameraFrame& f = v.frames[k];
  const double ox = f.origin[0], oy = f.origin[1];
  const double dir = place.yaw_rad + d.u(-0.6, 0.6) * v.half_hfov_rad;
  const double dx = std::cos(dir), dy = std::sin(dir);
  // The farthest a board of this size stays usable (3 times the usable area, seen head-on).
  const double fill = b.shape == BoardShape::kEllipse ? kPi / 4.0 : 1.0;
  const double reach = v.focal_px * std::sqrt(b.width_m * b.height_m * fill / (3.0 * v.usable_px));
  // The wall ahead.
  double wall_t = 1e9;
  const Wall* wall = nullptr;
  const std::vector<Wall> walls = walls_of(s.room);
  for (const Wall& w : walls) {
    const double denom = dx * w.nx + dy * w.ny;
    if (denom >= -1e-9) continue;
    const double t = ((w.x0 - ox) * w.nx + (w.y0 - oy) * w.ny) / denom;
    if (t > 0.0 && t < wall_t) {
      wall_t = t;
      wall = &w;
    }
  }
  if (wall == nullptr || reach < 0.8) return std::nullopt;
  const bool on_wall = wall_t <= reach && d.chance(0.7);
  double cx = 0, cy = 0, facing = 0, horizontal = 0;
  if (on_wall) {
    const double hx = ox + wall_t * dx, hy = oy + wall_t * dy;
    const double normal = std::atan2(wall->ny, wall->nx);
    const double to_cam = std::atan2(oy - hy, ox - hx);
    const double turn =
        std::clamp(algorithms::wrap_angle_rad(to_cam - normal) + d.u(-5.0, 5.0) * kDeg,
                   -20.0 * kDeg, 20.0 * kDeg);
    facing = normal + turn;
    const double off = kWallGap_m + 0.5 * b.width_m * std::fabs(std::sin(turn)) + 0.01;
    cx = hx + wall->nx * off;
    cy = hy + wall->ny * off;
    // Wholly on its wall, clear of the corners.
    const double along = wall->nx != 0.0 ? cy : cx;
    const double lo = wall->nx != 0.0 ? s.room.y_m[0] : s.room.x_m[0];
    const double hi = wall->nx != 0.0 ? s.room.y_m[1] : s.room.x_m[1];
    if (along - 0.5 * b.width_m < lo + 0.1 || along + 0.5 * b.width_m > hi - 0.1)
      return std::nullopt;
    horizontal = wall_t;
  } else {
    const double most = std::min(reach, wall_t - 0.4);
    if (most < 0.9) return std::nullopt;
    horizontal = d.u(0.9, most);
    cx = ox + horizontal * dx;
    cy = oy + horizontal * dy;
    facing = std::atan2(oy - cy, ox - cx) + d.u(-20.0, 20.0) * kDeg;
    b.stand = true;
  }
  // Height: within the middle of the view from that place, on the wall or stand's range.
  const double pitch = s.camera.pitch_deg * kDeg;
  const double elevation = pitch + d.u(-0.5, 0.5) * v.half_vfov_rad;
  double z = s.camera.height_m + horizontal * std::tan(elevation);
  const double half_h = 0.5 * b.height_m;
  double z_lo = half_h + 0.05, z_hi = s.room.height_m - half_h - 0.1;
  if (b.stand) z_hi = std::min(z_hi, 1.8);
  if (on_wall && s.desk.present && wall->ny < 0.0 && cx + 0.5 * b.width_m > s.desk.x_m[0] - 0.05 &&
      cx - 0.5 * b.width_m < s.desk.x_m[1] + 0.05)
    z_lo = std::max(z_lo, s.desk.height_m + half_h + 0.05);  // above the desk
  if (z_lo > z_hi) return std::nullopt;
  z = std::clamp(z, z_lo, z_hi);
  // A slight tilt now and then, towards the camera's height.
  if (d.chance(0.3)) {
    const double tilt =
        std::clamp(std::atan2(s.camera.height_m - z, horizontal), -10.0 * kDeg, 10.0 * kDeg);
    b.tilt_rad = q(tilt / kDeg, 10.0) * kDeg;
  }
  b.centre_x_m = q(cx, 1000.0);
  b.centre_y_m = q(cy, 1000.0);
  b.centre_z_m = q(z, 1000.0);
  b.facing_yaw_rad = q(algorithms::wrap_angle_rad(facing) / kDeg, 10.0) * kDeg;
  // Clear of the other boards, the walls (a stand), the desk and the route.
  const double radius = bounding_radius(b);
  for (const BoardSpec& o : placed) {
    const double gap = std::sqrt(std::pow(o.centre_x_m - b.centre_x_m, 2) +
                                 std::pow(o.centre_y_m - b.centre_y_m, 2) +
                                 std::pow(o.centre_z_m - b.centre_z_m, 2));
    if (gap < radius + bounding_radius(o) + 0.05) return std::nullopt;
  }
  if (b.stand) {
    if (cx < s.room.x_m[0] + radius + 0.1 || cx > s.room.x_m[1] - radius - 0.1 ||
        cy < s.room.y_m[0] + radius + 0.1 || cy > s.room.y_m[1] - radius - 0.1)
      return std::nullopt;
    if (s.desk.present && cx > s.desk.x_m[0] - radius && cx < s.desk.x_m[1] + radius &&
        cy > s.desk.front_y_m - radius)
      return std::nullopt;
    for (const Pose2& p : v.places) {
      if (std::hypot(p.x_m - cx, p.y_m - cy) < kStandClearance_m + radius) return std::nullopt;
    }
  }
  return b;
}

}  // namespace

Views views_of(const Scenario& s) {
  Views v;
  v.proxy = proxy_of(s);
  v.lens = LensModel(v.proxy.camera);
  v.places = route_places(s.route);
  for (const Pose2& p : v.places) v.frames.push_back(camera_frame_of(v.proxy.camera, p));
  const CameraSpec& c = v.proxy.camera;
  v.frame_px = static_cast<double>(c.width_px) * c.height_px;
  v.usable_px = std::max(60.0, kUsableBoardShare * v.frame_px);
  const Intrinsics in = intrinsics_of(c);
  v.focal_px = in.focal_px;
  double x = 0, y = 0;
  v.half_hfov_rad = v.lens.undistort(0.5 * c.width_px / in.focal_px, 0.0, x, y)
                        ? std::atan(x)
                        : std::atan(v.lens.max_radius());
  v.half_vfov_rad = v.lens.undistort(0.0, 0.5 * c.height_px / in.focal_px, x, y)
                        ? std::atan(y)
                        : std::atan(v.lens.max_radius());
  return v;
}

// Places @p count boards greedily: each where it serves the places with the fewest boards in view
// best (by the approximate areas). Empty when some place is left with fewer than 2.
std::optional<std::vector<BoardSpec>> place_boards(Draw& d, const Scenario& s, const Views& v,
                                                   int count) {
  constexpr int kCandidates = 30;
  const std::size_t n = v.places.size();
  std::vector<int> cover(n, 0);
  std::vector<BoardSpec> boards;
  std::vector<char> sees(n), best_sees(n);
  // @p count boards, and more (up to 8) while some place sees fewer than 2.
  for (int b = 0; b < count || (b < 8 && *std::min_element(cover.begin(), cover.end()) < 2); ++b) {
    const int least = *std::min_element(cover.begin(), cover.end());
    std::vector<std::size_t> needy;
    for (std::size_t k = 0; k < n; ++k) {
      if (cover[k] == least) needy.push_back(k);
    }
    double best_score = 0.0;
    std::optional<BoardSpec> best;
    for (int c = 0; c < kCandidates; ++c) {
      const std::size_t k =
          needy[static_cast<std::size_t>(d.i(0, static_cast<int>(needy.size()) - 1))];
      const std::optional<BoardSpec> cand = candidate(d, s, v, k, boards);
      if (!cand) continue;
      double score = 0.0;
      bool too_big = false;
      for (std::size_t j = 0; j < n; ++j) {
        const double area = approx_area(v, v.frames[j], *cand);
        too_big = too_big || area > 0.3 * v.frame_px;
        sees[j] = area >= 2.0 * v.usable_px ? 1 : 0;
        if (sees[j])
          score += cover[j] == 0 ? 100.0 : cover[j] == 1 ? 30.0 : cover[j] == 2 ? 3.0 : 0.3;
      }
      if (too_big || score <= best_score) continue;
      best_score = score;
      best = cand;
      best_sees = sees;
    }
    if (!best) return std::nullopt;
    for (std::size_t j = 0; j < n; ++j) cover[j] += best_sees[j];
    boards.push_back(*best);
  }
  if (*std::min_element(cover.begin(), cover.end()) < 2) return std::nullopt;
  return boards;
}

}  // namespace harmoloc::sim_host::random_scene_detail
