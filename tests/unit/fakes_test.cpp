// The host board's hal/ implementations: FileCamera (frames from a dataset folder), LogEncoders
// (a candump log) and the SerialLink driver on a regular file and on a pseudo-terminal.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "harmoloc/algorithms/can_encoder_layout.hpp"
#include "harmoloc/dataset/encoder_csv.hpp"
#include "harmoloc/dataset/frame_index.hpp"
#include "harmoloc/dataset/metadata.hpp"
#include "harmoloc/drivers/serial_link.hpp"
#include "harmoloc/host/file_camera.hpp"
#include "harmoloc/host/gpio_log_encoders.hpp"
#include "harmoloc/host/log_encoders.hpp"
#include "test_support.hpp"

namespace hd = harmoloc::dataset;
namespace hh = harmoloc::host;
namespace ha = harmoloc::algorithms;
namespace hal = harmoloc::hal;
namespace fs = std::filesystem;
namespace ht = harmoloc::test;

namespace {

// The pixels of frame @p k: every byte distinct between frames.
std::vector<std::uint8_t> frame_pixels(std::size_t k, std::size_t bytes) {
  std::vector<std::uint8_t> p(bytes);
  for (std::size_t i = 0; i < bytes; ++i) p[i] = static_cast<std::uint8_t>(k * 50U + i * 7U + 1U);
  return p;
}

constexpr std::uint32_t kW = 4, kH = 3;

// A dataset of @p n frames at 1000, 2000, ... ns.
hd::DatasetMetadata make_dataset(const ht::TempDir& dir, std::size_t n,
                                 hal::PixelFormat format = hal::PixelFormat::kRgb24) {
  hd::DatasetMetadata m;
  m.name = "fake";
  m.image_width_px = kW;
  m.image_height_px = kH;
  m.pixel_format = format;
  dir.mkdir("frames");
  std::vector<hd::FrameEntry> index;
  for (std::size_t k = 0; k < n; ++k) {
    char name[32];
    if (format == hal::PixelFormat::kRgb24) {
      std::snprintf(name, sizeof name, "frames/%06zu.ppm", k);
      hd::write_ppm(dir.path(name), kW, kH, frame_pixels(k, kW * kH * 3).data());
    } else {
      std::snprintf(name, sizeof name, "frames/%06zu.yuyv", k);
      dir.write_bytes(name, frame_pixels(k, kW * kH * 2));
    }
    index.push_back(hd::FrameEntry{1000U * (k + 1), name});
  }
  hd::write_frame_index(dir.path("frames.csv"), index);
  hd::write_metadata(dir.dir(), m);
  return hd::read_metadata(dir.dir());
}

std::string construct_error(const ht::TempDir& dir, const hd::DatasetMetadata& m) {
  return ht::error_of([&] { hh::FileCamera camera(dir.dir(), m); });
}

}  // namespace

// --- FileCamera --------------------------------------------------------------------------------

TEST(FileCamera, FramesComeOutInOrderWithTimestamps) {
  ht::TempDir dir;
  const hd::DatasetMetadata m = make_dataset(dir, 3);
  hh::FileCamera camera(dir.dir(), m);
  EXPECT_EQ(camera.frame_count(), 3U);
  EXPECT_EQ(camera.first_timestamp_ns(), 1000U);
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(camera.next_timestamp_ns(), 1000U * (k + 1));
    hal::FrameView f;
    ASSERT_EQ(camera.acquire(f, 0), hal::CameraStatus::kFrame) << k;
    EXPECT_EQ(f.timestamp_ns, 1000U * (k + 1));
    EXPECT_EQ(f.sequence, k);
    EXPECT_EQ(f.width_px, kW);
    EXPECT_EQ(f.height_px, kH);
    EXPECT_EQ(f.stride_bytes, kW * 3);
    EXPECT_EQ(f.format, hal::PixelFormat::kRgb24);
    const auto expected = frame_pixels(k, kW * kH * 3);
    ASSERT_NE(f.data, nullptr);
    EXPECT_TRUE(std::equal(expected.begin(), expected.end(), f.data)) << "pixels of frame " << k;
    camera.release();
  }
  hal::FrameView f;
  EXPECT_EQ(camera.acquire(f, 0), hal::CameraStatus::kEnded);
  EXPECT_EQ(camera.acquire(f, 0), hal::CameraStatus::kEnded);
  EXPECT_EQ(camera.counters().frames, 3U);
  EXPECT_EQ(camera.counters().corrupt, 0U);
}

