// The link's inbound side: the frame parser (garbage, false start bytes, split reads, checksums,
// headers it cannot check, its work budget), MAVLink 2 signing (SHA-256, outbound signatures,
// replay rules) and the command receiver (target, source and signature checks, per-cycle
// limits, a stalled false start). Frames come from the independent builder in
// mavlink_test_frames.hpp.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "harmoloc/firmware/config.hpp"
#include "harmoloc/firmware/mavlink_inbound.hpp"
#include "harmoloc/firmware/mavlink_parser.hpp"
#include "harmoloc/firmware/mavlink_signing.hpp"
#include "harmoloc/firmware/mavlink_v2.hpp"
#include "mavlink_test_frames.hpp"

namespace mv = harmoloc::firmware::mavlink;
namespace hf = harmoloc::firmware;
namespace tf = harmoloc::test::mav;

namespace {

constexpr std::array<float, 7> kNoParams{};

tf::Key test_key(std::uint8_t first = 1) {
  tf::Key k{};
  for (std::size_t i = 0; i < k.size(); ++i) k[i] = static_cast<std::uint8_t>(first + 7 * i);
  return k;
}

// Feeds @p bytes and collects every frame found (unlimited work).
std::vector<mv::RxFrame> parse_all(mv::FrameParser& p, const tf::Bytes& bytes) {
  std::vector<mv::RxFrame> out;
  std::size_t done = 0;
  mv::RxFrame f;
  for (;;) {
    std::size_t work = 1U << 30U;
    while (p.next(f, work)) out.push_back(f);
    if (done == bytes.size()) break;
    done += p.push(bytes.data() + done, bytes.size() - done);
  }
  return out;
}

void expect_bytes_accounted(const mv::FrameParser& p) {
  const mv::ParserCounters& c = p.counters();
  EXPECT_EQ(c.bytes, c.garbage_bytes + c.frame_bytes + p.buffered());
}

tf::Bytes heartbeat_from_gcs() {
  return tf::frame(0, {0, 0, 0, 0, 6, 8, 0, 0, 3});
}

tf::Bytes random_garbage(std::size_t n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  tf::Bytes g(n);
  for (auto& b : g) b = static_cast<std::uint8_t>(rng() % 7 == 0 ? 0xFD : rng());
  return g;
}

hf::LinkConfig link_config() {
  hf::LinkConfig c;  // system 1, component 197; accepts 255 / 190
  return c;
}

}  // namespace

// ---- the parser ---------------------------------------------------------------------------

TEST(MavlinkParser, MessageTableMatchesTheCommonSet) {
  // CRC_EXTRA and longest payload of the messages this firmware acts on or sends (values of
  // node-mavlink 2.3.0's common set); an unknown id has no entry.
  ASSERT_NE(mv::message_info(76), nullptr);
  EXPECT_EQ(mv::message_info(76)->crc_extra, 152);
  EXPECT_EQ(mv::message_info(76)->max_payload, 33);
  EXPECT_EQ(mv::message_info(77)->crc_extra, 143);
  EXPECT_EQ(mv::message_info(77)->max_payload, 10);
  EXPECT_EQ(mv::message_info(0)->crc_extra, 50);
  EXPECT_EQ(mv::message_info(331)->crc_extra, 91);
  EXPECT_EQ(mv::message_info(331)->max_payload, 233);
  EXPECT_EQ(mv::message_info(253)->crc_extra, 83);
  EXPECT_EQ(mv::message_info(3), nullptr);
  EXPECT_EQ(mv::message_info(512), nullptr);
  EXPECT_EQ(mv::message_info(0xFFFFFF), nullptr);
}

TEST(MavlinkParser, FindsFramesBetweenGarbage) {
  const tf::Bytes cmd = tf::command(mv::kCmdSetPose, {1, 2, 3, 0, 0, 0, 0});
  tf::Bytes s = random_garbage(300, 1);
  const tf::Bytes hb = heartbeat_from_gcs();
  s.insert(s.end(), hb.begin(), hb.end());
  const tf::Bytes g2 = random_garbage(200, 2);
  s.insert(s.end(), g2.begin(), g2.end());
  s.insert(s.end(), cmd.begin(), cmd.end());
  mv::FrameParser p;
  const auto frames = parse_all(p, s);
  // Random garbage may hold a frame by chance only with a valid checksum: none here.
  ASSERT_EQ(frames.size(), 2U);
  EXPECT_EQ(frames[0].msg_id, 0U);
  EXPECT_EQ(frames[1].msg_id, 76U);
  EXPECT_EQ(tf::Bytes(frames[1].bytes, frames[1].bytes + frames[1].size), cmd);
  EXPECT_EQ(p.counters().frames, 2U);
  EXPECT_GT(p.counters().garbage_bytes, 400U);
  expect_bytes_accounted(p);
}

