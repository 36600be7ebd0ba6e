// project_outline runs an outline's points four at a time and clips only against the frame's
// sides some point lies beyond. Its result must be the one a point-by-point projection and a clip
// against all four sides give, to the last bit: the same IEEE operations in the same order, on
// outlines of every length (the lanes past the outline masked out), partly outside the frame,
// behind the camera, beyond the lens's monotonic region, with and without tangential terms.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstddef>
#include <random>

#include "harmoloc/algorithms/projected_bearing.hpp"

namespace ha = harmoloc::algorithms;

namespace {

struct Point {
  float u, v;
};

template <typename Keep>
std::size_t clip_reference(const Point* in, std::size_t n, Point* out, Keep keep) {
  std::size_t m = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Point& cur = in[i];
    const Point& prev = in[i == 0 ? n - 1 : i - 1];
    const float kc = keep(cur), kp = keep(prev);
    if ((kc >= 0.0F) != (kp >= 0.0F) && m < 12) {
      const float t = kp / (kp - kc);
      out[m++] = {prev.u + t * (cur.u - prev.u), prev.v + t * (cur.v - prev.v)};
    }
    if (kc >= 0.0F && m < 12) out[m++] = cur;
  }
  return m;
}

// One point at a time, every side clipped: the arithmetic project_outline must reproduce.
// @p cut: whether some point lay beyond a side of the frame.
ha::ProjectedOutline reference(const ha::BearingProjection& p, const ha::CameraAtPose& c,
                               std::size_t b, bool area, bool& cut) {
  cut = false;
  ha::ProjectedOutline out{};
  const std::size_t n = p.points[b];
  std::array<Point, 12> a{}, spare{};
  bool ahead = false, unprojected = false;
  for (std::size_t i = 0; i < n; ++i) {
    const float w0 = p.point_m(b, i, 0) - c.origin[0], w1 = p.point_m(b, i, 1) - c.origin[1],
                w2 = p.point_m(b, i, 2) - c.origin[2];
    const float z = w0 * c.forward[0] + w1 * c.forward[1] + w2 * c.forward[2];
    ahead = ahead || z > 0.0F;
    const float inv_z = 1.0F / z;
    const float x = (w0 * c.right[0] + w1 * c.right[1] + w2 * c.right[2]) * inv_z;
    const float y = (w0 * c.down[0] + w1 * c.down[1] + w2 * c.down[2]) * inv_z;
    const float r2 = x * x + y * y;
    const float radial = 1.0F + r2 * (p.k1 + r2 * (p.k2 + p.k3 * r2));
    float xd = x * radial, yd = y * radial;
    if (p.p1 != 0.0F || p.p2 != 0.0F) {
      xd += 2.0F * p.p1 * x * y + p.p2 * (r2 + 2.0F * x * x);
      yd += p.p1 * (r2 + 2.0F * y * y) + 2.0F * p.p2 * x * y;
    }
    if (!(z > 0.01F) || !(r2 < p.max_radius2)) unprojected = true;
    a[i] = {p.focal_px * xd + p.cx_px, p.focal_px * yd + p.cy_px};
  }
  if (!area && unprojected) return out;
  float a2 = 0.0F;
  if (!unprojected) {
    float cu = 0.0F;
    for (std::size_t i = 1; i + 1 < n; ++i) {
      const float ui = a[i].u - a[0].u, vi = a[i].v - a[0].v, uk = a[i + 1].u - a[0].u,
                  vk = a[i + 1].v - a[0].v;
      const float cross = ui * vk - uk * vi;
      a2 += cross;
      cu += (ui + uk) * cross;
    }
    if (a2 > 1e-3F || a2 < -1e-3F) {
      out.has_column = true;
      out.column_px = a[0].u + cu / (3.0F * a2);
    }
  }
  if (!area) return out;
  if (!ahead) {
    out.has_area = true;
    return out;
  }
  if (unprojected) return out;
  out.has_area = true;
  const float u0 = -0.5F, v0 = -0.5F;
  const float u1 = static_cast<float>(p.width_px) - 0.5F;
  const float v1 = static_cast<float>(p.height_px) - 0.5F;
  for (std::size_t i = 0; i < n; ++i)
    cut = cut || a[i].u < u0 || a[i].u > u1 || a[i].v < v0 || a[i].v > v1;
  std::size_t m = n;
  m = clip_reference(a.data(), m, spare.data(), [u0](const Point& q) { return q.u - u0; });
  m = clip_reference(spare.data(), m, a.data(), [u1](const Point& q) { return u1 - q.u; });
  m = clip_reference(a.data(), m, spare.data(), [v0](const Point& q) { return q.v - v0; });
  m = clip_reference(spare.data(), m, a.data(), [v1](const Point& q) { return v1 - q.v; });
  if (m < 3) return out;
  float clipped2 = 0.0F;
  for (std::size_t i = 1; i + 1 < m; ++i)
    clipped2 +=
        (a[i].u - a[0].u) * (a[i + 1].v - a[0].v) - (a[i + 1].u - a[0].u) * (a[i].v - a[0].v);
  out.area_px = 0.5F * (clipped2 < 0.0F ? -clipped2 : clipped2);
  return out;
}