TEST(FileCamera, YuyvFrames) {
  ht::TempDir dir;
  const hd::DatasetMetadata m = make_dataset(dir, 2, hal::PixelFormat::kYuyv);
  hh::FileCamera camera(dir.dir(), m);
  for (std::size_t k = 0; k < 2; ++k) {
    hal::FrameView f;
    ASSERT_EQ(camera.acquire(f, 0), hal::CameraStatus::kFrame);
    EXPECT_EQ(f.format, hal::PixelFormat::kYuyv);
    EXPECT_EQ(f.stride_bytes, kW * 2);
    const auto expected = frame_pixels(k, kW * kH * 2);
    EXPECT_TRUE(std::equal(expected.begin(), expected.end(), f.data));
  }
  // A raw frame one byte short is refused at start-up.
  auto bytes = ht::read_bytes(dir.path("frames/000001.yuyv"));
  bytes.pop_back();
  ht::write_bytes(dir.path("frames/000001.yuyv"), bytes);
  const std::string msg = construct_error(dir, m);
  EXPECT_NE(msg.find("000001.yuyv"), std::string::npos) << msg;
}

TEST(FileCamera, StartupRejectsTruncatedFrame) {
  ht::TempDir dir;
  const hd::DatasetMetadata m = make_dataset(dir, 3);
  auto bytes = ht::read_bytes(dir.path("frames/000001.ppm"));
  bytes.resize(bytes.size() - 5);
  ht::write_bytes(dir.path("frames/000001.ppm"), bytes);
  const std::string msg = construct_error(dir, m);
  EXPECT_NE(msg.find("frames/000001.ppm"), std::string::npos) << msg;
  EXPECT_NE(msg.find("truncated"), std::string::npos) << msg;
  EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
}

TEST(FileCamera, StartupRejectsWrongSizePpm) {
  ht::TempDir dir;
  const hd::DatasetMetadata m = make_dataset(dir, 3);
  hd::write_ppm(dir.path("frames/000002.ppm"), kW + 1, kH,
                frame_pixels(2, (kW + 1) * kH * 3).data());
  const std::string msg = construct_error(dir, m);
  EXPECT_NE(msg.find("frames/000002.ppm"), std::string::npos) << msg;
  EXPECT_NE(msg.find("5x3"), std::string::npos) << msg;
  // Same byte count, other shape (3x4 instead of 4x3): the header says so.
  hd::write_ppm(dir.path("frames/000002.ppm"), kH, kW, frame_pixels(2, kW * kH * 3).data());
  EXPECT_NE(construct_error(dir, m).find("frames/000002.ppm"), std::string::npos);
  // Not a PPM at all.
  ht::write_bytes(dir.path("frames/000002.ppm"), std::vector<std::uint8_t>(60, 'x'));
  EXPECT_NE(construct_error(dir, m).find("frames/000002.ppm"), std::string::npos);
}

TEST(FileCamera, StartupRejectsMissingFileAndEmptyIndex) {
  ht::TempDir dir;
  const hd::DatasetMetadata m = make_dataset(dir, 3);
  fs::remove(dir.path("frames/000000.ppm"));
  const std::string msg = construct_error(dir, m);
  EXPECT_NE(msg.find("frames/000000.ppm"), std::string::npos) << msg;
  EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;

  ht::TempDir other;
  const hd::DatasetMetadata m2 = make_dataset(other, 1);
  hd::write_frame_index(other.path("frames.csv"), {});
  EXPECT_NE(construct_error(other, m2).find("no frames"), std::string::npos);
}

TEST(FileCamera, FrameCorruptedAfterStartupIsCountedAndSkipped) {
  ht::TempDir dir;
  const hd::DatasetMetadata m = make_dataset(dir, 4);
  hh::FileCamera camera(dir.dir(), m);
  // Truncate frame 1, grow frame 2, and give frame 3 a header of the same length but another shape.
  auto bytes = ht::read_bytes(dir.path("frames/000001.ppm"));
  bytes.resize(bytes.size() / 2);
  ht::write_bytes(dir.path("frames/000001.ppm"), bytes);
  bytes = ht::read_bytes(dir.path("frames/000002.ppm"));
  bytes.push_back(0);
  ht::write_bytes(dir.path("frames/000002.ppm"), bytes);
  bytes = ht::read_bytes(dir.path("frames/000003.ppm"));
  ASSERT_EQ(bytes[3], '4');
  bytes[3] = '3';
  bytes[5] = '4';  // "P6\n3 4\n255\n"
  ht::write_bytes(dir.path("frames/000003.ppm"), bytes);

  hal::FrameView f;
  ASSERT_EQ(camera.acquire(f, 0), hal::CameraStatus::kFrame);
  EXPECT_EQ(f.timestamp_ns, 1000U);
  EXPECT_EQ(camera.acquire(f, 0), hal::CameraStatus::kCorrupt);
  EXPECT_EQ(camera.counters().corrupt, 1U);
  EXPECT_EQ(camera.acquire(f, 0), hal::CameraStatus::kCorrupt);
  EXPECT_EQ(camera.acquire(f, 0), hal::CameraStatus::kCorrupt);
  EXPECT_EQ(camera.counters().corrupt, 3U);
  EXPECT_EQ(camera.acquire(f, 0), hal::CameraStatus::kEnded);
  EXPECT_EQ(camera.counters().frames, 1U);
}

