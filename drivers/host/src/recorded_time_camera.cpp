#include "harmoloc/host/recorded_time_camera.hpp"

namespace harmoloc::host {

hal::CameraStatus RecordedTimeCamera::acquire(hal::FrameView& frame, std::uint64_t deadline_ns) {
  if (taken_ >= inner_.frame_count()) return hal::CameraStatus::kEnded;
  if (due_ns() > deadline_ns) return hal::CameraStatus::kNoFrame;
  hal::CameraStatus status = inner_.acquire(frame, deadline_ns);
  ++taken_;
  // Bounded by the frames of the recording.
  while (taken_ < inner_.frame_count() && due_ns() <= deadline_ns) {
    if (status == hal::CameraStatus::kFrame) ++dropped_;
    status = inner_.acquire(frame, deadline_ns);
    ++taken_;
  }
  return status;
}

hal::CameraCounters RecordedTimeCamera::counters() const {
  hal::CameraCounters c = inner_.counters();
  c.dropped += dropped_;
  return c;
}

std::uint64_t RecordedTimeCamera::due_ns() const {
  const std::uint64_t t = inner_.next_timestamp_ns();
  return wall_start_ns_ + (t > data_start_ns_ ? t - data_start_ns_ : 0);
}

}  // namespace harmoloc::host
