// Start-up map loading: unreadable and corrupt files give one line, and a map trained for another
// camera mode or other colour thresholds is refused.
#include "harmoloc/firmware/map_loader.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "harmoloc/algorithms/map_codec.hpp"
#include "harmoloc/firmware/config.hpp"
#include "test_support.hpp"

namespace hf = harmoloc::firmware;
namespace ha = harmoloc::algorithms;
namespace ht = harmoloc::test;

namespace {

// A small valid map trained with the default thresholds on 320x240 frames.
std::unique_ptr<ha::MapFile> make_map() {
  auto map = std::make_unique<ha::MapFile>();
  map->image_width_px = 320;
  map->image_height_px = 240;
  map->thresholds = hf::default_config().thresholds;
  ha::HarmonicModel& m = map->model;
  m.sample_count = 3;
  m.feature_count = 2;
  m.board_index = {0, 4, 0, 0, 0, 0, 0, 0};
  m.area_scale = 100.0F / (320.0F * 240.0F);
  m.sigma_x = m.sigma_y = 2.0F;
  m.max_nearest_distance = 1.0F;
  for (std::size_t i = 0; i < 3; ++i) {
    m.sample(i)[0] = static_cast<float>(i);
    m.sample(i)[1] = 1.0F;
    m.target_x_m[i] = static_cast<float>(i) * 0.5F;
    m.target_y_m[i] = 1.0F;
  }
  return map;
}

void expect_one_line_about(const std::string& msg, const std::string& path,
                           const std::string& what) {
  ASSERT_FALSE(msg.empty());
  ht::expect_one_line(msg, "map " + path + ": ", what);
}

}  // namespace

TEST(MapLoader, LoadsAValidMap) {
  ht::TempDir dir;
  const auto map = make_map();
  const std::string path = dir.write_bytes("route.map", ha::encode_map(*map));
  auto out = std::make_unique<ha::MapFile>();
  EXPECT_EQ(hf::load_map(path, *out), "");
  EXPECT_EQ(out->model.sample_count, 3U);
  EXPECT_TRUE(out->thresholds == map->thresholds);
}

TEST(MapLoader, MissingFile) {
  ht::TempDir dir;
  const std::string path = dir.path("nope.map");
  auto out = std::make_unique<ha::MapFile>();
  expect_one_line_about(hf::load_map(path, *out), path, "cannot open");
}

TEST(MapLoader, GarbageEmptyAndCorruptFiles) {
  ht::TempDir dir;
  auto out = std::make_unique<ha::MapFile>();
  std::vector<std::uint8_t> garbage(300);
  for (std::size_t i = 0; i < garbage.size(); ++i)
    garbage[i] = static_cast<std::uint8_t>(i * 37U + 11U);
  std::string path = dir.write_bytes("garbage.map", garbage);
  expect_one_line_about(hf::load_map(path, *out), path, "magic");
  EXPECT_NE(hf::load_map(path, *out).find("(at byte 0)"), std::string::npos);

  path = dir.write_bytes("empty.map", {});
  expect_one_line_about(hf::load_map(path, *out), path, "short");

  std::vector<std::uint8_t> bytes = ha::encode_map(*make_map());
  bytes[40] ^= 0xFFU;
  path = dir.write_bytes("corrupt.map", bytes);
  expect_one_line_about(hf::load_map(path, *out), path, "checksum");
  EXPECT_NE(hf::load_map(path, *out).find("(at byte " + std::to_string(bytes.size() - 4) + ")"),
            std::string::npos)
      << hf::load_map(path, *out);

  bytes = ha::encode_map(*make_map());
  bytes.resize(bytes.size() / 2);
  path = dir.write_bytes("truncated.map", bytes);
  EXPECT_FALSE(hf::load_map(path, *out).empty());
}

TEST(MapLoader, DirectoryIsNotAMap) {
  // `--map` pointed at a folder: a one-line refusal, not an exception out of load_map.
  ht::TempDir dir;
  auto out = std::make_unique<ha::MapFile>();
  std::string msg;
  EXPECT_NO_THROW(msg = hf::load_map(dir.path(""), *out));
  EXPECT_FALSE(msg.empty());
  EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
  EXPECT_EQ(msg.rfind("map ", 0), 0U) << msg;
}

// --map used to read the whole file before checking it (a 300 MB file took 529 MB of memory):
// now anything larger than the format allows is refused from its size, unread; a FIFO or device
// is refused without blocking.
TEST(MapLoader, FileLargerThanAnyMapOrNotARegularFileIsRefusedUnread) {
  ht::TempDir dir;
  auto out = std::make_unique<ha::MapFile>();
  std::vector<std::uint8_t> bytes = ha::encode_map(*make_map());
  bytes.resize(ha::kMaxMapFileBytes + 1, 0);
  std::string path = dir.write_bytes("big.map", bytes);
  expect_one_line_about(hf::load_map(path, *out), path, "more than the");
  path = dir.path("huge.map");
  {
    std::FILE* f = std::fopen(path.c_str(), "wb");
    ASSERT_NE(f, nullptr);
    std::fwrite(bytes.data(), 1, 64, f);
    ASSERT_EQ(std::fseek(f, 300L * 1000 * 1000, SEEK_SET), 0);
    std::fputc(0, f);
    std::fclose(f);
  }
  expect_one_line_about(hf::load_map(path, *out), path, "300000001 bytes, more than the");
  expect_one_line_about(hf::load_map("/dev/zero", *out), "/dev/zero", "not a regular file");
  const std::string fifo = dir.path("map.fifo");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  expect_one_line_about(hf::load_map(fifo, *out), fifo, "not a regular file (a FIFO)");
}

TEST(MapLoader, MatchingMapPasses) {
  const auto map = make_map();
  EXPECT_EQ(hf::check_map_matches(*map, hf::default_config(), 320, 240), "");
}

TEST(MapLoader, ImageSizeMismatch) {
  const auto map = make_map();
  for (const auto& [w, h] :
       {std::pair<std::uint32_t, std::uint32_t>{640, 480}, {320, 200}, {240, 320}}) {
    const std::string msg = hf::check_map_matches(*map, hf::default_config(), w, h);
    ASSERT_FALSE(msg.empty()) << w << "x" << h;
    EXPECT_EQ(msg.find('\n'), std::string::npos);
    EXPECT_NE(msg.find("320x240"), std::string::npos) << msg;
    EXPECT_NE(msg.find(std::to_string(w) + "x" + std::to_string(h)), std::string::npos) << msg;
  }
}

TEST(MapLoader, ThresholdMismatch) {
  const auto map = make_map();
  hf::FirmwareConfig config = hf::default_config();
  config.source = "robot.toml";
  config.thresholds.boards[2].saturation_min = 111;  // blue, board 3
  std::string msg = hf::check_map_matches(*map, config, 320, 240);
  ASSERT_FALSE(msg.empty());
  EXPECT_EQ(msg.find('\n'), std::string::npos);
  EXPECT_NE(msg.find("board 3"), std::string::npos) << msg;
  EXPECT_NE(msg.find("blue"), std::string::npos) << msg;
  EXPECT_NE(msg.find("robot.toml"), std::string::npos) << msg;

  config = hf::default_config();
  config.thresholds.boards[0].hue_min_deg = 341.0F;
  EXPECT_NE(hf::check_map_matches(*map, config, 320, 240).find("board 1"), std::string::npos);

  config = hf::default_config();
  config.thresholds.count = 5;
  msg = hf::check_map_matches(*map, config, 320, 240);
  EXPECT_NE(msg.find("6 boards"), std::string::npos) << msg;
}