TEST(MavlinkParser, FrameHiddenBehindAFalseStartIsFound) {
  // A false start byte whose header claims a COMMAND_LONG: its "frame" swallows the start of
  // the real one and fails its checksum; the search resumes one byte on and finds the real one.
  const tf::Bytes cmd = tf::command(mv::kCmdRelocalize, kNoParams);
  tf::Bytes s = {0xFD, 33, 0, 0, 0, 255, 190, 76, 0, 0, 1, 2, 3};
  s.insert(s.end(), cmd.begin(), cmd.end());
  mv::FrameParser p;
  const auto frames = parse_all(p, s);
  ASSERT_EQ(frames.size(), 1U);
  EXPECT_EQ(tf::Bytes(frames[0].bytes, frames[0].bytes + frames[0].size), cmd);
  EXPECT_EQ(p.counters().crc_errors, 1U);
  EXPECT_EQ(p.counters().garbage_bytes, 13U);
  expect_bytes_accounted(p);
}

TEST(MavlinkParser, SplitAcrossReadsOneByteAtATime) {
  const tf::Key key = test_key();
  const tf::Bytes cmd = tf::command(mv::kCmdSetPose, {1, 2, 3, 0, 0, 0, 0}, 255, 190, &key, 1000);
  mv::FrameParser p;
  mv::RxFrame f;
  for (std::size_t i = 0; i < cmd.size(); ++i) {
    ASSERT_EQ(p.push(&cmd[i], 1), 1U);
    std::size_t work = 10000;
    const bool found = p.next(f, work);
    ASSERT_EQ(found, i + 1 == cmd.size()) << i;
  }
  EXPECT_TRUE(f.is_signed());
  EXPECT_EQ(f.size, cmd.size());
  EXPECT_EQ(f.size, 12U + 32U + 13U);  // confirmation 0 trimmed
  expect_bytes_accounted(p);
}

TEST(MavlinkParser, ChecksumCoversHeaderPayloadAndCrcExtra) {
  tf::Bytes cmd = tf::command(mv::kCmdSetPose, {1, 2, 3, 0, 0, 0, 0});
  for (const std::size_t flip : {std::size_t{4}, std::size_t{5}, std::size_t{12}, cmd.size() - 1}) {
    tf::Bytes bad = cmd;
    bad[flip] ^= 0x10;
    mv::FrameParser p;
    EXPECT_TRUE(parse_all(p, bad).empty()) << flip;
    EXPECT_EQ(p.counters().crc_errors, 1U) << flip;
  }
  // The same bytes with another message's CRC_EXTRA (HEARTBEAT's) do not pass as COMMAND_LONG.
  tf::Bytes wrong_extra = cmd;
  std::uint16_t crc = tf::crc16(wrong_extra.data() + 1, wrong_extra.size() - 3);
  const std::uint8_t extra = 50;
  crc = tf::crc16(&extra, 1, crc);
  wrong_extra[wrong_extra.size() - 2] = static_cast<std::uint8_t>(crc);
  wrong_extra[wrong_extra.size() - 1] = static_cast<std::uint8_t>(crc >> 8U);
  mv::FrameParser p;
  EXPECT_TRUE(parse_all(p, wrong_extra).empty());
  EXPECT_EQ(p.counters().crc_errors, 1U);
}

TEST(MavlinkParser, HeadersItCannotCheckAreSkipped) {
  mv::FrameParser p;
  tf::Bytes s;
  const tf::Bytes unknown = tf::frame(9999, {1, 2, 3});            // no CRC_EXTRA known
  tf::Bytes reserved = tf::frame(0, {1, 2, 3, 4, 5, 6, 7, 8, 9});  // incompat 0x02
  reserved[2] = 0x02;
  tf::Bytes too_long = tf::frame(0, tf::Bytes(20, 1));                  // HEARTBEAT is 9 bytes
  tf::Bytes empty = {0xFD, 0, 0, 0, 0, 255, 190, 0, 0, 0, 0x12, 0x34};  // length 0
  for (const tf::Bytes& b : {unknown, reserved, too_long, empty})
    s.insert(s.end(), b.begin(), b.end());
  const tf::Bytes hb = heartbeat_from_gcs();
  s.insert(s.end(), hb.begin(), hb.end());
  const auto frames = parse_all(p, s);
  ASSERT_EQ(frames.size(), 1U);
  EXPECT_EQ(frames[0].msg_id, 0U);
  EXPECT_EQ(p.counters().bad_headers, 4U);
  EXPECT_EQ(p.counters().crc_errors, 0U);
  expect_bytes_accounted(p);
}

TEST(MavlinkParser, TrimmedPayloadReadsBackWithZeros) {
  // Only param1 set: everything after its 4 bytes is zero and trimmed, except the command id
  // and targets, which are not zero. A relocalize with all params 0 and confirmation 0 keeps
  // 32 of the 33 bytes.
  const tf::Bytes cmd = tf::command(mv::kCmdRelocalize, kNoParams);
  EXPECT_EQ(cmd[1], 32);
  mv::FrameParser p;
  const auto frames = parse_all(p, cmd);
  ASSERT_EQ(frames.size(), 1U);
  const mv::CommandLong c = mv::decode_command_long(frames[0]);
  EXPECT_EQ(c.command, mv::kCmdRelocalize);
  EXPECT_EQ(c.target_system, 1);
  EXPECT_EQ(c.target_component, 197);
  EXPECT_EQ(c.confirmation, 0);
  EXPECT_EQ(c.source_system, 255);
  EXPECT_EQ(c.source_component, 190);
  for (float v : c.param) EXPECT_EQ(v, 0.0F);
}

