#pragma once
/// @file hal::Camera backed by a dataset folder: the frames listed in its index, one file a
/// frame (binary PPM or raw YUYV). Start-up checks every file; the cycle then reads each into one
/// buffer reserved up front, with plain read(2) calls.

#include <cstdint>
#include <string>
#include <vector>

#include "harmoloc/dataset/metadata.hpp"
#include "harmoloc/hal/camera.hpp"

namespace harmoloc::host {

class FileCamera final : public hal::Camera {
 public:
  /// Reads the index and checks that every frame file exists with the size and header the
  /// metadata promises. Throws std::runtime_error with one line naming the first bad file.
  FileCamera(const std::string& dataset_dir, const dataset::DatasetMetadata& metadata);

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
  /// A hole in the recording (the next frame more than 1.5 frame periods after the last one)
  /// comes out as a live camera's would in a camera-paced cycle: one kNoFrame per period of the
  /// metadata's rate that has no frame, each an acquire() that found nothing by its deadline.
  /// Off by default (a timer-paced replay has its own clock and needs no such ticks); with it,
  /// next_timestamp_ns() gives the time of the next tick, frame or not.
  void set_fill_gaps(bool fill) { fill_gaps_ = fill; }
  /// Ticks without a frame handed out for holes in the recording.
  std::uint64_t gap_ticks() const { return gap_ticks_; }

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
  std::uint64_t period_ns_ = 0;  // of the metadata's frame rate
  bool fill_gaps_ = false;
  bool have_last_ = false;
  std::uint64_t last_ns_ = 0;  // time of the last acquire() that was not kEnded (frame or tick)
  std::uint64_t gap_ticks_ = 0;
  hal::FrameView view_{};
  hal::CameraCounters counters_{};
};

}  // namespace harmoloc::host
