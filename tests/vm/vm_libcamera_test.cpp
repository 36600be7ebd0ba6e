// The libcamera driver against vimc (the kernel's virtual media-controller camera, built out of
// tree for the test VM) through Debian's libcamera 0.0.3 and its vimc pipeline handler.
// Runs inside the VM only (tests/vm/run_vm_tests.sh); a separate program because anything that
// links libcamera hangs under qemu-user.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "harmoloc/drivers/libcamera_camera.hpp"
#include "harmoloc/drivers/monotonic_clock.hpp"

namespace hd = harmoloc::drivers;
namespace hal = harmoloc::hal;

namespace {

hd::LibcameraOptions options(std::uint32_t w, std::uint32_t h) {
  hd::LibcameraOptions o;
  o.width_px = w;
  o.height_px = h;
  o.format = hd::FormatRequest::kAuto;
  o.buffers = 4;
  return o;
}

TEST(Vimc, ListsTheVimcCamera) {
  const std::vector<std::string> ids = hd::LibcameraCamera::list_cameras();
  ASSERT_FALSE(ids.empty()) << "libcamera finds no camera (vimc loaded? IPA module there?)";
  for (const std::string& id : ids) std::printf("VMSTAT libcamera_camera=%s\n", id.c_str());
}

TEST(Vimc, StreamsThirtyFramesThroughTheRingWithoutCopies) {
  hd::MonotonicClock clock;
  // A size the pipeline adjusts (vimc aligns the width) fails start-up and names what it gives.
  std::uint32_t w = 0, h = 0;
  {
    hd::LibcameraCamera probe(clock);
    const std::string e = probe.open(options(640, 480));
    const std::size_t at = e.find("the camera gives BGR888 ");
    ASSERT_NE(at, std::string::npos) << e;
    ASSERT_EQ(std::sscanf(e.c_str() + at + 24, "%ux%u", &w, &h), 2) << e;
    std::printf("VMSTAT libcamera_adjusted=%s\n", e.c_str());
  }
  hd::LibcameraCamera cam(clock);
  const std::uint64_t start = clock.now_ns();
  ASSERT_EQ(cam.open(options(w, h)), "");
  std::printf("VMSTAT libcamera_config=%s\n", cam.description().c_str());
  // vimc's pipeline gives RGB formats only: auto falls back from YUYV to RGB24 (BGR888).
  EXPECT_EQ(cam.pixel_format(), hal::PixelFormat::kRgb24);
  std::vector<std::uint64_t> stamps;
  std::vector<std::uint32_t> sequences;
  int no_frame = 0;
  const std::uint64_t end = clock.now_ns() + 90000000000ULL;
  while (stamps.size() < 32 && clock.now_ns() < end) {
    hal::FrameView f;
    const std::uint64_t deadline = clock.now_ns() + 500000000ULL;
    const hal::CameraStatus s = cam.acquire(f, deadline);
    EXPECT_LE(clock.now_ns(), deadline + 50000000ULL) << "acquire overstayed its deadline";
    if (s != hal::CameraStatus::kFrame) {
      ++no_frame;
      continue;
    }
    EXPECT_EQ(f.width_px, w);
    EXPECT_EQ(f.height_px, h);
    EXPECT_GE(f.stride_bytes, w * 3U);
    EXPECT_EQ(f.format, hal::PixelFormat::kRgb24);
    bool varied = false;
    for (std::uint32_t x = 1; x < f.stride_bytes && !varied; ++x) varied = f.data[x] != f.data[0];
    EXPECT_TRUE(varied) << "an empty frame";
    stamps.push_back(f.timestamp_ns);
    sequences.push_back(f.sequence);
    cam.release();  // back to libcamera through the requeue thread
  }
  // More frames than buffers: the requests went round through release() and the requeuer.
  ASSERT_GE(stamps.size(), 30U);
  std::uint64_t gaps = 0;
  for (std::size_t i = 1; i < stamps.size(); ++i) {
    EXPECT_GT(stamps[i], stamps[i - 1]);
    EXPECT_GT(sequences[i], sequences[i - 1]);
    gaps += sequences[i] - sequences[i - 1] - 1;
  }
  EXPECT_GE(stamps.front(), start) << "not CLOCK_MONOTONIC";
  EXPECT_LE(stamps.back(), clock.now_ns() + 500000000ULL);
  const hal::CameraCounters c = cam.counters();
  EXPECT_EQ(c.frames, stamps.size());
  EXPECT_EQ(c.corrupt, 0U);
  std::printf("VMSTAT libcamera_frames=%zu seconds=%.1f gaps=%llu dropped=%llu no_frame=%d\n",
              stamps.size(), static_cast<double>(clock.now_ns() - start) / 1e9,
              static_cast<unsigned long long>(gaps), static_cast<unsigned long long>(c.dropped),
              no_frame);
}

TEST(Vimc, AnUnknownCameraIdFailsWithOneLine) {
  hd::MonotonicClock clock;
  hd::LibcameraCamera cam(clock);
  hd::LibcameraOptions o = options(640, 480);
  o.camera_id = "no-such-camera";
  const std::string e = cam.open(o);
  EXPECT_EQ(e.rfind("libcamera: no camera 'no-such-camera' (found: ", 0), 0U) << e;
  EXPECT_EQ(e.find('\n'), std::string::npos);
}

}  // namespace
