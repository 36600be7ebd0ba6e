#pragma once
/// @file hal::Camera on libcamera (Debian's 0.0.3): one camera picked by id (or the first),
/// one viewfinder stream in YUYV or RGB24 at the configured size, a fixed set of buffers
/// allocated and mapped at start-up with one request each.
///
/// Hand-off without locks or allocation in the cycle (completion_handoff.hpp): libcamera completes
/// requests in its own thread; the completion handler pushes the Request pointer into a fixed
/// single-producer single-consumer ring and bumps an eventfd. acquire() waits on that eventfd
/// with ppoll until the deadline and pops the ring. release() pushes the request into a second
/// ring and bumps a second eventfd; a small requeue thread (not the cycle) gives it back to
/// libcamera, whose queueRequest() allocates its internal messages.
///
/// Anything linking libcamera hangs under qemu-user (lttng-ust's start-up fork): this driver is
/// its own library (harmoloc_drivers_libcamera) and its tests run natively only.

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "harmoloc/algorithms/quadrature.hpp"
#include "harmoloc/drivers/completion_handoff.hpp"
#include "harmoloc/drivers/v4l2_format.hpp"
#include "harmoloc/hal/camera.hpp"
#include "harmoloc/hal/clock.hpp"

namespace libcamera {
class Camera;
class CameraManager;
class FrameBufferAllocator;
class Request;
class Stream;
}  // namespace libcamera

namespace harmoloc::drivers {

struct LibcameraOptions {
  std::string camera_id;  ///< "" = the first camera libcamera lists
  std::uint32_t width_px = 320;
  std::uint32_t height_px = 240;
  FormatRequest format = FormatRequest::kAuto;
  std::uint32_t buffers = 4;
};

class LibcameraCamera final : public hal::Camera {
 public:
  static constexpr std::size_t kMaxBuffers = 8;

  explicit LibcameraCamera(hal::Clock& clock);
  ~LibcameraCamera();
  LibcameraCamera(const LibcameraCamera&) = delete;
  LibcameraCamera& operator=(const LibcameraCamera&) = delete;

  /// Starts the camera manager, picks and configures the camera, allocates, maps and queues
  /// the buffers and starts streaming. Returns an empty string on success, else one line.
  std::string open(const LibcameraOptions& options);

  hal::CameraStatus acquire(hal::FrameView& frame, std::uint64_t deadline_ns) override;
  void release() override;
  hal::CameraCounters counters() const override;

  hal::PixelFormat pixel_format() const { return format_; }
  const std::string& description() const { return description_; }
  /// The ids of the cameras libcamera finds (start-up diagnostics; starts a manager if needed).
  static std::vector<std::string> list_cameras();

 private:
  void on_request_completed(libcamera::Request* request);
  void requeue_loop();
  void shutdown();

  struct Mapping {
    void* base = nullptr;  ///< what mmap returned (the plane's file from offset 0)
    std::size_t length = 0;
    const std::uint8_t* address = nullptr;  ///< the plane's first byte
  };

  hal::Clock& clock_;
  LibcameraOptions options_;
  std::unique_ptr<libcamera::CameraManager> manager_;
  std::shared_ptr<libcamera::Camera> camera_;
  std::unique_ptr<libcamera::FrameBufferAllocator> allocator_;
  std::vector<std::unique_ptr<libcamera::Request>> requests_;  // built at start-up
  std::vector<Mapping> mappings_;                              // one per request (cookie)
  libcamera::Stream* stream_ = nullptr;
  bool acquired_ = false;
  bool started_ = false;

  // Every request is in one place at a time (libcamera, a ring, held by the cycle), so with at
  // most kMaxBuffers of them neither ring can fill.
  CompletionHandoff<libcamera::Request*, 16> handoff_;
  static_assert(kMaxBuffers <= decltype(handoff_)::capacity(), "a ring could fill up");
  std::thread requeuer_;
  libcamera::Request* held_ = nullptr;

  hal::PixelFormat format_ = hal::PixelFormat::kYuyv;
  std::uint32_t stride_bytes_ = 0;
  std::string description_;
  algorithms::SequenceGapCounter sequence_;
  hal::CameraCounters counters_{};
  std::atomic<std::uint64_t> cancelled_{0};
};

}  // namespace harmoloc::drivers