TEST(ProjectedOutline, IsThePointByPointProjectionToTheLastBit) {
  std::mt19937 rng(20261207);
  std::uniform_real_distribution<float> unit(-1.0F, 1.0F);
  std::size_t compared = 0, whole = 0, cut = 0, behind = 0, unfollowed = 0;
  std::array<std::size_t, ha::BearingProjection::kMaxPoints + 1> lengths{};
  for (int trial = 0; trial < 4000; ++trial) {
    ha::BearingProjection p{};
    // A camera 30 cm up looking along the robot's x, tilted up to 0.2 rad.
    const float tilt = 0.2F * unit(rng);
    p.origin_m = {0.1F, 0.0F, 0.3F};
    p.forward = {std::cos(tilt), 0.0F, std::sin(tilt)};
    p.right = {0.0F, -1.0F, 0.0F};
    p.down = {std::sin(tilt), 0.0F, -std::cos(tilt)};
    p.focal_px = 250.0F + 100.0F * unit(rng);
    p.cx_px = 160.0F;
    p.cy_px = 120.0F;
    p.width_px = 320;
    p.height_px = 240;
    p.k1 = 0.1F * unit(rng);
    p.k2 = 0.05F * unit(rng);
    p.k3 = 0.01F * unit(rng);
    if (trial % 2 == 1) {
      p.p1 = 0.01F * unit(rng);
      p.p2 = 0.01F * unit(rng);
    }
    p.max_radius2 = 1.0F + 0.5F * unit(rng);
    for (std::size_t b = 0; b < ha::kMaxBoards; ++b) {
      const std::size_t n = 3 + (rng() % (ha::BearingProjection::kMaxPoints - 2));
      p.points[b] = static_cast<std::uint8_t>(n);
      // A disc 30 cm across facing the robot's x, within 2 m of it on every side.
      const float x = 2.0F * unit(rng), y = 2.0F * unit(rng), z = 0.5F + 0.3F * unit(rng);
      for (std::size_t i = 0; i < n; ++i) {
        const float angle = 6.2831853F * static_cast<float>(i) / static_cast<float>(n);
        p.point_m(b, i, 0) = x;
        p.point_m(b, i, 1) = y + 0.3F * std::cos(angle);
        p.point_m(b, i, 2) = z + 0.3F * std::sin(angle);
      }
    }
    const float yaw = 3.1415927F * unit(rng);
    const ha::CameraAtPose c =
        ha::camera_at_pose(p, 0.5F * unit(rng), 0.5F * unit(rng), std::cos(yaw), std::sin(yaw));
    for (std::size_t b = 0; b < ha::kMaxBoards; ++b) {
      for (const bool area : {false, true}) {
        const ha::ProjectedOutline got = ha::project_outline(p, c, b, area);
        bool cut_by_frame = false;
        const ha::ProjectedOutline want = reference(p, c, b, area, cut_by_frame);
        ASSERT_EQ(got.has_column, want.has_column) << "trial " << trial << " board " << b;
        ASSERT_EQ(got.has_area, want.has_area) << "trial " << trial << " board " << b;
        if (want.has_column) {
          ASSERT_EQ(got.column_px, want.column_px) << "trial " << trial;
        }
        if (want.has_area) {
          ASSERT_EQ(got.area_px, want.area_px) << "trial " << trial;
        }
        ++compared;
        if (!area) continue;
        ++lengths[p.points[b]];
        if (want.has_area && want.area_px == 0.0F) ++behind;
        if (!want.has_area) ++unfollowed;
        if (want.has_area && want.area_px > 0.0F) ++(cut_by_frame ? cut : whole);
      }
    }
  }
  EXPECT_EQ(compared, 4000U * ha::kMaxBoards * 2U);
  // Every case met often enough for the comparison to mean something.
  for (std::size_t n = 3; n <= ha::BearingProjection::kMaxPoints; ++n)
    EXPECT_GT(lengths[n], 1000U) << n << " points";
  EXPECT_GT(whole, 1000U);
  EXPECT_GT(cut, 1000U);
  EXPECT_GT(behind, 1000U);
  EXPECT_GT(unfollowed, 1000U);
}

}  // namespace