TEST(MavlinkParser, WorkBudgetBoundsEachCallAndTheRestWaits) {
  // Worst case for the parser: every byte a start byte of a checkable header whose checksum
  // fails. A call stops when its budget is spent; later calls go on from there.
  tf::Bytes flood;
  while (flood.size() < 500) {
    const tf::Bytes f = {0xFD, 33, 0, 0, 0, 255, 190, 76, 0, 0};
    flood.insert(flood.end(), f.begin(), f.end());
  }
  const tf::Bytes cmd = tf::command(mv::kCmdRelocalize, kNoParams);
  mv::FrameParser p;
  ASSERT_EQ(p.push(flood.data(), flood.size()), flood.size());
  mv::RxFrame f;
  std::size_t work = 100;
  EXPECT_FALSE(p.next(f, work));
  EXPECT_LT(work, 46U);  // spent (down to less than one candidate's size)
  const std::size_t left = p.buffered();
  EXPECT_GT(left, 0U);
  // Feed the real frame and let it through over several budgets.
  std::size_t fed = p.push(cmd.data(), cmd.size());
  int calls = 0;
  bool found = false;
  while (!found && calls < 1000) {
    std::size_t budget = 300;
    found = p.next(f, budget);
    if (fed < cmd.size()) fed += p.push(cmd.data() + fed, cmd.size() - fed);
    ++calls;
  }
  ASSERT_TRUE(found);
  EXPECT_GT(calls, 1);
  EXPECT_EQ(f.msg_id, 76U);
}

TEST(MavlinkParser, WindowHoldsTwoLongestFrames) {
  mv::FrameParser p;
  std::size_t room = 0;
  p.write_area(room);
  EXPECT_EQ(room, 2 * mv::kMaxSignedFrameBytes);
  tf::Bytes big(1000, 0x55);
  EXPECT_EQ(p.push(big.data(), big.size()), 2 * mv::kMaxSignedFrameBytes);
  p.write_area(room);
  EXPECT_EQ(room, 0U);
  EXPECT_TRUE(p.skip_candidate());
  p.write_area(room);
  EXPECT_EQ(room, 1U);
}

// ---- signing --------------------------------------------------------------------------------

TEST(MavlinkSigning, Sha256FromNettle) {
  tf::Key k{};
  for (std::size_t i = 0; i < k.size(); ++i) k[i] = static_cast<std::uint8_t>(i);
  const std::uint8_t abc[] = {'a', 'b', 'c'};
  // sha256(bytes(range(32)) + b"abc")[:6], computed with Python's hashlib.
  const auto h = mv::signature_hash(k, abc, 3);
  EXPECT_EQ(h, (std::array<std::uint8_t, 6>{0x42, 0xfd, 0x4a, 0x8c, 0x52, 0x9f}));
}

TEST(MavlinkSigning, TimestampUnits) {
  EXPECT_EQ(mv::signing_timestamp_from_unix_us(mv::kSigningEpochUnixUs), 0U);
  EXPECT_EQ(mv::signing_timestamp_from_unix_us(mv::kSigningEpochUnixUs + 1000000U), 100000U);
  EXPECT_EQ(mv::signing_timestamp_from_unix_us(0), 0U);  // a clock before 2015
}

TEST(MavlinkSigning, OutboundFramesCarryAValidSignatureAndRisingTimestamps) {
  const tf::Key key = test_key(3);
  mv::Signer signer;
  signer.configure(key, 7);
  signer.set_time(5000000, 0);
  mv::Encoder enc(1, 197);
  enc.set_signer(&signer);
  mv::FrameBuffer f{};
  tf::Bytes stream;
  for (int i = 0; i < 5; ++i) {  // several frames within one clock reading
    const std::size_t n =
        i % 2 == 0
            ? enc.heartbeat(mv::Heartbeat{}, f)
            : enc.command_ack(mv::CommandAck{512, mv::MavResult::kDenied, 0, 9, 255, 190}, f);
    stream.insert(stream.end(), f.begin(), f.begin() + static_cast<std::ptrdiff_t>(n));
  }
  signer.advance(2'000'000'000ULL);  // 2 s later: 200000 units
  const std::size_t n = enc.statustext(mv::kSeverityInfo, "x", f);
  stream.insert(stream.end(), f.begin(), f.begin() + static_cast<std::ptrdiff_t>(n));
  const auto frames = tf::decode(stream, &key);
  ASSERT_EQ(frames.size(), 6U);
  std::uint64_t last = 0;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    EXPECT_TRUE(frames[i].is_signed) << i;
    EXPECT_TRUE(frames[i].signature_ok) << i;
    EXPECT_EQ(frames[i].link_id, 7);
    EXPECT_GT(frames[i].timestamp, last) << i;
    last = frames[i].timestamp;
  }
  EXPECT_EQ(frames[0].timestamp, 5000000U);
  EXPECT_EQ(frames[4].timestamp, 5000004U);
  EXPECT_EQ(frames[5].timestamp, 5200000U);
  const tf::Ack ack = tf::ack_of(frames[1]);
  EXPECT_EQ(ack.command, 512);
  EXPECT_EQ(ack.result, 2);
  EXPECT_EQ(ack.result_param2, 9);
  EXPECT_EQ(ack.target_system, 255);
  EXPECT_EQ(ack.target_component, 190);
  // Another key does not verify them.
  const tf::Key other = test_key(4);
  for (const auto& d : tf::decode(stream, &other)) EXPECT_FALSE(d.signature_ok);
}

