#include "harmoloc/sim_host/scene_renderer.hpp"

#include <algorithm>
#include <cmath>

namespace harmoloc::sim_host {

using algorithms::kPi;
using algorithms::Pose2;

namespace {

constexpr int kNoBoard = -1;

// Undistorts a radius: solves r_u (1 + k r_u^2) = r_d by Newton's method. Returns false where no
// solution exists on the monotonic branch (outside the lens's image circle for k < 0).
bool undistort_radius(double r_d, double k, double& r_u) {
  if (r_d == 0.0) {
    r_u = 0.0;
    return true;
  }
  double limit = 1e9;
  if (k < 0.0) {
    const double r_star = 1.0 / std::sqrt(-3.0 * k);
    limit = r_star;
    if (r_d >= r_star * (1.0 + k * r_star * r_star)) return false;
  }
  double r = r_d;
  for (int i = 0; i < 50; ++i) {
    const double f = r * (1.0 + k * r * r) - r_d;
    const double df = 1.0 + 3.0 * k * r * r;
    const double next = r - f / df;
    if (std::fabs(next - r) < 1e-12) {
      r = next;
      break;
    }
    r = std::min(std::max(next, 0.0), limit);
  }
  r_u = r;
  return true;
}

Rgb scale(const Rgb& c, double g) {
  auto s = [g](std::uint8_t v) {
    return static_cast<std::uint8_t>(std::clamp(std::lround(v * g), 0L, 255L));
  };
  return Rgb{s(c.r), s(c.g), s(c.b)};
}

}  // namespace

SceneRenderer::SceneRenderer(const Scenario& scenario) : scenario_(scenario) {
  const CameraSpec& c = scenario.camera;
  const double f = 0.5 * c.width_px / std::tan(0.5 * c.horizontal_fov_deg * kPi / 180.0);
  const double cx = 0.5 * c.width_px - 0.5, cy = 0.5 * c.height_px - 0.5;
  rays_.resize(static_cast<std::size_t>(c.width_px) * c.height_px);
  for (std::uint32_t v = 0; v < c.height_px; ++v) {
    for (std::uint32_t u = 0; u < c.width_px; ++u) {
      const double xd = (u - cx) / f, yd = (v - cy) / f;
      const double rd = std::hypot(xd, yd);
      double ru = 0.0;
      Ray& ray = rays_[static_cast<std::size_t>(v) * c.width_px + u];
      ray.valid = undistort_radius(rd, c.radial_k, ru);
      const double s = rd > 0.0 ? ru / rd : 1.0;
      ray.x = xd * s;
      ray.y = yd * s;
      ray.z = 1.0;
    }
  }
  set_time(0.0);
}

void SceneRenderer::set_time(double t_s) {
  time_s_ = t_s;
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
  occluders_.clear();
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
    occluders_.push_back(PlacedOccluder{x, y, o.radius_m, o.height_m, o.colour});
  }
}

