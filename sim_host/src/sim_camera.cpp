#include "harmoloc/sim_host/sim_camera.hpp"

#include <stdexcept>

namespace harmoloc::sim_host {

SimCamera::SimCamera(ScenarioRun& run) : run_(run) {
  if (run.next_frame() != 0) {
    throw std::logic_error("SimCamera: the run has rendered frames already (it renders them all)");
  }
  const CameraSpec& c = run.scenario().camera;
  buffer_.resize(static_cast<std::size_t>(c.width_px) * c.height_px * 3U);
  view_.width_px = c.width_px;
  view_.height_px = c.height_px;
  view_.format = hal::PixelFormat::kRgb24;
  view_.stride_bytes = c.width_px * 3U;
}

std::uint64_t SimCamera::next_timestamp_ns() const {
  return next_ < run_.frame_count() ? run_.frame_timestamp_ns(next_) : 0;
}

hal::CameraStatus SimCamera::acquire(hal::FrameView& frame, std::uint64_t /*deadline_ns*/) {
  if (next_ >= run_.frame_count()) return hal::CameraStatus::kEnded;
  const std::size_t k = next_++;
  run_.render(k, buffer_);  // same size every time: no reallocation
  view_.data = buffer_.data();
  view_.timestamp_ns = run_.frame_timestamp_ns(k);
  view_.sequence = static_cast<std::uint32_t>(k);
  ++counters_.frames;
  frame = view_;
  return hal::CameraStatus::kFrame;
}

}  // namespace harmoloc::sim_host
