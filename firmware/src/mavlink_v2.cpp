#include "harmoloc/firmware/mavlink_v2.hpp"

#include <cstring>

#include "harmoloc/firmware/mavlink_signing.hpp"

namespace harmoloc::firmware::mavlink {

namespace {

constexpr std::uint8_t kCrcExtraHeartbeat = 50;
constexpr std::uint8_t kCrcExtraStatustext = 83;
constexpr std::uint8_t kCrcExtraOdometry = 91;

// Little-endian field writer into the payload area of a frame.
class Payload {
 public:
  explicit Payload(std::uint8_t* p) : p_(p) {}
  void u8(std::uint8_t v) { p_[n_++] = v; }
  void u16(std::uint16_t v) {
    u8(static_cast<std::uint8_t>(v));
    u8(static_cast<std::uint8_t>(v >> 8U));
  }
  void u32(std::uint32_t v) {
    for (int i = 0; i < 4; ++i) u8(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  void u64(std::uint64_t v) {
    for (int i = 0; i < 8; ++i) u8(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  void f32(float v) {
    std::uint32_t u = 0;
    std::memcpy(&u, &v, 4);
    u32(u);
  }
  std::size_t size() const { return n_; }

 private:
  std::uint8_t* p_;
  std::size_t n_ = 0;
};

}  // namespace

std::uint16_t crc_x25(const std::uint8_t* data, std::size_t size, std::uint16_t crc) {
  for (std::size_t i = 0; i < size; ++i) {
    std::uint8_t tmp = static_cast<std::uint8_t>(data[i] ^ static_cast<std::uint8_t>(crc & 0xFFU));
    tmp = static_cast<std::uint8_t>(tmp ^ static_cast<std::uint8_t>(tmp << 4U));
    crc = static_cast<std::uint16_t>((crc >> 8U) ^ (static_cast<std::uint16_t>(tmp) << 8U) ^
                                     (static_cast<std::uint16_t>(tmp) << 3U) ^ (tmp >> 4U));
  }
  return crc;
}

std::size_t Encoder::finish(std::uint32_t msg_id, std::uint8_t crc_extra, std::size_t payload_len,
                            FrameBuffer& out) {
  // MAVLink 2 drops trailing zero bytes of the payload (at least one byte stays).
  while (payload_len > 1 && out[kHeaderBytes + payload_len - 1] == 0) --payload_len;
  const bool sign = signer_ != nullptr && signer_->enabled();
  out[0] = kStx;
  out[1] = static_cast<std::uint8_t>(payload_len);
  out[2] = sign ? kIncompatSigned : 0;  // the flag is covered by the checksum
  out[3] = 0;                           // compat flags
  out[4] = sequence_++;
  out[5] = system_id_;
  out[6] = component_id_;
  out[7] = static_cast<std::uint8_t>(msg_id);
  out[8] = static_cast<std::uint8_t>(msg_id >> 8U);
  out[9] = static_cast<std::uint8_t>(msg_id >> 16U);
  std::uint16_t crc = crc_x25(out.data() + 1, kHeaderBytes - 1 + payload_len);
  crc = crc_x25(&crc_extra, 1, crc);
  out[kHeaderBytes + payload_len] = static_cast<std::uint8_t>(crc);
  out[kHeaderBytes + payload_len + 1] = static_cast<std::uint8_t>(crc >> 8U);
  const std::size_t size = kHeaderBytes + payload_len + kChecksumBytes;
  return sign ? size + signer_->sign(out.data(), size) : size;
}

std::size_t Encoder::heartbeat(const Heartbeat& m, FrameBuffer& out) {
  Payload p(out.data() + kHeaderBytes);
  p.u32(m.custom_mode);
  p.u8(m.type);
  p.u8(m.autopilot);
  p.u8(m.base_mode);
  p.u8(m.system_status);
  p.u8(m.mavlink_version);
  return finish(kMsgHeartbeat, kCrcExtraHeartbeat, p.size(), out);
}

std::size_t Encoder::odometry(const Odometry& m, FrameBuffer& out) {
  // Wire order: fields by size (largest first), then the extensions in declaration order.
  Payload p(out.data() + kHeaderBytes);
  p.u64(m.time_usec);
  p.f32(m.x);
  p.f32(m.y);
  p.f32(m.z);
  for (float v : m.q) p.f32(v);
  p.f32(m.vx);
  p.f32(m.vy);
  p.f32(m.vz);
  p.f32(m.rollspeed);
  p.f32(m.pitchspeed);
  p.f32(m.yawspeed);
  for (float v : m.pose_covariance) p.f32(v);
  for (float v : m.velocity_covariance) p.f32(v);
  p.u8(m.frame_id);
  p.u8(m.child_frame_id);
  p.u8(m.reset_counter);
  p.u8(m.estimator_type);
  p.u8(static_cast<std::uint8_t>(m.quality));
  return finish(kMsgOdometry, kCrcExtraOdometry, p.size(), out);
}

std::size_t Encoder::command_ack(const CommandAck& m, FrameBuffer& out) {
  Payload p(out.data() + kHeaderBytes);
  p.u16(m.command);
  p.u8(static_cast<std::uint8_t>(m.result));
  p.u8(m.progress);  // extensions from here on, in declaration order
  p.u32(static_cast<std::uint32_t>(m.result_param2));
  p.u8(m.target_system);
  p.u8(m.target_component);
  return finish(kMsgCommandAck, kCrcExtraCommandAck, p.size(), out);
}

std::size_t Encoder::timesync(const Timesync& m, FrameBuffer& out) {
  Payload p(out.data() + kHeaderBytes);
  p.u64(static_cast<std::uint64_t>(m.tc1));
  p.u64(static_cast<std::uint64_t>(m.ts1));
  p.u8(m.target_system);  // extensions
  p.u8(m.target_component);
  return finish(kMsgTimesync, kCrcExtraTimesync, p.size(), out);
}

std::size_t Encoder::named_value_float(std::uint32_t time_boot_ms, const char* name, float value,
                                       FrameBuffer& out) {
  Payload p(out.data() + kHeaderBytes);
  p.u32(time_boot_ms);
  p.f32(value);
  std::size_t n = 0;
  for (; n < kNamedValueNameBytes && name[n] != '\0'; ++n) p.u8(static_cast<std::uint8_t>(name[n]));
  for (; n < kNamedValueNameBytes; ++n) p.u8(0);
  return finish(kMsgNamedValueFloat, kCrcExtraNamedValueFloat, p.size(), out);
}

std::size_t Encoder::command_long(std::uint16_t command, const std::array<float, 7>& params,
                                  std::uint8_t target_system, std::uint8_t target_component,
                                  FrameBuffer& out) {
  Payload p(out.data() + kHeaderBytes);
  for (const float v : params) p.f32(v);
  p.u16(command);
  p.u8(target_system);
  p.u8(target_component);
  p.u8(0);  // confirmation
  return finish(kMsgCommandLong, kCrcExtraCommandLong, p.size(), out);
}

std::size_t Encoder::statustext(std::uint8_t severity, const char* text, FrameBuffer& out) {
  Payload p(out.data() + kHeaderBytes);
  p.u8(severity);
  std::size_t n = 0;
  for (; n < 50 && text[n] != '\0'; ++n) p.u8(static_cast<std::uint8_t>(text[n]));
  for (; n < 50; ++n) p.u8(0);
  p.u16(0);  // id: 0 = not part of a multi-chunk message
  p.u8(0);   // chunk_seq
  return finish(kMsgStatustext, kCrcExtraStatustext, p.size(), out);
}

}  // namespace harmoloc::firmware::mavlink
