// A localization cycle on fakes for tests of the whole cycle: a camera that shows one red board
// filling the frame or nothing, no encoders, a queue for the link, a clock that advances a little
// at every reading, and a three-sample map whose sample 0 is the full red frame.
#pragma once

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "harmoloc/algorithms/map_codec.hpp"
#include "harmoloc/firmware/config.hpp"
#include "harmoloc/firmware/localization_cycle.hpp"
#include "mavlink_test_frames.hpp"

namespace harmoloc::test::one_board {

namespace ha = harmoloc::algorithms;
namespace hf = harmoloc::firmware;
namespace hh = harmoloc::hal;
namespace tf = harmoloc::test::mav;

constexpr std::uint32_t kWidth = 16, kHeight = 8;
constexpr std::array<float, 7> kNoParams{};
// The map's training positions (map frame); sample 0 is what a frame full of red looks like.
constexpr double kTargets[3][2] = {{1.0, 0.5}, {3.0, 0.5}, {2.0, 2.5}};

// Shows @p rgb (kWidth x kHeight RGB24; by default all red) while frames is true.
class FakeCamera final : public hh::Camera {
 public:
  FakeCamera() : rgb_(kWidth * kHeight * 3) {
    for (std::size_t i = 0; i < rgb_.size(); i += 3) rgb_[i] = 255;
  }
  explicit FakeCamera(std::vector<std::uint8_t> rgb) : rgb_(std::move(rgb)) {}
  hh::CameraStatus acquire(hh::FrameView& f, std::uint64_t) override {
    t_ += 33'333'333;
    if (!frames) return hh::CameraStatus::kNoFrame;
    f.data = rgb_.data();
    f.width_px = kWidth;
    f.height_px = kHeight;
    f.stride_bytes = kWidth * 3;
    f.format = hh::PixelFormat::kRgb24;
    f.timestamp_ns = t_;
    return hh::CameraStatus::kFrame;
  }
  void release() override {}
  hh::CameraCounters counters() const override { return {}; }
  bool frames = false;

 private:
  std::vector<std::uint8_t> rgb_;
  std::uint64_t t_ = 0;
};

class NoEncoders final : public hh::WheelEncoders {
 public:
  hh::EncoderStatus read(std::uint64_t, hh::EncoderCounts&) override {
    return hh::EncoderStatus::kNoData;
  }
  hh::EncoderCounters counters() const override { return {}; }
};

class StepClock final : public hh::Clock {
 public:
  std::uint64_t now_ns() const override { return now_ += step; }
  void sleep_until(std::uint64_t) override {}
  std::uint64_t step = 1000;  ///< every reading of the clock advances it this much

 private:
  mutable std::uint64_t now_ = 0;
};

// A map for the rig's frames without samples: the default boards, features in percent of the
// frame, kernel widths 1.
inline std::unique_ptr<ha::MapFile> empty_rig_map() {
  auto m = std::make_unique<ha::MapFile>();
  m->image_width_px = kWidth;
  m->image_height_px = kHeight;
  m->thresholds = hf::default_config().thresholds;
  m->model.area_scale = 100.0F / (kWidth * kHeight);
  m->model.sigma_x = m->model.sigma_y = 1.0F;
  return m;
}

inline const ha::MapFile& test_map() {
  static const std::unique_ptr<ha::MapFile> map = [] {
    auto m = empty_rig_map();
    ha::HarmonicModel& h = m->model;
    h.sample_count = 3;
    h.feature_count = 1;
    h.board_index[0] = 0;  // red
    h.max_nearest_distance = 5.0F;
    const float features[3] = {100.0F, 50.0F, 25.0F};
    for (std::size_t i = 0; i < 3; ++i) {
      h.sample(i)[0] = features[i];
      h.target_x_m[i] = static_cast<float>(kTargets[i][0]);
      h.target_y_m[i] = static_cast<float>(kTargets[i][1]);
    }
    return m;
  }();
  return *map;
}

// The rig's map with a calibration (the fix's error 3 cm; each sample's fixes 1 cm off) and a
// forward map over 4 m x 4 m (2 cm cells) that expects the one board at @p expected everywhere,
// in a noise of 5.
inline std::unique_ptr<ha::MapFile> calibrated_flat_map(float expected) {
  auto map = std::make_unique<ha::MapFile>(test_map());
  map->calibration.present = true;
  map->calibration.fix_rmse_x_m = map->calibration.fix_rmse_y_m = 0.03F;
  map->calibration.pass_spread_m = 0.02F;
  ha::ForwardMap& f = map->forward;
  EXPECT_TRUE(ha::lay_out_grid(f, 200, 200, nullptr));
  f.origin_x_m = -0.5F;
  f.origin_y_m = -1.5F;
  f.cell_m = 0.02F;
  f.board_count = 1;
  f.sigma[0] = 5.0F;
  for (std::size_t c = 0; c < f.stored_cells(); ++c) f.expected[c * ha::kMaxBoards] = expected;
  for (std::size_t i = 0; i < map->model.sample_count; ++i) map->model.fix_error_m[i] = 0.01F;
  return map;
}

struct Rig {
  explicit Rig(const tf::Key* signing_key = nullptr) {
    config.filter.particles = 512;
    if (signing_key != nullptr) {
      config.link.has_signing_key = true;
      config.link.signing_key = *signing_key;
      key = *signing_key;
    }
  }
  void start() {
    cycle =
        std::make_unique<hf::LocalizationCycle>(config, test_map(), camera, encoders, link, clock);
  }
  // Runs one cycle and returns the frames it wrote.
  std::vector<tf::Decoded> run() {
    const std::size_t before = link.written.size();
    cycle->run_once();
    return tf::decode(
        tf::Bytes(link.written.begin() + static_cast<std::ptrdiff_t>(before), link.written.end()),
        config.link.has_signing_key ? &key : nullptr);
  }
  // The frames of one cycle after @p bytes arrived, by message id in order.
  std::vector<tf::Decoded> send_and_run(const tf::Bytes& bytes) {
    link.send(bytes);
    return run();
  }

  hf::FirmwareConfig config = hf::default_config();
  tf::Key key{};
  FakeCamera camera;
  NoEncoders encoders;
  tf::QueueLink link;
  StepClock clock;
  std::unique_ptr<hf::LocalizationCycle> cycle;
};

inline std::vector<tf::Decoded> of_type(const std::vector<tf::Decoded>& frames, std::uint32_t id) {
  std::vector<tf::Decoded> out;
  for (const auto& f : frames)
    if (f.msg_id == id) out.push_back(f);
  return out;
}

}  // namespace harmoloc::test::one_board