// Returns the index of the board hit, or kNoBoard; @p colour is what the ray sees.
int SceneRenderer::trace(const double o[3], const double d[3], Rgb& colour) const {
  const Scenario& s = scenario_;
  double best = 1e30;
  int hit_board = kNoBoard;
  colour = Rgb{0, 0, 0};
  auto consider_plane = [&](int axis, double value, const Rgb& c) {
    if (std::fabs(d[axis]) < 1e-12) return;
    const double t = (value - o[axis]) / d[axis];
    if (t > 1e-6 && t < best) {
      best = t;
      colour = c;
      hit_board = kNoBoard;
    }
  };
  // Room: floor (tiled), ceiling, four walls.
  if (d[2] < 0.0) {
    const double t = -o[2] / d[2];
    if (t < best) {
      best = t;
      const double fx = o[0] + t * d[0], fy = o[1] + t * d[1];
      const bool tile =
          (static_cast<long>(std::floor(fx / 0.3)) + static_cast<long>(std::floor(fy / 0.3))) % 2 ==
          0;
      colour = tile ? Rgb{112, 112, 108} : Rgb{96, 96, 93};
    }
  }
  consider_plane(2, 2.6, Rgb{215, 215, 212});
  consider_plane(1, s.wall_y_m, Rgb{200, 198, 188});
  consider_plane(1, -0.6, Rgb{200, 198, 188});
  consider_plane(0, -0.6, Rgb{190, 190, 182});
  consider_plane(0, s.floor_length_m + 0.6, Rgb{190, 190, 182});
  // Desk: a box from x 1.1 to 3.3 between its front face and the wall.
  const double desk_x0 = 1.1, desk_x1 = 3.3;
  if (std::fabs(d[1]) > 1e-12) {
    const double t = (s.desk_front_y_m - o[1]) / d[1];
    const double x = o[0] + t * d[0], z = o[2] + t * d[2];
    if (t > 1e-6 && t < best && x >= desk_x0 && x <= desk_x1 && z >= 0.0 && z <= s.desk_height_m) {
      best = t;
      colour = Rgb{118, 84, 54};
      hit_board = kNoBoard;
    }
  }
  if (std::fabs(d[2]) > 1e-12) {
    const double t = (s.desk_height_m - o[2]) / d[2];
    const double x = o[0] + t * d[0], y = o[1] + t * d[1];
    if (t > 1e-6 && t < best && x >= desk_x0 && x <= desk_x1 && y >= s.desk_front_y_m &&
        y <= s.wall_y_m) {
      best = t;
      colour = Rgb{150, 110, 70};
      hit_board = kNoBoard;
    }
  }
  // Boards: upright rectangles; the back is plain grey.
  for (std::size_t b = 0; b < boards_.size(); ++b) {
    const BoardSpec& board = boards_[b];
    const double nx = std::cos(board.facing_yaw_rad), ny = std::sin(board.facing_yaw_rad);
    const double denom = d[0] * nx + d[1] * ny;
    if (std::fabs(denom) < 1e-12) continue;
    const double t = ((board.centre_x_m - o[0]) * nx + (board.centre_y_m - o[1]) * ny) / denom;
    if (t <= 1e-6 || t >= best) continue;
    const double qx = o[0] + t * d[0] - board.centre_x_m, qy = o[1] + t * d[1] - board.centre_y_m;
    const double qz = o[2] + t * d[2] - board.centre_z_m;
    const double along = -qx * ny + qy * nx;
    if (std::fabs(along) > 0.5 * board.width_m || std::fabs(qz) > 0.5 * board.height_m) continue;
    best = t;
    if (denom < 0.0) {
      const double norm = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      colour = scale(board.colour, 0.8 + 0.2 * (-denom / norm));
      hit_board = static_cast<int>(b);
    } else {
      colour = Rgb{80, 80, 80};
      hit_board = kNoBoard;
    }
  }
  // Occluders: upright cylinders on the floor (side and top), shaded by the angle of incidence.
  // Seen from inside (the camera within one), the far side hides everything.
  for (const PlacedOccluder& c : occluders_) {
    const double px = o[0] - c.x_m, py = o[1] - c.y_m;
    const double a = d[0] * d[0] + d[1] * d[1];
    const double b = px * d[0] + py * d[1];
    const double cc = px * px + py * py - c.radius_m * c.radius_m;
    if (a > 1e-18) {
      const double disc = b * b - a * cc;
      if (disc >= 0.0) {
        const double root = std::sqrt(disc);
        for (const double t : {(-b - root) / a, (-b + root) / a}) {
          if (t <= 1e-6 || t >= best) continue;
          const double z = o[2] + t * d[2];
          if (z < 0.0 || z > c.height_m) continue;
          best = t;
          const double nx = (px + t * d[0]) / c.radius_m, ny = (py + t * d[1]) / c.radius_m;
          const double cosine =
              std::fabs(nx * d[0] + ny * d[1]) / std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
          colour = scale(c.colour, 0.7 + 0.3 * cosine);
          hit_board = kNoBoard;
          break;
        }
      }
    }
    if (std::fabs(d[2]) > 1e-12) {  // the top
      const double t = (c.height_m - o[2]) / d[2];
      const double qx = px + t * d[0], qy = py + t * d[1];
      if (t > 1e-6 && t < best && qx * qx + qy * qy <= c.radius_m * c.radius_m) {
        best = t;
        colour = c.colour;
        hit_board = kNoBoard;
      }
    }
  }
  return hit_board;
}