// A frame file replaced by a FIFO (or a device) during the run blocked the cycle for ever in
// open(2); it is now a corrupt frame, at once. A frame path leading out of the dataset (a
// symbolic link) stops start-up.
TEST(FileCamera, FrameReplacedByAFifoDoesNotBlock) {
  ht::TempDir dir;
  const hd::DatasetMetadata m = make_dataset(dir, 3);
  hh::FileCamera camera(dir.dir(), m);
  fs::remove(dir.path("frames/000001.ppm"));
  ASSERT_EQ(::mkfifo(dir.path("frames/000001.ppm").c_str(), 0600), 0);
  fs::remove(dir.path("frames/000002.ppm"));
  fs::create_symlink("/dev/zero", dir.path("frames/000002.ppm"));
  hal::FrameView f;
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_EQ(camera.acquire(f, 0), hal::CameraStatus::kFrame);
  EXPECT_EQ(camera.acquire(f, 0), hal::CameraStatus::kCorrupt);
  EXPECT_EQ(camera.acquire(f, 0), hal::CameraStatus::kCorrupt);
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(1));
  EXPECT_EQ(camera.counters().corrupt, 2U);
}

TEST(FileCamera, StartupRejectsFramesThatAreNotRegularFiles) {
  ht::TempDir dir;
  const hd::DatasetMetadata m = make_dataset(dir, 3);
  fs::remove(dir.path("frames/000001.ppm"));
  ASSERT_EQ(::mkfifo(dir.path("frames/000001.ppm").c_str(), 0600), 0);
  ht::expect_one_line(construct_error(dir, m), "frame frames/000001.ppm: ", "not a regular file");
  fs::remove(dir.path("frames/000001.ppm"));
  fs::create_symlink("/dev/zero", dir.path("frames/000001.ppm"));
  ht::expect_one_line(construct_error(dir, m), "frame frames/000001.ppm: ", "not a regular file");
}

