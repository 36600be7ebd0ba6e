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

namespace hal = harmoloc::hal;
namespace fs = std::filesystem;

namespace {

void round_trip(hal::PixelFormat format) {
  const std::string dir =
      (fs::temp_directory_path() / ("harmoloc_recording_replay_" + std::to_string(::getpid()) +
                                    "_" + std::to_string(static_cast<int>(format))))
          .string();
  fs::remove_all(dir);
  fs::create_directories(dir);
  constexpr std::uint32_t kW = 8, kH = 4;
  const std::uint32_t row = kW * (format == hal::PixelFormat::kRgb24 ? 3U : 2U);
  const std::uint32_t stride = row + 8;  // padded rows, as a driver may hand them
  std::vector<std::vector<std::uint8_t>> sent;
  {
    harmoloc::drivers::FrameRecorder recorder;
    ASSERT_EQ(recorder.start(dir, kW, kH, format, {}), "");
    for (std::uint8_t n = 0; n < 5; ++n) {
      std::vector<std::uint8_t> buffer(std::size_t{stride} * kH, 0xEE);
      std::vector<std::uint8_t> packed;
      for (std::uint32_t y = 0; y < kH; ++y) {
        for (std::uint32_t x = 0; x < row; ++x) {
          const auto v = static_cast<std::uint8_t>(n * 31 + y * 7 + x);
          buffer[std::size_t{y} * stride + x] = v;
          packed.push_back(v);
        }
      }
      sent.push_back(packed);
      hal::FrameView f;
      f.data = buffer.data();
      f.width_px = kW;
      f.height_px = kH;
      f.stride_bytes = stride;
      f.format = format;
      f.timestamp_ns = 1767225600000000000ULL + n * 33333333ULL;
      recorder.offer(f);
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
        ASSERT_EQ(f.data[std::size_t{y} * f.stride_bytes + x], sent[n][std::size_t{y} * row + x])
            << "frame " << n << " row " << y << " byte " << x;
      }
    }
    camera.release();
  }
  fs::remove_all(dir);
}

TEST(RecordingReplay, YuyvFramesRecordedOnTheRobotReplayByteForByte) {
  round_trip(hal::PixelFormat::kYuyv);
}

TEST(RecordingReplay, RgbFramesReplayByteForByte) {
  round_trip(hal::PixelFormat::kRgb24);
}

}  // namespace
