#pragma once
/// @file A recording as a live camera would deliver it, for timer-paced real-time replays on the
/// host board: a frame is there from its recorded time on (mapped onto the monotonic clock from
/// the start of the run), acquire() never waits, and of the frames due by its deadline it hands
/// over the newest, dropping the older ones as the V4L2 and libcamera drivers do.

#include <cstddef>
#include <cstdint>

#include "harmoloc/hal/camera.hpp"
#include "harmoloc/host/file_camera.hpp"

namespace harmoloc::host {

class RecordedTimeCamera final : public hal::Camera {
 public:
  explicit RecordedTimeCamera(FileCamera& inner) : inner_(inner) {}
  /// The run starts: the recording's @p data_start_ns is due at @p wall_start_ns.
  void start(std::uint64_t wall_start_ns, std::uint64_t data_start_ns) {
    wall_start_ns_ = wall_start_ns;
    data_start_ns_ = data_start_ns;
  }
  hal::CameraStatus acquire(hal::FrameView& frame, std::uint64_t deadline_ns) override;
  void release() override { inner_.release(); }
  hal::CameraCounters counters() const override;

 private:
  std::uint64_t due_ns() const;
  FileCamera& inner_;
  std::uint64_t wall_start_ns_ = 0, data_start_ns_ = 0;
  std::size_t taken_ = 0;
  std::uint64_t dropped_ = 0;
};

}  // namespace harmoloc::host