TEST(MavlinkSigning, UnsignedBadAndReplayedFramesAreRejected) {
  const tf::Key key = test_key();
  mv::Signer s;
  s.configure(key, 0);
  s.set_time(10'000'000, 0);
  const auto verify = [&s](const tf::Bytes& b) { return s.verify(b.data(), b.size()); };
  const auto cmd = [&key](std::uint64_t ts, std::uint8_t link = 0, std::uint8_t sys = 255) {
    return tf::command(mv::kCmdRelocalize, kNoParams, sys, 190, &key, ts, link);
  };
  EXPECT_EQ(verify(tf::command(mv::kCmdRelocalize, kNoParams)), mv::SignatureCheck::kUnsigned);
  const tf::Key wrong = test_key(2);
  EXPECT_EQ(verify(tf::command(mv::kCmdRelocalize, kNoParams, 255, 190, &wrong, 10'000'001)),
            mv::SignatureCheck::kBadSignature);
  tf::Bytes tampered = cmd(10'000'001);
  tampered[10] ^= 1;  // payload changed after signing (checksum not even fixed: verify is on bytes)
  EXPECT_EQ(verify(tampered), mv::SignatureCheck::kBadSignature);
  tf::Bytes ts_changed = cmd(10'000'001);
  ts_changed[ts_changed.size() - 7] ^= 1;  // the timestamp is signed too
  EXPECT_EQ(verify(ts_changed), mv::SignatureCheck::kBadSignature);

  const tf::Bytes first = cmd(10'000'001);
  EXPECT_EQ(verify(first), mv::SignatureCheck::kAccepted);
  EXPECT_EQ(verify(first), mv::SignatureCheck::kReplay);              // the same frame again
  EXPECT_EQ(verify(cmd(10'000'000)), mv::SignatureCheck::kReplay);    // older, same stream
  EXPECT_EQ(verify(cmd(10'000'002)), mv::SignatureCheck::kAccepted);  // newer
  // Another link id is another stream: its own timestamps, but not from long before now.
  EXPECT_EQ(verify(cmd(9'000'000, 1)), mv::SignatureCheck::kAccepted);  // 10 s behind
  EXPECT_EQ(verify(cmd(3'000'000, 2)), mv::SignatureCheck::kReplay);    // 70 s behind
  EXPECT_EQ(s.now(), 10'000'002U);
}

TEST(MavlinkSigning, NewStreamWithinAMinuteOfTheLocalClock) {
  const tf::Key key = test_key();
  mv::Signer s;
  mv::SigningOptions lead;  // here a peer may be up to 2000 s ahead (the default is 60 s)
  lead.max_ahead = 2000 * mv::kSigningUnitsPerSecond;
  s.configure(key, 0, lead);
  s.set_time(100'000'000, 0);
  const auto verify = [&](std::uint64_t ts, std::uint8_t sys) {
    const tf::Bytes b = tf::command(mv::kCmdRelocalize, kNoParams, sys, 190, &key, ts);
    return s.verify(b.data(), b.size());
  };
  EXPECT_EQ(verify(100'000'000 - mv::kReplayWindow, 10), mv::SignatureCheck::kAccepted);
  EXPECT_EQ(verify(100'000'000 - mv::kReplayWindow - 1, 11), mv::SignatureCheck::kReplay);
  // A peer ahead of us carries the clock up; a stream that starts a minute behind it is old.
  EXPECT_EQ(verify(200'000'000, 12), mv::SignatureCheck::kAccepted);
  EXPECT_EQ(s.now(), 200'000'000U);
  EXPECT_EQ(verify(150'000'000, 13), mv::SignatureCheck::kReplay);
  // Frames sent from now on are not behind what was accepted.
  mv::Encoder enc(1, 197);
  enc.set_signer(&s);
  mv::FrameBuffer f{};
  const std::size_t n = enc.heartbeat(mv::Heartbeat{}, f);
  const auto d = tf::decode(tf::Bytes(f.begin(), f.begin() + static_cast<std::ptrdiff_t>(n)), &key);
  ASSERT_EQ(d.size(), 1U);
  EXPECT_EQ(d[0].timestamp, 200'000'001U);
}

TEST(MavlinkSigning, StreamTableEvictsTheLeastRecentlyUsed) {
  const tf::Key key = test_key();
  mv::Signer s;
  s.configure(key, 0);
  s.set_time(1'000'000, 0);
  const auto verify = [&](std::uint64_t ts, std::uint8_t sys) {
    const tf::Bytes b = tf::command(mv::kCmdRelocalize, kNoParams, sys, 190, &key, ts);
    return s.verify(b.data(), b.size());
  };
  for (std::uint8_t sys = 1; sys <= mv::Signer::kMaxStreams; ++sys)
    ASSERT_EQ(verify(1'000'000 + sys, sys), mv::SignatureCheck::kAccepted);
  EXPECT_EQ(verify(1'000'001, 1), mv::SignatureCheck::kReplay);      // still remembered
  EXPECT_EQ(verify(2'000'000, 1), mv::SignatureCheck::kAccepted);    // stream 1 used last now
  EXPECT_EQ(verify(2'000'001, 200), mv::SignatureCheck::kAccepted);  // evicts stream 2
  EXPECT_EQ(verify(1'000'002, 2), mv::SignatureCheck::kAccepted);    // forgotten: new, in window
  EXPECT_EQ(verify(2'000'000, 1), mv::SignatureCheck::kReplay);      // stream 1 kept
}

