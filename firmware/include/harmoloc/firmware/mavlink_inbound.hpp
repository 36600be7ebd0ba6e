#pragma once
/// @file The inbound side of the link: reads what the peer sends (non-blocking, a bounded number
/// of bytes and of frames a cycle), finds the frames (mavlink_parser.hpp) and lets through only
/// COMMAND_LONG addressed to us, from an accepted system and component, and, when a signing key
/// is configured, signed with it and not replayed (mavlink_signing.hpp), and TIMESYNC requests
/// to answer. Everything else is dropped and counted. The cycle acts on what comes out
/// (LocalizationCycle) and answers each command with a COMMAND_ACK. No allocation after
/// construction. Protocol: docs/wire-protocol.md.

#include <array>
#include <bitset>
#include <cstddef>
#include <cstdint>

#include "harmoloc/firmware/config.hpp"
#include "harmoloc/firmware/inbound_counters.hpp"
#include "harmoloc/firmware/mavlink_parser.hpp"
#include "harmoloc/firmware/mavlink_signing.hpp"
#include "harmoloc/firmware/mavlink_v2.hpp"
#include "harmoloc/hal/pose_link.hpp"

namespace harmoloc::firmware::mavlink {

/// The commands the firmware acts on (MAV_CMD ids). The two user commands are from the range
/// the common set leaves to users (MAV_CMD_USER_1 and _2).
constexpr std::uint16_t kCmdRequestMessage = 512;  ///< MAV_CMD_REQUEST_MESSAGE
constexpr std::uint16_t kCmdRelocalize = 31010;    ///< MAV_CMD_USER_1
constexpr std::uint16_t kCmdSetPose = 31011;       ///< MAV_CMD_USER_2

struct CommandLong {
  std::array<float, 7> param{};
  std::uint16_t command = 0;
  std::uint8_t target_system = 0;
  std::uint8_t target_component = 0;
  std::uint8_t confirmation = 0;
  std::uint8_t source_system = 0;  ///< from the frame's header
  std::uint8_t source_component = 0;
};

/// Decodes a COMMAND_LONG payload (the frame's zero-restored payload).
CommandLong decode_command_long(const RxFrame& frame);

/// Decodes a TIMESYNC payload.
Timesync decode_timesync(const RxFrame& frame);

/// A TIMESYNC request to answer: the requester's time and identity.
struct TimesyncRequest {
  std::int64_t ts1 = 0;
  std::uint8_t system_id = 0;
  std::uint8_t component_id = 0;
};

/// "Set pose", checked and turned into the map frame (z up).
struct SetPoseRequest {
  double x_m = 0.0;
  double y_m = 0.0;
  double yaw_rad = 0.0;  ///< wrapped to [-pi, pi)
  double position_sigma_m = 0.0;
  double yaw_sigma_rad = 0.0;
};
/// Limits of "set pose": a coordinate beyond this is a mistake of units, not a place.
constexpr double kMaxSetPoseCoordinateM = 10000.0;
constexpr double kMaxSetPosePositionSigmaM = 10.0;
constexpr double kDefaultSetPoseYawSigmaRad = 0.05;

/// Reads "set pose": param1..3 x, y (m) and yaw (rad) in MAV_FRAME_LOCAL_FRD, as ODOMETRY
/// reports them; param4, param5 the position and yaw standard deviations (0 or NaN: @p
/// default_position_sigma_m and kDefaultSetPoseYawSigmaRad). kAccepted with @p out filled, or
/// kDenied for a value that is not finite or out of range.
MavResult read_set_pose(const CommandLong& command, double default_position_sigma_m,
                        SetPoseRequest& out);

/// Reads "request message": param1 is a message id (a whole number 0..2^24-1): kAccepted with
/// @p msg_id, else kDenied.
MavResult read_request_message(const CommandLong& command, std::uint32_t& msg_id);

class CommandReceiver {
 public:
  /// Per-cycle limits. At 921600 baud a line brings about 3 KiB a cycle at 30 Hz; commands are
  /// rare and small, so what a flood leaves waiting is read in the next cycles (or lost in the
  /// line's own buffer), never at the cost of the cycle.
  static constexpr std::size_t kMaxBytesPerCycle = 2048;
  static constexpr std::size_t kMaxFramesPerCycle = 32;
  static constexpr std::size_t kMaxCommandsPerCycle = 8;
  /// Bytes examined by the parser a cycle (checksums over candidate frames, skipped bytes).
  static constexpr std::size_t kWorkPerCycle = 8192;
  /// Cycles without a byte after which a partial candidate at the front of the window is taken
  /// for a false start (1 s at 30 Hz; no real frame pauses that long in the middle).
  static constexpr std::uint32_t kStallCycles = 30;

  /// Our identity and the accepted sources come from @p link; @p signer (may be nullptr) checks
  /// signatures when it holds a key.
  CommandReceiver(const LinkConfig& link, Signer* signer);

  /// Resets the per-cycle limits; call once at the start of each cycle's link service.
  void begin_cycle();
  /// Reads and parses until a command passes every check (true, in @p out) or a limit or the
  /// end of the waiting bytes is reached (false).
  bool next_command(hal::PoseLink& link, CommandLong& out);
  /// The latest TIMESYNC request of this cycle's reading, if any (true; it is then cleared).
  /// A request (tc1 = 0) addressed to us or to every system is taken from any source: answering
  /// changes nothing here. With a signing key it must be signed and not replayed, as commands.
  bool take_timesync(TimesyncRequest& out);
  /// Counts the answer the cycle gave the last command.
  void count_result(MavResult result);

  InboundCounters counters() const;
  const FrameParser& parser() const { return parser_; }
  /// The frame of the last command next_command() returned (valid until its next call).
  const RxFrame& last_frame() const { return frame_; }

 private:
  bool admit(const RxFrame& frame, CommandLong& out);
  // Whether a frame's signature holds up when a key is configured (rejections counted).
  bool signature_ok(const RxFrame& frame);
  void note_timesync(const RxFrame& frame);

  std::bitset<256> accept_systems_;
  std::bitset<256> accept_components_;
  std::uint8_t system_id_;
  std::uint8_t component_id_;
  Signer* signer_;
  FrameParser parser_;
  RxFrame frame_;
  std::size_t bytes_this_cycle_ = 0;
  std::size_t frames_this_cycle_ = 0;
  std::size_t commands_this_cycle_ = 0;
  std::size_t work_ = 0;
  std::uint32_t idle_cycles_ = 0;
  bool got_bytes_ = false;
  bool saturated_ = false;
  bool timesync_pending_ = false;
  TimesyncRequest timesync_{};
  InboundCounters counters_{};
};

}  // namespace harmoloc::firmware::mavlink
