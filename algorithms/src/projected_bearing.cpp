#include "harmoloc/algorithms/projected_bearing.hpp"

#include <limits>

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

namespace {

struct ImagePoint {
  float u, v;
};

// Keeps the part of @p in (@p n points) where @p keep(point) >= 0 (linear in the point), into
// @p out (room for kCapacity points); returns its points (Sutherland-Hodgman).
template <std::size_t kCapacity, typename Keep>
std::size_t clip(const ImagePoint* in, std::size_t n, ImagePoint* out, Keep keep) {
  std::size_t m = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const ImagePoint& cur = in[i];
    const ImagePoint& prev = in[i == 0 ? n - 1 : i - 1];
    const float kc = keep(cur), kp = keep(prev);
    // An outline the lens bends out of convex may cross an edge more than twice: the points
    // beyond the capacity are dropped (the area then errs, the work stays bounded).
    if ((kc >= 0.0F) != (kp >= 0.0F) && m < kCapacity) {
      const float t = kp / (kp - kc);
      out[m++] = {prev.u + t * (cur.u - prev.u), prev.v + t * (cur.v - prev.v)};
    }
    if (kc >= 0.0F && m < kCapacity) out[m++] = cur;
  }
  return m;
}

}  // namespace

namespace {

// project_outline, with the area's work compiled out of the bearings' loop (kArea false): the
// filter takes a bearing alone at most particles, and that loop is tuned for its instruction
// count (docs/performance.md).
template <bool kArea>
ProjectedOutline project(const BearingProjection& p, const CameraAtPose& c, std::size_t b) {
  ProjectedOutline out{};
  if (b >= kMaxBoards) return out;
  const std::size_t n = p.points[b];
  if (n < 3 || n > BearingProjection::kMaxPoints) return out;
  constexpr std::size_t kLanes = BearingProjection::kMaxPoints;
  // Four clips add at most one point each.
  constexpr std::size_t kMaxClipped = kLanes + 4;
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
  const float u0 = -0.5F, v0 = -0.5F;
  const float u1 = static_cast<float>(p.width_px) - 0.5F;
  const float v1 = static_cast<float>(p.height_px) - 0.5F;
  std::array<float, kLanes> u{}, v{};
  bool ahead = false, unprojected = false;
  float u_lo = u0, u_hi = u0, v_lo = v0, v_hi = v0;
  if constexpr (kArea) {
    u_lo = v_lo = std::numeric_limits<float>::infinity();
    u_hi = v_hi = -std::numeric_limits<float>::infinity();
  }
  for (std::size_t i = 0; i < n; ++i) {
    const float w0 = px[i] - o0, w1 = py[i] - o1, w2 = pz[i] - o2;
    const float z = w0 * f0 + w1 * f1 + w2 * f2;
    // Bitwise, not ||: no branch per point.
    if constexpr (kArea) ahead |= z > 0.0F;
    // Behind the camera (or NaN), or beyond the lens's monotonic region: no column; the area
    // still needs to know whether any point lies ahead.
    if (!(z > 0.01F)) {
      if constexpr (!kArea) return out;
      unprojected = true;
      continue;
    }
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
    if (!(r2 < max_r2)) {
      if constexpr (!kArea) return out;
      unprojected = true;
      continue;
    }
    u[i] = focal * xd + cx;
    v[i] = focal * yd + cy;
    if constexpr (kArea) {
      // The points' bounds, one min or max each: cheaper than four tests a point.
      u_lo = u[i] < u_lo ? u[i] : u_lo;
      u_hi = u[i] > u_hi ? u[i] : u_hi;
      v_lo = v[i] < v_lo ? v[i] : v_lo;
      v_hi = v[i] > v_hi ? v[i] : v_hi;
    }
  }
  // The whole polygon's area and centroid (shoelace), about its first point to keep the
  // products small.
  float a2 = 0.0F;
  if (!unprojected) {
    float cu = 0.0F;
    for (std::size_t i = 1; i + 1 < n; ++i) {
      const float ui = u[i] - u[0], vi = v[i] - v[0], uk = u[i + 1] - u[0], vk = v[i + 1] - v[0];
      const float cross = ui * vk - uk * vi;
      a2 += cross;
      cu += (ui + uk) * cross;
    }
    if (a2 > 1e-3F || a2 < -1e-3F) {
      out.has_column = true;
      out.column_px = u[0] + cu / (3.0F * a2);
    }
  }
  if constexpr (kArea) {
    if (!ahead) {
      out.has_area = true;  // wholly behind the camera: nothing in the frame
      return out;
    }
    if (unprojected) return out;
    out.has_area = true;
    if (u_lo >= u0 && u_hi <= u1 && v_lo >= v0 && v_hi <= v1) {
      out.area_px = 0.5F * (a2 < 0.0F ? -a2 : a2);
      return out;
    }
    std::array<ImagePoint, kMaxClipped> a{}, bpoly{};
    for (std::size_t i = 0; i < n; ++i) a[i] = {u[i], v[i]};
    std::size_t m = n;
    m = clip<kMaxClipped>(a.data(), m, bpoly.data(),
                          [u0](const ImagePoint& q) { return q.u - u0; });
    m = clip<kMaxClipped>(bpoly.data(), m, a.data(),
                          [u1](const ImagePoint& q) { return u1 - q.u; });
    m = clip<kMaxClipped>(a.data(), m, bpoly.data(),
                          [v0](const ImagePoint& q) { return q.v - v0; });
    m = clip<kMaxClipped>(bpoly.data(), m, a.data(),
                          [v1](const ImagePoint& q) { return v1 - q.v; });
    if (m < 3) return out;
    float clipped2 = 0.0F;
    for (std::size_t i = 1; i + 1 < m; ++i) {
      clipped2 +=
          (a[i].u - a[0].u) * (a[i + 1].v - a[0].v) - (a[i + 1].u - a[0].u) * (a[i].v - a[0].v);
    }
    out.area_px = 0.5F * (clipped2 < 0.0F ? -clipped2 : clipped2);
  }
  return out;
}

}  // namespace

ProjectedOutline project_outline(const BearingProjection& p, const CameraAtPose& c, std::size_t b,
                                 bool area) {
  return area ? project<true>(p, c, b) : project<false>(p, c, b);
}

bool projected_area_px(const BearingProjection& p, const CameraAtPose& c, std::size_t b,
                       float& area_px) {
  const ProjectedOutline o = project_outline(p, c, b, true);
  area_px = o.area_px;
  return o.has_area;
}

bool projected_centroid_column(const BearingProjection& p, const CameraAtPose& c, std::size_t b,
                               float& column_px) {
  const ProjectedOutline o = project_outline(p, c, b, false);
  if (o.has_column) column_px = o.column_px;
  return o.has_column;
}

}  // namespace harmoloc::algorithms
