// The drivers against the Linux kernel's own virtual devices, inside the test VM
// (tests/vm/run_vm_tests.sh boots it): vivid for V4L2 capture, vcan for SocketCAN, gpio-sim for
// the GPIO quadrature encoders. A missing device fails the test: in the VM it must be there.
//
// Environment (set by the VM's init): HARMOLOC_VM_GPIO_CHIP (gpio-sim's chip name),
// HARMOLOC_VM_GPIO_SYSFS (its sysfs folder with sim_gpioN/pull), HARMOLOC_VM_CAN_LOG (a candump
// log to play onto vcan0).
#include <gtest/gtest.h>

#include <fcntl.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/videodev2.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "harmoloc/algorithms/odometry.hpp"
#include "harmoloc/drivers/gpio_quadrature_encoders.hpp"
#include "harmoloc/drivers/monotonic_clock.hpp"
#include "harmoloc/drivers/socketcan_encoders.hpp"
#include "harmoloc/drivers/v4l2_camera.hpp"

namespace hd = harmoloc::drivers;
namespace hal = harmoloc::hal;
namespace ha = harmoloc::algorithms;

namespace {

std::string env(const char* name) {
  const char* v = std::getenv(name);
  return v != nullptr ? v : "";
}

void sleep_ms(int ms) {
  std::this_thread::sleep_for(std::chrono::milliseconds(ms));
}

// ---- V4L2 (vivid)
// --------------------------------------------------------------------------------

const char* kVideo = "/dev/video0";

// Sets a vivid control by its name (VIDIOC_QUERYCTRL walk) through a second descriptor.
bool set_control(const std::string& name, int value) {
  const int fd = ::open(kVideo, O_RDWR);
  if (fd < 0) return false;
  bool done = false;
  v4l2_queryctrl q{};
  q.id = V4L2_CTRL_FLAG_NEXT_CTRL;
  while (::ioctl(fd, VIDIOC_QUERYCTRL, &q) == 0) {
    if (name == reinterpret_cast<const char*>(q.name)) {
      v4l2_control c{};
      c.id = q.id;
      c.value = value;
      done = ::ioctl(fd, VIDIOC_S_CTRL, &c) == 0;
      break;
    }
    q.id |= V4L2_CTRL_FLAG_NEXT_CTRL;
  }
  ::close(fd);
  return done;
}

hd::V4l2Options options(std::uint32_t w, std::uint32_t h, hd::FormatRequest f) {
  hd::V4l2Options o;
  o.device = kVideo;
  o.width_px = w;
  o.height_px = h;
  o.format = f;
  o.buffers = 4;
  o.reopen_interval_ms = 100;
  o.newest_frame = false;  // every frame, in order: the test checks the sequence
  return o;
}

struct Capture {
  std::vector<hal::FrameView> frames;
  int no_frame = 0;
  int corrupt = 0;
};

// Acquires until @p n frames arrived or @p seconds passed; checks each frame's shape.
Capture capture(hd::V4l2Camera& cam, hd::MonotonicClock& clock, int n, double seconds,
                std::uint32_t w, std::uint32_t h, hal::PixelFormat f) {
  Capture c;
  const std::uint64_t end = clock.now_ns() + static_cast<std::uint64_t>(seconds * 1e9);
  while (static_cast<int>(c.frames.size()) < n && clock.now_ns() < end) {
    hal::FrameView v;
    const std::uint64_t deadline = clock.now_ns() + 500000000ULL;
    const hal::CameraStatus s = cam.acquire(v, deadline);
    // Generous: the emulated machine may be descheduled by the host for a while.
    EXPECT_LE(clock.now_ns(), deadline + 250000000ULL) << "acquire overstayed its deadline";
    if (s == hal::CameraStatus::kFrame) {
      EXPECT_EQ(v.width_px, w);
      EXPECT_EQ(v.height_px, h);
      EXPECT_EQ(v.format, f);
      EXPECT_GE(v.stride_bytes, w * (f == hal::PixelFormat::kYuyv ? 2U : 3U));
      // vivid draws colour bars: the first row is not all one value.
      bool varied = false;
      for (std::uint32_t x = 1; x < v.stride_bytes && !varied; ++x) varied = v.data[x] != v.data[0];
      EXPECT_TRUE(varied) << "an empty frame";
      c.frames.push_back(v);
      cam.release();
    } else if (s == hal::CameraStatus::kCorrupt) {
      ++c.corrupt;
    } else {
      ++c.no_frame;
    }
  }
  return c;
}

TEST(Vivid, YuyvStreamOfThirtyFramesWithTimestampsAndSequence) {
  hd::MonotonicClock clock;
  hd::V4l2Camera cam(clock);
  const std::uint64_t start = clock.now_ns();
  ASSERT_EQ(cam.open(options(320, 180, hd::FormatRequest::kAuto)), "");
  EXPECT_EQ(cam.pixel_format(), hal::PixelFormat::kYuyv) << "auto must prefer YUYV";
  EXPECT_EQ(cam.stride_bytes(), 640U);
  const auto t0 = std::chrono::steady_clock::now();
  const Capture c = capture(cam, clock, 40, 60.0, 320, 180, hal::PixelFormat::kYuyv);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_GE(c.frames.size(), 30U);
  std::uint64_t gaps = 0;
  for (std::size_t i = 0; i < c.frames.size(); ++i) {
    const hal::FrameView& f = c.frames[i];
    EXPECT_GE(f.timestamp_ns, start) << "timestamp before the stream started (not monotonic?)";
    // vivid stamps the ideal end of each frame's period, which can lie a little ahead of the
    // moment the frame is handed out; more than half a second would be another clock.
    EXPECT_LE(f.timestamp_ns, clock.now_ns() + 500000000ULL);
    if (i > 0) {
      EXPECT_GT(f.timestamp_ns, c.frames[i - 1].timestamp_ns);
      EXPECT_GT(f.sequence, c.frames[i - 1].sequence);
      gaps += f.sequence - c.frames[i - 1].sequence - 1;
    }
  }
  EXPECT_EQ(cam.counters().frames, c.frames.size());
  EXPECT_EQ(cam.counters().dropped, gaps) << "dropped must be the sequence gaps";
  EXPECT_EQ(cam.counters().errors, 0U);
  std::printf("VMSTAT v4l2_frames=%zu v4l2_seconds=%.2f v4l2_fps=%.1f v4l2_gaps=%llu\n",
              c.frames.size(), s, static_cast<double>(c.frames.size()) / s,
              static_cast<unsigned long long>(gaps));
}

TEST(Vivid, Rgb24AtAnotherSize) {
  hd::MonotonicClock clock;
  hd::V4l2Camera cam(clock);
  ASSERT_EQ(cam.open(options(640, 360, hd::FormatRequest::kRgb24)), "");
  EXPECT_EQ(cam.pixel_format(), hal::PixelFormat::kRgb24);
  EXPECT_EQ(cam.stride_bytes(), 1920U);
  const Capture c = capture(cam, clock, 5, 30.0, 640, 360, hal::PixelFormat::kRgb24);
  EXPECT_EQ(c.frames.size(), 5U);
}

TEST(Vivid, ASizeTheDeviceCannotGiveFailsStartUpWithOneLine) {
  hd::MonotonicClock clock;
  hd::V4l2Camera cam(clock);
  const std::string e = cam.open(options(320, 240, hd::FormatRequest::kAuto));
  EXPECT_NE(e.find("asked for 320x240, the device gives"), std::string::npos) << e;
  EXPECT_EQ(e.find('\n'), std::string::npos);
  hd::V4l2Camera missing(clock);
  hd::V4l2Options o = options(320, 180, hd::FormatRequest::kAuto);
  o.device = "/dev/video9";
  const std::string m = missing.open(o);
  EXPECT_EQ(m.rfind("/dev/video9: ", 0), 0U) << m;
}

TEST(Vivid, DeadlineIsKeptWhenNoFrameComes) {
  hd::MonotonicClock clock;
  hd::V4l2Camera cam(clock);
  ASSERT_EQ(cam.open(options(320, 180, hd::FormatRequest::kAuto)), "");
  // Ask for a frame within 2 ms, 20 times: vivid (5 fps here) mostly has none. An acquire that
  // waited for the next frame would come back up to 200 ms late, most times.
  int late = 0;
  for (int i = 0; i < 20; ++i) {
    hal::FrameView v;
    const std::uint64_t deadline = clock.now_ns() + 2000000ULL;
    const hal::CameraStatus s = cam.acquire(v, deadline);
    const std::uint64_t now = clock.now_ns();
    if (s == hal::CameraStatus::kFrame) cam.release();
    if (now > deadline + 60000000ULL) ++late;
  }
  EXPECT_LE(late, 2) << "acquire returned more than 60 ms after its deadline " << late << " times";
}

TEST(Vivid, DroppedBuffersAreCountedFromSequenceGaps) {
  hd::MonotonicClock clock;
  hd::V4l2Camera cam(clock);
  ASSERT_EQ(cam.open(options(320, 180, hd::FormatRequest::kAuto)), "");
  ASSERT_TRUE(set_control("Percentage of Dropped Buffers", 50));
  const Capture c = capture(cam, clock, 12, 60.0, 320, 180, hal::PixelFormat::kYuyv);
  ASSERT_TRUE(set_control("Percentage of Dropped Buffers", 0));
  ASSERT_GE(c.frames.size(), 12U);
  std::uint64_t gaps = 0;
  for (std::size_t i = 1; i < c.frames.size(); ++i)
    gaps += c.frames[i].sequence - c.frames[i - 1].sequence - 1;
  EXPECT_GT(gaps, 0U) << "vivid dropped nothing at 50%";
  EXPECT_EQ(cam.counters().dropped, gaps);
  std::printf("VMSTAT v4l2_dropped_at_50pct=%llu of %llu\n", static_cast<unsigned long long>(gaps),
              static_cast<unsigned long long>(gaps + c.frames.size()));
}

TEST(Vivid, ErrorFlaggedBufferIsCorruptAndRequeued) {
  hd::MonotonicClock clock;
  hd::V4l2Camera cam(clock);
  ASSERT_EQ(cam.open(options(320, 180, hd::FormatRequest::kAuto)), "");
  ASSERT_TRUE(set_control("Inject V4L2_BUF_FLAG_ERROR", 1));
  const Capture c = capture(cam, clock, 6, 30.0, 320, 180, hal::PixelFormat::kYuyv);
  EXPECT_EQ(c.corrupt, 1);
  EXPECT_EQ(cam.counters().corrupt, 1U);
  EXPECT_EQ(c.frames.size(), 6U) << "the stream goes on after a bad buffer";
}

TEST(Vivid, FatalStreamingErrorIsRecoveredByReopening) {
  hd::MonotonicClock clock;
  hd::V4l2Camera cam(clock);
  ASSERT_EQ(cam.open(options(320, 180, hd::FormatRequest::kAuto)), "");
  ASSERT_EQ(capture(cam, clock, 2, 20.0, 320, 180, hal::PixelFormat::kYuyv).frames.size(), 2U);
  ASSERT_TRUE(set_control("Inject Fatal Streaming Error", 1));
  const Capture c = capture(cam, clock, 3, 30.0, 320, 180, hal::PixelFormat::kYuyv);
  EXPECT_EQ(c.frames.size(), 3U) << "no frames after the error";
  EXPECT_EQ(cam.counters().errors, 1U);
  EXPECT_EQ(cam.counters().reopens, 1U);
}

TEST(Vivid, UnpluggedDeviceIsReopenedWhenItComesBack) {
  hd::MonotonicClock clock;
  hd::V4l2Camera cam(clock);
  ASSERT_EQ(cam.open(options(320, 180, hd::FormatRequest::kAuto)), "");
  ASSERT_EQ(capture(cam, clock, 2, 20.0, 320, 180, hal::PixelFormat::kYuyv).frames.size(), 2U);
  // vivid's "Disconnect" unregisters the node as an unplug does: poll says POLLERR|POLLHUP and
  // every ioctl ENODEV. The driver counts the error and closes the device at once.
  ASSERT_TRUE(set_control("Disconnect", 1));
  hal::FrameView v;
  EXPECT_EQ(cam.acquire(v, clock.now_ns() + 200000000ULL), hal::CameraStatus::kNoFrame);
  EXPECT_EQ(cam.counters().errors, 1U);
  EXPECT_FALSE(cam.streaming());
  // Keep it unplugged: with nobody holding it, the module can go. Reopen attempts fail quietly
  // and acquire keeps its deadlines meanwhile.
  ASSERT_EQ(std::system("rmmod vivid"), 0);
  const Capture gone = capture(cam, clock, 1, 1.5, 320, 180, hal::PixelFormat::kYuyv);
  EXPECT_EQ(gone.frames.size(), 0U);
  EXPECT_GE(gone.no_frame, 2);
  EXPECT_FALSE(cam.streaming());
  EXPECT_EQ(cam.counters().reopens, 0U);
  // Plugged back in: the driver finds it again by itself.
  ASSERT_EQ(std::system("modprobe vivid"), 0);
  const Capture back = capture(cam, clock, 3, 30.0, 320, 180, hal::PixelFormat::kYuyv);
  EXPECT_EQ(back.frames.size(), 3U);
  EXPECT_EQ(cam.counters().reopens, 1U);
  EXPECT_EQ(cam.counters().errors, 1U);
}

// ---- SocketCAN (vcan0) --------------------------------------------------------------------------

struct Totals {
  std::int64_t left = 0, right = 0;
  int fresh = 0;
  std::uint64_t first_ts = 0, last_ts = 0;
};

// Plays the test log with canplayer (at its recorded pace) while reading every 2 ms; sums the
// wrapped deltas between successive fresh reads, from the log's first counts (left 0xFFFFFFF0,
// right 0x10): a slow VM may read first after the second frame, and a read sees only the
// latest counts.
Totals play_and_read(hd::SocketCanEncoders& enc, std::uint64_t& t_before, std::uint64_t& t_after) {
  hd::MonotonicClock clock;
  Totals t;
  hal::EncoderCounts last{};
  last.left_ticks = 0xFFFFFFF0U;
  last.right_ticks = 0x10U;
  bool have = false;
  t_before = clock.now_ns();
  const std::string cmd = "canplayer -I " + env("HARMOLOC_VM_CAN_LOG") + " vcan0=can0 &";
  EXPECT_EQ(std::system(cmd.c_str()), 0);
  const std::uint64_t end = clock.now_ns() + 3000000000ULL;
  while (clock.now_ns() < end) {
    hal::EncoderCounts c;
    if (enc.read(clock.now_ns(), c) == hal::EncoderStatus::kFresh) {
      t.left += ha::wrapped_delta(last.left_ticks, c.left_ticks, c.counter_bits);
      t.right += ha::wrapped_delta(last.right_ticks, c.right_ticks, c.counter_bits);
      if (have)
        EXPECT_GT(c.timestamp_ns, last.timestamp_ns);
      else
        t.first_ts = c.timestamp_ns;
      t.last_ts = c.timestamp_ns;
      last = c;
      have = true;
      ++t.fresh;
    }
    sleep_ms(2);
  }
  t_after = clock.now_ns();
  return t;
}

TEST(Vcan, PlayedLogGivesCountsAcrossTheWrapAndCountsBadFrames) {
  hd::SocketCanEncoders enc;
  hd::SocketCanOptions o;
  o.interface = "vcan0";  // default layout: 0x181, 8 bytes, 32-bit little-endian
  ASSERT_EQ(enc.open(o), "");
  std::uint64_t before = 0, after = 0;
  const Totals t = play_and_read(enc, before, after);
  // The log: left 0xFFFFFFF0 -> 0x30 (+64 through the wrap), right 0x10 -> 0xFFFFFFE0 (-48).
  EXPECT_EQ(t.left, 64);
  EXPECT_EQ(t.right, -48);
  EXPECT_GE(t.fresh, 2);
  const hal::EncoderCounters k = enc.counters();
  EXPECT_EQ(k.samples, 5U);
  EXPECT_EQ(k.bad_length, 1U);
  EXPECT_EQ(k.ignored_id, 0U) << "the kernel filter passes our ID only";
  // Kernel receive timestamps, on the monotonic clock, within the playing.
  EXPECT_GE(t.first_ts, before);
  EXPECT_LE(t.last_ts, after);
  // The log spans 50 ms; the first read may come after its first two frames (0 and 10 ms).
  EXPECT_GE(t.last_ts - t.first_ts, 15000000ULL) << "the log's good frames span 50 ms";
  std::printf("VMSTAT can_samples=%llu can_fresh_reads=%d can_span_ms=%.1f\n",
              static_cast<unsigned long long>(k.samples), t.fresh,
              static_cast<double>(t.last_ts - t.first_ts) / 1e6);
}

TEST(Vcan, WithoutTheKernelFilterForeignIdsAreCounted) {
  hd::SocketCanEncoders enc;
  hd::SocketCanOptions o;
  o.interface = "vcan0";
  o.kernel_filter = false;
  ASSERT_EQ(enc.open(o), "");
  std::uint64_t before = 0, after = 0;
  const Totals t = play_and_read(enc, before, after);
  EXPECT_EQ(t.left, 64);
  EXPECT_EQ(enc.counters().ignored_id, 1U);
  EXPECT_EQ(enc.counters().bad_length, 1U);
}

TEST(Vcan, ErrorFramesAndBusOffAreCounted) {
  hd::SocketCanEncoders enc;
  hd::SocketCanOptions o;
  o.interface = "vcan0";
  ASSERT_EQ(enc.open(o), "");
  const int s = ::socket(PF_CAN, SOCK_RAW, CAN_RAW);
  ASSERT_GE(s, 0);
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = static_cast<int>(::if_nametoindex("vcan0"));
  ASSERT_EQ(::bind(s, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
  can_frame busoff{};
  busoff.can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF;
  busoff.can_dlc = CAN_ERR_DLC;
  can_frame ctrl{};
  ctrl.can_id = CAN_ERR_FLAG | CAN_ERR_CRTL;
  ctrl.can_dlc = CAN_ERR_DLC;
  ctrl.data[1] = CAN_ERR_CRTL_RX_OVERFLOW;
  ASSERT_EQ(::write(s, &busoff, sizeof busoff), static_cast<ssize_t>(sizeof busoff));
  ASSERT_EQ(::write(s, &ctrl, sizeof ctrl), static_cast<ssize_t>(sizeof ctrl));
  ::close(s);
  sleep_ms(50);
  hal::EncoderCounts c;
  EXPECT_EQ(enc.read(~0ULL, c), hal::EncoderStatus::kNoData);
  EXPECT_EQ(enc.counters().bus_errors, 2U);
  EXPECT_EQ(enc.counters().bus_off, 1U);
}

TEST(Vcan, MissingInterfaceFailsWithOneLine) {
  hd::SocketCanEncoders enc;
  hd::SocketCanOptions o;
  o.interface = "vcan9";
  EXPECT_EQ(enc.open(o), "CAN interface vcan9: no such interface");
}

// ---- GPIO quadrature (gpio-sim) -----------------------------------------------------------------

void pull(unsigned line, bool up) {
  const std::string path =
      env("HARMOLOC_VM_GPIO_SYSFS") + "/sim_gpio" + std::to_string(line) + "/pull";
  std::ofstream f(path);
  f << (up ? "pull-up" : "pull-down");
  f.flush();
  ASSERT_TRUE(f.good()) << path;
}

// Drives a wheel's A/B lines (a, b) through @p steps quarter-steps (negative: reverse), from
// 00, waiting @p gap_ms between edges.
void drive(unsigned a, unsigned b, int steps, int gap_ms, int& phase) {
  static const bool kA[4] = {false, true, true, false};  // 00 10 11 01
  static const bool kB[4] = {false, false, true, true};
  const int dir = steps > 0 ? 1 : -1;
  for (int i = 0; i != steps; i += dir) {
    const int next = (phase + dir + 4) % 4;
    if (kA[next] != kA[phase]) pull(a, kA[next]);
    if (kB[next] != kB[phase]) pull(b, kB[next]);
    phase = next;
    if (gap_ms > 0) sleep_ms(gap_ms);
  }
}

void all_low() {
  for (unsigned l = 0; l < 4; ++l) pull(l, false);
  sleep_ms(20);
}

hd::GpioEncoderOptions gpio_options(hd::GpioReader reader, std::uint32_t debounce_us = 0) {
  hd::GpioEncoderOptions o;
  o.chip = env("HARMOLOC_VM_GPIO_CHIP");
  o.left_lines = {0, 1};
  o.right_lines = {2, 3};
  o.reader = reader;
  o.debounce_us = debounce_us;
  return o;
}

TEST(GpioSim, ForwardAndReverseCountFourPerCycleWithTheReaderThread) {
  ASSERT_FALSE(env("HARMOLOC_VM_GPIO_CHIP").empty());
  all_low();
  hd::GpioQuadratureEncoders enc;
  ASSERT_EQ(enc.open(gpio_options(hd::GpioReader::kThread)), "");
  int left_phase = 0, right_phase = 0;
  drive(0, 1, 40, 2, left_phase);    // left: 10 cycles forward
  drive(2, 3, -12, 2, right_phase);  // right: 3 cycles backward
  drive(0, 1, -6, 2, left_phase);    // left: back 6
  sleep_ms(200);
  EXPECT_EQ(enc.left_position(), 34);
  EXPECT_EQ(enc.right_position(), -12);
  hal::EncoderCounts c;
  ASSERT_EQ(enc.read(123456789, c), hal::EncoderStatus::kFresh);
  EXPECT_EQ(c.left_ticks, 34U);
  EXPECT_EQ(c.right_ticks, static_cast<std::uint32_t>(-12));
  EXPECT_EQ(c.counter_bits, 32);
  EXPECT_EQ(c.timestamp_ns, 123456789U);
  EXPECT_EQ(enc.counters().glitches, 0U);
  std::printf("VMSTAT gpio_left=%lld gpio_right=%lld\n",
              static_cast<long long>(enc.left_position()),
              static_cast<long long>(enc.right_position()));
  drive(0, 1, -left_phase, 2, left_phase);  // back to 00 for the next test
  drive(2, 3, 4 - right_phase, 2, right_phase);
}

TEST(GpioSim, LostEdgesOnBothLinesAreAGlitch) {
  all_low();
  {
    hd::GpioQuadratureEncoders enc;
    ASSERT_EQ(enc.open(gpio_options(hd::GpioReader::kCycle)), "");
    // Without reading, 17 edges on each left line: the kernel keeps 16 a line (v1 API), so the
    // events say "back at 00" while both lines are high: a jump of two steps.
    bool level = false;
    for (int i = 0; i < 17; ++i) {
      level = !level;
      pull(0, level);
    }
    level = false;
    for (int i = 0; i < 17; ++i) {
      level = !level;
      pull(1, level);
    }
    sleep_ms(50);
    hal::EncoderCounts c;
    for (int i = 0; i < 4; ++i) {
      enc.read(0, c);
      sleep_ms(30);
    }
    EXPECT_EQ(enc.counters().glitches, 1U);
    EXPECT_EQ(enc.left_position(), 0);
  }
  // Negative control: the same edges, read as they come, are no glitch.
  all_low();
  hd::GpioQuadratureEncoders slow;
  ASSERT_EQ(slow.open(gpio_options(hd::GpioReader::kCycle)), "");
  hal::EncoderCounts c;
  int phase = 0;
  for (int i = 0; i < 16; ++i) {
    drive(2, 3, 1, 0, phase);
    sleep_ms(5);
    slow.read(0, c);
  }
  for (int i = 0; i < 3; ++i) {
    sleep_ms(30);
    slow.read(0, c);
  }
  EXPECT_EQ(slow.counters().glitches, 0U);
  EXPECT_EQ(slow.right_position(), 16);
  all_low();
}

TEST(GpioSim, OneLostEdgeIsResynchronisedAndCounted) {
  all_low();
  hd::GpioQuadratureEncoders enc;
  ASSERT_EQ(enc.open(gpio_options(hd::GpioReader::kCycle)), "");
  bool level = false;
  for (int i = 0; i < 17; ++i) {  // A ends high, the events end low
    level = !level;
    pull(2, level);
  }
  sleep_ms(50);
  hal::EncoderCounts c;
  for (int i = 0; i < 4; ++i) {
    enc.read(0, c);
    sleep_ms(30);
  }
  EXPECT_EQ(enc.counters().overflows, 1U);
  EXPECT_EQ(enc.counters().glitches, 0U);
  EXPECT_EQ(enc.right_position(), 1);  // 00 -> 10 is one step forward
  all_low();
}

TEST(GpioSim, DebounceIgnoresShortPulses) {
  all_low();
  hd::GpioQuadratureEncoders enc;
  ASSERT_EQ(enc.open(gpio_options(hd::GpioReader::kThread, 50000)), "");  // 50 ms
  // A pulse on left A: up and straight back down (microseconds apart).
  pull(0, true);
  pull(0, false);
  sleep_ms(300);
  EXPECT_EQ(enc.left_position(), 0) << "a bounce was counted";
  // A steady edge counts once it has held for the debounce time.
  pull(0, true);
  sleep_ms(300);
  EXPECT_EQ(enc.left_position(), 1);
  EXPECT_EQ(enc.counters().glitches, 0U);
  all_low();
}

TEST(GpioSim, BadLinesFailStartUpWithOneLine) {
  hd::GpioQuadratureEncoders enc;
  hd::GpioEncoderOptions o = gpio_options(hd::GpioReader::kCycle);
  o.right_lines = {2, 99};
  const std::string e = enc.open(o);
  EXPECT_NE(e.find("right B line 99 does not exist"), std::string::npos) << e;
  hd::GpioQuadratureEncoders missing;
  o = gpio_options(hd::GpioReader::kCycle);
  o.chip = "gpiochip7";
  EXPECT_EQ(missing.open(o).rfind("GPIO chip gpiochip7: ", 0), 0U);
}

}  // namespace
