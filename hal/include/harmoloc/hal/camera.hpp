#pragma once
/// @file Camera interface: the cycle acquires one frame, processes it in place, then releases it.

#include <cstdint>

#include "harmoloc/hal/frame.hpp"

namespace harmoloc::hal {

enum class CameraStatus : std::uint8_t {
  kFrame = 0,    ///< a frame was acquired and must be released
  kNoFrame = 1,  ///< nothing arrived before the deadline; try next cycle
  kCorrupt = 2,  ///< a frame arrived but could not be used (counted, already released)
  kEnded = 3,    ///< the source has no more frames (end of a recording)
};

/// Counters a camera keeps about itself; read by the firmware for its stats.
struct CameraCounters {
  std::uint64_t frames = 0;
  std::uint64_t corrupt = 0;
  std::uint64_t dropped = 0;  ///< gaps in the sequence numbers
  std::uint64_t errors = 0;   ///< device errors (EIO, unplugged): the device is reopened
  std::uint64_t reopens = 0;  ///< times the device was opened again after an error
};

/// A source of frames. Implementations reserve every buffer before the cycle starts;
/// acquire() must not allocate and must not block past its deadline.
class Camera {
 public:
  /// Waits at most until @p deadline_ns (on the monotonic clock) for the next frame.
  virtual CameraStatus acquire(FrameView& frame, std::uint64_t deadline_ns) = 0;
  /// Hands the last acquired frame's buffer back to the camera.
  virtual void release() = 0;
  virtual CameraCounters counters() const = 0;

 protected:
  ~Camera() = default;
};

}  // namespace harmoloc::hal
