#pragma once
/// @file hal::PoseLink over a file descriptor: a serial line or pty (raw mode, configured baud,
/// non-blocking) or a plain file. A frame the line cannot take whole is kept and finished first
/// on the next write; frames that arrive meanwhile are dropped and counted. The wire never sees
/// half a frame and the cycle never waits. A serial line or pty is read as well (non-blocking:
/// the commands a peer sends); a plain file is output only, unless open_input() names a file
/// or FIFO to read the inbound bytes from (host tests).

#include <array>
#include <cstdint>
#include <string>

#include "harmoloc/hal/pose_link.hpp"

namespace harmoloc::drivers {

class SerialLink final : public hal::PoseLink {
 public:
  static constexpr std::size_t kMaxFrameBytes = 512;

  SerialLink() = default;
  ~SerialLink();
  SerialLink(const SerialLink&) = delete;
  SerialLink& operator=(const SerialLink&) = delete;

  /// Opens @p path: a character device is put in raw mode at @p baud (and read from, when it is
  /// a terminal and opens read-write); anything else is created or truncated as a regular file.
  /// Returns an empty string on success, else the reason.
  std::string open(const std::string& path, unsigned baud);
  /// Takes the inbound bytes from @p path (a file or FIFO, opened non-blocking) instead of the
  /// output device. Returns an empty string on success, else the reason.
  std::string open_input(const std::string& path);
  bool is_tty() const { return is_tty_; }
  bool can_receive() const { return in_fd_ >= 0; }

  hal::LinkWrite write_frame(const std::uint8_t* bytes, std::size_t size) override;
  hal::LinkCounters counters() const override { return counters_; }
  std::size_t read_bytes(std::uint8_t* dst, std::size_t max) override;

 private:
  bool flush_pending();

  int fd_ = -1;
  int in_fd_ = -1;  ///< fd_ itself for a terminal, a separate descriptor after open_input()
  bool is_tty_ = false;
  bool input_failed_ = false;  ///< counted once: a broken input must not flood the error count
  std::array<std::uint8_t, kMaxFrameBytes> pending_{};
  std::size_t pending_size_ = 0;
  std::size_t pending_sent_ = 0;
  hal::LinkCounters counters_{};
};

}  // namespace harmoloc::drivers
