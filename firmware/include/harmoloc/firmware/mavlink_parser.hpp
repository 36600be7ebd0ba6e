#pragma once
/// @file Incremental MAVLink v2 frame parser for the inbound side of the link. Bytes are pushed
/// in whatever pieces the line delivers into a fixed window; next() finds the frames in it.
/// A candidate frame is a start byte (0xFD) followed by a header the parser can check: reserved
/// incompat flags clear, a payload of 1 byte or more and no longer than its message allows, and
/// a message id it knows the CRC_EXTRA of (message_info()). A candidate that fails any check,
/// or its checksum, costs one byte: the search for a start byte resumes right after it, so a
/// real frame hidden behind a false start byte is still found. Work per call is bounded by a
/// budget, so a flood of garbage cannot hold up the cycle. No allocation.

#include <array>
#include <cstddef>
#include <cstdint>

#include "harmoloc/firmware/mavlink_v2.hpp"

namespace harmoloc::firmware::mavlink {

/// What the parser knows of a message: its CRC_EXTRA and its longest payload (extensions
/// included).
struct MessageInfo {
  std::uint32_t id;
  std::uint8_t crc_extra;
  std::uint8_t max_payload;
};

/// The message's entry, or nullptr for an id the firmware does not know (common set: the
/// messages a ground station or an autopilot typically sends on such a line, and ours).
const MessageInfo* message_info(std::uint32_t msg_id);

/// One frame with a valid checksum, as found in the parser's window.
struct RxFrame {
  const std::uint8_t* bytes = nullptr;  ///< start byte to end of frame (signature included);
                                        ///< valid until the next write_area() or push()
  std::size_t size = 0;
  std::uint8_t payload_length = 0;
  std::uint8_t incompat_flags = 0;
  std::uint8_t sequence = 0;
  std::uint8_t system_id = 0;
  std::uint8_t component_id = 0;
  std::uint32_t msg_id = 0;
  /// The payload with the zeros MAVLink 2 trims from its end restored (zero to 255 bytes).
  std::array<std::uint8_t, kMaxPayloadBytes> payload{};

  bool is_signed() const { return (incompat_flags & kIncompatSigned) != 0; }
};

struct ParserCounters {
  std::uint64_t bytes = 0;          ///< bytes pushed in
  std::uint64_t frames = 0;         ///< frames with a valid checksum
  std::uint64_t frame_bytes = 0;    ///< bytes of those frames
  std::uint64_t crc_errors = 0;     ///< candidates with a checkable header and a wrong checksum
  std::uint64_t bad_headers = 0;    ///< start bytes followed by a header that cannot be checked
  std::uint64_t garbage_bytes = 0;  ///< bytes dropped outside frames (false start bytes too)
};

class FrameParser {
 public:
  /// Room for two of the longest frames: a whole frame always fits behind a partial one.
  static constexpr std::size_t kWindowBytes = 2 * kMaxSignedFrameBytes;

  /// Where the next bytes go, and how many fit (the window is compacted first).
  std::uint8_t* write_area(std::size_t& room);
  /// Takes @p n bytes written into write_area().
  void commit(std::size_t n);
  /// Copies in up to @p n bytes; returns how many fitted.
  std::size_t push(const std::uint8_t* data, std::size_t n);

  /// Finds the next frame with a valid checksum in the window. @p work is the budget in bytes
  /// examined (each checksum costs the candidate's length, each skipped byte one); it is
  /// reduced, and the search stops with false when it runs out, or when the window holds no
  /// complete frame (yet): the rest stays for the next call.
  bool next(RxFrame& out, std::size_t& work);

  /// Gives up on the candidate at the front of the window (one byte dropped, the search goes
  /// on after it): for a false start byte whose claimed length holds back the frames behind it
  /// while the line has gone quiet. Returns false if the window is empty.
  bool skip_candidate();

  std::size_t buffered() const { return end_ - start_; }
  const ParserCounters& counters() const { return counters_; }

 private:
  void drop(std::size_t n);

  std::array<std::uint8_t, kWindowBytes> window_{};
  std::size_t start_ = 0;
  std::size_t end_ = 0;
  ParserCounters counters_{};
};

}  // namespace harmoloc::firmware::mavlink
