// MAVLink v2 framing: the checksum, a HEARTBEAT built by hand byte for byte, ODOMETRY's field
// layout and zero truncation, sequence numbers, STATUSTEXT.
#include "harmoloc/firmware/mavlink_v2.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

namespace mv = harmoloc::firmware::mavlink;

namespace {

// CRC-16/MCRF4XX written independently: bitwise, reflected polynomial 0x8408, init 0xFFFF.
std::uint16_t bitwise_crc(const std::uint8_t* p, std::size_t n, std::uint16_t crc = 0xFFFF) {
  for (std::size_t i = 0; i < n; ++i) {
    crc = static_cast<std::uint16_t>(crc ^ p[i]);
    for (int b = 0; b < 8; ++b) {
      crc = (crc & 1U) != 0U ? static_cast<std::uint16_t>((crc >> 1U) ^ 0x8408U)
                             : static_cast<std::uint16_t>(crc >> 1U);
    }
  }
  return crc;
}

// Checks the frame's structure and checksum (with @p crc_extra) and returns its payload.
std::vector<std::uint8_t> check_frame(const mv::FrameBuffer& f, std::size_t size,
                                      std::uint32_t msg_id, std::uint8_t crc_extra) {
  EXPECT_GE(size, mv::kHeaderBytes + 1 + mv::kChecksumBytes);
  EXPECT_EQ(f[0], 0xFD);
  const std::size_t len = f[1];
  EXPECT_EQ(size, mv::kHeaderBytes + len + mv::kChecksumBytes);
  EXPECT_GE(len, 1U);
  EXPECT_EQ(f[2], 0);  // incompat flags: no signature
  EXPECT_EQ(f[3], 0);
  EXPECT_EQ(f[7] | (f[8] << 8U) | (f[9] << 16U), static_cast<int>(msg_id));
  std::uint16_t crc = bitwise_crc(f.data() + 1, mv::kHeaderBytes - 1 + len);
  crc = bitwise_crc(&crc_extra, 1, crc);
  EXPECT_EQ(f[mv::kHeaderBytes + len], crc & 0xFFU);
  EXPECT_EQ(f[mv::kHeaderBytes + len + 1], crc >> 8U);
  return std::vector<std::uint8_t>(f.begin() + mv::kHeaderBytes,
                                   f.begin() + static_cast<std::ptrdiff_t>(mv::kHeaderBytes + len));
}

float f32_at(const std::vector<std::uint8_t>& p, std::size_t at) {
  // Truncated zeros read back as zero, as a receiver does.
  std::uint8_t b[4] = {0, 0, 0, 0};
  for (std::size_t i = 0; i < 4; ++i) b[i] = at + i < p.size() ? p[at + i] : 0;
  std::uint32_t u = static_cast<std::uint32_t>(b[0]) | static_cast<std::uint32_t>(b[1]) << 8U |
                    static_cast<std::uint32_t>(b[2]) << 16U |
                    static_cast<std::uint32_t>(b[3]) << 24U;
  float f = 0.0F;
  std::memcpy(&f, &u, 4);
  return f;
}

}  // namespace

TEST(Mavlink, CrcX25CheckValue) {
  const std::string s = "123456789";
  const auto* p = reinterpret_cast<const std::uint8_t*>(s.data());
  EXPECT_EQ(mv::crc_x25(p, s.size()), 0x6F91);
  EXPECT_EQ(bitwise_crc(p, s.size()), 0x6F91);
  EXPECT_EQ(mv::crc_x25(p, 0), 0xFFFF);
  EXPECT_EQ(mv::crc_x25(p + 3, 6, mv::crc_x25(p, 3)), 0x6F91);  // accumulates
}

TEST(Mavlink, HeartbeatBytesByHand) {
  mv::Encoder enc(1, 197);
  mv::Heartbeat hb;
  hb.custom_mode = 0x01020304;
  hb.type = mv::kMavTypeOnboardController;  // 18
  hb.autopilot = mv::kMavAutopilotInvalid;  // 8
  hb.base_mode = 0;
  hb.system_status = mv::kMavStateActive;  // 4
  hb.mavlink_version = 3;
  mv::FrameBuffer f{};
  const std::size_t n = enc.heartbeat(hb, f);
  std::vector<std::uint8_t> expected = {0xFD,
                                        9,
                                        0,
                                        0,
                                        0 /*seq*/,
                                        1 /*sysid*/,
                                        197 /*compid*/,
                                        0,
                                        0,
                                        0 /*msgid 0*/,
                                        0x04,
                                        0x03,
                                        0x02,
                                        0x01 /*custom_mode LE*/,
                                        18,
                                        8,
                                        0,
                                        4,
                                        3};
  // X.25 over everything after STX, then the message's CRC_EXTRA (50 for HEARTBEAT).
  std::uint16_t crc = bitwise_crc(expected.data() + 1, expected.size() - 1);
  const std::uint8_t extra = 50;
  crc = bitwise_crc(&extra, 1, crc);
  expected.push_back(static_cast<std::uint8_t>(crc & 0xFFU));
  expected.push_back(static_cast<std::uint8_t>(crc >> 8U));
  ASSERT_EQ(n, expected.size());
  EXPECT_EQ(std::vector<std::uint8_t>(f.begin(), f.begin() + static_cast<std::ptrdiff_t>(n)),
            expected);
}

