#pragma once
/// @file hal::Camera on a V4L2 capture device: format negotiation (YUYV first, then RGB24),
/// mmap streaming with a fixed set of buffers, the driver's own buffer timestamps, poll with a
/// deadline, dequeue -> segment in place -> requeue (no copy), sequence gaps counted as dropped
/// frames, and recovery from EIO or an unplugged device by reopening it.

#include <array>
#include <cstdint>
#include <string>

#include "harmoloc/algorithms/quadrature.hpp"
#include "harmoloc/drivers/v4l2_format.hpp"
#include "harmoloc/hal/camera.hpp"
#include "harmoloc/hal/clock.hpp"

namespace harmoloc::drivers {

struct V4l2Options {
  std::string device = "/dev/video0";
  std::uint32_t width_px = 320;
  std::uint32_t height_px = 240;
  FormatRequest format = FormatRequest::kAuto;
  std::uint32_t buffers = 4;                ///< mmap buffers (2..V4l2Camera::kMaxBuffers)
  std::uint32_t reopen_interval_ms = 1000;  ///< after an error, try to reopen this often
  /// When several frames are waiting, hand the newest to the cycle and requeue the others at
  /// once (counted as dropped): the pose stays current when a cycle ran late.
  bool newest_frame = true;
};

class V4l2Camera final : public hal::Camera {
 public:
  static constexpr std::uint32_t kMaxBuffers = 8;

  explicit V4l2Camera(hal::Clock& clock) : clock_(clock) {}
  ~V4l2Camera();
  V4l2Camera(const V4l2Camera&) = delete;
  V4l2Camera& operator=(const V4l2Camera&) = delete;

  /// Opens the device, negotiates the format, maps the buffers and starts streaming. Returns an
  /// empty string on success, else one line saying what is wrong.
  std::string open(const V4l2Options& options);

  hal::CameraStatus acquire(hal::FrameView& frame, std::uint64_t deadline_ns) override;
  void release() override;
  hal::CameraCounters counters() const override;

  hal::PixelFormat pixel_format() const { return format_; }
  std::uint32_t stride_bytes() const { return stride_bytes_; }
  std::uint32_t buffer_count() const { return buffer_count_; }
  bool streaming() const { return fd_ >= 0; }
  /// The device's name (VIDIOC_QUERYCAP card) and the format in use, for the start-up line.
  const std::string& description() const { return description_; }

 private:
  std::string start();  // open + negotiate + map + stream on
  void stop();          // stream off, unmap, close
  void fail_device();   // an error: close, count, schedule a reopen
  void requeue(std::uint32_t index);

  struct Mapping {
    void* address = nullptr;
    std::size_t length = 0;
  };

  hal::Clock& clock_;
  V4l2Options options_;
  int fd_ = -1;
  std::array<Mapping, kMaxBuffers> buffers_{};
  std::uint32_t buffer_count_ = 0;
  std::uint32_t fourcc_ = 0;
  hal::PixelFormat format_ = hal::PixelFormat::kYuyv;
  std::uint32_t stride_bytes_ = 0;
  std::uint32_t image_bytes_ = 0;
  std::int64_t held_ = -1;  ///< index of the buffer the cycle holds, -1 for none
  std::uint64_t next_reopen_ns_ = 0;
  std::string description_;
  algorithms::SequenceGapCounter sequence_;
  hal::CameraCounters counters_{};
};

}  // namespace harmoloc::drivers
