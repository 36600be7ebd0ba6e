#include "bench_fixtures.hpp"

#include <cmath>

#include <algorithm>

#include "harmoloc/algorithms/random.hpp"
#include "harmoloc/sim_host/route.hpp"
#include "harmoloc/sim_host/scenario.hpp"
#include "harmoloc/sim_host/scene_renderer.hpp"

namespace harmoloc::bench {

namespace {

std::uint8_t clamp_u8(double v) {
  return static_cast<std::uint8_t>(std::clamp(v + 0.5, 0.0, 255.0));
}

}  // namespace

Frames simulated_frames(std::uint32_t width_px, std::uint32_t height_px, std::size_t count) {
  sim_host::Scenario scenario = sim_host::load_scenario("desk-shuttle");
  scenario.camera.width_px = width_px;
  scenario.camera.height_px = height_px;
  algorithms::Pcg32 rng(7, 1);
  const auto motion = sim_host::simulate_motion(scenario, 0.01, rng, nullptr);
  const sim_host::SceneRenderer renderer(scenario);
  Frames frames;
  frames.width_px = width_px;
  frames.height_px = height_px;
  for (std::size_t i = 0; i < count; ++i) {
    const auto& pose = motion[(i * 2 + 1) * motion.size() / (2 * count)].pose;
    std::vector<std::uint8_t> rgb;
    renderer.render(pose, rng, rgb);
    // BT.601 limited range, the inverse of the decoder the firmware uses.
    std::vector<std::uint8_t> yuyv(static_cast<std::size_t>(width_px) * height_px * 2U);
    for (std::size_t p = 0; p + 1 < static_cast<std::size_t>(width_px) * height_px; p += 2) {
      double u = 0, v = 0;
      for (int k = 0; k < 2; ++k) {
        const double r = rgb[(p + k) * 3], g = rgb[(p + k) * 3 + 1], b = rgb[(p + k) * 3 + 2];
        yuyv[(p + k) * 2] = clamp_u8(16 + 0.257 * r + 0.504 * g + 0.098 * b);
        u += 128 - 0.148 * r - 0.291 * g + 0.439 * b;
        v += 128 + 0.439 * r - 0.368 * g - 0.071 * b;
      }
      yuyv[p * 2 + 1] = clamp_u8(u / 2);
      yuyv[p * 2 + 3] = clamp_u8(v / 2);
    }
    frames.rgb.push_back(std::move(rgb));
    frames.yuyv.push_back(std::move(yuyv));
  }
  return frames;
}

algorithms::ThresholdSet board_thresholds(std::size_t boards) {
  algorithms::ThresholdSet set = firmware::default_config().thresholds;
  set.boards[6] = algorithms::ColourThreshold{0.0F, 360.0F, 0, 180, 255};  // light greys
  set.boards[7] = algorithms::ColourThreshold{0.0F, 360.0F, 0, 0, 50};     // dark pixels
  set.count = std::min(boards, algorithms::kMaxBoards);
  return set;
}

void synthetic_map(std::size_t samples, std::uint32_t width_px, std::uint32_t height_px,
                   algorithms::MapFile& map, std::size_t boards) {
  algorithms::reset_in_place(map);
  map.image_width_px = width_px;
  map.image_height_px = height_px;
  map.thresholds = board_thresholds(boards);
  auto& m = map.model;
  m.sample_count = static_cast<std::uint32_t>(samples);
  m.feature_count = static_cast<std::uint32_t>(map.thresholds.count);
  for (std::size_t k = 0; k < m.feature_count; ++k) m.board_index[k] = static_cast<std::uint8_t>(k);
  m.area_scale = 100.0F / static_cast<float>(width_px * height_px);
  m.sigma_x = 0.1F;
  m.sigma_y = 5.0F;
  m.max_nearest_distance = 100.0F;
  algorithms::Pcg32 rng(11, 2);
  for (std::size_t i = 0; i < samples; ++i) {
    for (std::size_t k = 0; k < m.feature_count; ++k)
      m.sample(i)[k] = static_cast<float>(rng.uniform(0.0, 3.0));
    m.target_x_m[i] = static_cast<float>(rng.uniform(1.9, 2.3));
    m.target_y_m[i] = static_cast<float>(rng.uniform(0.3, 1.7));
  }
  // A forward map over the same region (2 cm cells, as the trainer makes them), smooth fields.
  auto& f = map.forward;
  algorithms::lay_out_grid(f, 46, 88);
  f.origin_x_m = 1.65F;
  f.origin_y_m = 0.1F;
  f.cell_m = 0.02F;
  f.board_count = static_cast<std::uint32_t>(map.thresholds.count);
  f.has_heading = true;
  for (std::size_t b = 0; b < f.board_count; ++b) f.sigma[b] = 0.05F;
  for (std::uint32_t r = 0; r < f.rows; ++r) {
    for (std::uint32_t c = 0; c < f.columns; ++c) {
      const float x = f.origin_x_m + f.cell_m * static_cast<float>(c);
      const float y = f.origin_y_m + f.cell_m * static_cast<float>(r);
      float* e = f.cell(c, r);
      for (std::size_t b = 0; b < f.board_count; ++b)
        e[b] = 1.5F + std::sin(1.3F * x * static_cast<float>(b + 1)) * std::cos(0.7F * y);
      f.route_distance_m[f.index(c, r)] = std::fabs(x - 2.1F);
      f.heading_rad[f.index(c, r)] = 1.57F;
      // Every board's bearing, as a version 6 map holds them: boards in a row 1 m beyond the
      // region, ahead of a robot facing +y.
      for (std::size_t b = 0; b < f.board_count; ++b)
        f.bearing_rad[f.index(c, r) * algorithms::kMaxBoards + b] =
            std::atan2(2.7F - y, 1.2F + 0.3F * static_cast<float>(b) - x);
    }
  }
  f.has_bearings = true;
  f.bearing_a1_rad = 1.05F;  // a pinhole of about 60 degrees
  f.bearing_a3_rad = -0.05F;
  // Seen from the camera's place 10 cm ahead of the axle (map version 9, what the trainer writes
  // when the camera's offset is given): each particle reads them at its own camera place.
  f.bearing_camera_forward_m = 0.1F;
  for (std::size_t b = 0; b < f.board_count; ++b) f.bearing_sigma_rad[b] = 0.007F;
}

void project_every_board(algorithms::ForwardMap& f, bool areas) {
  algorithms::BearingProjection& p = f.projection;
  p.width_px = 320;
  p.height_px = 240;
  // Level, 10 cm ahead of the axle and 30 cm up, about 60 degrees across, a barrel lens.
  p.origin_m = {0.1F, 0.0F, 0.3F};
  p.right = {0.0F, -1.0F, 0.0F};
  p.down = {0.0F, 0.0F, -1.0F};
  p.forward = {1.0F, 0.0F, 0.0F};
  p.focal_px = 277.0F;
  p.cx_px = 159.5F;
  p.cy_px = 119.5F;
  p.k1 = -0.15F;
  p.k2 = 0.02F;
  p.max_radius2 = 2.0F;
  // The boards of synthetic_map's bearings: 20 cm squares at the camera's height, facing -y.
  for (std::size_t b = 0; b < f.board_count; ++b) {
    const float cx = 1.2F + 0.3F * static_cast<float>(b);
    const float corners[5][3] = {{cx + 0.1F, 2.7F, 0.2F},
                                 {cx - 0.1F, 2.7F, 0.2F},
                                 {cx - 0.1F, 2.7F, 0.4F},
                                 {cx + 0.1F, 2.7F, 0.4F},
                                 {cx + 0.1F, 2.7F, 0.2F}};
    std::size_t n = 0;
    for (std::size_t i = 0; i < 4; ++i) {
      for (std::size_t d = 0; d < 3; ++d) p.point_m(b, n, d) = corners[i][d];
      ++n;
      if (!areas) continue;
      // The middle of the side towards the next corner.
      for (std::size_t d = 0; d < 3; ++d)
        p.point_m(b, n, d) = 0.5F * (corners[i][d] + corners[i + 1][d]);
      ++n;
    }
    p.points[b] = static_cast<std::uint8_t>(n);
    if (areas) {
      // About 1.4 features for the some 1400 px a board shows from the benchmarks' pose.
      p.area_per_px[b] = 1.0e-3F;
      p.area_sigma[b] = 0.02F;
    }
  }
}

void bench_observation(const algorithms::ForwardMap& map, algorithms::BoardFeatures& observed) {
  observed.count = map.board_count;
  observed.angle_mask = 0;
  for (std::size_t b = 0; b < observed.count; ++b) {
    observed.value[b] = 1.4F;
    // What a robot at (2.1, 1.0) facing +y sees: every board whole (the bearing term's cost).
    observed.angle_rad[b] = 1.5708F - std::atan2(1.7F, 1.2F + 0.3F * static_cast<float>(b) - 2.1F);
    observed.angle_mask |= 1U << b;
  }
}

hal::CameraStatus MemoryCamera::acquire(hal::FrameView& frame, std::uint64_t) {
  const std::size_t i = static_cast<std::size_t>(next_ % frames_.rgb.size());
  const bool yuyv = format_ == hal::PixelFormat::kYuyv;
  frame.data = yuyv ? frames_.yuyv[i].data() : frames_.rgb[i].data();
  frame.width_px = frames_.width_px;
  frame.height_px = frames_.height_px;
  frame.stride_bytes = frames_.width_px * (yuyv ? 2U : 3U);
  frame.format = format_;
  frame.timestamp_ns = 1000000000ULL + next_ * 33333333ULL;
  frame.sequence = static_cast<std::uint32_t>(next_++);
  return hal::CameraStatus::kFrame;
}

hal::EncoderStatus MemoryEncoders::read(std::uint64_t data_time_ns, hal::EncoderCounts& counts) {
  left_ += 40;
  right_ += 42;
  counts = hal::EncoderCounts{left_, right_, 32, data_time_ns};
  return hal::EncoderStatus::kFresh;
}

}  // namespace harmoloc::bench