namespace {

void camera_frame(const Scenario& s, const Pose2& robot, double origin[3], double right[3],
                  double down[3], double fwd[3]) {
  const CameraSpec& c = s.camera;
  const double psi = robot.yaw_rad + c.mount_yaw_deg * kPi / 180.0;
  const double pitch = c.pitch_deg * kPi / 180.0;
  origin[0] = robot.x_m + c.forward_offset_m * std::cos(robot.yaw_rad);
  origin[1] = robot.y_m + c.forward_offset_m * std::sin(robot.yaw_rad);
  origin[2] = c.height_m;
  fwd[0] = std::cos(psi) * std::cos(pitch);
  fwd[1] = std::sin(psi) * std::cos(pitch);
  fwd[2] = std::sin(pitch);
  right[0] = std::sin(psi);
  right[1] = -std::cos(psi);
  right[2] = 0.0;
  // down = forward x right
  down[0] = fwd[1] * right[2] - fwd[2] * right[1];
  down[1] = fwd[2] * right[0] - fwd[0] * right[2];
  down[2] = fwd[0] * right[1] - fwd[1] * right[0];
}

}  // namespace

void SceneRenderer::render(const Pose2& robot_pose, algorithms::Pcg32& rng,
                           std::vector<std::uint8_t>& rgb) const {
  const CameraSpec& c = scenario_.camera;
  rgb.resize(rays_.size() * 3U);
  double o[3], r[3], dn[3], f[3];
  camera_frame(scenario_, robot_pose, o, r, dn, f);
  for (std::size_t i = 0; i < rays_.size(); ++i) {
    const Ray& ray = rays_[i];
    Rgb colour{0, 0, 0};
    if (ray.valid) {
      const double d[3] = {ray.x * r[0] + ray.y * dn[0] + f[0], ray.x * r[1] + ray.y * dn[1] + f[1],
                           ray.x * r[2] + ray.y * dn[2] + f[2]};
      trace(o, d, colour);
      colour = scale(colour, c.light_gain);
    }
    const std::uint8_t in[3] = {colour.r, colour.g, colour.b};
    for (int ch = 0; ch < 3; ++ch) {
      const double v = ray.valid ? in[ch] + c.pixel_noise * rng.normal() : 0.0;
      rgb[i * 3U + static_cast<std::size_t>(ch)] =
          static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L));
    }
  }
}

std::vector<std::uint32_t> SceneRenderer::visible_board_pixels(const Pose2& robot_pose) const {
  std::vector<std::uint32_t> counts(scenario_.boards.size(), 0U);
  double o[3], r[3], dn[3], f[3];
  camera_frame(scenario_, robot_pose, o, r, dn, f);
  for (const Ray& ray : rays_) {
    if (!ray.valid) continue;
    const double d[3] = {ray.x * r[0] + ray.y * dn[0] + f[0], ray.x * r[1] + ray.y * dn[1] + f[1],
                         ray.x * r[2] + ray.y * dn[2] + f[2]};
    Rgb colour{};
    const int b = trace(o, d, colour);
    if (b >= 0) ++counts[static_cast<std::size_t>(b)];
  }
  return counts;
}

}  // namespace harmoloc::sim_host