TEST(Mavlink, HeartbeatOfZerosKeepsOnePayloadByte) {
  mv::Encoder enc(1, 1);
  mv::Heartbeat hb;
  hb.type = 0;
  hb.autopilot = 0;
  hb.system_status = 0;
  hb.mavlink_version = 0;
  mv::FrameBuffer f{};
  const std::size_t n = enc.heartbeat(hb, f);
  EXPECT_EQ(f[1], 1);  // never an empty payload
  EXPECT_EQ(n, mv::kHeaderBytes + 1 + mv::kChecksumBytes);
  const auto payload = check_frame(f, n, mv::kMsgHeartbeat, 50);
  EXPECT_EQ(payload, std::vector<std::uint8_t>{0});
  // Zeros in the middle stay; only the tail is cut.
  hb.custom_mode = 0x00000100;
  const std::size_t n2 = enc.heartbeat(hb, f);
  EXPECT_EQ(f[1], 2);
  EXPECT_EQ(check_frame(f, n2, mv::kMsgHeartbeat, 50), (std::vector<std::uint8_t>{0x00, 0x01}));
}

TEST(Mavlink, OdometryFieldLayout) {
  mv::Encoder enc(3, 197);
  mv::Odometry m;
  m.time_usec = 0x1122334455667788ULL;
  m.x = 1.0F;
  m.y = 2.0F;
  m.z = 3.0F;
  m.q = {0.5F, 0.25F, 0.125F, 0.0625F};
  m.vx = 4.0F;
  m.vy = 5.0F;
  m.vz = 6.0F;
  m.rollspeed = 7.0F;
  m.pitchspeed = 8.0F;
  m.yawspeed = 9.0F;
  for (std::size_t i = 0; i < 21; ++i) {
    m.pose_covariance[i] = 100.0F + static_cast<float>(i);
    m.velocity_covariance[i] = 200.0F + static_cast<float>(i);
  }
  m.frame_id = mv::kMavFrameLocalFrd;
  m.child_frame_id = mv::kMavFrameBodyFrd;
  m.reset_counter = 9;
  m.estimator_type = mv::kMavEstimatorTypeVision;
  m.quality = 77;
  mv::FrameBuffer f{};
  const std::size_t n = enc.odometry(m, f);
  const auto p = check_frame(f, n, mv::kMsgOdometry, 91);
  ASSERT_EQ(p.size(), 233U);  // 230 base bytes + 3 extension bytes
  // msgid 331 = 0x00014B, little endian in the header.
  EXPECT_EQ(f[7], 0x4B);
  EXPECT_EQ(f[8], 0x01);
  EXPECT_EQ(f[9], 0x00);
  // Fields sorted by size (uint64, then floats, then uint8), extensions last in declaration order.
  for (std::size_t i = 0; i < 8; ++i)
    EXPECT_EQ(p[i], static_cast<std::uint8_t>(m.time_usec >> (8 * i))) << i;
  EXPECT_EQ(f32_at(p, 8), 1.0F);
  EXPECT_EQ(f32_at(p, 12), 2.0F);
  EXPECT_EQ(f32_at(p, 16), 3.0F);
  EXPECT_EQ(f32_at(p, 20), 0.5F);
  EXPECT_EQ(f32_at(p, 32), 0.0625F);
  EXPECT_EQ(f32_at(p, 36), 4.0F);
  EXPECT_EQ(f32_at(p, 44), 6.0F);
  EXPECT_EQ(f32_at(p, 48), 7.0F);
  EXPECT_EQ(f32_at(p, 56), 9.0F);
  EXPECT_EQ(f32_at(p, 60), 100.0F);
  EXPECT_EQ(f32_at(p, 60 + 20 * 4), 120.0F);
  EXPECT_EQ(f32_at(p, 144), 200.0F);
  EXPECT_EQ(f32_at(p, 144 + 20 * 4), 220.0F);
  EXPECT_EQ(p[228], mv::kMavFrameLocalFrd);
  EXPECT_EQ(p[229], mv::kMavFrameBodyFrd);
  EXPECT_EQ(p[230], 9);
  EXPECT_EQ(p[231], mv::kMavEstimatorTypeVision);
  EXPECT_EQ(p[232], 77);
}

