// A recording made by `harmoloc --record` replays on the host board with no conversion: the
// frames a FrameRecorder wrote (YUYV as a V4L2 camera gives them, or RGB) and the metadata the
// recording writes are read back by the host board's FileCamera byte for byte, at their times.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "harmoloc/dataset/metadata.hpp"
#include "harmoloc/drivers/frame_recorder.hpp"
#include "harmoloc/host/file_camera.hpp"
#include "strided_frame.hpp"
#include "test_support.hpp"

namespace hal = harmoloc::hal;

namespace {

void round_trip(hal::PixelFormat format) {
  const harmoloc::test::TempDir temp;
  const std::string dir = temp.dir();
  constexpr std::uint32_t kW = 8, kH = 4;
  const auto value = [](std::uint32_t n) {
    return [n](std::uint32_t y, std::uint32_t x) { return n * 31 + y * 7 + x; };
  };
  std::uint32_t row = 0;
  {
    harmoloc::drivers::FrameRecorder recorder;
    ASSERT_EQ(recorder.start(dir, kW, kH, format, {}), "");
    for (std::uint32_t n = 0; n < 5; ++n) {
      const harmoloc::test::StridedFrame f(kW, kH, format, 1767225600000000000ULL + n * 33333333ULL,
                                           value(n));
      row = f.row_bytes();
      recorder.offer(f.view());
      // One frame at a time: the writer thread takes it before the buffer goes away.
      for (int i = 0; i < 1000 && recorder.counters().recorded <= n; ++i) ::usleep(2000);
    }
    recorder.stop();
    ASSERT_EQ(recorder.counters().recorded, 5U);
  }
  harmoloc::dataset::DatasetMetadata meta;
  meta.image_width_px = kW;
  meta.image_height_px = kH;
  meta.pixel_format = format;
  meta.encoder_source = harmoloc::dataset::EncoderSource::kGpio;
  meta.encoder_log = "encoders.csv";
  meta.ground_truth.clear();
  harmoloc::dataset::write_metadata(dir, meta);
  const harmoloc::dataset::DatasetMetadata read = harmoloc::dataset::read_metadata(dir);
  EXPECT_EQ(read.pixel_format, format);
  harmoloc::host::FileCamera camera(dir, read);
  ASSERT_EQ(camera.frame_count(), 5U);
  for (std::size_t n = 0; n < 5; ++n) {
    hal::FrameView f;
    ASSERT_EQ(camera.acquire(f, ~std::uint64_t{0}), hal::CameraStatus::kFrame) << "frame " << n;
    EXPECT_EQ(f.format, format);
    EXPECT_EQ(f.timestamp_ns, 1767225600000000000ULL + n * 33333333ULL);
    for (std::uint32_t y = 0; y < kH; ++y) {
      for (std::uint32_t x = 0; x < row; ++x) {
        ASSERT_EQ(f.data[std::size_t{y} * f.stride_bytes + x],
                  static_cast<std::uint8_t>(value(static_cast<std::uint32_t>(n))(y, x)))
            << "frame " << n << " row " << y << " byte " << x;
      }
    }
    camera.release();
  }
}

TEST(RecordingReplay, YuyvFramesRecordedOnTheRobotReplayByteForByte) {
  round_trip(hal::PixelFormat::kYuyv);
}

TEST(RecordingReplay, RgbFramesReplayByteForByte) {
  round_trip(hal::PixelFormat::kRgb24);
}

}  // namespace
