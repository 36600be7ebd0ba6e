// MAVLink v2 frames built and read for the tests, written apart from the firmware's encoder and
// parser (bitwise checksum, the signed bytes assembled here), so that a test compares two
// implementations. SHA-256 itself is libnettle's. Also a link fake with an inbound queue.
#pragma once

#include <gtest/gtest.h>
#include <nettle/sha2.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <deque>
#include <map>
#include <vector>

#include "harmoloc/hal/pose_link.hpp"

namespace harmoloc::test::mav {

using Bytes = std::vector<std::uint8_t>;
using Key = std::array<std::uint8_t, 32>;

inline std::uint16_t crc16(const std::uint8_t* p, std::size_t n, std::uint16_t crc = 0xFFFF) {
  for (std::size_t i = 0; i < n; ++i) {
    crc = static_cast<std::uint16_t>(crc ^ p[i]);
    for (int b = 0; b < 8; ++b) {
      crc = (crc & 1U) != 0U ? static_cast<std::uint16_t>((crc >> 1U) ^ 0x8408U)
                             : static_cast<std::uint16_t>(crc >> 1U);
    }
  }
  return crc;
}

/// CRC_EXTRA of the messages the tests send or read.
inline std::uint8_t crc_extra(std::uint32_t msg_id) {
  static const std::map<std::uint32_t, std::uint8_t> extras = {
      {0, 50}, {76, 152}, {77, 143}, {253, 83}, {331, 91}, {75, 158}, {111, 34}, {251, 170}};
  const auto it = extras.find(msg_id);
  return it == extras.end() ? 0 : it->second;
}

/// A whole frame. The payload's trailing zeros are trimmed (one byte stays) unless @p trim is
/// false; @p incompat 0x01 marks it signed (append the block with sign()).
inline Bytes frame(std::uint32_t msg_id, Bytes payload, std::uint8_t system_id = 255,
                   std::uint8_t component_id = 190, std::uint8_t seq = 0, std::uint8_t incompat = 0,
                   bool trim = true) {
  if (trim) {
    while (payload.size() > 1 && payload.back() == 0) payload.pop_back();
  }
  // Sized once and filled by index (inserting into a braced-initialised vector trips a false
  // -Warray-bounds in GCC 12).
  Bytes f(10 + payload.size());
  const std::uint8_t header[10] = {0xFD,
                                   static_cast<std::uint8_t>(payload.size()),
                                   incompat,
                                   0,
                                   seq,
                                   system_id,
                                   component_id,
                                   static_cast<std::uint8_t>(msg_id),
                                   static_cast<std::uint8_t>(msg_id >> 8U),
                                   static_cast<std::uint8_t>(msg_id >> 16U)};
  std::copy(header, header + 10, f.begin());
  std::copy(payload.begin(), payload.end(), f.begin() + 10);
  std::uint16_t crc = crc16(f.data() + 1, f.size() - 1);
  const std::uint8_t extra = crc_extra(msg_id);
  crc = crc16(&extra, 1, crc);
  f.push_back(static_cast<std::uint8_t>(crc));
  f.push_back(static_cast<std::uint8_t>(crc >> 8U));
  return f;
}

inline void put_f32(Bytes& p, float v) {
  std::uint32_t u = 0;
  std::memcpy(&u, &v, 4);
  for (int i = 0; i < 4; ++i) p.push_back(static_cast<std::uint8_t>(u >> (8 * i)));
}

inline Bytes command_long_payload(std::uint16_t command, const std::array<float, 7>& params,
                                  std::uint8_t target_system, std::uint8_t target_component,
                                  std::uint8_t confirmation = 0) {
  Bytes p;
  for (float v : params) put_f32(p, v);
  p.push_back(static_cast<std::uint8_t>(command));
  p.push_back(static_cast<std::uint8_t>(command >> 8U));
  p.push_back(target_system);
  p.push_back(target_component);
  p.push_back(confirmation);
  return p;
}

/// COMMAND_LONG to system 1 / component 197 (the firmware's defaults) from @p system_id /
/// @p component_id; signed with @p key at @p timestamp when @p key is given.
inline Bytes command(std::uint16_t cmd, const std::array<float, 7>& params,
                     std::uint8_t system_id = 255, std::uint8_t component_id = 190,
                     const Key* key = nullptr, std::uint64_t timestamp = 0,
                     std::uint8_t link_id = 0, std::uint8_t target_system = 1,
                     std::uint8_t target_component = 197, std::uint8_t seq = 0);

/// SHA-256(key + bytes), first 6 bytes.
inline std::array<std::uint8_t, 6> sha256_48(const Key& key, const std::uint8_t* bytes,
                                             std::size_t n) {
  sha256_ctx ctx;
  sha256_init(&ctx);
  sha256_update(&ctx, key.size(), key.data());
  sha256_update(&ctx, n, bytes);
  std::array<std::uint8_t, SHA256_DIGEST_SIZE> d{};
  sha256_digest(&ctx, d.size(), d.data());
  return {d[0], d[1], d[2], d[3], d[4], d[5]};
}

/// Appends the signature block to a frame built with incompat 0x01.
inline void sign(Bytes& f, const Key& key, std::uint8_t link_id, std::uint64_t timestamp) {
  f.push_back(link_id);
  for (int i = 0; i < 6; ++i) f.push_back(static_cast<std::uint8_t>(timestamp >> (8 * i)));
  const auto h = sha256_48(key, f.data(), f.size());
  f.insert(f.end(), h.begin(), h.end());
}

inline Bytes command(std::uint16_t cmd, const std::array<float, 7>& params, std::uint8_t system_id,
                     std::uint8_t component_id, const Key* key, std::uint64_t timestamp,
                     std::uint8_t link_id, std::uint8_t target_system,
                     std::uint8_t target_component, std::uint8_t seq) {
  Bytes f = frame(76, command_long_payload(cmd, params, target_system, target_component), system_id,
                  component_id, seq, key != nullptr ? 0x01 : 0x00);
  if (key != nullptr) sign(f, *key, link_id, timestamp);
  return f;
}

/// A TIMESYNC frame (tc1, ts1, then the extension's target system and component) from
/// @p system_id / @p component_id, signed with @p key at @p timestamp when given.
inline Bytes timesync(std::int64_t tc1, std::int64_t ts1, std::uint8_t target_system = 0,
                      std::uint8_t target_component = 0, std::uint8_t system_id = 1,
                      std::uint8_t component_id = 1, const Key* key = nullptr,
                      std::uint64_t timestamp = 0) {
  Bytes p;
  for (const std::int64_t v : {tc1, ts1})
    for (int i = 0; i < 8; ++i)
      p.push_back(static_cast<std::uint8_t>(static_cast<std::uint64_t>(v) >> (8 * i)));
  p.push_back(target_system);
  p.push_back(target_component);
  Bytes f = frame(111, p, system_id, component_id, 0, key != nullptr ? 0x01 : 0x00);
  if (key != nullptr) sign(f, *key, 0, timestamp);
  return f;
}

/// A TIMESYNC read back: tc1, ts1, target system and component.
inline std::int64_t i64(const Bytes& p, std::size_t at) {
  std::uint64_t u = 0;
  for (std::size_t i = 0; i < 8 && at + i < p.size(); ++i)
    u |= static_cast<std::uint64_t>(p[at + i]) << (8 * i);
  return static_cast<std::int64_t>(u);
}

/// One frame read back from a byte stream.
struct Decoded {
  std::uint32_t msg_id = 0;
  std::uint8_t system_id = 0;
  std::uint8_t component_id = 0;
  std::uint8_t seq = 0;
  bool is_signed = false;
  bool signature_ok = false;  ///< when a key was given to decode()
  std::uint8_t link_id = 0;
  std::uint64_t timestamp = 0;
  Bytes payload;  ///< zero-extended to 255 bytes
};

/// Reads back a stream of well-formed frames (the firmware's output): fails the test on a bad
/// checksum or a byte outside a frame. Checks signatures with @p key when given.
inline std::vector<Decoded> decode(const Bytes& s, const Key* key = nullptr) {
  std::vector<Decoded> out;
  std::size_t i = 0;
  while (i < s.size()) {
    EXPECT_EQ(s[i], 0xFD) << "byte " << i << " outside a frame";
    if (s[i] != 0xFD || i + 12 > s.size()) break;
    Decoded d;
    const std::size_t len = s[i + 1];
    d.is_signed = (s[i + 2] & 1U) != 0;
    d.seq = s[i + 4];
    d.system_id = s[i + 5];
    d.component_id = s[i + 6];
    d.msg_id = s[i + 7] | (s[i + 8] << 8U) | (s[i + 9] << 16U);
    const std::size_t size = 12 + len + (d.is_signed ? 13 : 0);
    EXPECT_LE(i + size, s.size());
    if (i + size > s.size()) break;
    std::uint16_t crc = crc16(s.data() + i + 1, 9 + len);
    const std::uint8_t extra = crc_extra(d.msg_id);
    crc = crc16(&extra, 1, crc);
    EXPECT_EQ(s[i + 10 + len] | (s[i + 11 + len] << 8U), crc) << "msg " << d.msg_id;
    d.payload.assign(s.begin() + static_cast<std::ptrdiff_t>(i + 10),
                     s.begin() + static_cast<std::ptrdiff_t>(i + 10 + len));
    d.payload.resize(255, 0);
    if (d.is_signed) {
      const std::size_t b = i + 12 + len;
      d.link_id = s[b];
      for (int k = 5; k >= 0; --k) d.timestamp = (d.timestamp << 8U) | s[b + 1 + k];
      if (key != nullptr) {
        const auto h = sha256_48(*key, s.data() + i, 12 + len + 7);
        d.signature_ok =
            std::equal(h.begin(), h.end(), s.begin() + static_cast<std::ptrdiff_t>(b + 7));
      }
    }
    out.push_back(d);
    i += size;
  }
  return out;
}

inline float f32(const Bytes& p, std::size_t at) {
  std::uint32_t u =
      static_cast<std::uint32_t>(p[at]) | static_cast<std::uint32_t>(p[at + 1]) << 8U |
      static_cast<std::uint32_t>(p[at + 2]) << 16U | static_cast<std::uint32_t>(p[at + 3]) << 24U;
  float f = 0.0F;
  std::memcpy(&f, &u, 4);
  return f;
}

/// COMMAND_ACK fields.
struct Ack {
  std::uint16_t command;
  std::uint8_t result;
  std::int32_t result_param2;
  std::uint8_t target_system;
  std::uint8_t target_component;
};
inline Ack ack_of(const Decoded& d) {
  const Bytes& p = d.payload;
  std::int32_t param2 = 0;
  const std::uint32_t u =
      static_cast<std::uint32_t>(p[4]) | static_cast<std::uint32_t>(p[5]) << 8U |
      static_cast<std::uint32_t>(p[6]) << 16U | static_cast<std::uint32_t>(p[7]) << 24U;
  std::memcpy(&param2, &u, 4);
  return Ack{static_cast<std::uint16_t>(p[0] | (p[1] << 8U)), p[2], param2, p[8], p[9]};
}

/// A link whose peer side is a byte queue (what the peer sent) and a byte log (what the
/// firmware wrote). read_bytes() hands out at most @p chunk bytes a call.
class QueueLink final : public hal::PoseLink {
 public:
  hal::LinkWrite write_frame(const std::uint8_t* bytes, std::size_t size) override {
    written.insert(written.end(), bytes, bytes + size);
    ++counters_.frames_sent;
    counters_.bytes_sent += size;
    return hal::LinkWrite::kSent;
  }
  hal::LinkCounters counters() const override { return counters_; }
  std::size_t read_bytes(std::uint8_t* dst, std::size_t max) override {
    ++reads;
    if (max > largest_request) largest_request = max;
    std::size_t n = 0;
    while (n < max && n < chunk && !inbound.empty()) {
      dst[n++] = inbound.front();
      inbound.pop_front();
    }
    bytes_read += n;
    return n;
  }
  void send(const Bytes& b) { inbound.insert(inbound.end(), b.begin(), b.end()); }

  std::deque<std::uint8_t> inbound;
  Bytes written;
  std::size_t chunk = 1 << 20;
  std::size_t reads = 0;
  std::size_t largest_request = 0;
  std::size_t bytes_read = 0;

 private:
  hal::LinkCounters counters_{};
};

}  // namespace harmoloc::test::mav
