#include "harmoloc/algorithms/projected_bearing.hpp"

#include <cstdint>
#include <cstring>
#include <limits>
#include <utility>

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

// Four floats, and four lanes' masks (0 or -1) from comparing them.
using F4 = float __attribute__((vector_size(16)));
using I4 = std::int32_t __attribute__((vector_size(16)));
constexpr I4 kLaneIndex = {0, 1, 2, 3};

F4 load4(const float* p) {
  F4 out;
  std::memcpy(&out, p, sizeof out);
  return out;
}

void store4(float* p, F4 in) {
  std::memcpy(p, &in, sizeof in);
}

bool any(I4 mask) {
  return (mask[0] | mask[1] | mask[2] | mask[3]) != 0;
}

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
  static_assert(kLanes % 4 == 0, "the points run four at a time");
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
  // Four points at a time in GCC's portable vectors (SSE and NEON; plain floats where a target has
  // none): each lane is the same IEEE arithmetic as the point alone. A point's verdicts are or-ed
  // into lane masks; a lane past the outline (i >= n) computes from the outline's zero padding and
  // is masked out of them.
  // Two lanes beyond the points: the shoelace below reads a point's next two.
  std::array<float, kLanes + 2> u{}, v{};
  I4 ahead4{}, unprojected4{};
  // The points beyond each of the frame's sides: left, right, top, bottom.
  std::array<I4, 4> beyond4{};
  for (std::size_t g = 0; g < n; g += 4) {
    const I4 used = (kLaneIndex + static_cast<std::int32_t>(g)) < static_cast<std::int32_t>(n);
    const F4 w0 = load4(px + g) - o0, w1 = load4(py + g) - o1, w2 = load4(pz + g) - o2;
    const F4 z = w0 * f0 + w1 * f1 + w2 * f2;
    const F4 inv_z = 1.0F / z;
    const F4 x = (w0 * r0 + w1 * r1 + w2 * r_2) * inv_z;
    const F4 y = (w0 * d0 + w1 * d1 + w2 * d2) * inv_z;
    const F4 r2 = x * x + y * y;
    const F4 radial = 1.0F + r2 * (k1 + r2 * (k2 + k3 * r2));
    F4 xd = x * radial, yd = y * radial;
    if (tangential) {
      xd += 2.0F * t1 * x * y + t2 * (r2 + 2.0F * x * x);
      yd += t1 * (r2 + 2.0F * y * y) + 2.0F * t2 * x * y;
    }
    const F4 ug = focal * xd + cx, vg = focal * yd + cy;
    store4(u.data() + g, ug);
    store4(v.data() + g, vg);
    ahead4 |= used & (z > 0.0F);
    // Behind the camera (or NaN), or beyond the lens's monotonic region: no column, and no area
    // unless every point lies behind.
    unprojected4 |= used & ~((z > 0.01F) & (r2 < max_r2));
    if constexpr (kArea) {
      beyond4[0] |= used & (ug < u0);
      beyond4[1] |= used & (ug > u1);
      beyond4[2] |= used & (vg < v0);
      beyond4[3] |= used & (vg > v1);
    }
  }
  const bool ahead = any(ahead4), unprojected = any(unprojected4);
  if constexpr (!kArea) {
    if (unprojected) return out;
  }
  // The whole polygon's area and centroid (shoelace), about its first point to keep the
  // products small: triangle (0, i, i + 1)'s cross product four at a time, the sums in order.
  float a2 = 0.0F;
  if (!unprojected) {
    std::array<float, kLanes> cross{}, moment{};
    const float ua = u[0], va = v[0];
    for (std::size_t g = 0; g + 2 < n; g += 4) {
      const F4 ui = load4(u.data() + g + 1) - ua, vi = load4(v.data() + g + 1) - va;
      const F4 uk = load4(u.data() + g + 2) - ua, vk = load4(v.data() + g + 2) - va;
      const F4 c4 = ui * vk - uk * vi;
      store4(cross.data() + g, c4);
      store4(moment.data() + g, (ui + uk) * c4);
    }
    float cu = 0.0F;
    for (std::size_t i = 1; i + 1 < n; ++i) {
      a2 += cross[i - 1];
      cu += moment[i - 1];
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
    if (!any(beyond4[0] | beyond4[1] | beyond4[2] | beyond4[3])) {
      out.area_px = 0.5F * (a2 < 0.0F ? -a2 : a2);
      return out;
    }
    std::array<ImagePoint, kMaxClipped> a{}, bpoly{};
    for (std::size_t i = 0; i < n; ++i) a[i] = {u[i], v[i]};
    // Only the sides some point lies beyond: a side every point is within keeps the polygon as
    // it is (its clips' points lie between two points within it), so the area is the same.
    ImagePoint* in = a.data();
    ImagePoint* spare = bpoly.data();
    std::size_t m = n;
    const auto clip_side = [&](std::size_t side, auto keep) {
      if (!any(beyond4[side])) return;
      m = clip<kMaxClipped>(in, m, spare, keep);
      std::swap(in, spare);
    };
    clip_side(0, [u0](const ImagePoint& q) { return q.u - u0; });
    clip_side(1, [u1](const ImagePoint& q) { return u1 - q.u; });
    clip_side(2, [v0](const ImagePoint& q) { return q.v - v0; });
    clip_side(3, [v1](const ImagePoint& q) { return v1 - q.v; });
    if (m < 3) return out;
    float clipped2 = 0.0F;
    for (std::size_t i = 1; i + 1 < m; ++i) {
      clipped2 += (in[i].u - in[0].u) * (in[i + 1].v - in[0].v) -
                  (in[i + 1].u - in[0].u) * (in[i].v - in[0].v);
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
