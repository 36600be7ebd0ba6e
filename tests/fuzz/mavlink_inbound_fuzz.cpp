// libFuzzer target: the link's inbound side. Bytes from the peer go through the frame parser,
// the command receiver (target, source, signature and replay checks), the dispatcher's reading
// of each command (read_set_pose, read_request_message) and the signed COMMAND_ACK sent back.
//
// Input: one mode byte (bit 0: a signing key is configured; bit 1: structured; bits 2-4: how many
// bytes the line delivers a read), then either the raw bytes of the line, or a program that
// builds it: garbage, commands (valid, wrongly signed, unsigned, from other sources, to other
// targets, with replayed or stale timestamps, corrupted), other messages and false start bytes.
// The structured mode gets the fuzzer past checksums and signatures, as map_decode does with the
// map's CRC.
//
// Checked: per-cycle limits (bytes read, commands); at most one TIMESYNC request taken a cycle,
// none more than the receiver counted; every admitted command is a COMMAND_LONG with
// a valid checksum, from an accepted source, to us, and with a key, signed with it and newer than
// its stream's last; every frame is counted once (bytes and frames add up); an accepted "set pose"
// is finite and in range; every ACK sent is one valid frame, signed iff there is a key, and the
// whole outbound stream passes our own inbound signature and replay checks.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <map>
#include <tuple>
#include <vector>

#include "fuzz_common.hpp"
#include "harmoloc/firmware/config.hpp"
#include "harmoloc/firmware/mavlink_inbound.hpp"
#include "harmoloc/firmware/mavlink_parser.hpp"
#include "harmoloc/firmware/mavlink_signing.hpp"
#include "harmoloc/firmware/mavlink_v2.hpp"
#include "harmoloc/hal/pose_link.hpp"

namespace {

namespace mv = harmoloc::firmware::mavlink;
using Bytes = std::vector<std::uint8_t>;

constexpr std::uint64_t kBaseTimestamp = 1'000'000'000;  // the signing clock at the start
constexpr std::uint64_t kCycleNs = 33'333'333;

mv::SigningKey make_key(std::uint8_t seed) {
  mv::SigningKey k{};
  for (std::size_t i = 0; i < k.size(); ++i) k[i] = static_cast<std::uint8_t>(seed + 31 * i);
  return k;
}
const mv::SigningKey kKey = make_key(11);
const mv::SigningKey kWrongKey = make_key(12);

// Checks each frame the firmware sends: one valid COMMAND_ACK, signed iff there is a key, and,
// with a key, accepted by a Signer's inbound checks (signature and replay) in order.
class FuzzLink final : public harmoloc::hal::PoseLink {
 public:
  FuzzLink(const Bytes& in, std::size_t chunk, bool keyed) : in_(in), chunk_(chunk), keyed_(keyed) {
    // The checker is a peer without a clock of its own: it takes its time from our first frame
    // (else it would find our timestamps too far ahead of its clock at 0).
    mv::SigningOptions peer;
    peer.peer_clock = true;
    if (keyed) checker_.configure(kKey, 0, peer);
  }
  harmoloc::hal::LinkWrite write_frame(const std::uint8_t* bytes, std::size_t size) override {
    mv::FrameParser p;
    HARMOLOC_FUZZ_CHECK(p.push(bytes, size) == size, "an ACK larger than the parser's window");
    mv::RxFrame f;
    std::size_t work = 1U << 20U;
    HARMOLOC_FUZZ_CHECK(p.next(f, work), "an ACK the parser does not take");
    HARMOLOC_FUZZ_CHECK(f.size == size && p.buffered() == 0, "an ACK that is not one frame");
    HARMOLOC_FUZZ_CHECK(f.msg_id == mv::kMsgCommandAck, "sent something other than an ACK");
    HARMOLOC_FUZZ_CHECK(f.is_signed() == keyed_, "ACK signed without a key or unsigned with one");
    if (keyed_) {
      HARMOLOC_FUZZ_CHECK(checker_.verify(bytes, size) == mv::SignatureCheck::kAccepted,
                          "our own signed ACK fails our signature or replay check");
    }
    ++acks;
    return harmoloc::hal::LinkWrite::kSent;
  }
  harmoloc::hal::LinkCounters counters() const override { return {}; }
  std::size_t read_bytes(std::uint8_t* dst, std::size_t max) override {
    const std::size_t n = std::min({max, chunk_, in_.size() - pos_});
    if (n > 0) std::memcpy(dst, in_.data() + pos_, n);
    pos_ += n;
    read_this_cycle += n;
    return n;
  }
  bool drained() const { return pos_ == in_.size(); }

