#pragma once
/// @file A camera that hands every frame it acquires to a FrameRecorder before the cycle sees it.
/// The cycle pays one memcpy of the frame (when a slot is free); nothing waits for the disk.

#include "harmoloc/drivers/frame_recorder.hpp"
#include "harmoloc/hal/camera.hpp"

namespace harmoloc::drivers {

class RecordingCamera final : public hal::Camera {
 public:
  RecordingCamera(hal::Camera& inner, FrameRecorder& recorder)
      : inner_(inner), recorder_(recorder) {}

  hal::CameraStatus acquire(hal::FrameView& frame, std::uint64_t deadline_ns) override {
    const hal::CameraStatus status = inner_.acquire(frame, deadline_ns);
    if (status == hal::CameraStatus::kFrame) recorder_.offer(frame);
    return status;
  }
  void release() override { inner_.release(); }
  hal::CameraCounters counters() const override { return inner_.counters(); }

 private:
  hal::Camera& inner_;
  FrameRecorder& recorder_;
};

}  // namespace harmoloc::drivers
