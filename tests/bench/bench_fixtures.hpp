#pragma once
/// @file Inputs shared by the benchmarks and the instruction counter: simulated frames at any
/// resolution, synthetic maps, and in-memory hal fakes that feed the whole cycle forever.

#include <cstdint>
#include <vector>

#include "harmoloc/algorithms/board_observation.hpp"
#include "harmoloc/algorithms/map_codec.hpp"
#include "harmoloc/firmware/config.hpp"
#include "harmoloc/hal/camera.hpp"
#include "harmoloc/hal/clock.hpp"
#include "harmoloc/hal/pose_link.hpp"
#include "harmoloc/hal/wheel_encoders.hpp"

namespace harmoloc::bench {

struct Frames {
  std::uint32_t width_px = 0, height_px = 0;
  std::vector<std::vector<std::uint8_t>> rgb;   ///< RGB24
  std::vector<std::vector<std::uint8_t>> yuyv;  ///< the same frames as YUYV
};

/// @p count frames of the default scenario along its route, rendered at @p width x @p height.
Frames simulated_frames(std::uint32_t width_px, std::uint32_t height_px, std::size_t count);

/// The firmware's default windows (six boards) for @p boards <= 6; 7 and 8 add a window of light
/// greys and one of dark pixels, so that every board count 1..8 can be measured.
algorithms::ThresholdSet board_thresholds(std::size_t boards = 6);

/// A map with @p samples random samples over the first @p boards boards of board_thresholds()
/// (values in a plausible range).
void synthetic_map(std::size_t samples, std::uint32_t width_px, std::uint32_t height_px,
                   algorithms::MapFile& map, std::size_t boards = 6);

/// Gives synthetic_map's forward map projected bearings (map version 15): a camera and an outline
/// for every board, where its bearings place it, all seen whole from the benchmarks' pose. With
/// @p areas, every board's areas projected too (map version 17), from the eight-point outline the
/// trainer writes for a rectangle (four corners otherwise).
void project_every_board(algorithms::ForwardMap& map, bool areas = false);

/// One frame's observation for the filter benchmarks on synthetic_map's forward map: every board
/// with an area and a bearing (the default update's whole cost).
void bench_observation(const algorithms::ForwardMap& map, algorithms::BoardFeatures& observed);

/// Serves the frames (RGB24 or their YUYV versions) again and again, timestamps 1/30 s apart.
class MemoryCamera final : public hal::Camera {
 public:
  explicit MemoryCamera(const Frames& frames, hal::PixelFormat format = hal::PixelFormat::kRgb24)
      : frames_(frames), format_(format) {}
  hal::CameraStatus acquire(hal::FrameView& frame, std::uint64_t deadline_ns) override;
  void release() override {}
  hal::CameraCounters counters() const override { return {}; }

 private:
  const Frames& frames_;
  hal::PixelFormat format_;
  std::uint64_t next_ = 0;
};

/// Wheel counters of a robot creeping forward and turning gently, one sample per read.
class MemoryEncoders final : public hal::WheelEncoders {
 public:
  hal::EncoderStatus read(std::uint64_t data_time_ns, hal::EncoderCounts& counts) override;
  hal::EncoderCounters counters() const override { return {}; }

 private:
  std::uint32_t left_ = 0, right_ = 0;
};

class NullLink final : public hal::PoseLink {
 public:
  hal::LinkWrite write_frame(const std::uint8_t*, std::size_t) override {
    return hal::LinkWrite::kSent;
  }
  hal::LinkCounters counters() const override { return {}; }
};

/// A clock that does not touch the OS (instruction counts must not include vDSO noise).
class StepClock final : public hal::Clock {
 public:
  std::uint64_t now_ns() const override { return now_ += 1000; }
  void sleep_until(std::uint64_t) override {}

 private:
  mutable std::uint64_t now_ = 0;
};

}  // namespace harmoloc::bench