  std::size_t read_this_cycle = 0;
  std::size_t acks = 0;

 private:
  const Bytes& in_;
  std::size_t chunk_;
  std::size_t pos_ = 0;
  bool keyed_;
  mv::Signer checker_;
};

// Reads the structured program; past the end, every value is 0.
class Reader {
 public:
  Reader(const std::uint8_t* d, std::size_t n) : d_(d), n_(n) {}
  bool more() const { return i_ < n_; }
  std::uint8_t u8() { return i_ < n_ ? d_[i_++] : 0; }
  std::uint16_t u16() { return static_cast<std::uint16_t>(u8() | (u8() << 8U)); }
  std::uint32_t u32() {
    return static_cast<std::uint32_t>(u16()) | static_cast<std::uint32_t>(u16()) << 16U;
  }

 private:
  const std::uint8_t* d_;
  std::size_t n_;
  std::size_t i_ = 0;
};

Bytes frame(std::uint32_t msg_id, Bytes payload, std::uint8_t sys, std::uint8_t comp,
            const mv::SigningKey* key, std::uint64_t timestamp, std::uint8_t link_id) {
  while (payload.size() > 1 && payload.back() == 0) payload.pop_back();
  if (payload.empty()) payload.push_back(0);
  Bytes f = {0xFD,
             static_cast<std::uint8_t>(payload.size()),
             static_cast<std::uint8_t>(key != nullptr ? mv::kIncompatSigned : 0),
             0,
             0,
             sys,
             comp,
             static_cast<std::uint8_t>(msg_id),
             static_cast<std::uint8_t>(msg_id >> 8U),
             static_cast<std::uint8_t>(msg_id >> 16U)};
  f.insert(f.end(), payload.begin(), payload.end());
  const mv::MessageInfo* info = mv::message_info(msg_id);
  const std::uint8_t extra = info != nullptr ? info->crc_extra : 0;
  std::uint16_t crc = mv::crc_x25(f.data() + 1, f.size() - 1);
  crc = mv::crc_x25(&extra, 1, crc);
  f.push_back(static_cast<std::uint8_t>(crc));
  f.push_back(static_cast<std::uint8_t>(crc >> 8U));
  if (key != nullptr) {
    f.push_back(link_id);
    for (int i = 0; i < 6; ++i) f.push_back(static_cast<std::uint8_t>(timestamp >> (8 * i)));
    const auto h = mv::signature_hash(*key, f.data(), f.size());
    f.insert(f.end(), h.begin(), h.end());
  }
  return f;
}

float interesting_float(Reader& r) {
  static const float kValues[] = {0.0F,   -0.0F,    1.0F,      -1.0F,       0.5F,        3.1416F,
                                  331.0F, 512.0F,   1e4F,      1.0001e4F,   1e30F,       1e-30F,
                                  NAN,    INFINITY, -INFINITY, 16777215.0F, 16777216.0F, 10.0F};
  switch (r.u8() % 3) {
    case 0:
      return 0.0F;
    case 1: {
      const std::uint32_t u = r.u32();
      float f = 0.0F;
      std::memcpy(&f, &u, 4);
      return f;
    }
    default:
      return kValues[r.u8() % (sizeof kValues / sizeof kValues[0])];
  }
}

Bytes build_stream(Reader& r) {
  Bytes out;
  Bytes last;
  std::uint64_t ts = kBaseTimestamp;
  static const std::uint32_t kOther[] = {0, 1, 75, 77, 253, 331, 256, 110, 111};
  while (r.more() && out.size() < 65536) {
    switch (r.u8() % 6) {
      case 0: {  // raw bytes
        const std::size_t n = r.u8();
        for (std::size_t i = 0; i < n && r.more(); ++i) out.push_back(r.u8());
        break;
      }
      case 1: {  // a command
        const std::uint8_t s = r.u8();
        const std::uint8_t sys = (s & 3U) == 0   ? 255
                                 : (s & 3U) == 1 ? 254
                                 : (s & 3U) == 2 ? 42
                                                 : r.u8();
        const std::uint8_t comp = ((s >> 2U) & 1U) == 0 ? 190 : r.u8();
        static const std::uint8_t kTargets[4][2] = {{1, 197}, {1, 0}, {2, 197}, {1, 5}};
        const auto* t = kTargets[(s >> 3U) & 3U];
        static const std::uint16_t kCommands[] = {31010, 31011, 512, 400};
        const std::uint8_t c = r.u8();
        const std::uint16_t command = (c & 7U) < 4 ? kCommands[c & 3U] : r.u16();
        Bytes p;
        for (int i = 0; i < 7; ++i) {
          const float v = interesting_float(r);
          std::uint32_t u = 0;
          std::memcpy(&u, &v, 4);
          for (int k = 0; k < 4; ++k) p.push_back(static_cast<std::uint8_t>(u >> (8 * k)));
        }
        p.push_back(static_cast<std::uint8_t>(command));
        p.push_back(static_cast<std::uint8_t>(command >> 8U));
        p.push_back(t[0]);
        p.push_back(t[1]);
        p.push_back(r.u8());  // confirmation
        const std::uint8_t how = r.u8();
        const mv::SigningKey* key = (how & 3U) == 0   ? nullptr
                                    : (how & 3U) == 3 ? &kWrongKey
                                                      : &kKey;
        // Timestamps mostly move on; some go back (replays) or start far behind (stale).
        const auto delta = static_cast<std::int16_t>(r.u16());
        if ((how & 0x30U) == 0x30U) {
          ts = kBaseTimestamp > mv::kReplayWindow ? kBaseTimestamp - mv::kReplayWindow - 1 : 0;
        } else {
          ts = static_cast<std::uint64_t>(
              std::max<std::int64_t>(0, static_cast<std::int64_t>(ts) + delta));
        }
        last = frame(mv::kMsgCommandLong, p, sys, comp, key, ts, (how >> 2U) & 3U);
        if ((how & 0xC0U) == 0xC0U)
          last[r.u8() % last.size()] ^= static_cast<std::uint8_t>(1U << (r.u8() & 7U));
        out.insert(out.end(), last.begin(), last.end());
        break;
      }
      case 2: {  // another message
        const std::uint32_t id = kOther[r.u8() % (sizeof kOther / sizeof kOther[0])];
        const std::size_t len = 1 + r.u8() % mv::message_info(id)->max_payload;
        Bytes p;
        for (std::size_t i = 0; i < len; ++i) p.push_back(r.u8());
        const std::uint8_t how = r.u8();
        const Bytes f = frame(id, p, (how & 1U) != 0 ? 255 : r.u8(), 190,
                              (how & 2U) != 0 ? &kKey : nullptr, ++ts, 0);
        out.insert(out.end(), f.begin(), f.end());
        break;
      }
      case 3:  // the last command again, byte for byte
        out.insert(out.end(), last.begin(), last.end());
        break;
      case 4: {  // the start of the last command only
        const std::size_t n = last.empty() ? 0 : r.u8() % last.size();
        out.insert(out.end(), last.begin(), last.begin() + static_cast<std::ptrdiff_t>(n));
        break;
      }
      default: {  // a false start byte with a checkable header
        const std::uint32_t id = kOther[r.u8() % (sizeof kOther / sizeof kOther[0])];
        const std::uint8_t len =
            static_cast<std::uint8_t>(1 + r.u8() % mv::message_info(id)->max_payload);
        const Bytes h = {0xFD,
                         len,
                         static_cast<std::uint8_t>(r.u8() & 1U),
                         0,
                         0,
                         255,
                         190,
                         static_cast<std::uint8_t>(id),
                         static_cast<std::uint8_t>(id >> 8U),
                         0};
        out.insert(out.end(), h.begin(), h.end());
        break;
      }
    }
  }
  return out;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const std::uint8_t mode = data[0];
  const bool keyed = (mode & 1U) != 0;
  const bool structured = (mode & 2U) != 0;
  static const std::size_t kChunks[8] = {1, 2, 3, 5, 17, 64, 300, 4096};
  const std::size_t chunk = kChunks[(mode >> 2U) & 7U];

  Bytes stream;
  if (structured) {
    Reader r(data + 1, size - 1);
    stream = build_stream(r);
  } else {
    stream.assign(data + 1, data + size);
  }

  harmoloc::firmware::LinkConfig lc;  // we are 1 / 197
  lc.accept_system_ids = {255, 254};
  lc.accept_component_ids = {190};
  mv::Signer signer;
  if (keyed) signer.configure(kKey, 0);
  signer.set_time(kBaseTimestamp, 0);
  mv::CommandReceiver rx(lc, &signer);
  mv::Encoder encoder(1, 197);
  encoder.set_signer(&signer);
  mv::FrameBuffer buffer{};
  FuzzLink link(stream, chunk, keyed);

  std::map<std::tuple<int, int, int>, std::uint64_t> stream_last;
  std::uint64_t admitted = 0;
  std::uint64_t timesyncs = 0;
  std::uint32_t idle = 0;
  for (std::uint64_t cycle = 0; idle < mv::CommandReceiver::kStallCycles + 3; ++cycle) {
    signer.advance(cycle * kCycleNs);
    rx.begin_cycle();
    link.read_this_cycle = 0;
    std::size_t commands = 0;
    mv::CommandLong c;
    while (rx.next_command(link, c)) {
      ++commands;
      ++admitted;
      const mv::RxFrame& f = rx.last_frame();
      HARMOLOC_FUZZ_CHECK(f.msg_id == mv::kMsgCommandLong,
                          "admitted a message that is not a command");
      std::uint16_t crc = mv::crc_x25(f.bytes + 1, mv::kHeaderBytes - 1 + f.payload_length);
      const std::uint8_t extra = mv::kCrcExtraCommandLong;
      crc = mv::crc_x25(&extra, 1, crc);
      HARMOLOC_FUZZ_CHECK(f.bytes[mv::kHeaderBytes + f.payload_length] == (crc & 0xFFU) &&
                              f.bytes[mv::kHeaderBytes + f.payload_length + 1] == (crc >> 8U),
                          "admitted a command with a bad checksum");
      HARMOLOC_FUZZ_CHECK(
          (c.source_system == 255 || c.source_system == 254) && c.source_component == 190,
          "admitted a command from a source not accepted");
      HARMOLOC_FUZZ_CHECK(
          c.target_system == 1 && (c.target_component == 197 || c.target_component == 0),
          "admitted a command for someone else");
      if (keyed) {
        HARMOLOC_FUZZ_CHECK(f.is_signed(), "admitted an unsigned command with a key");
        const auto h = mv::signature_hash(kKey, f.bytes, f.size - mv::kSignatureHashBytes);
        HARMOLOC_FUZZ_CHECK(std::memcmp(h.data(), f.bytes + f.size - 6, 6) == 0,
                            "admitted a command with a wrong signature");
        const std::uint8_t* block = f.bytes + f.size - mv::kSignatureBytes;
        std::uint64_t ts = 0;
        for (int i = 5; i >= 0; --i) ts = (ts << 8U) | block[1 + i];
        const auto [it, fresh] =
            stream_last.try_emplace({f.system_id, f.component_id, block[0]}, ts);
        HARMOLOC_FUZZ_CHECK(fresh || ts > it->second, "admitted a replayed command");
        it->second = ts;
      }
      // The dispatcher's reading of the command, as the cycle does it.
      mv::CommandAck ack;
      ack.command = c.command;
      ack.target_system = c.source_system;
      ack.target_component = c.source_component;
      if (c.command == mv::kCmdSetPose) {
        mv::SetPoseRequest p;
        ack.result = mv::read_set_pose(c, 0.05, p);
        if (ack.result == mv::MavResult::kAccepted) {
          HARMOLOC_FUZZ_CHECK(
              std::isfinite(p.x_m) && std::isfinite(p.y_m) && std::isfinite(p.yaw_rad),
              "set pose accepted a value that is not finite");
          HARMOLOC_FUZZ_CHECK(std::fabs(p.x_m) <= mv::kMaxSetPoseCoordinateM &&
                                  std::fabs(p.y_m) <= mv::kMaxSetPoseCoordinateM,
                              "set pose accepted a coordinate out of range");
          HARMOLOC_FUZZ_CHECK(p.yaw_rad >= -3.14159266 && p.yaw_rad < 3.14159266,
                              "yaw not wrapped");
          HARMOLOC_FUZZ_CHECK(p.position_sigma_m > 0.0 &&
                                  p.position_sigma_m <= mv::kMaxSetPosePositionSigmaM &&
                                  p.yaw_sigma_rad > 0.0 && p.yaw_sigma_rad <= 3.14159266,
                              "set pose accepted a spread out of range");
        } else {
          HARMOLOC_FUZZ_CHECK(ack.result == mv::MavResult::kDenied,
                              "set pose refused with another result");
        }
      } else if (c.command == mv::kCmdRequestMessage) {
        std::uint32_t id = 0;
        ack.result = mv::read_request_message(c, id);
        if (ack.result == mv::MavResult::kAccepted) {
          HARMOLOC_FUZZ_CHECK(static_cast<float>(id) == c.param[0] && id <= 0xFFFFFFU,
                              "request message read a different id");
        }
      } else if (c.command != mv::kCmdRelocalize) {
        ack.result = mv::MavResult::kUnsupported;
      }
      rx.count_result(ack.result);
      link.write_frame(buffer.data(), encoder.command_ack(ack, buffer));
    }
    mv::TimesyncRequest request;
    if (rx.take_timesync(request)) ++timesyncs;
    HARMOLOC_FUZZ_CHECK(!rx.take_timesync(request), "a TIMESYNC request taken twice");
    HARMOLOC_FUZZ_CHECK(link.read_this_cycle <= mv::CommandReceiver::kMaxBytesPerCycle,
                        "read more than the per-cycle limit");
    HARMOLOC_FUZZ_CHECK(commands <= mv::CommandReceiver::kMaxCommandsPerCycle,
                        "took more commands than the per-cycle limit");
    idle = link.drained() && link.read_this_cycle == 0 && commands == 0 ? idle + 1 : 0;
    HARMOLOC_FUZZ_CHECK(cycle < 100000, "the receiver does not come to an end");
  }

  const mv::InboundCounters k = rx.counters();
  const mv::ParserCounters& p = rx.parser().counters();
  HARMOLOC_FUZZ_CHECK(link.drained() && k.bytes_in == stream.size(),
                      "the line was not read to its end, or more was read than sent");
  HARMOLOC_FUZZ_CHECK(p.bytes == p.garbage_bytes + p.frame_bytes + rx.parser().buffered(),
                      "bytes in do not add up to garbage, frames and what is buffered");
  HARMOLOC_FUZZ_CHECK(k.frames_in == admitted + k.rejected_unsigned + k.rejected_bad_signature +
                                         k.rejected_replay + k.rejected_source +
                                         k.ignored_messages + k.timesync_requests,
                      "a frame was not counted exactly once");
  HARMOLOC_FUZZ_CHECK(k.commands_accepted + k.commands_refused == admitted,
                      "an answer not counted");
  HARMOLOC_FUZZ_CHECK(link.acks == admitted, "a command without exactly one ACK");
  HARMOLOC_FUZZ_CHECK(timesyncs <= k.timesync_requests, "a TIMESYNC request taken but not counted");
  if (!keyed) {
    HARMOLOC_FUZZ_CHECK(k.rejected_unsigned + k.rejected_bad_signature + k.rejected_replay == 0,
                        "signature checks without a key");
  }
  return 0;
}
