#pragma once
/// @file MAVLink v2 framing and the messages the firmware sends: HEARTBEAT (#0), STATUSTEXT
/// (#253), ODOMETRY (#331), COMMAND_ACK (#77), TIMESYNC (#111) and NAMED_VALUE_FLOAT (#251),
/// from the common message set. Frames are built
/// into a caller's fixed buffer and signed when a Signer is set; nothing allocates. Wire details
/// in docs/wire-protocol.md. Inbound frames: mavlink_parser.hpp, mavlink_inbound.hpp.

#include <array>
#include <cstddef>
#include <cstdint>

namespace harmoloc::firmware::mavlink {

constexpr std::uint8_t kStx = 0xFD;
constexpr std::size_t kHeaderBytes = 10;
constexpr std::size_t kChecksumBytes = 2;
constexpr std::size_t kMaxPayloadBytes = 255;
constexpr std::size_t kMaxFrameBytes = kHeaderBytes + kMaxPayloadBytes + kChecksumBytes;
/// Link id (1), timestamp (6) and signature (6) after the checksum of a signed frame.
constexpr std::size_t kSignatureBytes = 13;
constexpr std::size_t kMaxSignedFrameBytes = kMaxFrameBytes + kSignatureBytes;
constexpr std::uint8_t kIncompatSigned = 0x01;

constexpr std::uint32_t kMsgHeartbeat = 0;
constexpr std::uint32_t kMsgCommandLong = 76;
constexpr std::uint32_t kMsgCommandAck = 77;
constexpr std::uint32_t kMsgTimesync = 111;
constexpr std::uint32_t kMsgNamedValueFloat = 251;
constexpr std::uint32_t kMsgStatustext = 253;
constexpr std::uint32_t kMsgOdometry = 331;
constexpr std::uint8_t kCrcExtraCommandLong = 152;
constexpr std::uint8_t kCrcExtraCommandAck = 143;
constexpr std::uint8_t kCrcExtraTimesync = 34;
constexpr std::uint8_t kCrcExtraNamedValueFloat = 170;
/// NAMED_VALUE_FLOAT's name field: 10 characters, not terminated when all are used.
constexpr std::size_t kNamedValueNameBytes = 10;

// Enumerations of the common set used here.
constexpr std::uint8_t kMavTypeOnboardController = 18;
constexpr std::uint8_t kMavAutopilotInvalid = 8;
constexpr std::uint8_t kMavStateStandby = 3;
constexpr std::uint8_t kMavStateActive = 4;
constexpr std::uint8_t kMavStateCritical = 5;
constexpr std::uint8_t kMavStateEmergency = 6;
constexpr std::uint8_t kMavFrameBodyFrd = 12;
constexpr std::uint8_t kMavFrameLocalFrd = 20;
constexpr std::uint8_t kMavEstimatorTypeVision = 2;
constexpr std::uint8_t kSeverityCritical = 2;
constexpr std::uint8_t kSeverityWarning = 4;
constexpr std::uint8_t kSeverityInfo = 6;

/// MAV_RESULT values the firmware answers commands with.
enum class MavResult : std::uint8_t {
  kAccepted = 0,
  kTemporarilyRejected = 1,
  kDenied = 2,  ///< supported, but the parameters are invalid
  kUnsupported = 3,
  kFailed = 4,
};

/// CRC-16/MCRF4XX (X.25) as MAVLink uses it.
std::uint16_t crc_x25(const std::uint8_t* data, std::size_t size, std::uint16_t crc = 0xFFFF);

struct Odometry {
  std::uint64_t time_usec = 0;
  std::uint8_t frame_id = kMavFrameLocalFrd;
  std::uint8_t child_frame_id = kMavFrameBodyFrd;
  float x = 0, y = 0, z = 0;
  std::array<float, 4> q{1, 0, 0, 0};  ///< w, x, y, z
  float vx = 0, vy = 0, vz = 0;
  float rollspeed = 0, pitchspeed = 0, yawspeed = 0;
  std::array<float, 21> pose_covariance{};
  std::array<float, 21> velocity_covariance{};
  std::uint8_t reset_counter = 0;
  std::uint8_t estimator_type = kMavEstimatorTypeVision;
  std::int8_t quality = 0;  ///< 0..100, -1 = failed
};

struct Heartbeat {
  std::uint32_t custom_mode = 0;
  std::uint8_t type = kMavTypeOnboardController;
  std::uint8_t autopilot = kMavAutopilotInvalid;
  std::uint8_t base_mode = 0;
  std::uint8_t system_status = kMavStateStandby;
  std::uint8_t mavlink_version = 3;
};

struct CommandAck {
  std::uint16_t command = 0;
  MavResult result = MavResult::kAccepted;
  std::uint8_t progress = 0;
  std::int32_t result_param2 = 0;
  std::uint8_t target_system = 0;  ///< the commander's system and component
  std::uint8_t target_component = 0;
};

/// TIMESYNC (#111): a request has tc1 = 0 and the requester's time in ts1 (ns); the answer
/// carries the answering system's time in tc1 and the request's ts1, addressed to the requester.
struct Timesync {
  std::int64_t tc1 = 0;
  std::int64_t ts1 = 0;
  std::uint8_t target_system = 0;  ///< extension: 0 = every system
  std::uint8_t target_component = 0;
};

using FrameBuffer = std::array<std::uint8_t, kMaxSignedFrameBytes>;

class Signer;

/// Builds frames with one system/component identity and a running sequence number.
class Encoder {
 public:
  Encoder(std::uint8_t system_id, std::uint8_t component_id)
      : system_id_(system_id), component_id_(component_id) {}

  /// Signs every frame built from now on with @p signer when it holds a key (nullptr: none).
  void set_signer(Signer* signer) { signer_ = signer; }

  std::size_t heartbeat(const Heartbeat& msg, FrameBuffer& out);
  std::size_t odometry(const Odometry& msg, FrameBuffer& out);
  /// @p text is cut at 50 characters.
  std::size_t statustext(std::uint8_t severity, const char* text, FrameBuffer& out);
  std::size_t command_ack(const CommandAck& msg, FrameBuffer& out);
  std::size_t timesync(const Timesync& msg, FrameBuffer& out);
  /// @p name is cut at kNamedValueNameBytes characters.
  std::size_t named_value_float(std::uint32_t time_boot_ms, const char* name, float value,
                                FrameBuffer& out);
  /// COMMAND_LONG (what a ground station or harmoloc-monitor sends): @p params 1..7.
  std::size_t command_long(std::uint16_t command, const std::array<float, 7>& params,
                           std::uint8_t target_system, std::uint8_t target_component,
                           FrameBuffer& out);

 private:
  std::size_t finish(std::uint32_t msg_id, std::uint8_t crc_extra, std::size_t payload_len,
                     FrameBuffer& out);

  std::uint8_t system_id_;
  std::uint8_t component_id_;
  std::uint8_t sequence_ = 0;
  Signer* signer_ = nullptr;
};

}  // namespace harmoloc::firmware::mavlink
