#include "harmoloc/algorithms/projected_bearing.hpp"

namespace harmoloc::algorithms {

CameraAtPose camera_at_pose(const BearingProjection& p, float x_m, float y_m, float cos_yaw,
                            float sin_yaw) {
  CameraAtPose c{};
  // The robot's frame turned by the heading: (x, y) -> (x cos - y sin, x sin + y cos).
  const auto turn = [cos_yaw, sin_yaw](const std::array<float, 3>& v, float* out) {
    out[0] = v[0] * cos_yaw - v[1] * sin_yaw;
    out[1] = v[0] * sin_yaw + v[1] * cos_yaw;
    out[2] = v[2];
  };
  turn(p.origin_m, c.origin);
  c.origin[0] += x_m;
  c.origin[1] += y_m;
  turn(p.right, c.right);
  turn(p.down, c.down);
  turn(p.forward, c.forward);
  return c;
}

bool projected_centroid_column(const BearingProjection& p, const CameraAtPose& c, std::size_t b,
                               float& column_px) {
  if (b >= kMaxBoards) return false;
  const std::size_t n = p.points[b];
  if (n < 3 || n > BearingProjection::kMaxPoints) return false;
  constexpr std::size_t kLanes = BearingProjection::kMaxPoints;
  const float* px = p.outline_m.data() + b * 3 * kLanes;
  const float* py = px + kLanes;
  const float* pz = py + kLanes;
  // The parameters in registers: the loop below stores to u and v, and without these copies the
  // compiler reloads each one for every point.
  const float o0 = c.origin[0], o1 = c.origin[1], o2 = c.origin[2];
  const float f0 = c.forward[0], f1 = c.forward[1], f2 = c.forward[2];
  const float r0 = c.right[0], r1 = c.right[1], r_2 = c.right[2];
  const float d0 = c.down[0], d1 = c.down[1], d2 = c.down[2];
  const float k1 = p.k1, k2 = p.k2, k3 = p.k3, t1 = p.p1, t2 = p.p2;
  const float focal = p.focal_px, cx = p.cx_px, cy = p.cy_px, max_r2 = p.max_radius2;
  const bool tangential = t1 != 0.0F || t2 != 0.0F;
  std::array<float, kLanes> u{}, v{};
  for (std::size_t i = 0; i < n; ++i) {
    const float w0 = px[i] - o0, w1 = py[i] - o1, w2 = pz[i] - o2;
    const float z = w0 * f0 + w1 * f1 + w2 * f2;
    // Behind the camera (or NaN): no column.
    if (!(z > 0.01F)) return false;
    const float inv_z = 1.0F / z;
    const float x = (w0 * r0 + w1 * r1 + w2 * r_2) * inv_z;
    const float y = (w0 * d0 + w1 * d1 + w2 * d2) * inv_z;
    const float r2 = x * x + y * y;
    const float radial = 1.0F + r2 * (k1 + r2 * (k2 + k3 * r2));
    float xd = x * radial, yd = y * radial;
    if (tangential) {
      xd += 2.0F * t1 * x * y + t2 * (r2 + 2.0F * x * x);
      yd += t1 * (r2 + 2.0F * y * y) + 2.0F * t2 * x * y;
    }
    // Beyond the lens's monotonic region the image folds back: no column.
    if (!(r2 < max_r2)) return false;
    u[i] = focal * xd + cx;
    v[i] = focal * yd + cy;
  }
  // The polygon's centroid (shoelace), about its first point to keep the products small.
  float a2 = 0.0F, cu = 0.0F;
  for (std::size_t i = 1; i + 1 < n; ++i) {
    const float ui = u[i] - u[0], vi = v[i] - v[0], uk = u[i + 1] - u[0], vk = v[i + 1] - v[0];
    const float cross = ui * vk - uk * vi;
    a2 += cross;
    cu += (ui + uk) * cross;
  }
  if (!(a2 > 1e-3F || a2 < -1e-3F)) return false;
  column_px = u[0] + cu / (3.0F * a2);
  return true;
}

}  // namespace harmoloc::algorithms
