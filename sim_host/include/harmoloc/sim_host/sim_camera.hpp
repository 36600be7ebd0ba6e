#pragma once
/// @file hal::Camera that renders a ScenarioRun's frames as they are acquired: a simulated run
/// without a dataset folder on disk. Frames come in order with the timestamps the dataset would
/// list (RGB24), then kEnded. The one frame buffer is reserved at construction.

#include <cstdint>
#include <vector>

#include "harmoloc/hal/camera.hpp"
#include "harmoloc/sim_host/scenario_run.hpp"

namespace harmoloc::sim_host {

class SimCamera final : public hal::Camera {
 public:
  /// @p run must outlive the camera and must not have rendered a frame yet (std::logic_error
  /// otherwise): the camera renders all of them, in order.
  explicit SimCamera(ScenarioRun& run);

  /// Renders the next frame (about 10 ms at 320 x 240 on the build machine; the deadline is not
  /// looked at: this is a replay, not a live camera).
  hal::CameraStatus acquire(hal::FrameView& frame, std::uint64_t deadline_ns) override;
  void release() override {}
  hal::CameraCounters counters() const override { return counters_; }

  std::size_t frame_count() const { return run_.frame_count(); }
  /// Timestamp of the next frame acquire() will return (0 when none remains).
  std::uint64_t next_timestamp_ns() const;
  std::uint64_t first_timestamp_ns() const { return run_.frame_timestamp_ns(0); }
  std::uint64_t last_timestamp_ns() const {
    return run_.frame_timestamp_ns(run_.frame_count() - 1);
  }

 private:
  ScenarioRun& run_;
  std::vector<std::uint8_t> buffer_;
  std::size_t next_ = 0;
  hal::FrameView view_{};
  hal::CameraCounters counters_{};
};

}  // namespace harmoloc::sim_host
