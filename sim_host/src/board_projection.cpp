#include "harmoloc/sim_host/board_projection.hpp"

#include <array>
#include <cmath>

namespace harmoloc::sim_host {

namespace {

constexpr int kMaxOutline = 4 * kBoardOutlinePointsPerSide;
// Clipping a convex-ish polygon by four half-planes adds at most one vertex per plane.
constexpr int kMaxClipped = kMaxOutline + 8;

struct Point {
  double u, v;
};

struct Polygon {
  std::array<Point, kMaxClipped> p{};
  int n = 0;
};

// Keeps the part of @p in on the side of one of the frame's edges where @p keep(p) >= 0 (keep is
// linear in the point), Sutherland-Hodgman.
template <typename Keep>
Polygon clip(const Polygon& in, Keep keep) {
  Polygon out;
  for (int i = 0; i < in.n; ++i) {
    const Point& cur = in.p[static_cast<std::size_t>(i)];
    const Point& prev = in.p[static_cast<std::size_t>(i == 0 ? in.n - 1 : i - 1)];
    const double kc = keep(cur), kp = keep(prev);
    if ((kc >= 0.0) != (kp >= 0.0) && out.n < kMaxClipped) {
      const double t = kp / (kp - kc);
      out.p[static_cast<std::size_t>(out.n++)] = {prev.u + t * (cur.u - prev.u),
                                                  prev.v + t * (cur.v - prev.v)};
    }
    if (kc >= 0.0 && out.n < kMaxClipped) out.p[static_cast<std::size_t>(out.n++)] = cur;
  }
  return out;
}

}  // namespace

BoardAxes board_axes(const BoardSpec& b) {
  const double cy = std::cos(b.facing_yaw_rad), sy = std::sin(b.facing_yaw_rad);
  const double ct = std::cos(b.tilt_rad), st = std::sin(b.tilt_rad);
  return BoardAxes{{b.centre_x_m, b.centre_y_m, b.centre_z_m},
                   {cy * ct, sy * ct, st},
                   {-sy, cy, 0.0},
                   {-cy * st, -sy * st, ct}};
}

BoardImage project_board(const CameraSpec& camera, const LensModel& lens, const BoardSpec& board,
                         const algorithms::Pose2& robot_pose) {
  BoardImage image;
  const CameraFrame f = camera_frame_of(camera, robot_pose);
  const Intrinsics in = intrinsics_of(camera);
  const BoardAxes axes = board_axes(board);
  const double hw = 0.5 * board.width_m, hh = 0.5 * board.height_m;

  // Outline in the board's plane, counter-clockwise seen from its face.
  std::array<std::array<double, 2>, kMaxOutline> outline{};
  int count = 0;
  if (board.shape == BoardShape::kEllipse) {
    for (int i = 0; i < kMaxOutline; ++i) {
      const double a = 2.0 * algorithms::kPi * i / kMaxOutline;
      outline[static_cast<std::size_t>(count++)] = {hw * std::cos(a), hh * std::sin(a)};
    }
  } else {
    // Each side from its corner towards the next, kBoardOutlinePointsPerSide points.
    const double corner[5][2] = {{-hw, -hh}, {hw, -hh}, {hw, hh}, {-hw, hh}, {-hw, -hh}};
    for (int side = 0; side < 4; ++side) {
      const double* a = corner[side];
      const double* b = corner[side + 1];
      for (int i = 0; i < kBoardOutlinePointsPerSide; ++i) {
        const double t = static_cast<double>(i) / kBoardOutlinePointsPerSide;
        outline[static_cast<std::size_t>(count++)] = {a[0] + t * (b[0] - a[0]),
                                                      a[1] + t * (b[1] - a[1])};
      }
    }
  }

  // The frame's edges (pixel centres at whole numbers).
  const double u0 = -0.5, v0 = -0.5;
  const double u1 = static_cast<double>(camera.width_px) - 0.5;
  const double v1 = static_cast<double>(camera.height_px) - 0.5;
  // Far enough outside any frame that clipping keeps the direction and drops the point.
  const double far_px = 1e3 * static_cast<double>(camera.width_px + camera.height_px);
  Polygon poly;
  bool any_ahead = false, any_unprojected = false, any_outside = false;
  for (int i = 0; i < count; ++i) {
    const auto& o = outline[static_cast<std::size_t>(i)];
    double p[3];
    for (int k = 0; k < 3; ++k) {
      p[k] = axes.centre[k] + o[0] * axes.width_dir[k] + o[1] * axes.height_dir[k];
    }
    const double w[3] = {p[0] - f.origin[0], p[1] - f.origin[1], p[2] - f.origin[2]};
    any_ahead = any_ahead || w[0] * f.forward[0] + w[1] * f.forward[1] + w[2] * f.forward[2] > 0.0;
    double u = 0.0, v = 0.0;
    if (!project_point(camera, lens, f, p, u, v)) {
      // Behind the camera or beyond the lens's monotonic region: its image would be meaningless
      // (or fold back into the frame), so it goes far out the way it points.
      any_unprojected = true;
      const double x = w[0] * f.right[0] + w[1] * f.right[1] + w[2] * f.right[2];
      const double y = w[0] * f.down[0] + w[1] * f.down[1] + w[2] * f.down[2];
      const double r = std::hypot(x, y);
      u = in.cx_px + (r > 0.0 ? x / r : 1.0) * far_px;
      v = in.cy_px + (r > 0.0 ? y / r : 0.0) * far_px;
    }
    any_outside = any_outside || u < u0 || u > u1 || v < v0 || v > v1;
    poly.p[static_cast<std::size_t>(poly.n++)] = {u, v};
  }
  if (!any_ahead) return image;
  image.cut = any_unprojected;

  Polygon c = clip(poly, [&](const Point& q) { return q.u - u0; });
  c = clip(c, [&](const Point& q) { return u1 - q.u; });
  c = clip(c, [&](const Point& q) { return q.v - v0; });
  c = clip(c, [&](const Point& q) { return v1 - q.v; });
  if (c.n < 3) return image;

  // Shoelace area and centroid.
  double a2 = 0.0, cu = 0.0, cv = 0.0;
  for (int i = 0; i < c.n; ++i) {
    const Point& p = c.p[static_cast<std::size_t>(i)];
    const Point& q = c.p[static_cast<std::size_t>((i + 1) % c.n)];
    const double cross = p.u * q.v - q.u * p.v;
    a2 += cross;
    cu += (p.u + q.u) * cross;
    cv += (p.v + q.v) * cross;
  }
  if (std::fabs(a2) < 1e-12) return image;
  image.area_px = 0.5 * std::fabs(a2);
  image.centroid_u_px = cu / (3.0 * a2);
  image.centroid_v_px = cv / (3.0 * a2);
  image.cut = image.cut || any_outside;
  return image;
}

}  // namespace harmoloc::sim_host
