#include "harmoloc/sim_host/scene_renderer.hpp"

#include <algorithm>
#include <cmath>

namespace harmoloc::sim_host {

using algorithms::kPi;
using algorithms::Pose2;

namespace {

constexpr int kNoBoard = -1;
// Culling objects: the desk, then the boards, then the cylinders (occluders, stands).
constexpr std::uint16_t kDesk = 0;
constexpr std::uint16_t kBoard0 = 1;
// Noise table: 4096 standard normal quantiles, three 12-bit indices a pixel from one 64-bit hash.
constexpr std::size_t kNoiseBits = 12;
constexpr std::size_t kNoiseEntries = std::size_t{1} << kNoiseBits;
constexpr std::uint64_t kNoiseMask = kNoiseEntries - 1;
constexpr Rgb kBoardBack{80, 80, 80};
constexpr Rgb kStandColour{70, 70, 72};
constexpr double kStandRadius_m = 0.015;

Rgb scale(const Rgb& c, double g) {
  auto s = [g](std::uint8_t v) {
    return static_cast<std::uint8_t>(std::clamp(std::lround(v * g), 0L, 255L));
  };
  return Rgb{s(c.r), s(c.g), s(c.b)};
}

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

// splitmix64's finaliser: a good 64-bit mix of a counter.
inline std::uint64_t mix64(std::uint64_t z) {
  z = (z ^ (z >> 30U)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27U)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31U);
}

void camera_frame(const Scenario& s, const Pose2& robot, double origin[3], double right[3],
                  double down[3], double fwd[3]) {
  const CameraFrame f = camera_frame_of(s.camera, robot);
  for (int i = 0; i < 3; ++i) {
    origin[i] = f.origin[i];
    right[i] = f.right[i];
    down[i] = f.down[i];
    fwd[i] = f.forward[i];
  }
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
  // The boards' geometry. Upright (tilt 0) the arithmetic is exactly the simulator's before
  // tilted boards existed: the extra terms are products with 0.
  placed_.clear();
  for (const BoardSpec& b : boards_) {
    PlacedBoard p{};
    const double cy = std::cos(b.facing_yaw_rad), sy = std::sin(b.facing_yaw_rad);
    const double ct = std::cos(b.tilt_rad), st = std::sin(b.tilt_rad);
    p.c[0] = b.centre_x_m;
    p.c[1] = b.centre_y_m;
    p.c[2] = b.centre_z_m;
    p.n[0] = cy * ct;
    p.n[1] = sy * ct;
    p.n[2] = st;
    p.u[0] = -sy;
    p.u[1] = cy;
    p.u[2] = 0.0;
    p.v[0] = -cy * st;
    p.v[1] = -sy * st;
    p.v[2] = ct;
    p.half_w = 0.5 * b.width_m;
    p.half_h = 0.5 * b.height_m;
    p.shape = b.shape;
    p.colour = b.colour;
    placed_.push_back(p);
    if (b.stand) {
      const double bottom = b.centre_z_m - 0.5 * b.height_m * std::fabs(ct);
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

void SceneRenderer::cull(const double o[3], const double r[3], const double dn[3],
                         const double f[3], std::vector<std::uint32_t>& begin,
                         std::vector<std::uint16_t>& objects) const {
  begin.assign(tiles_.size() + 1, 0U);
  objects.clear();
  const std::size_t object_count = kBoard0 + placed_.size() + cylinders_.size();
  std::vector<std::uint8_t> seen(object_count, 0);
  // Per sphere: direction from the camera, distance, and the sine and cosine of its angular
  // radius (inflated a little: never cull a hit).
  struct View {
    double w[3], sin_a, cos_a;
    bool contains;
  };
  std::vector<View> views(spheres_.size());
  for (std::size_t k = 0; k < spheres_.size(); ++k) {
    const Sphere& s = spheres_[k];
    View& v = views[k];
    const double w[3] = {s.c[0] - o[0], s.c[1] - o[1], s.c[2] - o[2]};
    const double dist = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    const double radius = s.r * (1.0 + 1e-6) + 1e-6;
    v.contains = dist <= radius;
    if (v.contains) continue;
    for (int i = 0; i < 3; ++i) v.w[i] = w[i] / dist;
    v.sin_a = radius / dist;
    v.cos_a = std::sqrt(1.0 - v.sin_a * v.sin_a);
  }
  for (std::size_t t = 0; t < tiles_.size(); ++t) {
    const Tile& tile = tiles_[t];
    begin[t] = static_cast<std::uint32_t>(objects.size());
    if (!tile.any_valid) continue;
    double a[3];
    for (int i = 0; i < 3; ++i)
      a[i] = tile.axis[0] * r[i] + tile.axis[1] * dn[i] + tile.axis[2] * f[i];
    std::fill(seen.begin(), seen.end(), std::uint8_t{0});
    for (std::size_t k = 0; k < spheres_.size(); ++k) {
      const std::uint16_t id = spheres_[k].object;
      if (seen[id]) continue;
      const View& v = views[k];
      bool hit = v.contains || tile.cos_half < -1.0;
      if (!hit) {
        // The sphere meets the cone when the angle between their axes is at most the sum of
        // their half-angles: cos(angle) >= cos(half + alpha).
        const double cos_beta = a[0] * v.w[0] + a[1] * v.w[1] + a[2] * v.w[2];
        hit = cos_beta >= tile.cos_half * v.cos_a - tile.sin_half * v.sin_a;
      }
      if (hit) seen[id] = 1;
    }
    for (std::size_t id = 0; id < object_count; ++id) {
      if (seen[id]) objects.push_back(static_cast<std::uint16_t>(id));
    }
  }
  begin[tiles_.size()] = static_cast<std::uint32_t>(objects.size());
}

// Returns the index of the board hit, or kNoBoard; @p colour is what the ray sees. Tests the room
// and then only @p objects (ids in increasing order: desk, boards, cylinders).
int SceneRenderer::trace(const double o[3], const double d[3], const std::uint16_t* objects,
                         std::size_t count, Rgb& colour) const {
  const Scenario& s = scenario_;
  const RoomSpec& room = s.room;
  double best = 1e30;
  int hit_board = kNoBoard;
  // Room: the box's exit face (the camera is inside). Ties keep the first: floor or ceiling,
  // then the walls at y, then those at x.
  enum Face { kNone, kFloor, kCeiling, kWallY, kWallX } face = kNone;
  if (d[2] < 0.0) {
    best = -o[2] / d[2];
    face = kFloor;
  } else if (std::fabs(d[2]) >= 1e-12) {
    const double t = (room.height_m - o[2]) / d[2];
    if (t > 1e-6 && t < best) {
      best = t;
      face = kCeiling;
    }
  }
  if (std::fabs(d[1]) >= 1e-12) {
    const double t = ((d[1] > 0.0 ? room.y_m[1] : room.y_m[0]) - o[1]) / d[1];
    if (t > 1e-6 && t < best) {
      best = t;
      face = kWallY;
    }
  }
  if (std::fabs(d[0]) >= 1e-12) {
    const double t = ((d[0] < 0.0 ? room.x_m[0] : room.x_m[1]) - o[0]) / d[0];
    if (t > 1e-6 && t < best) {
      best = t;
      face = kWallX;
    }
  }
  switch (face) {
    case kFloor: {
      colour = room.floor_colour;
      if (room.tile_m > 0.0) {
        const double fx = o[0] + best * d[0], fy = o[1] + best * d[1];
        const bool tile = (static_cast<long>(std::floor(fx / room.tile_m)) +
                           static_cast<long>(std::floor(fy / room.tile_m))) %
                              2 ==
                          0;
        colour = tile ? room.floor_colour : room.floor_tile_colour;
      }
      break;
    }
    case kCeiling:
      colour = room.ceiling_colour;
      break;
    case kWallY:
      colour = room.wall_colour;
      break;
    case kWallX:
      colour = room.side_wall_colour;
      break;
    case kNone:
      colour = Rgb{0, 0, 0};
      break;
  }
  const auto cylinder0 = static_cast<std::uint16_t>(kBoard0 + placed_.size());
  for (std::size_t k = 0; k < count; ++k) {
    const std::uint16_t id = objects[k];
    if (id == kDesk) {
      // Desk: a box from x0 to x1 between its front face and the wall at the room's far y.
      const DeskSpec& desk = s.desk;
      if (std::fabs(d[1]) > 1e-12) {
        const double t = (desk.front_y_m - o[1]) / d[1];
        const double x = o[0] + t * d[0], z = o[2] + t * d[2];
        if (t > 1e-6 && t < best && x >= desk.x_m[0] && x <= desk.x_m[1] && z >= 0.0 &&
            z <= desk.height_m) {
          best = t;
          colour = desk.colour;
          hit_board = kNoBoard;
        }
      }
      if (std::fabs(d[2]) > 1e-12) {
        const double t = (desk.height_m - o[2]) / d[2];
        const double x = o[0] + t * d[0], y = o[1] + t * d[1];
        if (t > 1e-6 && t < best && x >= desk.x_m[0] && x <= desk.x_m[1] && y >= desk.front_y_m &&
            y <= room.y_m[1]) {
          best = t;
          colour = desk.top_colour;
          hit_board = kNoBoard;
        }
      }
    } else if (id < cylinder0) {
      // A board: its face is lit by the angle of incidence; the back is plain grey.
      const std::size_t b = id - kBoard0;
      const PlacedBoard& p = placed_[b];
      const double denom = d[0] * p.n[0] + d[1] * p.n[1] + d[2] * p.n[2];
      if (std::fabs(denom) < 1e-12) continue;
      const double t =
          ((p.c[0] - o[0]) * p.n[0] + (p.c[1] - o[1]) * p.n[1] + (p.c[2] - o[2]) * p.n[2]) / denom;
      if (t <= 1e-6 || t >= best) continue;
      const double qx = o[0] + t * d[0] - p.c[0], qy = o[1] + t * d[1] - p.c[1];
      const double qz = o[2] + t * d[2] - p.c[2];
      const double along = qx * p.u[0] + qy * p.u[1] + qz * p.u[2];
      const double up = qx * p.v[0] + qy * p.v[1] + qz * p.v[2];
      if (p.shape == BoardShape::kEllipse) {
        const double a = along / p.half_w, e = up / p.half_h;
        if (a * a + e * e > 1.0) continue;
      } else if (std::fabs(along) > p.half_w || std::fabs(up) > p.half_h) {
        continue;
      }
      best = t;
      if (denom < 0.0) {
        const double norm = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        colour = scale(p.colour, 0.8 + 0.2 * (-denom / norm));
        hit_board = static_cast<int>(b);
      } else {
        colour = kBoardBack;
        hit_board = kNoBoard;
      }
    } else {
      // Occluders and stands: upright cylinders on the floor (side and top), shaded by the angle
      // of incidence. Seen from inside (the camera within one), the far side hides everything.
      const PlacedCylinder& c = cylinders_[id - cylinder0];
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
            const double cosine = std::fabs(nx * d[0] + ny * d[1]) /
                                  std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
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
  }
  return hit_board;
}

void SceneRenderer::render(const Pose2& robot_pose, algorithms::Pcg32& rng,
                           std::vector<std::uint8_t>& rgb) const {
  // The frame's noise key: each pixel's noise depends on it and the pixel's index only.
  const std::uint64_t hi = rng.next_u32();
  render(robot_pose, (hi << 32U) | rng.next_u32(), rgb);
}

void SceneRenderer::render(const Pose2& robot_pose, std::uint64_t key,
                           std::vector<std::uint8_t>& rgb) const {
  const CameraSpec& c = scenario_.camera;
  const std::size_t width = c.width_px;
  rgb.resize(rays_.size() * 3U);
  const bool noisy = !noise_.empty();
  const auto gain = static_cast<float>(gain_);
  double o[3], r[3], dn[3], f[3];
  camera_frame(scenario_, robot_pose, o, r, dn, f);
  std::vector<std::uint32_t> begin;
  std::vector<std::uint16_t> objects;
  cull(o, r, dn, f, begin, objects);
  for (std::size_t t = 0; t < tiles_.size(); ++t) {
    const Tile& tile = tiles_[t];
    const std::uint16_t* list = objects.data() + begin[t];
    const std::size_t count = begin[t + 1] - begin[t];
    for (std::uint32_t v = tile.v0; v < tile.v1; ++v) {
      for (std::uint32_t u = tile.u0; u < tile.u1; ++u) {
        const std::size_t i = v * width + u;
        std::uint8_t* out = rgb.data() + i * 3U;
        if (!valid_[i]) {
          out[0] = out[1] = out[2] = 0;
          continue;
        }
        const Ray& ray = rays_[i];
        const double d[3] = {ray.x * r[0] + ray.y * dn[0] + f[0],
                             ray.x * r[1] + ray.y * dn[1] + f[1],
                             ray.x * r[2] + ray.y * dn[2] + f[2]};
        Rgb colour{0, 0, 0};
        trace(o, d, list, count, colour);
        const float g = gain * vignette_[i];
        float value[3] = {colour.r * g, colour.g * g, colour.b * g};
        if (noisy) {
          const std::uint64_t h = mix64(key + (i + 1) * 0x9E3779B97F4A7C15ULL);
          value[0] += noise_[h & kNoiseMask];
          value[1] += noise_[(h >> kNoiseBits) & kNoiseMask];
          value[2] += noise_[(h >> (2 * kNoiseBits)) & kNoiseMask];
        }
        for (int ch = 0; ch < 3; ++ch) {  // min and max: no branches
          out[ch] = static_cast<std::uint8_t>(std::min(std::max(value[ch], 0.0F), 255.0F) + 0.5F);
        }
      }
    }
  }
}

std::vector<std::uint32_t> SceneRenderer::visible_board_pixels(const Pose2& robot_pose) const {
  std::vector<std::uint32_t> counts(scenario_.boards.size(), 0U);
  const std::size_t width = scenario_.camera.width_px;
  double o[3], r[3], dn[3], f[3];
  camera_frame(scenario_, robot_pose, o, r, dn, f);
  std::vector<std::uint32_t> begin;
  std::vector<std::uint16_t> objects;
  cull(o, r, dn, f, begin, objects);
  for (std::size_t t = 0; t < tiles_.size(); ++t) {
    const Tile& tile = tiles_[t];
    const std::size_t count = begin[t + 1] - begin[t];
    // Without a board among the tile's objects, no pixel of it can show one.
    bool any_board = false;
    for (std::size_t k = 0; k < count; ++k) {
      const std::uint16_t id = objects[begin[t] + k];
      any_board = any_board || (id >= kBoard0 && id < kBoard0 + placed_.size());
    }
    if (!any_board) continue;
    const std::uint16_t* list = objects.data() + begin[t];
    for (std::uint32_t v = tile.v0; v < tile.v1; ++v) {
      for (std::uint32_t u = tile.u0; u < tile.u1; ++u) {
        const std::size_t i = v * width + u;
        if (!valid_[i]) continue;
        const Ray& ray = rays_[i];
        const double d[3] = {ray.x * r[0] + ray.y * dn[0] + f[0],
                             ray.x * r[1] + ray.y * dn[1] + f[1],
                             ray.x * r[2] + ray.y * dn[2] + f[2]};
        Rgb colour{};
        const int b = trace(o, d, list, count, colour);
        if (b >= 0) ++counts[static_cast<std::size_t>(b)];
      }
    }
  }
  return counts;
}

}  // namespace harmoloc::sim_host
