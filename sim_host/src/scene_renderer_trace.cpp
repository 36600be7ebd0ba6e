#include "harmoloc/sim_host/scene_renderer.hpp"

#include <algorithm>
#include <cmath>

#include "scene_renderer_parts.hpp"

namespace harmoloc::sim_host {

using namespace scene_renderer_detail;

namespace {

Rgb scale(const Rgb& c, double g) {
  auto s = [g](std::uint8_t v) {
    return static_cast<std::uint8_t>(std::clamp(std::lround(v * g), 0L, 255L));
  };
  return Rgb{s(c.r), s(c.g), s(c.b)};
}

}  // namespace

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

}  // namespace harmoloc::sim_host
