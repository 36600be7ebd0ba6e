#pragma once
/// @file The link for the pose stream (a serial line in the robot, a file or pty on the host):
/// whole frames out, and the bytes a peer sends back (commands) in.

#include <cstddef>
#include <cstdint>

namespace harmoloc::hal {

enum class LinkWrite : std::uint8_t {
  kSent = 0,     ///< the whole frame was queued
  kDropped = 1,  ///< no room for the whole frame: nothing was written (never half a frame)
  kFailed = 2,   ///< the link is broken (hung up, I/O error)
};

struct LinkCounters {
  std::uint64_t frames_sent = 0;
  std::uint64_t frames_dropped = 0;
  std::uint64_t bytes_sent = 0;
  std::uint64_t errors = 0;
};

class PoseLink {
 public:
  /// Writes one whole frame or nothing. Never blocks.
  virtual LinkWrite write_frame(const std::uint8_t* bytes, std::size_t size) = 0;
  virtual LinkCounters counters() const = 0;
  /// Copies up to @p max bytes that arrived from the peer into @p dst and returns how many.
  /// Never blocks: 0 when nothing is waiting, and always 0 on a link that cannot receive (a
  /// plain output file), which is what this default is for.
  virtual std::size_t read_bytes(std::uint8_t* dst, std::size_t max) {
    (void)dst;
    (void)max;
    return 0;
  }

 protected:
  ~PoseLink() = default;
};

}  // namespace harmoloc::hal