// A hole in the recording: with gap filling (camera-paced replays), one kNoFrame a period of the
// metadata's rate (30 Hz here) until the next frame is due, and next_timestamp_ns() says when;
// without it, the frames come back to back as before.
TEST(FileCamera, HoleInTheRecordingGivesANoFrameTickEachPeriod) {
  ht::TempDir dir;
  hd::DatasetMetadata m = make_dataset(dir, 3);
  constexpr std::uint64_t kP = 33'333'333;  // llround(1e9 / 30)
  hd::write_frame_index(dir.path("frames.csv"), {{1'000'000'000ULL, "frames/000000.ppm"},
                                                 {1'000'000'000ULL + kP, "frames/000001.ppm"},
                                                 {1'200'000'000ULL, "frames/000002.ppm"}});
  for (const bool fill : {true, false}) {
    hh::FileCamera camera(dir.dir(), m);
    camera.set_fill_gaps(fill);
    std::vector<std::uint64_t> next;
    std::vector<hal::CameraStatus> got;
    hal::FrameView f;
    for (;;) {
      next.push_back(camera.next_timestamp_ns());
      const hal::CameraStatus s = camera.acquire(f, 0);
      if (s == hal::CameraStatus::kEnded) break;
      got.push_back(s);
    }
    if (!fill) {
      EXPECT_EQ(got.size(), 3U);
      EXPECT_EQ(camera.gap_ticks(), 0U);
      continue;
    }
    using S = hal::CameraStatus;
    const std::vector<S> expected = {S::kFrame,   S::kFrame,   S::kNoFrame, S::kNoFrame,
                                     S::kNoFrame, S::kNoFrame, S::kFrame};
    EXPECT_EQ(got, expected);
    EXPECT_EQ(camera.gap_ticks(), 4U);
    EXPECT_EQ(camera.counters().frames, 3U);
    const std::uint64_t t1 = 1'000'000'000ULL + kP;
    EXPECT_EQ(next[2], t1 + kP);
    EXPECT_EQ(next[5], t1 + 4 * kP);
    EXPECT_EQ(next[6], 1'200'000'000ULL);
    EXPECT_EQ(f.timestamp_ns, 1'200'000'000ULL);
  }
}

TEST(FileCamera, NextFrameAfterACorruptOneStillWorks) {
  ht::TempDir dir;
  const hd::DatasetMetadata m = make_dataset(dir, 3);
  hh::FileCamera camera(dir.dir(), m);
  fs::remove(dir.path("frames/000001.ppm"));  // vanished after start-up
  hal::FrameView f;
  ASSERT_EQ(camera.acquire(f, 0), hal::CameraStatus::kFrame);
  ASSERT_EQ(camera.acquire(f, 0), hal::CameraStatus::kCorrupt);
  ASSERT_EQ(camera.acquire(f, 0), hal::CameraStatus::kFrame);
  EXPECT_EQ(f.timestamp_ns, 3000U);
  EXPECT_EQ(f.sequence, 2U);
  const auto expected = frame_pixels(2, kW * kH * 3);
  EXPECT_TRUE(std::equal(expected.begin(), expected.end(), f.data));
  EXPECT_EQ(camera.acquire(f, 0), hal::CameraStatus::kEnded);
  EXPECT_EQ(camera.counters().frames, 2U);
  EXPECT_EQ(camera.counters().corrupt, 1U);
}

// --- LogEncoders -------------------------------------------------------------------------------

namespace {

ha::CanFrame frame_at(std::uint64_t t, std::uint32_t id, std::uint8_t length, std::uint32_t left,
                      std::uint32_t right) {
  ha::EncoderFrameLayout l;
  l.id = id;
  ha::CanFrame f = ha::encode_encoder_frame(l, left, right, t);
  f.length = length;
  return f;
}

}  // namespace

TEST(LogEncoders, HandsOutFramesByTimestamp) {
  const ha::EncoderFrameLayout layout;  // 0x181, 8 bytes
  std::vector<ha::CanFrame> frames = {
      frame_at(100, 0x181, 8, 1, 2), frame_at(200, 0x281, 8, 9, 9),  // foreign ID
      frame_at(300, 0x181, 4, 9, 9),                                 // ours, wrong length
      frame_at(400, 0x181, 8, 5, 6), frame_at(500, 0x181, 8, 7, 8),
  };
  hh::LogEncoders enc(frames, layout);
  EXPECT_EQ(enc.frame_count(), 5U);
  hal::EncoderCounts c;
  EXPECT_EQ(enc.read(50, c), hal::EncoderStatus::kNoData);
  ASSERT_EQ(enc.read(100, c), hal::EncoderStatus::kFresh);
  EXPECT_EQ(c.left_ticks, 1U);
  EXPECT_EQ(c.right_ticks, 2U);
  EXPECT_EQ(c.timestamp_ns, 100U);
  EXPECT_EQ(c.counter_bits, 32);
  EXPECT_EQ(enc.read(150, c), hal::EncoderStatus::kNoData);
  // The foreign and the short frame are drained, counted and not used.
  EXPECT_EQ(enc.read(350, c), hal::EncoderStatus::kNoData);
  EXPECT_EQ(c.left_ticks, 1U);
  EXPECT_EQ(c.timestamp_ns, 100U);
  EXPECT_EQ(enc.counters().ignored_id, 1U);
  EXPECT_EQ(enc.counters().bad_length, 1U);
  EXPECT_EQ(enc.counters().samples, 1U);
  // Two frames due at once: the latest counts are reported.
  ASSERT_EQ(enc.read(1000, c), hal::EncoderStatus::kFresh);
  EXPECT_EQ(c.left_ticks, 7U);
  EXPECT_EQ(c.right_ticks, 8U);
  EXPECT_EQ(c.timestamp_ns, 500U);
  EXPECT_EQ(enc.counters().samples, 3U);
  EXPECT_EQ(enc.read(2000, c), hal::EncoderStatus::kEnded);
  EXPECT_EQ(enc.read(3000, c), hal::EncoderStatus::kEnded);
}

TEST(LogEncoders, SixteenBitLayoutReportsItsWidth) {
  ha::EncoderFrameLayout layout;
  layout.length = 4;
  layout.right_offset = 2;
  layout.counter_bits = 16;
  hh::LogEncoders enc({ha::encode_encoder_frame(layout, 65535, 3, 10)}, layout);
  hal::EncoderCounts c;
  ASSERT_EQ(enc.read(10, c), hal::EncoderStatus::kFresh);
  EXPECT_EQ(c.left_ticks, 65535U);
  EXPECT_EQ(c.right_ticks, 3U);
  EXPECT_EQ(c.counter_bits, 16);
}

TEST(LogEncoders, FromALogFile) {
  ht::TempDir dir;
  const std::string log = dir.write("encoders.log",
                                    "(1.000000) can0 181#0100000002000000\n"
                                    "(1.005000) can0 281#0100300C00000000\n"
                                    "(1.010000) can0 181#0300000004000000\n");
  hh::LogEncoders enc(log, ha::EncoderFrameLayout{});
  EXPECT_EQ(enc.frame_count(), 3U);
  hal::EncoderCounts c;
  ASSERT_EQ(enc.read(1000000000ULL, c), hal::EncoderStatus::kFresh);
  EXPECT_EQ(c.left_ticks, 1U);
  EXPECT_EQ(c.right_ticks, 2U);
  ASSERT_EQ(enc.read(1010000000ULL, c), hal::EncoderStatus::kFresh);
  EXPECT_EQ(c.left_ticks, 3U);
  EXPECT_EQ(enc.counters().ignored_id, 1U);
  EXPECT_EQ(enc.read(2000000000ULL, c), hal::EncoderStatus::kEnded);

  const std::string bad =
      dir.write("bad.log", "(1.000000) can0 181#0100000002000000\n(1.010000) can0 181#R\n");
  const std::string msg =
      ht::error_of([&] { hh::LogEncoders from_bad_log(bad, ha::EncoderFrameLayout{}); });
  EXPECT_EQ(msg.rfind(bad + ":2: ", 0), 0U) << msg;
}

// An empty log, a folder in its place or a log without one encoder frame ran the whole replay
// vision-only with exit status 0; each now stops start-up with one line naming the file.
TEST(LogEncoders, ALogWithoutEncoderFramesIsRefused) {
  ht::TempDir dir;
  const auto error_of = [&](const std::string& path) {
    return ht::error_of([&] { hh::LogEncoders enc(path, ha::EncoderFrameLayout{}); });
  };
  std::string p = dir.write("empty.log", "");
  ht::expect_one_line(error_of(p), p + ": ", "no CAN frames");
  p = dir.write("blank.log", "\n\n");
  ht::expect_one_line(error_of(p), p + ": ", "no CAN frames");
  p = dir.mkdir("folder.log");
  ht::expect_one_line(error_of(p), p + ": ", "not a regular file (a directory)");
  p = dir.write("foreign.log",
                "(1.000000) can0 281#0100000002000000\n(1.010000) can0 181#01000000\n");
  ht::expect_one_line(error_of(p), p + ": ",
                      "none of its 2 frames is an encoder frame (ID 0x181, 8 bytes");
}

// --- GPIO encoder recordings ---------------------------------------------------------------------

TEST(GpioLogEncoders, HandsOutSamplesByTimestampWithTheRecordingsWidth) {
  hh::GpioLogEncoders enc({{100, 1, 2}, {200, 3, 4}, {300, 65535, 0}, {400, 2, 1}}, 16);
  EXPECT_EQ(enc.sample_count(), 4U);
  hal::EncoderCounts c;
  EXPECT_EQ(enc.read(50, c), hal::EncoderStatus::kNoData);
  ASSERT_EQ(enc.read(100, c), hal::EncoderStatus::kFresh);
  EXPECT_EQ(c.left_ticks, 1U);
  EXPECT_EQ(c.right_ticks, 2U);
  EXPECT_EQ(c.timestamp_ns, 100U);
  EXPECT_EQ(c.counter_bits, 16);
  EXPECT_EQ(enc.read(199, c), hal::EncoderStatus::kNoData);
  // Two samples due at once: the latest.
  ASSERT_EQ(enc.read(350, c), hal::EncoderStatus::kFresh);
  EXPECT_EQ(c.left_ticks, 65535U);
  EXPECT_EQ(c.timestamp_ns, 300U);
  EXPECT_EQ(enc.counters().samples, 3U);
  ASSERT_EQ(enc.read(400, c), hal::EncoderStatus::kFresh);
  EXPECT_EQ(enc.read(500, c), hal::EncoderStatus::kEnded);
  EXPECT_EQ(enc.counters().ignored_id + enc.counters().bad_length + enc.counters().glitches, 0U);
}

TEST(GpioLogEncoders, LoopsCarryTheCountersOnAcrossTheWrap) {
  // 8-bit counters advancing 200 a pass: the second pass continues from 210 and wraps.
  hh::GpioLogEncoders enc({{0, 10, 250}, {10, 210, 50}}, 8);
  enc.set_loops(2, 20);
  hal::EncoderCounts c;
  ASSERT_EQ(enc.read(10, c), hal::EncoderStatus::kFresh);
  EXPECT_EQ(c.left_ticks, 210U);
  ASSERT_EQ(enc.read(20, c), hal::EncoderStatus::kFresh);
  EXPECT_EQ(c.timestamp_ns, 20U);
  EXPECT_EQ(c.left_ticks, 210U);  // 10 + 200
  EXPECT_EQ(c.right_ticks, 50U);  // 250 + 56 (50 - 250 mod 256)
  ASSERT_EQ(enc.read(30, c), hal::EncoderStatus::kFresh);
  EXPECT_EQ(c.left_ticks, (210U + 200U) & 0xFFU);
  EXPECT_EQ(enc.read(40, c), hal::EncoderStatus::kEnded);
}

TEST(GpioLogEncoders, FromAFileAndItsErrors) {
  ht::TempDir dir;
  const std::string ok = dir.write("encoders.csv",
                                   "timestamp_ns,left_ticks,right_ticks\n"
                                   "1000000000,0,0\n1010000000,-3,7\n");
  hh::GpioLogEncoders enc(ok, 32);
  hal::EncoderCounts c;
  ASSERT_EQ(enc.read(1010000000ULL, c), hal::EncoderStatus::kFresh);
  EXPECT_EQ(c.left_ticks, 0xFFFFFFFDU);
  EXPECT_EQ(c.right_ticks, 7U);
  const std::string bad = dir.write("bad.csv",
                                    "timestamp_ns,left_ticks,right_ticks\n"
                                    "1000000000,0,0\n1010000000,70000,7\n");
  const std::string msg = ht::error_of([&] { hh::GpioLogEncoders from_bad(bad, 16); });
  EXPECT_EQ(msg.rfind(bad + ":3: ", 0), 0U) << msg;
}

// The recorder writes what the cycle read; replaying the file gives the same reads.
TEST(EncoderRecorder, RecordsFreshSamplesThatReplayIdentically) {
  ha::EncoderFrameLayout layout;
  layout.length = 4;
  layout.right_offset = 2;
  layout.counter_bits = 16;
  std::vector<ha::CanFrame> frames;
  for (std::uint64_t k = 0; k < 50; ++k) {
    frames.push_back(ha::encode_encoder_frame(layout, static_cast<std::uint32_t>(65500 + 7 * k),
                                              static_cast<std::uint32_t>(300 - 9 * k),
                                              1000 + k * 10));
  }
  frames.push_back(frame_at(1005, 0x281, 8, 1, 1));  // ignored by both
  ht::TempDir dir;
  const std::string path = dir.path("rec.csv");
  std::vector<std::pair<hal::EncoderStatus, hal::EncoderCounts>> original;
  {
    hh::LogEncoders can(frames, layout);
    hd::EncoderRecorder rec(can);
    ASSERT_TRUE(rec.open(path));
    for (std::uint64_t t = 990; t <= 1600; t += 33) {
      hal::EncoderCounts c;
      const hal::EncoderStatus s = rec.read(t, c);
      original.emplace_back(s, c);
    }
    EXPECT_EQ(rec.counter_bits(), 16);
    EXPECT_GT(rec.samples_written(), 10U);
    ASSERT_TRUE(rec.close());
  }
  hh::GpioLogEncoders replay(path, 16);
  std::size_t i = 0;
  for (std::uint64_t t = 990; t <= 1600; t += 33, ++i) {
    hal::EncoderCounts c;
    const hal::EncoderStatus s = replay.read(t, c);
    const auto& [os, oc] = original[i];
    if (os == hal::EncoderStatus::kFresh) {
      ASSERT_EQ(s, hal::EncoderStatus::kFresh) << "at " << t;
      EXPECT_EQ(c.left_ticks, oc.left_ticks) << "at " << t;
      EXPECT_EQ(c.right_ticks, oc.right_ticks) << "at " << t;
      EXPECT_EQ(c.timestamp_ns, oc.timestamp_ns) << "at " << t;
      EXPECT_EQ(c.counter_bits, oc.counter_bits);
    } else {
      EXPECT_NE(s, hal::EncoderStatus::kFresh) << "at " << t;
    }
  }
  EXPECT_FALSE(hd::EncoderRecorder(replay).open(dir.path("no/such/dir/rec.csv")));
}

// --- SerialLink --------------------------------------------------------------------------------

namespace {

// A frame with a recognisable shape: A5 5A, seq (LE16), length, payload, checksum (sum of all).
std::vector<std::uint8_t> test_frame(std::uint16_t seq) {
  const std::uint8_t len = static_cast<std::uint8_t>(10 + seq % 31);
  std::vector<std::uint8_t> f = {0xA5, 0x5A, static_cast<std::uint8_t>(seq),
                                 static_cast<std::uint8_t>(seq >> 8U), len};
  for (std::uint8_t i = 0; i < len; ++i) f.push_back(static_cast<std::uint8_t>(seq * 3U + i));
  std::uint8_t sum = 0;
  for (std::uint8_t b : f) sum = static_cast<std::uint8_t>(sum + b);
  f.push_back(sum);
  return f;
}

// Splits a byte stream into whole test frames; fails on anything else (a partial frame, junk).
std::vector<std::uint16_t> parse_frames(const std::vector<std::uint8_t>& s) {
  std::vector<std::uint16_t> seqs;
  std::size_t pos = 0;
  while (pos < s.size()) {
    if (s.size() - pos < 6) {
      ADD_FAILURE() << "partial frame at the end (" << s.size() - pos << " bytes) at offset "
                    << pos;
      break;
    }
    if (s[pos] != 0xA5 || s[pos + 1] != 0x5A) {
      ADD_FAILURE() << "no frame header at offset " << pos;
      break;
    }
    const auto seq = static_cast<std::uint16_t>(s[pos + 2] | (s[pos + 3] << 8U));
    const std::vector<std::uint8_t> expected = test_frame(seq);
    if (s.size() - pos < expected.size() ||
        !std::equal(expected.begin(), expected.end(),
                    s.begin() + static_cast<std::ptrdiff_t>(pos))) {
      ADD_FAILURE() << "frame " << seq << " at offset " << pos << " is damaged or cut";
      break;
    }
    seqs.push_back(seq);
    pos += expected.size();
  }
  return seqs;
}

}  // namespace

TEST(SerialLink, RegularFileGetsWholeFrames) {
  ht::TempDir dir;
  const std::string path = dir.write("link.bin", "old contents that must go");
  harmoloc::drivers::SerialLink link;
  ASSERT_EQ(link.open(path, 115200), "");
  EXPECT_FALSE(link.is_tty());
  std::vector<std::uint8_t> expected;
  for (std::uint16_t seq = 0; seq < 100; ++seq) {
    const auto f = test_frame(seq);
    ASSERT_EQ(link.write_frame(f.data(), f.size()), hal::LinkWrite::kSent);
    expected.insert(expected.end(), f.begin(), f.end());
  }
  EXPECT_EQ(link.counters().frames_sent, 100U);
  EXPECT_EQ(link.counters().frames_dropped, 0U);
  EXPECT_EQ(link.counters().bytes_sent, expected.size());
  EXPECT_EQ(ht::read_bytes(path), expected);
  EXPECT_EQ(parse_frames(ht::read_bytes(path)).size(), 100U);
  // A frame larger than the link's buffer is dropped whole.
  const std::vector<std::uint8_t> huge(harmoloc::drivers::SerialLink::kMaxFrameBytes + 1, 0xA5);
  EXPECT_EQ(link.write_frame(huge.data(), huge.size()), hal::LinkWrite::kDropped);
  EXPECT_EQ(link.counters().frames_dropped, 1U);
  EXPECT_EQ(ht::read_bytes(path).size(), expected.size());
}

TEST(SerialLink, OpenFailuresSayWhy) {
  harmoloc::drivers::SerialLink link;
  const std::string path = "/nonexistent-harmoloc-dir/sub/link.bin";
  const std::string msg = link.open(path, 115200);
  EXPECT_FALSE(msg.empty());
  EXPECT_NE(msg.find(path), std::string::npos) << msg;
  const std::uint8_t b[3] = {1, 2, 3};
  EXPECT_EQ(link.write_frame(b, 3), hal::LinkWrite::kFailed);  // never opened
  harmoloc::drivers::SerialLink unopened;
  EXPECT_EQ(unopened.write_frame(b, 3), hal::LinkWrite::kFailed);
}

TEST(SerialLink, FullPtyDropsWholeFramesAndNeverBlocks) {
  const int master = ::posix_openpt(O_RDWR | O_NOCTTY);
  ASSERT_GE(master, 0) << std::strerror(errno);
  ASSERT_EQ(::grantpt(master), 0);
  ASSERT_EQ(::unlockpt(master), 0);
  const char* slave_name = ::ptsname(master);
  ASSERT_NE(slave_name, nullptr);
  const std::string slave = slave_name;
  ASSERT_EQ(::fcntl(master, F_SETFL, ::fcntl(master, F_GETFL) | O_NONBLOCK), 0);

  std::vector<std::uint8_t> stream;
  auto drain = [&]() {
    std::uint8_t buf[4096];
    for (;;) {
      const ssize_t n = ::read(master, buf, sizeof buf);
      if (n > 0) {
        stream.insert(stream.end(), buf, buf + n);
        continue;
      }
      if (n < 0 && errno == EINTR) continue;
      break;  // EAGAIN: nothing more for now
    }
  };

  {
    harmoloc::drivers::SerialLink link;
    ASSERT_EQ(link.open(slave, 115200), "");
    EXPECT_TRUE(link.is_tty());
    // Flood without reading: the pty fills up, later frames are dropped, no call blocks.
    std::uint16_t seq = 0;
    std::size_t sent = 0, dropped = 0;
    double worst_ms = 0.0;
    for (; seq < 20000; ++seq) {
      const auto f = test_frame(seq);
      const auto t0 = std::chrono::steady_clock::now();
      const hal::LinkWrite r = link.write_frame(f.data(), f.size());
      const double ms =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      worst_ms = std::max(worst_ms, ms);
      ASSERT_NE(r, hal::LinkWrite::kFailed) << "frame " << seq;
      (r == hal::LinkWrite::kSent ? sent : dropped)++;
    }
    EXPECT_GT(dropped, 0U) << "the pty never filled up";
    EXPECT_GT(sent, 0U);
    EXPECT_EQ(link.counters().frames_sent, sent);
    EXPECT_EQ(link.counters().frames_dropped, dropped);
    EXPECT_LT(worst_ms, 50.0) << "a write blocked";

    // Drain, then keep writing (each write first finishes a frame the line took only in part)
    // until the line has taken everything.
    for (int round = 0; round < 100; ++round) {
      drain();
      const auto f = test_frame(seq++);
      const hal::LinkWrite r = link.write_frame(f.data(), f.size());
      ASSERT_NE(r, hal::LinkWrite::kFailed);
      (r == hal::LinkWrite::kSent ? sent : dropped)++;
      if (link.counters().bytes_sent == stream.size() + f.size() && r == hal::LinkWrite::kSent)
        break;
    }
    ::usleep(20000);
    drain();
    EXPECT_EQ(link.counters().bytes_sent, stream.size());
    const std::vector<std::uint16_t> seqs = parse_frames(stream);
    EXPECT_EQ(seqs.size(), link.counters().frames_sent);
    for (std::size_t i = 1; i < seqs.size(); ++i) {
      ASSERT_GT(seqs[i], seqs[i - 1]) << "frames out of order or repeated at " << i;
    }
    if (!seqs.empty()) {
      EXPECT_EQ(seqs.front(), 0U);
    }
  }
  ::close(master);
}

namespace {

// A pty pair: the link writes to the slave, the test holds the master.
struct Pty {
  Pty() {
    master = ::posix_openpt(O_RDWR | O_NOCTTY);
    if (master >= 0 && ::grantpt(master) == 0 && ::unlockpt(master) == 0 &&
        ::ptsname(master) != nullptr) {
      slave = ::ptsname(master);
      ::fcntl(master, F_SETFL, ::fcntl(master, F_GETFL) | O_NONBLOCK);
    }
  }
  ~Pty() {
    if (master >= 0) ::close(master);
  }
  Pty(const Pty&) = delete;
  Pty& operator=(const Pty&) = delete;
  void hang_up() {
    ::close(master);
    master = -1;
  }
  int master = -1;
  std::string slave;
};

}  // namespace

TEST(SerialLink, HungUpLineReportsFailed) {
  // hal::LinkWrite::kFailed: "the link is broken (hung up, I/O error)".
  Pty pty;
  ASSERT_FALSE(pty.slave.empty());
  harmoloc::drivers::SerialLink link;
  ASSERT_EQ(link.open(pty.slave, 115200), "");
  const auto f = test_frame(1);
  ASSERT_EQ(link.write_frame(f.data(), f.size()), hal::LinkWrite::kSent);
  pty.hang_up();
  EXPECT_EQ(link.write_frame(f.data(), f.size()), hal::LinkWrite::kFailed);
  EXPECT_GT(link.counters().errors, 0U);
}

TEST(SerialLink, HungUpLineWithAHalfSentFrameReportsFailed) {
  // The same when the line went away while a frame was only partly written.
  Pty pty;
  ASSERT_FALSE(pty.slave.empty());
  harmoloc::drivers::SerialLink link;
  ASSERT_EQ(link.open(pty.slave, 115200), "");
  std::uint16_t seq = 0;
  std::uint64_t dropped_before = 0;
  for (; seq < 20000 && link.counters().frames_dropped == 0; ++seq) {
    const auto f = test_frame(seq);
    link.write_frame(f.data(), f.size());
  }
  ASSERT_GT(link.counters().frames_dropped, 0U) << "the pty never filled up";
  dropped_before = link.counters().frames_dropped;
  pty.hang_up();
  const auto f = test_frame(seq);
  hal::LinkWrite r = hal::LinkWrite::kSent;
  for (int i = 0; i < 3; ++i) r = link.write_frame(f.data(), f.size());
  EXPECT_EQ(r, hal::LinkWrite::kFailed)
      << "dropped " << link.counters().frames_dropped - dropped_before << " more frames, errors "
      << link.counters().errors;
  EXPECT_GT(link.counters().errors, 0U);
}
