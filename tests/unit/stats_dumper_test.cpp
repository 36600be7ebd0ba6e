// The stats file on request (boards/common/stats_dumper.hpp): written whole, and a file that
// cannot be written is counted and said, never a half file or a stuck writer.
#include "stats_dumper.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <thread>

#include "harmoloc/algorithms/map_codec.hpp"
#include "harmoloc/firmware/config.hpp"
#include "harmoloc/firmware/localization_cycle.hpp"
#include "test_support.hpp"

namespace {

namespace ha = harmoloc::algorithms;
namespace hb = harmoloc::boards;
namespace hf = harmoloc::firmware;
namespace hh = harmoloc::hal;

constexpr std::uint32_t kWidth = 32, kHeight = 24;

class NoCamera final : public hh::Camera {
 public:
  hh::CameraStatus acquire(hh::FrameView&, std::uint64_t) override {
    return hh::CameraStatus::kNoFrame;
  }
  void release() override {}
  hh::CameraCounters counters() const override { return {}; }
};

class NoEncoders final : public hh::WheelEncoders {
 public:
  hh::EncoderStatus read(std::uint64_t, hh::EncoderCounts&) override {
    return hh::EncoderStatus::kNoData;
  }
  hh::EncoderCounters counters() const override { return {}; }
};

class NoLink final : public hh::PoseLink {
 public:
  hh::LinkWrite write_frame(const std::uint8_t*, std::size_t) override {
    return hh::LinkWrite::kSent;
  }
  hh::LinkCounters counters() const override { return {}; }
};

// Time passes only when the cycle waits: a cycle with no camera frame waits for its deadline.
class StepClock final : public hh::Clock {
 public:
  std::uint64_t now_ns() const override { return now_; }
  void sleep_until(std::uint64_t wake_ns) override { now_ = std::max(now_, wake_ns); }

 private:
  mutable std::uint64_t now_ = 0;
};

// The dumper's writer is a second thread, and qemu-user 7.2 never returns from a second thread's
// start (see SpscRing.TwoThreadsPassEveryValueInOrder): natively and under the sanitizers only;
// the VM bench asks the Linux board for its stats with SIGUSR1 on both architectures.
#ifdef HARMOLOC_TESTS_UNDER_QEMU_USER
#define SKIP_UNDER_QEMU_USER() GTEST_SKIP() << "threads hang under qemu-user"
#else
#define SKIP_UNDER_QEMU_USER() static_cast<void>(0)
#endif

// A cycle that has run a few times (no frames: the counters are what the file shows).
struct Rig {
  Rig() {
    map->image_width_px = kWidth;
    map->image_height_px = kHeight;
    map->thresholds = hf::default_config().thresholds;
    ha::HarmonicModel& h = map->model;
    h.sample_count = 1;
    h.feature_count = 1;
    h.area_scale = 100.0F / (kWidth * kHeight);
    h.sigma_x = h.sigma_y = 1.0F;
    h.max_nearest_distance = 5.0F;
    cycle = std::make_unique<hf::LocalizationCycle>(config, *map, camera, encoders, link, clock);
    for (int i = 0; i < 7; ++i) cycle->run_once();
  }
  // The cycle keeps references to the config and the map: both live as long as it does.
  hf::FirmwareConfig config = hf::default_config();
  std::unique_ptr<ha::MapFile> map = std::make_unique<ha::MapFile>();
  NoCamera camera;
  NoEncoders encoders;
  NoLink link;
  StepClock clock;
  std::unique_ptr<hf::LocalizationCycle> cycle;
  hf::RunCounters run;
};

// As the board's loop does: a request that finds the writer holding its lock (for an instant,
// as it starts waiting) is made again.
bool request(hb::StatsDumper& dumper, const Rig& rig) {
  for (int attempt = 0; attempt < 100000; ++attempt) {
    if (dumper.request(*rig.cycle, rig.run)) return true;
    std::this_thread::yield();
  }
  return false;
}

// A dumper started on @p path, asked once for a rig's stats and stopped: what it counted and
// what it said on stderr.
struct OneRequest {
  std::string start_error;
  bool requested = false;
  std::uint64_t written = 0;
  std::uint64_t failed = 0;
  std::string said;
};

OneRequest request_once(const std::string& path) {
  OneRequest r;
  Rig rig;
  hb::StatsDumper dumper;
  r.start_error = dumper.start(path, true);
  if (!r.start_error.empty()) return r;
  // Captured before the request: the writer may say it at once.
  testing::internal::CaptureStderr();
  r.requested = request(dumper, rig);
  dumper.stop();
  r.said = testing::internal::GetCapturedStderr();
  r.written = dumper.written();
  r.failed = dumper.failed();
  return r;
}

}  // namespace

TEST(StatsDumper, WritesTheWholeFileWhileRunning) {
  SKIP_UNDER_QEMU_USER();
  harmoloc::test::TempDir dir;
  Rig rig;
  hb::StatsDumper dumper;
  ASSERT_EQ(dumper.start(dir.path("stats.json"), true), "");
  ASSERT_TRUE(request(dumper, rig));
  dumper.stop();  // writes what was asked for first
  EXPECT_EQ(dumper.written(), 1U);
  EXPECT_EQ(dumper.failed(), 0U);
  std::ifstream in(dir.path("stats.json"));
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j.at("ended"), "running");
  EXPECT_EQ(j.at("cycles"), 7);
  EXPECT_FALSE(std::filesystem::exists(dir.path("stats.json.tmp")));
}

TEST(StatsDumper, AFolderThatIsNotThereIsCountedAsAFailure) {
  SKIP_UNDER_QEMU_USER();
  harmoloc::test::TempDir dir;
  const OneRequest r = request_once(dir.path("missing/stats.json"));
  ASSERT_EQ(r.start_error, "");
  ASSERT_TRUE(r.requested);
  EXPECT_EQ(r.written, 0U);
  EXPECT_EQ(r.failed, 1U);
  EXPECT_NE(r.said.find("harmoloc: stats on request: "), std::string::npos) << r.said;
  EXPECT_NE(r.said.find("missing/stats.json"), std::string::npos) << r.said;
}

TEST(StatsDumper, AFileThatCannotBeReplacedLeavesNoTemporaryBehind) {
  SKIP_UNDER_QEMU_USER();
  harmoloc::test::TempDir dir;
  // The path is a folder with something in it: the temporary file is written, the rename fails.
  dir.mkdir("stats.json/inside");
  const OneRequest r = request_once(dir.path("stats.json"));
  ASSERT_EQ(r.start_error, "");
  ASSERT_TRUE(r.requested);
  EXPECT_EQ(r.written, 0U);
  EXPECT_EQ(r.failed, 1U);
  EXPECT_NE(r.said.find("cannot replace"), std::string::npos) << r.said;
  EXPECT_FALSE(std::filesystem::exists(dir.path("stats.json.tmp")));
  EXPECT_TRUE(std::filesystem::is_directory(dir.path("stats.json/inside")));
}
