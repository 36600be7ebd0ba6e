#pragma once
/// @file hal::Camera backed by a dataset folder: the frames listed in its index, one file a
/// frame (binary PPM or raw YUYV). Start-up checks every file; the cycle then reads each into one
/// buffer reserved up front, with plain read(2) calls.

#include <cstdint>
#include <string>
#include <vector>

#include "harmoloc/hal/camera.hpp"
#include "harmoloc/sim_host/metadata.hpp"

namespace harmoloc::sim_host {

class FileCamera final : public hal::Camera {
 public:
  /// Reads the index and checks that every frame file exists with the size and header the
  /// metadata promises. Throws std::runtime_error with one line naming the first bad file.
  FileCamera(const std::string& dataset_dir, const DatasetMetadata& metadata);

  hal::CameraStatus acquire(hal::FrameView& frame, std::uint64_t deadline_ns) override;
  void release() override {}
  hal::CameraCounters counters() const override { return counters_; }

  /// Frames in the recording times the number of passes.
  std::size_t frame_count() const { return paths_.size() * loops_; }
  /// Timestamp of the next frame acquire() will return (valid while frames remain).
  std::uint64_t next_timestamp_ns() const;
  std::uint64_t first_timestamp_ns() const { return stamps_.empty() ? 0 : stamps_.front(); }
  std::uint64_t last_timestamp_ns() const { return stamps_.empty() ? 0 : stamps_.back(); }
  /// Replays the recording @p loops times; pass k is shifted by k x @p span_ns, so time runs on.
  void set_loops(std::uint32_t loops, std::uint64_t span_ns) {
    loops_ = loops == 0 ? 1 : loops;
    span_ns_ = span_ns;
  }

 private:
  std::vector<std::string> paths_;
  std::vector<std::uint64_t> stamps_;
  std::vector<std::uint8_t> buffer_;
  std::size_t data_offset_ = 0;  // where pixels start in a PPM (all frames share the header size)
  std::size_t file_size_ = 0;
  std::size_t next_ = 0;
  std::uint32_t loops_ = 1;
  std::uint32_t loop_ = 0;
  std::uint64_t span_ns_ = 0;
  hal::FrameView view_{};
  hal::CameraCounters counters_{};
};

}  // namespace harmoloc::sim_host
