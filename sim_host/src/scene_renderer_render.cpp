#include "harmoloc/sim_host/scene_renderer.hpp"

#include <algorithm>
#include <cmath>

#include "scene_renderer_parts.hpp"

namespace harmoloc::sim_host {

using algorithms::Pose2;
using namespace scene_renderer_detail;

namespace {

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