TEST(Mavlink, OdometryZeroTruncation) {
  mv::Encoder enc(1, 197);
  mv::FrameBuffer f{};
  mv::Odometry m;  // quality 0: the last byte is cut, estimator_type (2) stays
  std::size_t n = enc.odometry(m, f);
  EXPECT_EQ(check_frame(f, n, mv::kMsgOdometry, 91).size(), 232U);
  m.estimator_type = 0;  // reset_counter, estimator_type and quality all 0: the extensions go
  n = enc.odometry(m, f);
  EXPECT_EQ(check_frame(f, n, mv::kMsgOdometry, 91).size(), 230U);
  m.quality = -1;  // 0xFF: all 233 bytes
  n = enc.odometry(m, f);
  auto p = check_frame(f, n, mv::kMsgOdometry, 91);
  ASSERT_EQ(p.size(), 233U);
  EXPECT_EQ(p[232], 0xFF);
  // Everything zero (frame ids too): one byte stays.
  mv::Odometry zero;
  zero.frame_id = 0;
  zero.child_frame_id = 0;
  zero.q = {0, 0, 0, 0};
  zero.estimator_type = 0;
  n = enc.odometry(zero, f);
  EXPECT_EQ(check_frame(f, n, mv::kMsgOdometry, 91).size(), 1U);
  // A pose with values: the covariances' zeros in the middle are kept.
  zero.x = 1.5F;
  n = enc.odometry(zero, f);
  p = check_frame(f, n, mv::kMsgOdometry, 91);
  EXPECT_EQ(p.size(), 12U);  // up to the last non-zero byte of x (bytes 8..11, 1.5f = 0x3FC00000)
  EXPECT_EQ(f32_at(p, 8), 1.5F);
}

TEST(Mavlink, SequenceIncrementsAndWrapsAcrossMessageTypes) {
  mv::Encoder enc(1, 197);
  mv::FrameBuffer f{};
  for (int i = 0; i < 600; ++i) {
    switch (i % 3) {
      case 0:
        enc.heartbeat(mv::Heartbeat{}, f);
        break;
      case 1:
        enc.odometry(mv::Odometry{}, f);
        break;
      default:
        enc.statustext(mv::kSeverityInfo, "x", f);
        break;
    }
    ASSERT_EQ(f[4], static_cast<std::uint8_t>(i & 0xFF)) << i;
    ASSERT_EQ(f[5], 1);
    ASSERT_EQ(f[6], 197);
  }
  // Each encoder counts on its own.
  mv::Encoder other(2, 5);
  other.heartbeat(mv::Heartbeat{}, f);
  EXPECT_EQ(f[4], 0);
  EXPECT_EQ(f[5], 2);
  EXPECT_EQ(f[6], 5);
}

TEST(Mavlink, StatustextCutAtFiftyCharacters) {
  mv::Encoder enc(1, 197);
  mv::FrameBuffer f{};
  const std::string long_text =
      "0123456789abcdefghijABCDEFGHIJ0123456789klmnopqrstUVWXYZ-this-part-is-cut";
  std::size_t n = enc.statustext(mv::kSeverityWarning, long_text.c_str(), f);
  auto p = check_frame(f, n, mv::kMsgStatustext, 83);
  // severity, 50 characters, then id (uint16) and chunk_seq: zeros, truncated away.
  ASSERT_EQ(p.size(), 51U);
  EXPECT_EQ(p[0], mv::kSeverityWarning);
  EXPECT_EQ(std::string(p.begin() + 1, p.end()), long_text.substr(0, 50));

  n = enc.statustext(mv::kSeverityCritical, "camera lost", f);
  p = check_frame(f, n, mv::kMsgStatustext, 83);
  ASSERT_EQ(p.size(), 1U + 11U);
  EXPECT_EQ(p[0], mv::kSeverityCritical);
  EXPECT_EQ(std::string(p.begin() + 1, p.end()), "camera lost");

  n = enc.statustext(mv::kSeverityInfo, "", f);
  p = check_frame(f, n, mv::kMsgStatustext, 83);
  EXPECT_EQ(p, std::vector<std::uint8_t>{mv::kSeverityInfo});

  const std::string exactly50(50, 'z');
  n = enc.statustext(mv::kSeverityInfo, exactly50.c_str(), f);
  p = check_frame(f, n, mv::kMsgStatustext, 83);
  EXPECT_EQ(p.size(), 51U);
}