// Issue 16 item 2: one frame dated a year ahead moved the signing clock for good, after which
// the peer's current frames were replays. A frame more than signing_max_ahead_s (60 s) ahead of
// the local clock is refused and moves nothing.
TEST(MavlinkSigning, FramesTooFarAheadAreRefusedAndMoveNothing) {
  const tf::Key key = test_key();
  mv::Signer s;
  s.configure(key, 0);
  s.set_time(100'000'000, 0);
  const auto verify = [&](std::uint64_t ts, std::uint8_t sys = 255) {
    const tf::Bytes b = tf::command(mv::kCmdRelocalize, kNoParams, sys, 190, &key, ts);
    return s.verify(b.data(), b.size());
  };
  const std::uint64_t year = 365ULL * 86400ULL * mv::kSigningUnitsPerSecond;
  EXPECT_EQ(verify(100'000'000 + year), mv::SignatureCheck::kTooFarAhead);
  EXPECT_EQ(verify(100'000'000 + 6'000'001), mv::SignatureCheck::kTooFarAhead);  // 60 s + 10 us
  EXPECT_EQ(s.now(), 100'000'000U);
  EXPECT_EQ(verify(100'000'010), mv::SignatureCheck::kAccepted);  // the current frame is fine
  EXPECT_EQ(verify(100'000'000 + 6'000'000), mv::SignatureCheck::kAccepted);  // 60 s: at the edge
  // The clock moves on with time (1 s later), and the bound with it.
  s.advance(1'000'000'000ULL);
  EXPECT_EQ(verify(100'000'000 + 6'100'000, 1), mv::SignatureCheck::kAccepted);
}

// A board without a clock (signing_clock = "peer"): its clock is not trusted until the first
// signed frame it accepts, which sets it; from then on the lead is bounded as on any board.
TEST(MavlinkSigning, PeerClockIsSetByTheFirstAcceptedFrame) {
  const tf::Key key = test_key();
  mv::Signer s;
  mv::SigningOptions options;
  options.peer_clock = true;
  s.configure(key, 0, options);
  s.advance(0);
  const auto verify = [&](std::uint64_t ts, std::uint8_t sys = 255) {
    const tf::Bytes b = tf::command(mv::kCmdRelocalize, kNoParams, sys, 190, &key, ts);
    return s.verify(b.data(), b.size());
  };
  const std::uint64_t t = 300'000'000'000ULL;  // about 95 years of units: far from 0
  EXPECT_EQ(verify(t), mv::SignatureCheck::kAccepted);
  EXPECT_EQ(s.now(), t);
  s.advance(2'000'000'000ULL);  // 2 s later
  EXPECT_EQ(s.now(), t + 200'000U);
  EXPECT_EQ(verify(t + 200'000 + 6'000'001, 1), mv::SignatureCheck::kTooFarAhead);
  EXPECT_EQ(verify(t + 200'000 + 100, 1), mv::SignatureCheck::kAccepted);
}

// What the previous run persisted: nothing at or below its high-water mark is taken (a signed
// set-pose captured before a restart, or a day-old one on a board without a clock), and the
// streams go on from their last timestamps.
TEST(MavlinkSigning, RestoredStateRefusesWhatThePreviousRunCouldHaveAccepted) {
  const tf::Key key = test_key();
  for (const bool peer : {false, true}) {
    SCOPED_TRACE(peer ? "board without a clock" : "board with a clock");
    mv::Signer s;
    mv::SigningOptions options;
    options.peer_clock = peer;
    s.configure(key, 0, options);
    if (!peer) s.set_time(100'000'000, 0);  // the wall clock is (again) where it was
    s.advance(0);
    mv::SigningState state;
    state.high_water = 100'500'000;
    state.streams[0] = mv::SigningState::Stream{100'400'000, 200, 190, 0};
    state.stream_count = 1;
    s.restore(state);
    const auto verify = [&](std::uint64_t ts, std::uint8_t sys) {
      const tf::Bytes b = tf::command(mv::kCmdRelocalize, kNoParams, sys, 190, &key, ts);
      return s.verify(b.data(), b.size());
    };
    EXPECT_EQ(s.now(), 100'500'000U);
    EXPECT_EQ(verify(100'400'000, 255), mv::SignatureCheck::kReplay);    // captured last run
    EXPECT_EQ(verify(100'500'000, 255), mv::SignatureCheck::kReplay);    // at the mark
    EXPECT_EQ(verify(91'860'000, 255), mv::SignatureCheck::kReplay);     // a day-old capture
    EXPECT_EQ(verify(100'500'001, 255), mv::SignatureCheck::kAccepted);  // newer than the mark
    EXPECT_EQ(verify(100'500'002, 200), mv::SignatureCheck::kAccepted);  // the restored stream
    // Frames sent carry timestamps above the mark: a peer's replay check never trips on them.
    mv::Encoder enc(1, 197);
    enc.set_signer(&s);
    mv::FrameBuffer f{};
    const std::size_t n = enc.heartbeat(mv::Heartbeat{}, f);
    const auto d =
        tf::decode(tf::Bytes(f.begin(), f.begin() + static_cast<std::ptrdiff_t>(n)), &key);
    ASSERT_EQ(d.size(), 1U);
    EXPECT_GT(d[0].timestamp, 100'500'002U);
  }
}

// With persistence, a frame is taken only when the persisted high-water mark covers it, so that
// no crash can let it be replayed; the mark is renewed ahead of need, at most once a second.
TEST(MavlinkSigning, OnlyPersistedTimestampsAreAcceptedAndTheMarkIsRenewedAhead) {
  const tf::Key key = test_key();
  mv::Signer s;
  mv::SigningOptions options;
  options.persistent = true;
  s.configure(key, 0, options);
  s.set_time(100'000'000, 0);
  s.advance(0);
  const auto verify = [&](std::uint64_t ts) {
    const tf::Bytes b = tf::command(mv::kCmdRelocalize, kNoParams, 255, 190, &key, ts);
    return s.verify(b.data(), b.size());
  };
  // Nothing persisted yet: due at once; the snapshot covers clock + 60 s lead + 60 s reserve.
  EXPECT_TRUE(s.persist_due(0));
  EXPECT_EQ(verify(100'000'100), mv::SignatureCheck::kTooFarAhead);
  mv::SigningState snap = s.snapshot(0);
  EXPECT_EQ(snap.high_water, 100'000'100 + 6'000'000 + mv::kPersistReserve);  // the frame's need
  EXPECT_FALSE(s.persist_due(500'000'000ULL));  // offered half a second ago
  s.set_durable(snap.high_water);
  EXPECT_EQ(verify(100'000'200), mv::SignatureCheck::kAccepted);
  EXPECT_FALSE(s.persist_due(2'000'000'000ULL));  // 120 s of headroom
  // Time passes: 31 s later less than 30 s of headroom is left, so it is due again.
  s.advance(31'000'000'000ULL);
  EXPECT_TRUE(s.persist_due(31'000'000'000ULL));
  snap = s.snapshot(31'000'000'000ULL);
  EXPECT_EQ(snap.high_water, s.now() + 6'000'000 + mv::kPersistReserve);
  ASSERT_EQ(snap.stream_count, 1U);
  EXPECT_EQ(snap.streams[0].timestamp, 100'000'200U);
  // A clean stop leaves the highest timestamp used, not the reservation.
  EXPECT_EQ(s.final_state().high_water, 100'000'200U);
}

TEST(MavlinkSigning, StateFileRoundTripAndDamageIsRefused) {
  mv::SigningState st;
  st.high_water = (1ULL << 48) - 1;
  for (std::uint8_t i = 0; i < 32; ++i)
    st.streams[st.stream_count++] = mv::SigningState::Stream{1000U + i, i, 255, 7};
  char text[4096];
  const std::size_t n = mv::format_signing_state(st, text, sizeof text);
  ASSERT_GT(n, 0U);
  mv::SigningState back;
  EXPECT_EQ(mv::parse_signing_state(std::string_view(text, n), back), "");
  EXPECT_EQ(back.high_water, st.high_water);
  ASSERT_EQ(back.stream_count, 32U);
  EXPECT_EQ(back.streams[31].timestamp, 1031U);
  EXPECT_EQ(back.streams[31].system_id, 31);
  EXPECT_EQ(back.streams[31].component_id, 255);
  EXPECT_EQ(back.streams[31].link_id, 7);
  EXPECT_EQ(mv::format_signing_state(st, text, 100), 0U);  // does not fit: nothing
  const auto error_of = [](const std::string& t) {
    mv::SigningState s;
    return mv::parse_signing_state(t, s);
  };
  const std::string head = "harmoloc-signing-state 1\n";
  EXPECT_EQ(error_of(head + "high_water 5\nstream 1 2 3 4\n\n"), "");
  EXPECT_NE(error_of(""), "");
  EXPECT_NE(error_of("harmoloc-signing-state 2\nhigh_water 5\n"), "");
  EXPECT_NE(error_of(head), "");  // no high_water
  EXPECT_NE(error_of(head + "high_water -5\n"), "");
  EXPECT_NE(error_of(head + "high_water 281474976710656\n"), "");  // 2^48
  EXPECT_NE(error_of(head + "high_water 5\nhigh_water 6\n"), "");
  EXPECT_NE(error_of(head + "high_water 5\nstream 256 1 1 1\n"), "");
  EXPECT_NE(error_of(head + "high_water 5\nstream 1 1 1 6\n"), "");  // above high_water
  EXPECT_NE(error_of(head + "high_water 5\nstream 1 1 1\n"), "");
  EXPECT_NE(error_of(head + "high_water 5\nclock 5\n"), "");
  EXPECT_EQ(error_of(head + "high_water 5\nstream 1 1 x 1\n"),
            "line 3: expected 'stream SYSTEM COMPONENT LINK TIMESTAMP'");
}

// ---- the receiver ---------------------------------------------------------------------------

namespace {

struct Receiver {
  explicit Receiver(const hf::LinkConfig& c, mv::Signer* signer = nullptr) : rx(c, signer) {}
  // One cycle's worth: every command that passes.
  std::vector<mv::CommandLong> cycle() {
    rx.begin_cycle();
    std::vector<mv::CommandLong> out;
    mv::CommandLong c;
    while (rx.next_command(link, c)) {
      out.push_back(c);
      rx.count_result(mv::MavResult::kAccepted);
    }
    return out;
  }
  tf::QueueLink link;
  mv::CommandReceiver rx;
};

}  // namespace

TEST(MavlinkReceiver, TargetAndSourceChecks) {
  Receiver r(link_config());
  r.link.send(tf::command(mv::kCmdRelocalize, kNoParams));  // ok
  r.link.send(
      tf::command(mv::kCmdRelocalize, kNoParams, 255, 190, nullptr, 0, 0, 1, 0));  // comp 0: all
  r.link.send(
      tf::command(mv::kCmdRelocalize, kNoParams, 255, 190, nullptr, 0, 0, 2, 197));  // other system
  r.link.send(tf::command(mv::kCmdRelocalize, kNoParams, 255, 190, nullptr, 0, 0, 1,
                          100));                                     // other component
  r.link.send(tf::command(mv::kCmdRelocalize, kNoParams, 42, 190));  // source system not accepted
  r.link.send(tf::command(mv::kCmdRelocalize, kNoParams, 255, 1));  // source component not accepted
  r.link.send(heartbeat_from_gcs());
  const auto cmds = r.cycle();
  ASSERT_EQ(cmds.size(), 2U);
  EXPECT_EQ(cmds[1].target_component, 0);
  const mv::InboundCounters c = r.rx.counters();
  EXPECT_EQ(c.frames_in, 7U);
  EXPECT_EQ(c.ignored_messages, 3U);
  EXPECT_EQ(c.rejected_source, 2U);
  EXPECT_EQ(c.commands_accepted, 2U);
  EXPECT_EQ(c.rejected_unsigned, 0U);
}

TEST(MavlinkReceiver, TimesyncRequestsAreTakenFromAnySourceTheLatestOnly) {
  Receiver r(link_config());
  r.link.send(tf::timesync(0, 111));                 // autopilot 1/1, to everyone: taken
  r.link.send(tf::timesync(0, 222, 1, 197, 42, 7));  // to us, from anyone: taken
  r.link.send(tf::timesync(0, 333, 2, 0));           // to another system: ignored
  r.link.send(tf::timesync(0, 444, 1, 100));         // to another component: ignored
  r.link.send(tf::timesync(5, 555));                 // an answer (tc1 != 0): ignored
  EXPECT_TRUE(r.cycle().empty());                    // none of them is a command
  mv::TimesyncRequest t;
  ASSERT_TRUE(r.rx.take_timesync(t));
  EXPECT_EQ(t.ts1, 222);  // the latest of the cycle
  EXPECT_EQ(t.system_id, 42);
  EXPECT_EQ(t.component_id, 7);
  EXPECT_FALSE(r.rx.take_timesync(t));  // taken once
  const mv::InboundCounters c = r.rx.counters();
  EXPECT_EQ(c.frames_in, 5U);
  EXPECT_EQ(c.timesync_requests, 2U);
  EXPECT_EQ(c.ignored_messages, 3U);
  EXPECT_EQ(c.rejected_source, 0U);
}

TEST(MavlinkReceiver, TimesyncOnASignedLinkMustBeSigned) {
  const tf::Key key = test_key();
  mv::Signer signer;
  signer.configure(key, 0);
  signer.set_time(1'000'000, 0);
  Receiver r(link_config(), &signer);
  r.link.send(tf::timesync(0, 1));  // unsigned
  tf::Key other = key;
  other[3] ^= 1;
  r.link.send(tf::timesync(0, 2, 0, 0, 1, 1, &other, 1'000'100));  // wrong key
  r.cycle();
  mv::TimesyncRequest t;
  EXPECT_FALSE(r.rx.take_timesync(t));
  r.link.send(tf::timesync(0, 3, 0, 0, 1, 1, &key, 1'000'200));
  r.cycle();
  ASSERT_TRUE(r.rx.take_timesync(t));
  EXPECT_EQ(t.ts1, 3);
  const mv::InboundCounters c = r.rx.counters();
  EXPECT_EQ(c.rejected_unsigned, 1U);
  EXPECT_EQ(c.rejected_bad_signature, 1U);
  EXPECT_EQ(c.timesync_requests, 1U);
}

TEST(MavlinkReceiver, EmptyAcceptListTakesNoCommand) {
  hf::LinkConfig lc = link_config();
  lc.accept_system_ids.clear();
  Receiver r(lc);
  r.link.send(tf::command(mv::kCmdRelocalize, kNoParams));
  EXPECT_TRUE(r.cycle().empty());
  EXPECT_EQ(r.rx.counters().rejected_source, 1U);
}

TEST(MavlinkReceiver, WithAKeyOnlySignedFreshCommandsPass) {
  const tf::Key key = test_key();
  mv::Signer signer;
  signer.configure(key, 0);
  signer.set_time(50'000'000, 0);
  Receiver r(link_config(), &signer);
  const tf::Bytes good =
      tf::command(mv::kCmdSetPose, {1, 0, 0, 0, 0, 0, 0}, 255, 190, &key, 50'000'010);
  const tf::Key wrong = test_key(9);
  r.link.send(tf::command(mv::kCmdSetPose, {1, 0, 0, 0, 0, 0, 0}));  // unsigned
  r.link.send(tf::command(mv::kCmdSetPose, {1, 0, 0, 0, 0, 0, 0}, 255, 190, &wrong, 50'000'005));
  r.link.send(good);
  r.link.send(good);  // replayed
  r.link.send(tf::command(mv::kCmdSetPose, {1, 0, 0, 0, 0, 0, 0}, 42, 190, &key, 50'000'020));
  r.link.send(tf::command(mv::kCmdRelocalize, kNoParams, 255, 190, &key, 50'000'011));
  const auto cmds = r.cycle();
  ASSERT_EQ(cmds.size(), 2U);
  EXPECT_EQ(cmds[0].command, mv::kCmdSetPose);
  EXPECT_EQ(cmds[0].param[0], 1.0F);
  EXPECT_EQ(cmds[1].command, mv::kCmdRelocalize);
  const mv::InboundCounters c = r.rx.counters();
  EXPECT_EQ(c.rejected_unsigned, 1U);
  EXPECT_EQ(c.rejected_bad_signature, 1U);
  EXPECT_EQ(c.rejected_replay, 1U);
  EXPECT_EQ(c.rejected_source, 1U);
  EXPECT_EQ(c.commands_accepted, 2U);
}

TEST(MavlinkReceiver, WithoutAKeySignedAndUnsignedBothPass) {
  const tf::Key key = test_key();
  mv::Signer no_key;  // not configured
  Receiver r(link_config(), &no_key);
  r.link.send(tf::command(mv::kCmdRelocalize, kNoParams));
  r.link.send(tf::command(mv::kCmdRelocalize, kNoParams, 255, 190, &key, 5));
  EXPECT_EQ(r.cycle().size(), 2U);
}

TEST(MavlinkReceiver, SplitReadsAcrossCycles) {
  Receiver r(link_config());
  r.link.chunk = 5;  // the line delivers 5 bytes a read
  const tf::Bytes cmd = tf::command(mv::kCmdRelocalize, kNoParams);
  r.link.send(cmd);
  const auto cmds = r.cycle();  // keeps reading within the cycle until the line is empty
  ASSERT_EQ(cmds.size(), 1U);
  EXPECT_GE(r.link.reads, cmd.size() / 5);
  // A frame that arrives in two cycles is found in the second.
  r.link.send(tf::Bytes(cmd.begin(), cmd.begin() + 20));
  EXPECT_TRUE(r.cycle().empty());
  r.link.send(tf::Bytes(cmd.begin() + 20, cmd.end()));
  EXPECT_EQ(r.cycle().size(), 1U);
}

TEST(MavlinkReceiver, FloodIsBoundedPerCycle) {
  Receiver r(link_config());
  r.link.send(random_garbage(100000, 3));
  const tf::Bytes cmd = tf::command(mv::kCmdRelocalize, kNoParams);
  r.link.send(cmd);
  std::size_t cycles = 0;
  std::size_t commands = 0;
  std::size_t before = 0;
  while (commands == 0 && cycles < 1000) {
    commands += r.cycle().size();
    EXPECT_LE(r.link.bytes_read - before, mv::CommandReceiver::kMaxBytesPerCycle);
    before = r.link.bytes_read;
    ++cycles;
  }
  EXPECT_EQ(commands, 1U);  // the command behind the flood still arrives, cycles later
  EXPECT_GE(cycles, 100000 / mv::CommandReceiver::kMaxBytesPerCycle);
  EXPECT_GT(r.rx.counters().saturated_cycles, 10U);
  EXPECT_EQ(r.rx.counters().bytes_in, 100000U + cmd.size());

  // A flood of valid commands: at most kMaxCommandsPerCycle a cycle, none lost.
  Receiver q(link_config());
  for (int i = 0; i < 50; ++i) q.link.send(cmd);
  std::size_t total = 0;
  for (int k = 0; k < 20; ++k) {
    const std::size_t n = q.cycle().size();
    EXPECT_LE(n, mv::CommandReceiver::kMaxCommandsPerCycle);
    total += n;
  }
  EXPECT_EQ(total, 50U);
}

TEST(MavlinkReceiver, StalledFalseStartIsGivenUpWhenTheLineGoesQuiet) {
  // A false start claiming a 233-byte ODOMETRY holds the real command behind it until more
  // bytes come; when none come for kStallCycles cycles, the false start is dropped.
  Receiver r(link_config());
  tf::Bytes s = {0xFD, 233, 0, 0, 0, 1, 1, 0x4B, 0x01, 0};
  const tf::Bytes cmd = tf::command(mv::kCmdRelocalize, kNoParams);
  s.insert(s.end(), cmd.begin(), cmd.end());
  r.link.send(s);
  std::uint32_t cycles = 0;
  std::size_t got = 0;
  while (got == 0 && cycles < 100) {
    got = r.cycle().size();
    ++cycles;
  }
  EXPECT_EQ(got, 1U);
  EXPECT_GT(cycles, mv::CommandReceiver::kStallCycles);
  EXPECT_LE(cycles, mv::CommandReceiver::kStallCycles + 2);
}
