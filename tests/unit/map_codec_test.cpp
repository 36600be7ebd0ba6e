// The map file: round trip, byte layout, and every kind of corruption rejected with a reason.
#include "harmoloc/algorithms/map_codec.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "harmoloc/algorithms/board_observation.hpp"
#include "harmoloc/algorithms/crc32.hpp"
#include "test_support.hpp"

namespace ha = harmoloc::algorithms;
namespace ht = harmoloc::test;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kHalfPi = kPi / 2.0;
constexpr std::size_t kBoards = 6;
constexpr std::size_t kFeatures = 3;
constexpr std::size_t kSamples = 5;

// Offsets by hand from the layout: magic 8, version 4, width 4, height 4, board count 4,
// 12 bytes a board, sample count 4, feature count 4, one byte a feature, 6 floats, samples.
constexpr std::size_t kOffVersion = 8;
constexpr std::size_t kOffBoardCount = 20;
constexpr std::size_t kOffBoards = 24;
constexpr std::size_t kOffSampleCount = kOffBoards + 12 * kBoards;
constexpr std::size_t kOffFeatureCount = kOffSampleCount + 4;
constexpr std::size_t kOffBoardIndex = kOffFeatureCount + 4;
constexpr std::size_t kOffAreaScale = kOffBoardIndex + kFeatures;
constexpr std::size_t kOffSigmaX = kOffAreaScale + 4;
constexpr std::size_t kOffDissimilarity = kOffAreaScale + 6 * 4;
constexpr std::size_t kOffWeights = kOffAreaScale + 7 * 4;  // version 4
constexpr std::size_t kOffSamples = kOffWeights + kFeatures * 4;
// Version 3: the forward map's grid size (0 x 0 here: none), then the CRC.
constexpr std::size_t kOffForward = kOffSamples + kSamples * (kFeatures + 2) * 4;
// The forward map's grid size (0, 0: none), the calibration's entry count (0), the per-sample fix
// errors' count (0, version 11), the column gain (0, 0, version 13), the column weight (0,
// version 12), the CRC.
constexpr std::size_t kOffCalibration = kOffForward + 8;
constexpr std::size_t kExpectedSize = kOffCalibration + 4 + 4 + 8 + 4 + 4;
// What follows the calibration entries: the fix errors' count, the column gain, the column
// weight, the CRC.
constexpr std::size_t kAfterCalibration = 4 + 8 + 4 + 4;

std::unique_ptr<ha::MapFile> make_map() {
  auto map = std::make_unique<ha::MapFile>();
  map->image_width_px = 640;
  map->image_height_px = 480;
  map->thresholds.count = kBoards;
  // The six boards' hues, each with its own saturation and value bounds.
  for (std::size_t i = 0; i < kBoards; ++i) {
    map->thresholds.boards[i] = ha::ColourThreshold{
        ht::kBoardHuesDeg[i][0], ht::kBoardHuesDeg[i][1], static_cast<std::uint8_t>(100 + i),
        static_cast<std::uint8_t>(50 + i), static_cast<std::uint8_t>(250 - i)};
  }
  ha::HarmonicModel& m = map->model;
  m.sample_count = kSamples;
  m.feature_count = kFeatures;
  m.board_index = {0, 1, 4, 0, 0, 0, 0, 0};
  m.area_scale = 100.0F / (640.0F * 480.0F);
  m.sigma_x = 267.06F;
  m.sigma_y = 454.16F;
  m.gamma_x = 0.015F;
  m.gamma_y = 0.01F;
  m.max_nearest_distance = 0.75F;
  for (std::size_t i = 0; i < kSamples; ++i) {
    for (std::size_t k = 0; k < kFeatures; ++k)
      m.sample(i)[k] = 0.25F * static_cast<float>(i + 1) + static_cast<float>(k);
    m.target_x_m[i] = 1.5F + 0.1F * static_cast<float>(i);
    m.target_y_m[i] = -0.25F * static_cast<float>(i);
  }
  return map;
}

void put_u32(std::vector<std::uint8_t>& b, std::size_t at, std::uint32_t v) {
  for (int i = 0; i < 4; ++i)
    b[at + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(v >> (8 * i));
}
std::uint32_t get_u32(const std::vector<std::uint8_t>& b, std::size_t at) {
  std::uint32_t v = 0;
  for (int i = 0; i < 4; ++i)
    v |= static_cast<std::uint32_t>(b[at + static_cast<std::size_t>(i)]) << (8 * i);
  return v;
}
float get_f32(const std::vector<std::uint8_t>& b, std::size_t at) {
  const std::uint32_t u = get_u32(b, at);
  float f = 0.0F;
  std::memcpy(&f, &u, 4);
  return f;
}
void put_f32(std::vector<std::uint8_t>& b, std::size_t at, float f) {
  std::uint32_t u = 0;
  std::memcpy(&u, &f, 4);
  put_u32(b, at, u);
}
// Recomputes the trailing CRC so that a check other than the checksum has to catch the edit.
void fix_crc(std::vector<std::uint8_t>& b) {
  put_u32(b, b.size() - 4, ha::crc32(b.data(), b.size() - 4));
}

std::string decode_error(const std::vector<std::uint8_t>& b) {
  auto out = std::make_unique<ha::MapFile>();
  const ha::MapError e = ha::decode_map(b.data(), b.size(), *out);
  return e ? std::string(e.what) : std::string();
}

}  // namespace

TEST(Crc32, CheckValueAndChaining) {
  const std::string s = "123456789";
  const auto* p = reinterpret_cast<const std::uint8_t*>(s.data());
  EXPECT_EQ(ha::crc32(p, s.size()), 0xCBF43926U);
  EXPECT_EQ(ha::crc32(p, 0), 0U);
  EXPECT_EQ(ha::crc32(p + 4, s.size() - 4, ha::crc32(p, 4)), 0xCBF43926U);  // as zlib's crc32()
  const std::uint8_t a = 'a';
  EXPECT_EQ(ha::crc32(&a, 1), 0xE8B7BE43U);
}

TEST(MapCodec, RoundTripAndLayout) {
  const auto map = make_map();
  const std::vector<std::uint8_t> bytes = ha::encode_map(*map);
  ASSERT_EQ(bytes.size(), kExpectedSize);
  EXPECT_EQ(std::string(bytes.begin(), bytes.begin() + 8), "HARMOMAP");
  EXPECT_EQ(get_u32(bytes, kOffVersion), ha::kMapFormatVersion);
  EXPECT_EQ(get_u32(bytes, 12), 640U);
  EXPECT_EQ(get_u32(bytes, 16), 480U);
  EXPECT_EQ(get_u32(bytes, kOffBoardCount), kBoards);
  EXPECT_EQ(get_u32(bytes, kOffSampleCount), kSamples);
  EXPECT_EQ(get_u32(bytes, kOffFeatureCount), kFeatures);
  EXPECT_EQ(bytes[kOffBoardIndex + 2], 4U);
  EXPECT_EQ(get_u32(bytes, bytes.size() - 4), ha::crc32(bytes.data(), bytes.size() - 4));

  auto out = std::make_unique<ha::MapFile>();
  const ha::MapError e = ha::decode_map(bytes.data(), bytes.size(), *out);
  ASSERT_FALSE(e) << e.what;
  EXPECT_EQ(out->image_width_px, 640U);
  EXPECT_EQ(out->image_height_px, 480U);
  EXPECT_TRUE(out->thresholds == map->thresholds);
  const ha::HarmonicModel& a = map->model;
  const ha::HarmonicModel& b = out->model;
  EXPECT_EQ(b.sample_count, a.sample_count);
  EXPECT_EQ(b.feature_count, a.feature_count);
  for (std::size_t k = 0; k < kFeatures; ++k) EXPECT_EQ(b.board_index[k], a.board_index[k]);
  EXPECT_EQ(b.area_scale, a.area_scale);
  EXPECT_EQ(b.sigma_x, a.sigma_x);
  EXPECT_EQ(b.sigma_y, a.sigma_y);
  EXPECT_EQ(b.gamma_x, a.gamma_x);
  EXPECT_EQ(b.gamma_y, a.gamma_y);
  EXPECT_EQ(b.max_nearest_distance, a.max_nearest_distance);
  EXPECT_EQ(b.max_dissimilarity, a.max_dissimilarity);
  for (std::size_t i = 0; i < kSamples; ++i) {
    for (std::size_t k = 0; k < kFeatures; ++k)
      EXPECT_EQ(b.sample(i)[k], a.sample(i)[k]) << i << "," << k;
    EXPECT_EQ(b.target_x_m[i], a.target_x_m[i]);
    EXPECT_EQ(b.target_y_m[i], a.target_y_m[i]);
  }
  // Encoding the decoded map gives the same bytes.
  EXPECT_EQ(ha::encode_map(*out), bytes);
}

TEST(MapCodec, BadMagic) {
  std::vector<std::uint8_t> b = ha::encode_map(*make_map());
  b[0] = 'X';
  EXPECT_NE(decode_error(b).find("magic"), std::string::npos) << decode_error(b);
  fix_crc(b);
  EXPECT_NE(decode_error(b).find("magic"), std::string::npos) << decode_error(b);
}

TEST(MapCodec, UnsupportedVersion) {
  std::vector<std::uint8_t> b = ha::encode_map(*make_map());
  put_u32(b, kOffVersion, ha::kMapFormatVersion + 1);
  EXPECT_NE(decode_error(b).find("version"), std::string::npos) << decode_error(b);
  fix_crc(b);
  EXPECT_NE(decode_error(b).find("version"), std::string::npos) << decode_error(b);
}

// Removes the version 13 column gain (a map without columns: before the column weight).
static void strip_gain(std::vector<std::uint8_t>& b) {
  b.erase(b.end() - 16, b.end() - 8);
}

// Removes the version 13 column gain and the version 12 column weight (a map without columns)
// before the CRC.
static void strip_columns(std::vector<std::uint8_t>& b) {
  b.erase(b.end() - 16, b.end() - 4);
}

// Removes the version 11 per-sample fix errors' count, the column gain and the column weight (a
// map without them) before the CRC.
static void strip_fix_errors(std::vector<std::uint8_t>& b) {
  b.erase(b.end() - 20, b.end() - 4);
}

// Removes the version 4 calibration's entry count and all that follows it (a map with none of
// them) before the CRC.
static void strip_calibration(std::vector<std::uint8_t>& b) {
  b.erase(b.end() - 24, b.end() - 4);
}

// Removes the version 4 feature weights (after the calibration: offsets before it stay).
static void strip_weights(std::vector<std::uint8_t>& b) {
  b.erase(b.begin() + static_cast<std::ptrdiff_t>(kOffWeights),
          b.begin() + static_cast<std::ptrdiff_t>(kOffWeights + 4 * kFeatures));
}

// Maps written before the calibration existed (version 3) still load, without it.
TEST(MapCodec, ReadsVersionThree) {
  auto map = make_map();
  map->calibration.present = true;
  map->calibration.fix_rmse_x_m = 0.02F;
  std::vector<std::uint8_t> b = ha::encode_map(*make_map());
  strip_calibration(b);
  strip_weights(b);
  put_u32(b, kOffVersion, 3);
  fix_crc(b);
  auto out = std::make_unique<ha::MapFile>();
  out->calibration = map->calibration;  // whatever the object held before is replaced
  const ha::MapError e = ha::decode_map(b.data(), b.size(), *out);
  ASSERT_FALSE(e) << e.what;
  EXPECT_FALSE(out->calibration.present);
  for (std::size_t k = 0; k < kFeatures; ++k) EXPECT_EQ(out->model.feature_weight[k], 1.0F);
}

TEST(MapCodec, FeatureWeightsRoundTripAndChecks) {
  auto map = make_map();
  map->model.feature_weight[1] = 0.0F;
  std::vector<std::uint8_t> bytes = ha::encode_map(*map);
  auto out = std::make_unique<ha::MapFile>();
  ASSERT_FALSE(ha::decode_map(bytes.data(), bytes.size(), *out));
  EXPECT_EQ(out->model.feature_weight[0], 1.0F);
  EXPECT_EQ(out->model.feature_weight[1], 0.0F);
  for (float v : {-0.5F, 1.5F, std::numeric_limits<float>::quiet_NaN()}) {
    std::vector<std::uint8_t> b = bytes;
    put_f32(b, kOffWeights, v);
    fix_crc(b);
    EXPECT_NE(decode_error(b).find("feature weight"), std::string::npos) << decode_error(b);
  }
  std::vector<std::uint8_t> b = bytes;
  for (std::size_t k = 0; k < kFeatures; ++k) put_f32(b, kOffWeights + 4 * k, 0.0F);
  fix_crc(b);
  EXPECT_NE(decode_error(b).find("every feature weight"), std::string::npos) << decode_error(b);
}

TEST(MapCodec, CalibrationRoundTripAndChecks) {
  auto map = make_map();
  map->calibration.present = true;
  map->calibration.fix_rmse_x_m = 0.021F;
  map->calibration.fix_rmse_y_m = 0.034F;
  map->calibration.pass_spread_m = 0.012F;
  const std::vector<std::uint8_t> bytes = ha::encode_map(*map);
  ASSERT_EQ(bytes.size(), kExpectedSize + 24);
  auto out = std::make_unique<ha::MapFile>();
  ASSERT_FALSE(ha::decode_map(bytes.data(), bytes.size(), *out));
  EXPECT_TRUE(out->calibration.present);
  EXPECT_EQ(out->calibration.fix_rmse_x_m, 0.021F);
  EXPECT_EQ(out->calibration.fix_rmse_y_m, 0.034F);
  EXPECT_EQ(out->calibration.pass_spread_m, 0.012F);
  EXPECT_EQ(ha::encode_map(*out), bytes);
  // An entry this firmware does not know, a value out of range or not finite: refused.
  const std::size_t first_id = kOffCalibration + 4;
  std::vector<std::uint8_t> b = bytes;
  put_u32(b, first_id, 77);
  fix_crc(b);
  EXPECT_NE(decode_error(b).find("unknown calibration"), std::string::npos) << decode_error(b);
  for (float v : {-1.0F, 1e6F, std::numeric_limits<float>::quiet_NaN(),
                  std::numeric_limits<float>::infinity()}) {
    b = bytes;
    put_f32(b, first_id + 4, v);
    fix_crc(b);
    EXPECT_NE(decode_error(b).find("calibration value"), std::string::npos) << decode_error(b);
  }
  b = bytes;
  put_u32(b, kOffCalibration, 100000);  // the entry count
  fix_crc(b);
  EXPECT_NE(decode_error(b).find("calibration"), std::string::npos) << decode_error(b);
}

// The local linear correction's ridge travels as calibration entry 4, written only when the
// trainer chose it: a map without it is byte for byte what it was, and one with it alone (no
// measured calibration) is still a map without calibration.
TEST(MapCodec, LocalLinearRidgeRoundTrip) {
  auto map = make_map();
  const std::vector<std::uint8_t> plain = ha::encode_map(*map);
  map->model.local_linear_ridge = 0.03F;
  const std::vector<std::uint8_t> bytes = ha::encode_map(*map);
  ASSERT_EQ(bytes.size(), plain.size() + 8);
  auto out = std::make_unique<ha::MapFile>();
  ASSERT_FALSE(ha::decode_map(bytes.data(), bytes.size(), *out));
  EXPECT_EQ(out->model.local_linear_ridge, 0.03F);
  EXPECT_FALSE(out->calibration.present);
  EXPECT_EQ(ha::encode_map(*out), bytes);
  map->calibration.present = true;
  map->calibration.fix_rmse_x_m = 0.02F;
  const std::vector<std::uint8_t> both = ha::encode_map(*map);
  ASSERT_FALSE(ha::decode_map(both.data(), both.size(), *out));
  EXPECT_EQ(out->model.local_linear_ridge, 0.03F);
  EXPECT_TRUE(out->calibration.present);
  EXPECT_EQ(out->calibration.fix_rmse_x_m, 0.02F);
  // Only what encode_map writes is read: entries in order, 1 to 3 together, no ridge of 0.
  const std::size_t count_at = both.size() - kAfterCalibration - 4 - 4 * 8;
  ASSERT_EQ(get_u32(both, count_at), 4U);
  std::vector<std::uint8_t> b = both;
  put_u32(b, count_at + 4, 2);  // ids 2, 2, 3, 4
  fix_crc(b);
  EXPECT_NE(decode_error(b).find("out of order"), std::string::npos) << decode_error(b);
  b = both;
  put_f32(b, count_at + 4 + 3 * 8 + 4, 0.0F);  // the ridge
  fix_crc(b);
  EXPECT_NE(decode_error(b).find("ridge 0"), std::string::npos) << decode_error(b);
  b = both;
  b.erase(b.begin() + static_cast<std::ptrdiff_t>(count_at + 4 + 2 * 8),
          b.begin() + static_cast<std::ptrdiff_t>(count_at + 4 + 3 * 8));  // without entry 3
  put_u32(b, count_at, 3);
  fix_crc(b);
  EXPECT_NE(decode_error(b).find("incomplete"), std::string::npos) << decode_error(b);
  // Decoding a map without it into a model that had one leaves none.
  ASSERT_FALSE(ha::decode_map(plain.data(), plain.size(), *out));
  EXPECT_EQ(out->model.local_linear_ridge, 0.0F);
}

// The odometry's calibration travels as entries 5 to 7, written only when the trainer measured
// it: all three or none, each scale in [0.5, 2].
TEST(MapCodec, OdometryCalibrationRoundTripAndChecks) {
  auto map = make_map();
  const std::vector<std::uint8_t> plain = ha::encode_map(*map);
  map->calibration.odometry_present = true;
  map->calibration.left_wheel_scale = 0.994F;
  map->calibration.right_wheel_scale = 1.004F;
  map->calibration.track_scale = 1.03F;
  const std::vector<std::uint8_t> bytes = ha::encode_map(*map);
  ASSERT_EQ(bytes.size(), plain.size() + 24);
  auto out = std::make_unique<ha::MapFile>();
  ASSERT_FALSE(ha::decode_map(bytes.data(), bytes.size(), *out));
  EXPECT_TRUE(out->calibration.odometry_present);
  EXPECT_FALSE(out->calibration.present);
  EXPECT_EQ(out->calibration.left_wheel_scale, 0.994F);
  EXPECT_EQ(out->calibration.right_wheel_scale, 1.004F);
  EXPECT_EQ(out->calibration.track_scale, 1.03F);
  EXPECT_EQ(ha::encode_map(*out), bytes);
  const std::size_t count_at = bytes.size() - kAfterCalibration - 4 - 3 * 8;
  ASSERT_EQ(get_u32(bytes, count_at), 3U);
  for (float v : {0.3F, 2.5F}) {
    std::vector<std::uint8_t> b = bytes;
    put_f32(b, count_at + 4 + 8 + 4, v);  // the right wheel
    fix_crc(b);
    EXPECT_NE(decode_error(b).find("odometry scale"), std::string::npos) << decode_error(b);
  }
  std::vector<std::uint8_t> b = bytes;
  b.erase(b.begin() + static_cast<std::ptrdiff_t>(count_at + 4 + 2 * 8),
          b.begin() + static_cast<std::ptrdiff_t>(count_at + 4 + 3 * 8));  // without the track
  put_u32(b, count_at, 2);
  fix_crc(b);
  EXPECT_NE(decode_error(b).find("odometry calibration incomplete"), std::string::npos)
      << decode_error(b);
  // Decoding a map without it leaves none.
  ASSERT_FALSE(ha::decode_map(plain.data(), plain.size(), *out));
  EXPECT_FALSE(out->calibration.odometry_present);
  EXPECT_EQ(out->calibration.track_scale, 1.0F);
}

// The median heading difference between the training run's passes over one place travels as
// entry 8, after the odometry's, written only above 0; it says whether the map is a floor map.
TEST(MapCodec, PassHeadingSpreadRoundTripAndChecks) {
  auto map = make_map();
  const std::vector<std::uint8_t> plain = ha::encode_map(*map);
  map->calibration.odometry_present = true;
  map->calibration.pass_heading_spread_rad = 0.35F;  // 20 degrees: lanes at several headings
  const std::vector<std::uint8_t> bytes = ha::encode_map(*map);
  ASSERT_EQ(bytes.size(), plain.size() + 32);
  auto out = std::make_unique<ha::MapFile>();
  ASSERT_FALSE(ha::decode_map(bytes.data(), bytes.size(), *out));
  EXPECT_EQ(out->calibration.pass_heading_spread_rad, 0.35F);
  EXPECT_TRUE(out->calibration.odometry_present);
  EXPECT_TRUE(ha::is_floor_map(out->calibration));
  EXPECT_EQ(ha::encode_map(*out), bytes);
  const std::size_t count_at = bytes.size() - kAfterCalibration - 4 - 4 * 8;
  ASSERT_EQ(get_u32(bytes, count_at), 4U);
  const std::size_t entry = count_at + 4 + 3 * 8;
  ASSERT_EQ(get_u32(bytes, entry), 8U);
  for (float v : {0.0F, 3.2F}) {
    std::vector<std::uint8_t> b = bytes;
    put_f32(b, entry + 4, v);
    fix_crc(b);
    EXPECT_NE(decode_error(b).find("pass heading spread"), std::string::npos) << decode_error(b);
  }
  // Not before the odometry's entries: out of order.
  std::vector<std::uint8_t> b = bytes;
  put_u32(b, entry, 8U);
  put_u32(b, count_at + 4, 8U);
  put_f32(b, count_at + 4 + 4, 0.5F);
  put_u32(b, entry, 5U);
  put_f32(b, entry + 4, 0.994F);
  fix_crc(b);
  EXPECT_FALSE(decode_error(b).empty());
  // A route's few degrees are no floor; a map without the entry reads as 0.
  map->calibration.pass_heading_spread_rad = 0.05F;
  EXPECT_FALSE(ha::is_floor_map(map->calibration));
  ASSERT_FALSE(ha::decode_map(plain.data(), plain.size(), *out));
  EXPECT_EQ(out->calibration.pass_heading_spread_rad, 0.0F);
  EXPECT_FALSE(ha::is_floor_map(out->calibration));
}

// Version 11's per-sample fix errors follow the calibration, all or none: a map with none
// writes a count of 0, and every value must be finite and in 0..100 m.
TEST(MapCodec, FixErrorsRoundTripAndChecks) {
  auto map = make_map();
  for (std::size_t i = 0; i < kSamples; ++i)
    map->model.fix_error_m[i] = 0.01F * static_cast<float>(i % 4);
  const std::vector<std::uint8_t> bytes = ha::encode_map(*map);
  ASSERT_EQ(bytes.size(), kExpectedSize + 4 * kSamples);
  const std::size_t count_at = kExpectedSize - 20;
  EXPECT_EQ(get_u32(bytes, count_at), kSamples);
  auto out = std::make_unique<ha::MapFile>();
  ASSERT_FALSE(ha::decode_map(bytes.data(), bytes.size(), *out));
  for (std::size_t i = 0; i < kSamples; ++i)
    EXPECT_EQ(out->model.fix_error_m[i], map->model.fix_error_m[i]) << i;
  EXPECT_EQ(ha::encode_map(*out), bytes);
  EXPECT_FLOAT_EQ(
      ha::fix_error_near(out->model, map->model.target_x_m[3], map->model.target_y_m[3] + 0.001F),
      0.03F);
  // A map without them reads with 0 everywhere, whatever the object held before.
  const std::vector<std::uint8_t> plain = ha::encode_map(*make_map());
  ASSERT_FALSE(ha::decode_map(plain.data(), plain.size(), *out));
  for (std::size_t i = 0; i < kSamples; ++i) EXPECT_EQ(out->model.fix_error_m[i], 0.0F) << i;
  EXPECT_EQ(ha::fix_error_near(out->model, 0.0, 0.0), 0.0F);
  // Refused: a value out of range or not finite, all 0 written, a count that is neither 0 nor
  // the sample count, cut short.
  for (float v : {-0.01F, 101.0F, std::numeric_limits<float>::quiet_NaN(),
                  std::numeric_limits<float>::infinity()}) {
    std::vector<std::uint8_t> b = bytes;
    put_f32(b, count_at + 4 + 4, v);
    fix_crc(b);
    EXPECT_NE(decode_error(b).find("per-sample fix error not finite"), std::string::npos)
        << v << ": " << decode_error(b);
  }
  std::vector<std::uint8_t> b = bytes;
  for (std::size_t i = 0; i < kSamples; ++i) put_f32(b, count_at + 4 + 4 * i, 0.0F);
  fix_crc(b);
  EXPECT_NE(decode_error(b).find("all 0"), std::string::npos) << decode_error(b);
  b = bytes;
  put_u32(b, count_at, kSamples - 1);
  fix_crc(b);
  EXPECT_NE(decode_error(b).find("neither 0 nor the sample count"), std::string::npos)
      << decode_error(b);
  b.assign(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(count_at + 4 + 4));
  b.resize(b.size() + 4);
  fix_crc(b);
  EXPECT_FALSE(decode_error(b).empty());
  // Before version 11 there are none: the same bytes as version 10 have trailing bytes.
  b = bytes;
  put_u32(b, kOffVersion, 10);
  fix_crc(b);
  EXPECT_NE(decode_error(b).find("trailing bytes after the calibration"), std::string::npos)
      << decode_error(b);
  b = plain;
  strip_fix_errors(b);
  put_u32(b, kOffVersion, 10);
  fix_crc(b);
  EXPECT_EQ(decode_error(b), "");
}

// Version 12's centroid columns follow the fix errors: the weight (0: none follow), then every
// sample's column features, each within half the root of its area feature.
TEST(MapCodec, ColumnsRoundTripAndChecks) {
  auto map = make_map();
  map->model.column_weight = 0.5F;
  for (std::size_t i = 0; i < kSamples; ++i) {
    for (std::size_t k = 0; k < kFeatures; ++k)
      map->model.sample_columns(i)[k] =
          (i % 2 == 0 ? 0.3F : -0.4F) * std::sqrt(map->model.sample(i)[k]);
  }
  const std::vector<std::uint8_t> bytes = ha::encode_map(*map);
  ASSERT_EQ(bytes.size(), kExpectedSize + 4 * kSamples * kFeatures);
  const std::size_t weight_at = kExpectedSize - 8;
  EXPECT_EQ(get_f32(bytes, weight_at), 0.5F);
  auto out = std::make_unique<ha::MapFile>();
  ASSERT_FALSE(ha::decode_map(bytes.data(), bytes.size(), *out));
  EXPECT_EQ(out->model.column_weight, 0.5F);
  EXPECT_TRUE(out->model.uses_columns());
  for (std::size_t i = 0; i < kSamples; ++i) {
    for (std::size_t k = 0; k < kFeatures; ++k)
      EXPECT_EQ(out->model.sample_columns(i)[k], map->model.sample_columns(i)[k]) << i << " " << k;
  }
  EXPECT_EQ(ha::encode_map(*out), bytes);
  // A map without them reads with weight 0, whatever the object held before.
  const std::vector<std::uint8_t> plain = ha::encode_map(*make_map());
  ASSERT_FALSE(ha::decode_map(plain.data(), plain.size(), *out));
  EXPECT_EQ(out->model.column_weight, 0.0F);
  EXPECT_FALSE(out->model.uses_columns());
  // Refused: a weight out of range or not finite; a column feature beyond half the root of its
  // area feature (or not finite); cut short.
  for (float v : {-0.5F, 101.0F, std::numeric_limits<float>::quiet_NaN()}) {
    std::vector<std::uint8_t> b = bytes;
    put_f32(b, weight_at, v);
    fix_crc(b);
    EXPECT_NE(decode_error(b).find("column weight"), std::string::npos) << v << decode_error(b);
  }
  const float area = map->model.sample(0)[1];
  for (float v : {0.51F * std::sqrt(area), -0.51F * std::sqrt(area),
                  std::numeric_limits<float>::infinity()}) {
    std::vector<std::uint8_t> b = bytes;
    put_f32(b, weight_at + 4 + 4, v);
    fix_crc(b);
    EXPECT_NE(decode_error(b).find("column feature"), std::string::npos) << v << decode_error(b);
  }
  std::vector<std::uint8_t> b(bytes.begin(), bytes.end() - 8);
  b.resize(b.size() + 4);
  fix_crc(b);
  EXPECT_NE(decode_error(b).find("truncated column features"), std::string::npos)
      << decode_error(b);
  // Before version 12 there are none: the column weight is a trailing byte.
  b = plain;
  put_u32(b, kOffVersion, 11);
  fix_crc(b);
  EXPECT_NE(decode_error(b).find("trailing bytes after the per-sample fix errors"),
            std::string::npos)
      << decode_error(b);
  b = plain;
  strip_columns(b);
  put_u32(b, kOffVersion, 11);
  fix_crc(b);
  EXPECT_EQ(decode_error(b), "");
}

// Version 13's column gain sits between the fix errors and the column weight: two floats, 0 and 0
// for none; a gain beyond a factor of 4 anywhere in the frame is refused. A column feature comes
// from the plain area, so with a gain it may reach half the root of the sample's feature times
// the gain's largest value.
TEST(MapCodec, ColumnGainRoundTripAndChecks) {
  auto map = make_map();
  map->model.column_gain = ha::ColumnGain{2.0F, -6.0F};
  map->model.column_weight = 0.5F;
  // log G = 2 s - 6 s^2 over s = t^2 in [0, 0.25] is largest at s = 1/6: G = exp(1/6).
  const float most = std::exp(1.0F / 6.0F);
  for (std::size_t i = 0; i < kSamples; ++i) {
    for (std::size_t k = 0; k < kFeatures; ++k)
      map->model.sample_columns(i)[k] = 0.5F * std::sqrt(map->model.sample(i)[k] * most);
  }
  const std::vector<std::uint8_t> bytes = ha::encode_map(*map);
  ASSERT_EQ(bytes.size(), kExpectedSize + 4 * kSamples * kFeatures);
  const std::size_t gain_at = kExpectedSize - 16;
  EXPECT_EQ(get_f32(bytes, gain_at), 2.0F);
  EXPECT_EQ(get_f32(bytes, gain_at + 4), -6.0F);
  auto out = std::make_unique<ha::MapFile>();
  ASSERT_EQ(decode_error(bytes), "");
  ASSERT_FALSE(ha::decode_map(bytes.data(), bytes.size(), *out));
  EXPECT_EQ(out->model.column_gain.c2, 2.0F);
  EXPECT_EQ(out->model.column_gain.c4, -6.0F);
  EXPECT_TRUE(out->model.column_gain.present());
  EXPECT_EQ(ha::encode_map(*out), bytes);
  // The same column features are too large without the gain.
  std::vector<std::uint8_t> b = bytes;
  put_f32(b, gain_at, 0.0F);
  put_f32(b, gain_at + 4, 0.0F);
  fix_crc(b);
  EXPECT_NE(decode_error(b).find("column feature"), std::string::npos) << decode_error(b);
  // A plain map reads with no gain, whatever the object held before.
  const std::vector<std::uint8_t> plain = ha::encode_map(*make_map());
  ASSERT_FALSE(ha::decode_map(plain.data(), plain.size(), *out));
  EXPECT_FALSE(out->model.column_gain.present());
  // Refused: not finite; beyond a factor of 4 at the side (c2 = 6: G(0.5) = 4.48; -6: 1 / 4.48),
  // or inside the frame only (c2 = 24, c4 = -96: G(0.5) = 1, but 4.48 at t^2 = 1/8).
  for (const auto& [c2, c4] :
       {std::pair{std::numeric_limits<float>::quiet_NaN(), 0.0F},
        std::pair{0.0F, std::numeric_limits<float>::infinity()}, std::pair{6.0F, 0.0F},
        std::pair{-6.0F, 0.0F}, std::pair{24.0F, -96.0F}}) {
    b = plain;
    put_f32(b, plain.size() - 16, c2);
    put_f32(b, plain.size() - 12, c4);
    fix_crc(b);
    EXPECT_NE(decode_error(b).find("column gain"), std::string::npos)
        << c2 << " " << c4 << ": " << decode_error(b);
  }
  b.assign(plain.begin(), plain.end() - 12);
  fix_crc(b);
  EXPECT_NE(decode_error(b).find("column gain is missing"), std::string::npos) << decode_error(b);
  // A version 12 map has none: the same bytes without the gain read as before.
  b = plain;
  strip_gain(b);
  put_u32(b, kOffVersion, 12);
  fix_crc(b);
  EXPECT_EQ(decode_error(b), "");
}

// Maps written before the forward map existed (version 2) still load, without it.
TEST(MapCodec, ReadsVersionTwo) {
  const auto map = make_map();
  std::vector<std::uint8_t> b = ha::encode_map(*map);
  strip_calibration(b);
  b.erase(b.begin() + static_cast<std::ptrdiff_t>(kOffForward),
          b.begin() + static_cast<std::ptrdiff_t>(kOffForward + 8));
  strip_weights(b);
  put_u32(b, kOffVersion, 2);
  fix_crc(b);
  auto out = std::make_unique<ha::MapFile>();
  out->forward.columns = 3;  // whatever the object held before is replaced
  out->forward.has_heading_terms = true;
  out->forward.has_visibility = true;
  out->forward.visibility_angle_gain = 0.5F;
  const ha::MapError e = ha::decode_map(b.data(), b.size(), *out);
  ASSERT_FALSE(e) << e.what;
  EXPECT_FALSE(out->forward.present());
  EXPECT_FALSE(out->forward.has_heading_terms);
  EXPECT_FALSE(out->forward.has_visibility);
  EXPECT_EQ(out->forward.visibility_angle_gain, 0.0F);
  EXPECT_EQ(out->model.max_dissimilarity, map->model.max_dissimilarity);
  // The same bytes as version 3 miss the forward map's size.
  put_u32(b, kOffVersion, 3);
  fix_crc(b);
  EXPECT_NE(decode_error(b).find("truncated"), std::string::npos) << decode_error(b);
}

// Maps written before the dissimilarity bound existed (version 1) still load, without that test.
TEST(MapCodec, ReadsVersionOne) {
  const auto map = make_map();
  std::vector<std::uint8_t> b = ha::encode_map(*map);
  strip_calibration(b);
  b.erase(b.begin() + static_cast<std::ptrdiff_t>(kOffForward),
          b.begin() + static_cast<std::ptrdiff_t>(kOffForward + 8));
  strip_weights(b);
  b.erase(b.begin() + static_cast<std::ptrdiff_t>(kOffDissimilarity),
          b.begin() + static_cast<std::ptrdiff_t>(kOffDissimilarity + 4));
  put_u32(b, kOffVersion, 1);
  fix_crc(b);
  auto out = std::make_unique<ha::MapFile>();
  const ha::MapError e = ha::decode_map(b.data(), b.size(), *out);
  ASSERT_FALSE(e) << e.what;
  EXPECT_EQ(out->model.max_dissimilarity, 1.0F);
  EXPECT_EQ(out->model.target_y_m[kSamples - 1], map->model.target_y_m[kSamples - 1]);
}

TEST(MapCodec, DissimilarityBoundOutOfRange) {
  for (float v : {0.0F, -0.1F, 1.5F, std::numeric_limits<float>::quiet_NaN()}) {
    std::vector<std::uint8_t> b = ha::encode_map(*make_map());
    put_f32(b, kOffDissimilarity, v);
    fix_crc(b);
    EXPECT_NE(decode_error(b).find("dissimilarity"), std::string::npos)
        << v << ": " << decode_error(b);
  }
}

TEST(MapCodec, EveryFlippedByteIsRejected) {
  const std::vector<std::uint8_t> good = ha::encode_map(*make_map());
  for (std::size_t i = 0; i < good.size(); ++i) {
    std::vector<std::uint8_t> b = good;
    b[i] ^= 0x10U;
    const std::string why = decode_error(b);
    ASSERT_FALSE(why.empty()) << "flipped byte " << i << " accepted";
    // Past the magic and version, it is the checksum that notices.
    if (i >= 12) {
      EXPECT_NE(why.find("checksum"), std::string::npos) << "byte " << i << ": " << why;
    }
  }
  std::vector<std::uint8_t> b = good;
  b[kOffSamples + 5] ^= 0x01U;
  auto out = std::make_unique<ha::MapFile>();
  const ha::MapError e = ha::decode_map(b.data(), b.size(), *out);
  ASSERT_TRUE(e);
  EXPECT_EQ(e.offset, b.size() - 4);  // noticed where the stored checksum is
}

TEST(MapCodec, TruncatedAtEveryLength) {
  const std::vector<std::uint8_t> good = ha::encode_map(*make_map());
  for (std::size_t n = 0; n < good.size(); ++n) {
    const std::vector<std::uint8_t> b(good.begin(), good.begin() + static_cast<std::ptrdiff_t>(n));
    auto out = std::make_unique<ha::MapFile>();
    const ha::MapError e = ha::decode_map(b.data(), b.size(), *out);
    ASSERT_TRUE(e) << "truncated to " << n << " bytes and accepted";
    ASSERT_NE(e.what, nullptr);
    EXPECT_GT(std::strlen(e.what), 5U);
  }
  // A null pointer is not a map either.
  auto out = std::make_unique<ha::MapFile>();
  EXPECT_TRUE(ha::decode_map(nullptr, 100, *out));
}

TEST(MapCodec, TruncatedWithAValidChecksumIsStillRejected) {
  // Cut inside the samples and re-seal: the header's counts no longer fit the data.
  const std::vector<std::uint8_t> good = ha::encode_map(*make_map());
  for (std::size_t cut : {std::size_t{1}, std::size_t{4}, std::size_t{8}, std::size_t{9},
                          std::size_t{28}, std::size_t{29}, kSamples * (kFeatures + 2) * 4 + 8}) {
    std::vector<std::uint8_t> b(good.begin(), good.end() - 4 - static_cast<std::ptrdiff_t>(cut));
    b.resize(b.size() + 4);
    fix_crc(b);
    const std::string why = decode_error(b);
    ASSERT_FALSE(why.empty()) << "cut " << cut;
    EXPECT_NE(why.find("truncated"), std::string::npos) << "cut " << cut << ": " << why;
  }
}

TEST(MapCodec, TrailingBytes) {
  std::vector<std::uint8_t> b = ha::encode_map(*make_map());
  // Junk after the CRC: the last 4 bytes are taken as the checksum, which does not match.
  std::vector<std::uint8_t> junk = b;
  junk.insert(junk.end(), {1, 2, 3});
  EXPECT_FALSE(decode_error(junk).empty());
  // Junk between the map and a CRC that covers it: the length check has to catch it.
  b.resize(b.size() - 4);
  b.insert(b.end(), {0xAA, 0xBB, 0xCC, 0, 0, 0, 0});
  fix_crc(b);
  EXPECT_NE(decode_error(b).find("trailing"), std::string::npos) << decode_error(b);
}

TEST(MapCodec, SampleCountOutOfRangeWithValidChecksum) {
  for (std::uint32_t count : {0U, 4097U, 0xFFFFFFFFU}) {
    std::vector<std::uint8_t> b = ha::encode_map(*make_map());
    put_u32(b, kOffSampleCount, count);
    fix_crc(b);
    const std::string why = decode_error(b);
    EXPECT_NE(why.find("sample count"), std::string::npos) << count << ": " << why;
  }
}

TEST(MapCodec, FeatureAndBoardCountsOutOfRangeWithValidChecksum) {
  std::vector<std::uint8_t> b = ha::encode_map(*make_map());
  put_u32(b, kOffFeatureCount, 9);
  fix_crc(b);
  EXPECT_NE(decode_error(b).find("feature count"), std::string::npos) << decode_error(b);
  put_u32(b, kOffFeatureCount, 0);
  fix_crc(b);
  EXPECT_NE(decode_error(b).find("feature count"), std::string::npos) << decode_error(b);

  b = ha::encode_map(*make_map());
  put_u32(b, kOffBoardCount, 9);
  fix_crc(b);
  EXPECT_NE(decode_error(b).find("board count"), std::string::npos) << decode_error(b);

  b = ha::encode_map(*make_map());
  b[kOffBoardIndex + 1] = 6;  // board 7 of a 6-board map
  fix_crc(b);
  EXPECT_NE(decode_error(b).find("board"), std::string::npos) << decode_error(b);

  b = ha::encode_map(*make_map());
  put_u32(b, 12, 0);  // image width 0
  fix_crc(b);
  EXPECT_NE(decode_error(b).find("image size"), std::string::npos) << decode_error(b);
}

TEST(MapCodec, NonFiniteOrNonPositiveParametersWithValidChecksum) {
  const float bad[] = {std::numeric_limits<float>::quiet_NaN(),
                       std::numeric_limits<float>::infinity(), 0.0F, -1.0F};
  for (std::size_t field = 0; field < 3; ++field) {  // area scale, sigma x, sigma y
    for (float v : bad) {
      std::vector<std::uint8_t> b = ha::encode_map(*make_map());
      put_f32(b, kOffAreaScale + 4 * field, v);
      fix_crc(b);
      const std::string why = decode_error(b);
      EXPECT_NE(why.find("parameter"), std::string::npos)
          << "field " << field << " value " << v << ": " << why;
    }
  }
  std::vector<std::uint8_t> b = ha::encode_map(*make_map());
  put_f32(b, kOffSigmaX, std::numeric_limits<float>::quiet_NaN());
  fix_crc(b);
  EXPECT_FALSE(decode_error(b).empty());
  // A hue outside 0..360 and a NaN sample feature / coordinate.
  b = ha::encode_map(*make_map());
  put_f32(b, kOffBoards + 12 * 2 + 4, 400.0F);
  fix_crc(b);
  EXPECT_NE(decode_error(b).find("hue"), std::string::npos) << decode_error(b);
  b = ha::encode_map(*make_map());
  put_f32(b, kOffSamples + 4, std::numeric_limits<float>::quiet_NaN());
  fix_crc(b);
  EXPECT_NE(decode_error(b).find("sample feature"), std::string::npos) << decode_error(b);
  b = ha::encode_map(*make_map());
  put_f32(b, kOffSamples + 4 * kFeatures, std::numeric_limits<float>::infinity());
  fix_crc(b);
  EXPECT_NE(decode_error(b).find("coordinate"), std::string::npos) << decode_error(b);
}

// A training target at 1e30 m (a label at 1e30 gave such a map, which the firmware accepted and
// then published 3.7e28 m as a nominal pose) or anywhere beyond 10 km from the origin is refused;
// 10 km itself is still a map.
TEST(MapCodec, TargetsFartherThan10KmAreRefused) {
  for (const float v : {1.0e30F, -1.0e30F, 10000.5F, -2.0e4F, 3.0e38F}) {
    for (std::size_t axis = 0; axis < 2; ++axis) {
      std::vector<std::uint8_t> b = ha::encode_map(*make_map());
      const std::size_t record = (kFeatures + 2) * 4;
      put_f32(b, kOffSamples + 2 * record + 4 * (kFeatures + axis), v);
      fix_crc(b);
      EXPECT_NE(decode_error(b).find("farther than 10 km"), std::string::npos)
          << "axis " << axis << " value " << v << ": " << decode_error(b);
    }
  }
  auto map = make_map();
  map->model.target_x_m[0] = 1.0e4F;
  map->model.target_y_m[1] = -1.0e4F;
  EXPECT_EQ(decode_error(ha::encode_map(*map)), "");
}

// The largest map the format allows fits the loader's size cap exactly.
TEST(MapCodec, LargestMapFitsTheSizeCap) {
  auto map = make_map();
  ha::HarmonicModel& m = map->model;
  map->thresholds.count = ha::kMaxBoards;
  for (std::size_t i = kBoards; i < ha::kMaxBoards; ++i)
    map->thresholds.boards[i] = map->thresholds.boards[0];
  m.feature_count = ha::HarmonicModel::kMaxFeatures;
  for (std::size_t k = 0; k < m.feature_count; ++k) m.board_index[k] = static_cast<std::uint8_t>(k);
  m.sample_count = ha::HarmonicModel::kMaxSamples;
  for (std::size_t i = 0; i < m.sample_count; ++i) {
    for (std::size_t k = 0; k < m.feature_count; ++k) m.sample(i)[k] = 1.0F;
    m.target_x_m[i] = m.target_y_m[i] = 0.0F;
    m.fix_error_m[i] = 0.03F;  // version 11
    for (std::size_t k = 0; k < m.feature_count; ++k) m.sample_columns(i)[k] = -0.25F;
  }
  m.column_weight = 1.0F;  // version 12
  // The widest tile grid this build holds, as many of its tiles stored as it holds.
  ha::ForwardMap& f = map->forward;
  std::vector<std::uint8_t> stored(ha::ForwardMap::kMaxTileGrid, 0);
  for (std::size_t t = 0; t < ha::ForwardMap::kMaxTiles; ++t) stored[t * 7 % stored.size()] = 1;
  const auto side = static_cast<std::uint32_t>(std::sqrt(ha::ForwardMap::kMaxTileGrid));
  ASSERT_EQ(static_cast<std::size_t>(side) * side, ha::ForwardMap::kMaxTileGrid);
  ASSERT_TRUE(ha::lay_out_grid(f, side * ha::ForwardMap::kTileSide,
                               side * ha::ForwardMap::kTileSide, stored.data()));
  ASSERT_EQ(f.tile_count, ha::ForwardMap::kMaxTiles);
  f.cell_m = 0.05F;
  f.board_count = ha::kMaxBoards;
  f.sigma.fill(0.1F);
  f.has_heading = true;
  // Version 6: the bearings too (every cell without one, as lay_out_grid left them).
  f.has_bearings = true;
  f.bearing_a1_rad = 1.0F;
  f.bearing_sigma_rad.fill(0.05F);
  // Version 10: the visibility, the heading terms' (version 7) size and its angle gain.
  f.has_visibility = true;
  f.has_heading_coverage = true;  // version 8
  // Version 15: the projection, every board with the most outline points (version 16 their
  // spread, version 17 their feature per pixel and area noise).
  ha::BearingProjection& p = f.projection;
  p.width_px = map->image_width_px;
  p.height_px = map->image_height_px;
  p.right = {0.0F, -1.0F, 0.0F};
  p.down = {0.0F, 0.0F, -1.0F};
  p.forward = {1.0F, 0.0F, 0.0F};
  p.focal_px = 400.0F;
  p.cx_px = 0.5F * static_cast<float>(p.width_px);
  p.cy_px = 0.5F * static_cast<float>(p.height_px);
  p.max_radius2 = 2.0F;
  p.points.fill(static_cast<std::uint8_t>(ha::BearingProjection::kMaxPoints));
  const std::vector<std::uint8_t> b = ha::encode_map(*map);
  // Every count at its capacity but the calibration's (the trainer writes 3 of the 64 allowed).
  EXPECT_EQ(b.size() + ha::kMaxCalibrationEntries * 8U, ha::kMaxMapFileBytes);
  EXPECT_EQ(decode_error(b), "");
}

namespace {

// A 3 x 2 grid over 6 boards, the fourth not modelled, with headings: one tile, of which these
// six cells are in the grid.
std::unique_ptr<ha::MapFile> make_map_with_forward() {
  auto map = make_map();
  ha::ForwardMap& f = map->forward;
  EXPECT_TRUE(ha::lay_out_grid(f, 3, 2));
  f.origin_x_m = 1.5F;
  f.origin_y_m = 0.25F;
  f.cell_m = 0.05F;
  f.board_count = kBoards;
  f.sigma = {0.1F, 0.2F, 0.05F, 0.0F, 0.3F, 0.01F, 0.0F, 0.0F};
  f.has_heading = true;
  for (std::uint32_t r = 0; r < 2; ++r) {
    for (std::uint32_t c = 0; c < 3; ++c) {
      const std::size_t k = r * 3 + c, at = f.index(c, r);
      for (std::size_t b = 0; b < kBoards; ++b)
        f.expected[at * ha::kMaxBoards + b] = b == 3 ? 0.0F : 0.5F * static_cast<float>(k + b);
      f.route_distance_m[at] = 0.01F * static_cast<float>(k);
      f.heading_rad[at] = 1.5F - 0.1F * static_cast<float>(k);
    }
  }
  return map;
}

// Offsets inside the forward section (version 5: one tile of 64 cells stored).
constexpr std::size_t kTileCells = ha::ForwardMap::kTileCells;
constexpr std::size_t kOffGridSize = kOffForward;
constexpr std::size_t kOffCell = kOffForward + 16;
constexpr std::size_t kOffForwardBoards = kOffForward + 20;
constexpr std::size_t kOffSigma = kOffForward + 24;
constexpr std::size_t kOffFlags = kOffSigma + 4 * kBoards;
constexpr std::size_t kOffTileCount = kOffFlags + 4;
constexpr std::size_t kOffTileBitmap = kOffTileCount + 4;
constexpr std::size_t kOffExpected = kOffTileBitmap + 1;
constexpr std::size_t kOffRoute = kOffExpected + kTileCells * kBoards * 4;
constexpr std::size_t kOffHeading = kOffRoute + kTileCells * 4;

}  // namespace

TEST(MapCodec, ForwardMapRoundTripAndLayout) {
  const auto map = make_map_with_forward();
  const std::vector<std::uint8_t> bytes = ha::encode_map(*map);
  ASSERT_EQ(bytes.size(), kOffHeading + kTileCells * 4 + kAfterCalibration + 4);
  EXPECT_EQ(get_u32(bytes, kOffGridSize), 3U);
  EXPECT_EQ(get_u32(bytes, kOffTileCount), 1U);
  EXPECT_EQ(bytes[kOffTileBitmap], 1U);
  EXPECT_EQ(get_u32(bytes, kOffGridSize + 4), 2U);
  EXPECT_EQ(get_u32(bytes, kOffForwardBoards), kBoards);
  EXPECT_EQ(bytes[kOffFlags], 1U);
  auto out = std::make_unique<ha::MapFile>();
  const ha::MapError e = ha::decode_map(bytes.data(), bytes.size(), *out);
  ASSERT_FALSE(e) << e.what;
  const ha::ForwardMap& a = map->forward;
  const ha::ForwardMap& b = out->forward;
  ASSERT_TRUE(b.present());
  EXPECT_EQ(b.columns, 3U);
  EXPECT_EQ(b.rows, 2U);
  EXPECT_EQ(b.origin_x_m, a.origin_x_m);
  EXPECT_EQ(b.origin_y_m, a.origin_y_m);
  EXPECT_EQ(b.cell_m, a.cell_m);
  EXPECT_TRUE(b.has_heading);
  EXPECT_EQ(b.sigma, a.sigma);
  EXPECT_EQ(b.expected, a.expected);
  EXPECT_EQ(b.route_distance_m, a.route_distance_m);
  EXPECT_EQ(b.heading_rad, a.heading_rad);
  EXPECT_EQ(ha::encode_map(*out), bytes);

  for (std::uint32_t r = 0; r < 2; ++r) {
    for (std::uint32_t c = 0; c < 3; ++c) EXPECT_EQ(b.cell(c, r)[1], a.cell(c, r)[1]);
  }

  // Without headings the section is one value a stored cell shorter.
  map->forward.has_heading = false;
  EXPECT_EQ(ha::encode_map(*map).size(), bytes.size() - kTileCells * 4);
}

// Version 7: a floor map's heading terms follow the bearings (or the headings), flagged by bit 2,
// and read back exactly; a term that is not finite is refused.
TEST(MapCodec, HeadingTermsRoundTripAndChecks) {
  auto map = make_map_with_forward();
  const std::vector<std::uint8_t> plain = ha::encode_map(*map);
  ha::ForwardMap& f = map->forward;
  f.has_heading_terms = true;
  for (std::size_t c = 0; c < f.stored_cells(); ++c) {
    for (std::size_t b = 0; b < kBoards; ++b) {
      f.heading_terms[(c * ha::kMaxBoards + b) * 2] = 0.01F * static_cast<float>(c + b);
      f.heading_terms[(c * ha::kMaxBoards + b) * 2 + 1] = -0.02F * static_cast<float>(b);
    }
  }
  const std::vector<std::uint8_t> bytes = ha::encode_map(*map);
  ASSERT_EQ(bytes.size(), plain.size() + f.stored_cells() * kBoards * 8);
  EXPECT_EQ(bytes[kOffFlags], 5U);
  auto out = std::make_unique<ha::MapFile>();
  ASSERT_FALSE(ha::decode_map(bytes.data(), bytes.size(), *out));
  EXPECT_TRUE(out->forward.has_heading_terms);
  for (std::size_t i = 0; i < f.stored_cells() * ha::kMaxBoards * 2; ++i)
    ASSERT_EQ(out->forward.heading_terms[i], f.heading_terms[i]) << i;
  EXPECT_EQ(ha::encode_map(*out), bytes);
  // The first cell's first term sits right after the cells' headings, before the calibration
  // count, the fix errors' count, the column weight and the CRC.
  const std::size_t first = plain.size() - 4 - kAfterCalibration;
  for (float v : {std::numeric_limits<float>::infinity(), 2.0e6F}) {
    std::vector<std::uint8_t> b = bytes;
    put_f32(b, first, v);
    fix_crc(b);
    EXPECT_NE(decode_error(b).find("heading term"), std::string::npos) << v << decode_error(b);
  }
  std::vector<std::uint8_t> cut(bytes.begin(),
                                bytes.begin() + static_cast<std::ptrdiff_t>(first + 8));
  EXPECT_FALSE(decode_error(cut).empty());
  // A map without them reads with none.
  ASSERT_FALSE(ha::decode_map(plain.data(), plain.size(), *out));
  EXPECT_FALSE(out->forward.has_heading_terms);
}

namespace {

// A forward map whose cell (1, 0) expects board 0 at 1 + 0.5 cos(yaw) - 2 sin(yaw) once
// has_heading_terms is set (it is not yet).
std::unique_ptr<ha::MapFile> map_with_one_harmonic() {
  auto map = make_map_with_forward();
  ha::ForwardMap& f = map->forward;
  const std::size_t at = f.index(1, 0);
  f.expected[at * ha::kMaxBoards + 0] = 1.0F;
  f.heading_terms[at * ha::kMaxBoards * 2 + 0] = 0.5F;   // c
  f.heading_terms[at * ha::kMaxBoards * 2 + 1] = -2.0F;  // s
  return map;
}

}  // namespace

// What a cell with heading terms expects at a heading: the harmonic, never below 0; without a
// heading (or without terms) the cell's value alone.
TEST(ForwardMap, HeadingTermsAddTheFirstHarmonic) {
  auto map = map_with_one_harmonic();
  ha::ForwardMap& f = map->forward;
  const ha::GridPoint p = ha::locate(f, 1.55, 0.25);
  std::array<float, ha::kMaxBoards> e{};
  ha::expected_features(f, p, ha::seen_heading(0.0), e.data());
  EXPECT_FLOAT_EQ(e[0], 1.0F);  // no terms in the map yet
  f.has_heading_terms = true;
  ha::expected_features(f, p, ha::seen_heading(0.0), e.data());
  EXPECT_FLOAT_EQ(e[0], 1.5F);
  ha::expected_features(f, p, ha::seen_heading(-kHalfPi), e.data());
  EXPECT_FLOAT_EQ(e[0], 3.0F);
  ha::expected_features(f, p, ha::seen_heading(kHalfPi), e.data());
  EXPECT_FLOAT_EQ(e[0], 0.0F);  // 1 - 2 clamped
  ha::expected_features(f, p, e.data());
  EXPECT_FLOAT_EQ(e[0], 1.0F);
  // The most any heading expects there: 1 + hypot(0.5, 2).
  EXPECT_NEAR(ha::board_maxima(f)[0], 1.0F + std::hypot(0.5F, 2.0F), 1e-5F);
}

// Heading sectors: sixteen of 22.5 degrees from -pi, any angle wrapped.
TEST(ForwardMap, HeadingSectorsWrapTheCircle) {
  EXPECT_EQ(ha::heading_sector(-kPi), 0);
  EXPECT_EQ(ha::heading_sector(0.0), 8);
  EXPECT_EQ(ha::heading_sector(-0.01), 7);
  EXPECT_EQ(ha::heading_sector(kPi - 0.01), 15);
  EXPECT_EQ(ha::heading_sector(kPi + 0.01), 0);
  EXPECT_EQ(ha::heading_sector(4.0 * kPi + 0.01), 8);
  EXPECT_EQ(ha::heading_sector(-3.0 * kPi + 0.01), 0);
  EXPECT_EQ(ha::heading_sector(std::numeric_limits<double>::quiet_NaN()), 8);
  EXPECT_NEAR(ha::seen_heading(0.3).within, 0.3 / (kPi / 8.0), 1e-5);
}

// With coverage, a cell's heading terms are read at the heading itself only where the training
// run drove near it; elsewhere at the nearest edge of the covered sectors, so that the harmonic
// is not extrapolated to headings it was never fitted on.
TEST(ForwardMap, HeadingCoverageKeepsTheTermsToTrainedHeadings) {
  auto map = map_with_one_harmonic();
  ha::ForwardMap& f = map->forward;
  const std::size_t at = f.index(1, 0);
  f.has_heading_terms = true;
  f.has_heading_coverage = true;
  f.heading_cover[at] = (1U << 7) | (1U << 8);  // -22.5 to 22.5 degrees
  const ha::GridPoint p = ha::locate(f, 1.55, 0.25);
  std::array<float, ha::kMaxBoards> e{};
  const auto at_heading = [](double yaw) {
    return 1.0 + 0.5 * std::cos(yaw) - 2.0 * std::sin(yaw);
  };
  ha::expected_features(f, p, ha::seen_heading(0.1), e.data());
  EXPECT_NEAR(e[0], at_heading(0.1), 1e-5);  // covered
  EXPECT_TRUE(ha::heading_covered(f, p, ha::seen_heading(0.1)));
  EXPECT_FALSE(ha::heading_covered(f, p, ha::seen_heading(kHalfPi)));
  // 90 degrees: the upper edge, 22.5; -60 degrees: the lower edge, -22.5.
  ha::expected_features(f, p, ha::seen_heading(kHalfPi), e.data());
  EXPECT_NEAR(e[0], std::max(0.0, at_heading(kPi / 8.0)), 1e-5);
  ha::expected_features(f, p, ha::seen_heading(-kPi / 3.0), e.data());
  EXPECT_NEAR(e[0], at_heading(-kPi / 8.0), 1e-5);
  // Unless the heading asks to be read as it is (the filter's particles).
  ha::SeenHeading own = ha::seen_heading(-kPi / 3.0);
  own.keep_to_coverage = false;
  ha::expected_features(f, p, own, e.data());
  EXPECT_NEAR(e[0], at_heading(-kPi / 3.0), 1e-5);
  // Opposite (180 degrees, the sector just above -pi's edge... or below pi): an edge either way.
  ha::expected_features(f, p, ha::seen_heading(kPi - 0.05), e.data());
  EXPECT_NEAR(e[0], at_heading(kPi / 8.0), 1e-5);  // nearer the upper edge going down
  ha::expected_features(f, p, ha::seen_heading(-kPi + 0.05), e.data());
  EXPECT_NEAR(e[0], at_heading(-kPi / 8.0), 1e-5);
  // A cell with no coverage, or a map without it: the heading itself.
  f.heading_cover[at] = 0;
  ha::expected_features(f, p, ha::seen_heading(kHalfPi), e.data());
  EXPECT_NEAR(e[0], std::max(0.0, at_heading(kHalfPi)), 1e-5);
  f.heading_cover[at] = 1U << 8;
  f.has_heading_coverage = false;
  ha::expected_features(f, p, ha::seen_heading(-kHalfPi), e.data());
  EXPECT_NEAR(e[0], at_heading(-kHalfPi), 1e-5);
  EXPECT_TRUE(ha::heading_covered(f, p, ha::seen_heading(-kHalfPi)));
}

// Version 8: the heading coverage follows the heading terms, flagged by bit 3, one 16-bit mask a
// stored cell; it needs headings; a cut-short section is refused.
TEST(MapCodec, HeadingCoverageRoundTripAndChecks) {
  auto map = make_map_with_forward();
  const std::vector<std::uint8_t> plain = ha::encode_map(*map);
  ha::ForwardMap& f = map->forward;
  ASSERT_TRUE(f.has_heading);
  f.has_heading_coverage = true;
  for (std::size_t c = 0; c < f.stored_cells(); ++c)
    f.heading_cover[c] = static_cast<std::uint16_t>(0x8001U + 37U * c);
  const std::vector<std::uint8_t> bytes = ha::encode_map(*map);
  ASSERT_EQ(bytes.size(), plain.size() + f.stored_cells() * 2);
  EXPECT_EQ(bytes[kOffFlags], 9U);
  auto out = std::make_unique<ha::MapFile>();
  ASSERT_FALSE(ha::decode_map(bytes.data(), bytes.size(), *out));
  EXPECT_TRUE(out->forward.has_heading_coverage);
  for (std::size_t c = 0; c < f.stored_cells(); ++c)
    ASSERT_EQ(out->forward.heading_cover[c], f.heading_cover[c]) << c;
  EXPECT_EQ(ha::encode_map(*out), bytes);
  // Cut short inside the section.
  const std::size_t first = plain.size() - 4 - kAfterCalibration;
  std::vector<std::uint8_t> cut(bytes.begin(),
                                bytes.begin() + static_cast<std::ptrdiff_t>(first + 3));
  EXPECT_FALSE(decode_error(cut).empty());
  // Coverage flagged without headings.
  std::vector<std::uint8_t> b = bytes;
  b[kOffFlags] = 8U;
  fix_crc(b);
  EXPECT_NE(decode_error(b).find("no headings"), std::string::npos) << decode_error(b);
  // Bit 3 in a version 7 map is unknown.
  b = bytes;
  put_u32(b, 8, 7);
  fix_crc(b);
  EXPECT_NE(decode_error(b).find("unknown bits"), std::string::npos) << decode_error(b);
  // A map without it reads with none.
  ASSERT_FALSE(ha::decode_map(plain.data(), plain.size(), *out));
  EXPECT_FALSE(out->forward.has_heading_coverage);
}

// Only the tiles near the training run are stored: a lookup in one that is not reads the void
// cell, far from the route, which the route term rules out.
TEST(MapCodec, SparseTilesRoundTripAndTheVoid) {
  auto map = make_map_with_forward();
  ha::ForwardMap& f = map->forward;
  const std::uint8_t stored[] = {1, 0, 0, 0, 0, 1};  // 3 x 2 tiles: the first and the last
  ASSERT_TRUE(ha::lay_out_grid(f, 24, 16, stored));
  EXPECT_EQ(f.tile_count, 2U);
  EXPECT_EQ(f.stored_cells(), 2 * kTileCells);
  f.cell(0, 0)[0] = 1.0F;
  f.cell(23, 15)[0] = 2.0F;
  f.route_distance_m[f.index(23, 15)] = 0.02F;
  EXPECT_EQ(f.index(23, 15), 2 * kTileCells - 1);
  EXPECT_FALSE(f.stored(8, 0));
  const std::vector<std::uint8_t> bytes = ha::encode_map(*map);
  EXPECT_EQ(get_u32(bytes, kOffTileCount), 2U);
  EXPECT_EQ(bytes[kOffTileBitmap], 0x21U);
  auto out = std::make_unique<ha::MapFile>();
  ASSERT_FALSE(ha::decode_map(bytes.data(), bytes.size(), *out));
  const ha::ForwardMap& g = out->forward;
  EXPECT_EQ(g.cell(0, 0)[0], 1.0F);
  EXPECT_EQ(g.cell(23, 15)[0], 2.0F);
  EXPECT_EQ(ha::encode_map(*out), bytes);
  // A place in a tile that is not stored: no board expected, far from the route.
  const ha::GridPoint p = ha::locate(g, 1.5 + 0.05 * 12, 0.25 + 0.05 * 3);
  std::array<float, ha::kMaxBoards> e{};
  ha::expected_features(g, p, e.data());
  EXPECT_EQ(e[0], 0.0F);
  EXPECT_GE(ha::route_distance(g, p), ha::ForwardMap::kVoidRouteDistance_m);
  // Half-way between a stored cell and one that is not: as far as the void's weight says.
  const ha::GridPoint q = ha::locate(g, 1.5 + 0.05 * 7.5, 0.25);
  EXPECT_NEAR(ha::route_distance(g, q), 0.5F * ha::ForwardMap::kVoidRouteDistance_m, 1.0F);
}

// A version 4 map stores its forward map as a whole grid, row by row: it reads as a grid whose
// every tile is stored, with the same value at every cell, and is written back as version 5.
TEST(MapCodec, ReadsVersionFourForwardMapAsTiles) {
  const auto map = make_map_with_forward();
  const std::vector<std::uint8_t> v5 = ha::encode_map(*map);
  // The version 4 bytes: the header up to the flags, the six cells' values row by row.
  std::vector<std::uint8_t> v4(v5.begin(), v5.begin() + static_cast<std::ptrdiff_t>(kOffTileCount));
  const auto f32 = [&v4](float v) {
    v4.resize(v4.size() + 4);
    put_f32(v4, v4.size() - 4, v);
  };
  const ha::ForwardMap& f = map->forward;
  for (std::uint32_t r = 0; r < 2; ++r)
    for (std::uint32_t c = 0; c < 3; ++c)
      for (std::size_t b = 0; b < kBoards; ++b) f32(f.cell(c, r)[b]);
  for (std::uint32_t r = 0; r < 2; ++r)
    for (std::uint32_t c = 0; c < 3; ++c) f32(f.route_distance_m[f.index(c, r)]);
  for (std::uint32_t r = 0; r < 2; ++r)
    for (std::uint32_t c = 0; c < 3; ++c) f32(f.heading_rad[f.index(c, r)]);
  v4.insert(v4.end(), v5.end() - 8, v5.end());  // a count of 0 (the calibration's) and the CRC
  put_u32(v4, kOffVersion, 4);
  fix_crc(v4);
  auto out = std::make_unique<ha::MapFile>();
  const ha::MapError e = ha::decode_map(v4.data(), v4.size(), *out);
  ASSERT_FALSE(e) << e.what;
  const ha::ForwardMap& g = out->forward;
  EXPECT_EQ(g.tile_count, 1U);
  for (std::uint32_t r = 0; r < 2; ++r) {
    for (std::uint32_t c = 0; c < 3; ++c) {
      for (std::size_t b = 0; b < kBoards; ++b) EXPECT_EQ(g.cell(c, r)[b], f.cell(c, r)[b]);
      EXPECT_EQ(g.heading_rad[g.index(c, r)], f.heading_rad[f.index(c, r)]);
    }
  }
  EXPECT_EQ(ha::encode_map(*out), v5);
  // Version 4 grids stay within their old bounds.
  put_u32(v4, kOffGridSize, 257);
  fix_crc(v4);
  EXPECT_NE(decode_error(v4).find("at most 256"), std::string::npos) << decode_error(v4);
}

TEST(MapCodec, ForwardMapCorruptionWithValidChecksum) {
  const std::vector<std::uint8_t> good = ha::encode_map(*make_map_with_forward());
  const auto reject = [&](const char* what, auto edit, const char* expect) {
    std::vector<std::uint8_t> b = good;
    edit(b);
    fix_crc(b);
    const std::string why = decode_error(b);
    EXPECT_NE(why.find(expect), std::string::npos) << what << ": " << why;
  };
  reject(
      "too many columns", [](auto& b) { put_u32(b, kOffGridSize, 8193); }, "grid");
  reject(
      "tile grid too large",
      [](auto& b) {
        put_u32(b, kOffGridSize, 8 * 129);
        put_u32(b, kOffGridSize + 4, 8 * 129);
      },
      "tile grid");
  reject(
      "one side zero", [](auto& b) { put_u32(b, kOffGridSize + 4, 0); }, "grid");
  reject(
      "no tile", [](auto& b) { put_u32(b, kOffTileCount, 0); }, "tile count");
  reject(
      "more tiles than held",
      [](auto& b) {
        put_u32(b, kOffTileCount, static_cast<std::uint32_t>(ha::ForwardMap::kMaxTiles + 1));
      },
      "tile count");
  reject(
      "a tile beyond the grid", [](auto& b) { b[kOffTileBitmap] = 3; }, "beyond the tile grid");
  reject(
      "bitmap and count differ", [](auto& b) { put_u32(b, kOffTileCount, 2); }, "tile count");
  reject(
      "cell size 0", [](auto& b) { put_f32(b, kOffCell, 0.0F); }, "cell size");
  reject(
      "origin NaN",
      [](auto& b) { put_f32(b, kOffForward + 8, std::numeric_limits<float>::quiet_NaN()); },
      "origin");
  reject(
      "board count", [](auto& b) { put_u32(b, kOffForwardBoards, 5); }, "board count");
  reject(
      "sigma NaN",
      [](auto& b) { put_f32(b, kOffSigma + 4, std::numeric_limits<float>::quiet_NaN()); }, "sigma");
  reject(
      "sigma negative", [](auto& b) { put_f32(b, kOffSigma, -1.0F); }, "sigma");
  reject(
      "no board modelled",
      [](auto& b) {
        for (std::size_t k = 0; k < kBoards; ++k) put_f32(b, kOffSigma + 4 * k, 0.0F);
      },
      "models no board");
  reject(
      "unknown flag", [](auto& b) { b[kOffFlags] = 65; }, "flags");
  reject(
      "unknown high flag", [](auto& b) { b[kOffFlags] = 0x81; }, "flags");
  reject(
      "padding", [](auto& b) { b[kOffFlags + 2] = 1; }, "flags");
  reject(
      "expected negative", [](auto& b) { put_f32(b, kOffExpected + 8, -0.5F); }, "expected");
  reject(
      "expected infinite",
      [](auto& b) { put_f32(b, kOffExpected, std::numeric_limits<float>::infinity()); },
      "expected");
  reject(
      "route distance NaN",
      [](auto& b) { put_f32(b, kOffRoute + 4, std::numeric_limits<float>::quiet_NaN()); },
      "route distance");
  reject(
      "heading 5 rad", [](auto& b) { put_f32(b, kOffHeading, 5.0F); }, "heading");
  reject(
      "cells beyond the data",
      [](auto& b) {
        put_u32(b, kOffGridSize, 9);  // two tiles
        put_u32(b, kOffTileCount, 2);
        b[kOffTileBitmap] = 3;
      },
      "truncated");
  // A rejected map leaves no half-read forward map behind.
  std::vector<std::uint8_t> b = good;
  put_f32(b, kOffHeading, 5.0F);
  fix_crc(b);
  auto out = std::make_unique<ha::MapFile>();
  EXPECT_TRUE(ha::decode_map(b.data(), b.size(), *out));
  EXPECT_FALSE(out->forward.present());
}

namespace {

// make_map_with_forward's map with board bearings (version 6): the law, each board's spread
// (boards 3 and 6.. not modelled), and per stored cell of its one tile a bearing per board, some
// cells without one (kNoBearing: board 3 everywhere, board 1 at every fifth cell, the cells
// beyond the grid as lay_out_grid left them).
std::unique_ptr<ha::MapFile> make_map_with_bearings() {
  auto map = make_map_with_forward();
  ha::ForwardMap& f = map->forward;
  f.has_bearings = true;
  f.bearing_a1_rad = 1.2F;
  f.bearing_a3_rad = -0.15F;
  f.bearing_camera_forward_m = 0.12F;
  f.bearing_sigma_rad = {0.05F, 0.1F, 0.02F, 0.0F, 0.03F, 0.04F, 0.0F, 0.0F};
  for (std::uint32_t r = 0; r < 2; ++r) {
    for (std::uint32_t c = 0; c < 3; ++c) {
      const std::size_t k = r * 3 + c, at = f.index(c, r);
      for (std::size_t b = 0; b < kBoards; ++b) {
        const bool none = b == 3 || (b == 1 && k % 5 == 0);
        f.bearing_rad[at * ha::kMaxBoards + b] =
            none ? ha::ForwardMap::kNoBearing : -3.0F + 0.2F * static_cast<float>(k + 4 * b);
      }
    }
  }
  // The extremes a bearing may take.
  f.bearing_rad[f.index(2, 1) * ha::kMaxBoards + 0] = -3.1416F;
  f.bearing_rad[f.index(2, 1) * ha::kMaxBoards + 2] = 3.1416F;
  return map;
}

// Offsets of the version 6 bearings, after the headings of make_map_with_forward's map.
constexpr std::size_t kOffBearingA1 = kOffHeading + kTileCells * 4;
constexpr std::size_t kOffBearingA3 = kOffBearingA1 + 4;
constexpr std::size_t kOffBearingCamera = kOffBearingA3 + 4;  // version 9
constexpr std::size_t kOffBearingSigma = kOffBearingCamera + 4;
constexpr std::size_t kOffBearings = kOffBearingSigma + 4 * kBoards;
constexpr std::size_t kOffBearingsEnd = kOffBearings + kTileCells * kBoards * 4;

// True when @p f's bearings are as lay_out_grid leaves them: none, every stored cell and the
// void cell without a bearing.
bool bearings_cleared(const ha::ForwardMap& f) {
  if (f.has_bearings || f.bearing_a1_rad != 0.0F || f.bearing_a3_rad != 0.0F) return false;
  for (const float s : f.bearing_sigma_rad) {
    if (s != 0.0F) return false;
  }
  for (std::size_t i = 0; i < f.stored_cells() * ha::kMaxBoards; ++i) {
    if (f.bearing_rad[i] != ha::ForwardMap::kNoBearing) return false;
  }
  for (std::size_t b = 0; b < ha::kMaxBoards; ++b) {
    if (f.bearing_rad[ha::ForwardMap::kVoidCell * ha::kMaxBoards + b] != ha::ForwardMap::kNoBearing)
      return false;
  }
  return true;
}

}  // namespace

// Version 6: the board bearings follow the headings, flagged by bit 1, and read back exactly.
TEST(MapCodec, ForwardMapBearingsRoundTripAndLayout) {
  const auto map = make_map_with_bearings();
  const std::vector<std::uint8_t> bytes = ha::encode_map(*map);
  ASSERT_EQ(bytes.size(), kOffBearingsEnd + kAfterCalibration + 4);
  EXPECT_EQ(get_u32(bytes, kOffVersion), ha::kMapFormatVersion);
  EXPECT_EQ(bytes[kOffFlags], 3U);
  std::uint32_t bits = 0;
  std::memcpy(&bits, &map->forward.bearing_a1_rad, 4);
  EXPECT_EQ(get_u32(bytes, kOffBearingA1), bits);
  std::memcpy(&bits, &map->forward.bearing_a3_rad, 4);
  EXPECT_EQ(get_u32(bytes, kOffBearingA3), bits);
  std::memcpy(&bits, &map->forward.bearing_camera_forward_m, 4);
  EXPECT_EQ(get_u32(bytes, kOffBearingCamera), bits);
  std::memcpy(&bits, &map->forward.bearing_sigma_rad[1], 4);
  EXPECT_EQ(get_u32(bytes, kOffBearingSigma + 4), bits);
  // Cell (1, 0), board 2: storage index 1, its third value.
  std::memcpy(&bits, &map->forward.bearing_rad[1 * ha::kMaxBoards + 2], 4);
  EXPECT_EQ(get_u32(bytes, kOffBearings + (1 * kBoards + 2) * 4), bits);

  auto out = std::make_unique<ha::MapFile>();
  const ha::MapError e = ha::decode_map(bytes.data(), bytes.size(), *out);
  ASSERT_FALSE(e) << e.what;
  const ha::ForwardMap& a = map->forward;
  const ha::ForwardMap& b = out->forward;
  ASSERT_TRUE(b.present());
  EXPECT_TRUE(b.has_heading);
  EXPECT_TRUE(b.has_bearings);
  EXPECT_EQ(b.bearing_a1_rad, a.bearing_a1_rad);
  EXPECT_EQ(b.bearing_a3_rad, a.bearing_a3_rad);
  EXPECT_EQ(b.bearing_sigma_rad, a.bearing_sigma_rad);
  EXPECT_EQ(b.bearing_rad, a.bearing_rad);
  EXPECT_EQ(b.heading_rad, a.heading_rad);
  EXPECT_EQ(b.expected, a.expected);
  std::size_t none = 0, some = 0;
  for (std::size_t c = 0; c < b.stored_cells(); ++c) {
    for (std::size_t k = 0; k < kBoards; ++k) {
      const float v = b.bearing_rad[c * ha::kMaxBoards + k];
      (v == ha::ForwardMap::kNoBearing ? none : some) += 1;
    }
  }
  EXPECT_EQ(some, 6U * 5U - 2U);  // the grid's six cells, boards 0 to 5 but 3, board 1 twice none
  EXPECT_GT(none, 0U);
  EXPECT_EQ(b.bearing_rad[b.index(2, 1) * ha::kMaxBoards], -3.1416F);
  EXPECT_EQ(ha::encode_map(*out), bytes);

  // Bearings without headings: bit 1 alone, the section one value a stored cell shorter.
  auto bare = make_map_with_bearings();
  bare->forward.has_heading = false;
  const std::vector<std::uint8_t> no_heading = ha::encode_map(*bare);
  EXPECT_EQ(no_heading.size(), bytes.size() - kTileCells * 4);
  EXPECT_EQ(no_heading[kOffFlags], 2U);
  const ha::MapError e2 = ha::decode_map(no_heading.data(), no_heading.size(), *out);
  ASSERT_FALSE(e2) << e2.what;
  EXPECT_FALSE(out->forward.has_heading);
  EXPECT_TRUE(out->forward.has_bearings);
  EXPECT_EQ(out->forward.bearing_rad, a.bearing_rad);
  EXPECT_EQ(ha::encode_map(*out), no_heading);
}

// A map without bearings (version 6 without bit 1, or version 5) decodes without them, with the
// bearing arrays as lay_out_grid leaves them, even into a map object that held bearings before.
TEST(MapCodec, ForwardMapWithoutBearingsRoundTrip) {
  const auto map = make_map_with_forward();
  const std::vector<std::uint8_t> bytes = ha::encode_map(*map);
  ASSERT_EQ(bytes.size(), kOffHeading + kTileCells * 4 + kAfterCalibration + 4);
  EXPECT_EQ(bytes[kOffFlags], 1U);
  const std::vector<std::uint8_t> with = ha::encode_map(*make_map_with_bearings());
  auto out = std::make_unique<ha::MapFile>();
  ASSERT_FALSE(ha::decode_map(with.data(), with.size(), *out));
  ASSERT_TRUE(out->forward.has_bearings);

  const ha::MapError e = ha::decode_map(bytes.data(), bytes.size(), *out);
  ASSERT_FALSE(e) << e.what;
  EXPECT_TRUE(out->forward.present());
  EXPECT_TRUE(bearings_cleared(out->forward));
  EXPECT_EQ(ha::encode_map(*out), bytes);

  // The same map as version 5 still reads, the same map, and is written back as version 6.
  std::vector<std::uint8_t> v5 = bytes;
  strip_fix_errors(v5);
  put_u32(v5, kOffVersion, 5);
  fix_crc(v5);
  ASSERT_FALSE(ha::decode_map(with.data(), with.size(), *out));
  const ha::MapError e5 = ha::decode_map(v5.data(), v5.size(), *out);
  ASSERT_FALSE(e5) << e5.what;
  EXPECT_TRUE(bearings_cleared(out->forward));
  EXPECT_EQ(out->forward.heading_rad, map->forward.heading_rad);
  EXPECT_EQ(ha::encode_map(*out), bytes);

  // A map without a forward map has no bearings either.
  ASSERT_FALSE(ha::decode_map(with.data(), with.size(), *out));
  const std::vector<std::uint8_t> plain = ha::encode_map(*make_map());
  ASSERT_FALSE(ha::decode_map(plain.data(), plain.size(), *out));
  EXPECT_FALSE(out->forward.present());
  EXPECT_FALSE(out->forward.has_bearings);
}

// Version 9 put the camera's offset after the law; a version 6-8 map's bearings, without it, still
// read, seen from the axle's place (offset 0), and are written back as version 9 with a 0.
TEST(MapCodec, ForwardMapBearingsBeforeVersion9ReadFromTheAxle) {
  auto map = make_map_with_bearings();
  const std::vector<std::uint8_t> v9 = ha::encode_map(*map);
  std::vector<std::uint8_t> v8 = v9;
  v8.erase(v8.begin() + static_cast<std::ptrdiff_t>(kOffBearingCamera),
           v8.begin() + static_cast<std::ptrdiff_t>(kOffBearingCamera + 4));
  strip_fix_errors(v8);
  put_u32(v8, kOffVersion, 8);
  fix_crc(v8);
  auto out = std::make_unique<ha::MapFile>();
  ASSERT_FALSE(ha::decode_map(v9.data(), v9.size(), *out));
  EXPECT_FLOAT_EQ(out->forward.bearing_camera_forward_m, 0.12F);
  const ha::MapError e = ha::decode_map(v8.data(), v8.size(), *out);
  ASSERT_FALSE(e) << e.what;
  EXPECT_TRUE(out->forward.has_bearings);
  EXPECT_EQ(out->forward.bearing_camera_forward_m, 0.0F);
  EXPECT_EQ(out->forward.bearing_rad, map->forward.bearing_rad);
  map->forward.bearing_camera_forward_m = 0.0F;
  EXPECT_EQ(ha::encode_map(*out), ha::encode_map(*map));
  // Read as version 9, the same bytes are one float short: refused, not misread.
  put_u32(v8, kOffVersion, 9);
  fix_crc(v8);
  EXPECT_NE(decode_error(v8), "");
}

TEST(MapCodec, ForwardMapBearingsCorruptionWithValidChecksum) {
  const std::vector<std::uint8_t> good = ha::encode_map(*make_map_with_bearings());
  ASSERT_EQ(decode_error(good), "");
  const auto reject = [&](const char* what, auto edit, const char* expect) {
    std::vector<std::uint8_t> b = good;
    edit(b);
    fix_crc(b);
    const std::string why = decode_error(b);
    EXPECT_NE(why.find(expect), std::string::npos) << what << ": " << why;
  };
  const float nan = std::numeric_limits<float>::quiet_NaN();
  // Bit 1 means nothing before version 6: such a map is refused, not read with bearings.
  reject(
      "bearings in a version 5 map", [](auto& b) { put_u32(b, kOffVersion, 5); },
      "flags: unknown bits set");
  reject(
      "a1 0", [](auto& b) { put_f32(b, kOffBearingA1, 0.0F); }, "bearing law: a1");
  reject(
      "a1 NaN", [&](auto& b) { put_f32(b, kOffBearingA1, nan); }, "bearing law: a1");
  reject(
      "a1 negative", [](auto& b) { put_f32(b, kOffBearingA1, -1.2F); }, "bearing law: a1");
  reject(
      "a1 above 4 rad", [](auto& b) { put_f32(b, kOffBearingA1, 4.01F); }, "bearing law: a1");
  reject(
      "a3 below -a1 (the law would turn back)", [](auto& b) { put_f32(b, kOffBearingA3, -1.21F); },
      "bearing law: a3");
  reject(
      "a3 above 3 a1", [](auto& b) { put_f32(b, kOffBearingA3, 3.61F); }, "bearing law: a3");
  reject(
      "a3 NaN", [&](auto& b) { put_f32(b, kOffBearingA3, nan); }, "bearing law: a3");
  reject(
      "camera offset NaN", [&](auto& b) { put_f32(b, kOffBearingCamera, nan); }, "camera offset");
  reject(
      "camera offset beyond 1 m", [](auto& b) { put_f32(b, kOffBearingCamera, -1.01F); },
      "camera offset");
  reject(
      "bearing sigma negative", [](auto& b) { put_f32(b, kOffBearingSigma + 4, -0.1F); },
      "bearing sigma");
  reject(
      "bearing sigma NaN", [&](auto& b) { put_f32(b, kOffBearingSigma, nan); }, "bearing sigma");
  reject(
      "bearing sigma above 1 rad", [](auto& b) { put_f32(b, kOffBearingSigma, 1.5F); },
      "bearing sigma");
  reject(
      "every bearing sigma 0",
      [](auto& b) {
        for (std::size_t k = 0; k < kBoards; ++k) put_f32(b, kOffBearingSigma + 4 * k, 0.0F);
      },
      "every bearing sigma is 0");
  reject(
      "a bearing of 5 rad", [](auto& b) { put_f32(b, kOffBearings + 4 * 7, 5.0F); },
      "bearing neither");
  reject(
      "a bearing just beyond pi", [](auto& b) { put_f32(b, kOffBearings, 3.1417F); },
      "bearing neither");
  reject(
      "a bearing NaN", [&](auto& b) { put_f32(b, kOffBearingsEnd - 4, nan); }, "bearing neither");
  reject(
      "a bearing of -8 (not the no-bearing value)",
      [](auto& b) { put_f32(b, kOffBearings + 4, -ha::ForwardMap::kNoBearing); },
      "bearing neither");
  reject(
      "truncated inside the bearing cells",
      [](auto& b) {
        b.erase(b.begin() + static_cast<std::ptrdiff_t>(kOffBearingsEnd - 32),
                b.begin() + static_cast<std::ptrdiff_t>(kOffBearingsEnd));
      },
      "truncated: the forward map's bearings");
  reject(
      "truncated inside the bearing law",
      [](auto& b) {
        b.resize(kOffBearingA3 + 2);
        b.resize(b.size() + 4);  // the CRC
      },
      "truncated: the forward map's bearing law");
  // The values at the edges of what is allowed are a map.
  std::vector<std::uint8_t> b = good;
  put_f32(b, kOffBearingA1, 4.0F);
  put_f32(b, kOffBearingA3, -4.0F);
  put_f32(b, kOffBearingSigma, 1.0F);
  put_f32(b, kOffBearings, ha::ForwardMap::kNoBearing);
  put_f32(b, kOffBearingCamera, 1.0F);
  fix_crc(b);
  EXPECT_EQ(decode_error(b), "");
  put_f32(b, kOffBearingA3, 9.0F);
  fix_crc(b);
  EXPECT_EQ(decode_error(b), "");
  // A rejected map leaves no half-read forward map, and no bearings, behind.
  b = good;
  put_f32(b, kOffBearingsEnd - 4, 5.0F);
  fix_crc(b);
  auto out = std::make_unique<ha::MapFile>();
  EXPECT_TRUE(ha::decode_map(b.data(), b.size(), *out));
  EXPECT_FALSE(out->forward.present());
  EXPECT_FALSE(out->forward.has_bearings);
}

// Cut anywhere in the bearings and re-sealed, a map is refused as truncated.
TEST(MapCodec, ForwardMapBearingsTruncatedAtEveryLength) {
  const std::vector<std::uint8_t> good = ha::encode_map(*make_map_with_bearings());
  auto out = std::make_unique<ha::MapFile>();
  for (std::size_t n = kOffBearingA1; n < kOffBearingsEnd; ++n) {
    std::vector<std::uint8_t> b(good.begin(), good.begin() + static_cast<std::ptrdiff_t>(n));
    b.resize(n + 4);
    fix_crc(b);
    const ha::MapError e = ha::decode_map(b.data(), b.size(), *out);
    ASSERT_TRUE(e) << "cut to " << n << " bytes and accepted";
    EXPECT_NE(std::string(e.what).find("truncated"), std::string::npos) << n << ": " << e.what;
    EXPECT_LE(e.offset, n);
    EXPECT_FALSE(out->forward.has_bearings);
  }
}

// Version 10: a floor map's visibility (bit 4) takes the heading terms' place after the
// bearings, per board the feature seen whole and the angular half-width, and reads back exactly;
// version 14 adds the gain's optical axis after the gain. It needs bearings, excludes heading
// terms, and a value out of range is refused; before version 10 the bit is unknown, and a version
// 13 map without the axis loads with 0.
TEST(MapCodec, VisibilityRoundTripAndChecks) {
  auto map = make_map_with_bearings();
  const std::vector<std::uint8_t> plain = ha::encode_map(*map);
  ha::ForwardMap& f = map->forward;
  f.has_visibility = true;
  f.visibility_angle_gain = 0.4F;
  f.visibility_axis_rad = -0.03F;
  for (std::size_t c = 0; c < f.stored_cells(); ++c) {
    for (std::size_t b = 0; b < kBoards; ++b) {
      f.heading_terms[(c * ha::kMaxBoards + b) * 2] = 0.01F * static_cast<float>(c + b);
      f.heading_terms[(c * ha::kMaxBoards + b) * 2 + 1] = 0.001F * static_cast<float>(b);
    }
  }
  const std::vector<std::uint8_t> bytes = ha::encode_map(*map);
  ASSERT_EQ(bytes.size(), plain.size() + 8 + f.stored_cells() * kBoards * 8);
  EXPECT_EQ(bytes[kOffFlags], plain[kOffFlags] | 16U);
  auto out = std::make_unique<ha::MapFile>();
  ASSERT_FALSE(ha::decode_map(bytes.data(), bytes.size(), *out));
  EXPECT_TRUE(out->forward.has_visibility);
  EXPECT_FLOAT_EQ(out->forward.visibility_angle_gain, 0.4F);
  EXPECT_FLOAT_EQ(out->forward.visibility_axis_rad, -0.03F);
  EXPECT_FALSE(out->forward.has_heading_terms);
  for (std::size_t i = 0; i < f.stored_cells() * ha::kMaxBoards * 2; ++i)
    ASSERT_EQ(out->forward.heading_terms[i], f.heading_terms[i]) << i;
  EXPECT_EQ(ha::encode_map(*out), bytes);
  // The angle gain and the axis sit right after the bearings, before the two counts, the column
  // weight and the CRC; then the first cell's first feature and its half-width.
  const std::size_t first = plain.size() - 4 - kAfterCalibration + 8;
  const auto refused = [&](std::size_t at, float v, const char* what) {
    std::vector<std::uint8_t> b = bytes;
    put_f32(b, at, v);
    fix_crc(b);
    EXPECT_NE(decode_error(b).find(what), std::string::npos) << v << ": " << decode_error(b);
  };
  for (float v : {std::numeric_limits<float>::quiet_NaN(), -2.1F, 2.1F})
    refused(first - 8, v, "visibility: angle gain");
  // The axis within the law's half field of view.
  const float half_fov = ha::half_field_of_view(f);
  for (float v : {std::numeric_limits<float>::quiet_NaN(), -1.01F * half_fov, 1.01F * half_fov})
    refused(first - 4, v, "visibility: optical axis");
  for (float v : {std::numeric_limits<float>::quiet_NaN(), -0.1F, 2.0e6F})
    refused(first, v, "visibility: a feature");
  for (float v : {std::numeric_limits<float>::infinity(), -0.01F, 3.3F})
    refused(first + 4, v, "visibility: a half-width");
  for (const std::size_t length : {first - 2, first + 8}) {
    std::vector<std::uint8_t> cut(bytes.begin(),
                                  bytes.begin() + static_cast<std::ptrdiff_t>(length));
    EXPECT_FALSE(decode_error(cut).empty());
  }
  // With heading terms too, without bearings, or in a version 9 map: refused.
  std::vector<std::uint8_t> b = bytes;
  b[kOffFlags] |= 4U;
  fix_crc(b);
  EXPECT_NE(decode_error(b).find("visibility without bearings or with heading terms"),
            std::string::npos)
      << decode_error(b);
  b = bytes;
  b[kOffFlags] &= static_cast<std::uint8_t>(~2U);
  fix_crc(b);
  EXPECT_NE(decode_error(b).find("visibility without bearings"), std::string::npos)
      << decode_error(b);
  b = bytes;
  put_u32(b, kOffVersion, 9);
  fix_crc(b);
  EXPECT_NE(decode_error(b).find("unknown bits"), std::string::npos) << decode_error(b);
  // Version 13: no axis; the same map centred on the centre column.
  b = bytes;
  b.erase(b.begin() + static_cast<std::ptrdiff_t>(first - 4),
          b.begin() + static_cast<std::ptrdiff_t>(first));
  put_u32(b, kOffVersion, 13);
  fix_crc(b);
  ASSERT_FALSE(ha::decode_map(b.data(), b.size(), *out)) << decode_error(b);
  EXPECT_TRUE(out->forward.has_visibility);
  EXPECT_FLOAT_EQ(out->forward.visibility_angle_gain, 0.4F);
  EXPECT_EQ(out->forward.visibility_axis_rad, 0.0F);
  for (std::size_t i = 0; i < f.stored_cells() * ha::kMaxBoards * 2; ++i)
    ASSERT_EQ(out->forward.heading_terms[i], f.heading_terms[i]) << i;
  // Written only with bearings: a map that lost them writes no visibility.
  map->forward.has_bearings = false;
  ASSERT_FALSE(ha::decode_map(ha::encode_map(*map).data(), ha::encode_map(*map).size(), *out));
  EXPECT_FALSE(out->forward.has_visibility);
}

// Version 15: the projected bearings follow the forward map's other sections, flagged by bit 5:
// the frame's size, the camera on the robot, its intrinsics and lens, then per board its outline's
// point count and points (version 16: and its bearings' spread); they read back exactly. They
// need bearings, an outline only for a board whose bearings are modelled, and the map's frame
// size; a value out of range is refused; before version 15 the bit is unknown, and a version 15
// map reads without the spreads.
TEST(MapCodec, ProjectionRoundTripAndChecks) {
  auto map = make_map_with_bearings();
  const std::vector<std::uint8_t> plain = ha::encode_map(*map);
  ha::BearingProjection& p = map->forward.projection;
  p.width_px = map->image_width_px;
  p.height_px = map->image_height_px;
  p.origin_m = {0.1F, 0.0F, 0.35F};
  p.right = {0.0F, -1.0F, 0.0F};
  p.down = {0.0F, 0.0F, -1.0F};
  p.forward = {1.0F, 0.0F, 0.0F};
  p.focal_px = 400.0F;
  p.cx_px = 320.5F;
  p.cy_px = 239.0F;
  p.k1 = -0.2F;
  p.k2 = 0.03F;
  p.p1 = 1e-3F;
  p.max_radius2 = 2.5F;
  p.points[0] = 4;
  p.points[2] = 8;
  for (std::size_t i = 0; i < 3 * 4; ++i) p.point_m(0, i / 3, i % 3) = 0.1F * static_cast<float>(i);
  for (std::size_t i = 0; i < 3 * 8; ++i)
    p.point_m(2, i / 3, i % 3) = -0.2F * static_cast<float>(i);
  p.sigma_rad[0] = 0.003F;
  p.sigma_rad[2] = 0.004F;
  p.area_per_px[2] = 3.25e-4F;  // board 0's areas from the cells
  p.area_sigma[2] = 0.0125F;
  const std::vector<std::uint8_t> bytes = ha::encode_map(*map);
  ASSERT_EQ(bytes.size(), plain.size() + 92 + 4 * kBoards + 12 * (4 + 8) + 12 * 2);
  EXPECT_EQ(bytes[kOffFlags], plain[kOffFlags] | 32U);
  auto out = std::make_unique<ha::MapFile>();
  ASSERT_FALSE(ha::decode_map(bytes.data(), bytes.size(), *out)) << decode_error(bytes);
  const ha::BearingProjection& q = out->forward.projection;
  EXPECT_TRUE(q.present());
  EXPECT_EQ(q.points, p.points);
  EXPECT_EQ(q.outline_m, p.outline_m);
  EXPECT_EQ(q.sigma_rad, p.sigma_rad);
  EXPECT_EQ(q.area_per_px, p.area_per_px);
  EXPECT_EQ(q.area_sigma, p.area_sigma);
  EXPECT_EQ(q.forward, p.forward);
  EXPECT_EQ(q.origin_m, p.origin_m);
  EXPECT_FLOAT_EQ(q.focal_px, 400.0F);
  EXPECT_FLOAT_EQ(q.k2, 0.03F);
  EXPECT_FLOAT_EQ(q.max_radius2, 2.5F);
  EXPECT_EQ(ha::encode_map(*out), bytes);

  // Its offsets: right after the bearings (the map has no heading terms, visibility or coverage).
  const std::size_t first = plain.size() - 4 - kAfterCalibration;
  const auto refused = [&](std::size_t at, float v, const char* what) {
    std::vector<std::uint8_t> b = bytes;
    put_f32(b, at, v);
    fix_crc(b);
    EXPECT_NE(decode_error(b).find(what), std::string::npos) << v << ": " << decode_error(b);
  };
  const auto refused_u32 = [&](std::size_t at, std::uint32_t v, const char* what) {
    std::vector<std::uint8_t> b = bytes;
    put_u32(b, at, v);
    fix_crc(b);
    EXPECT_NE(decode_error(b).find(what), std::string::npos) << v << ": " << decode_error(b);
  };
  refused_u32(first, 0, "frame size out of range");
  refused_u32(first, 1280, "frame size differs from the map's");
  refused(first + 8, std::numeric_limits<float>::quiet_NaN(), "camera place");
  refused(first + 8 + 8, 11.0F, "camera place");
  refused(first + 20, 0.5F, "not a unit vector");      // right x: |right| > 1
  refused(first + 32 + 4, 0.5F, "not a unit vector");  // down y
  refused(first + 44, 0.5F, "not a unit vector");      // forward x
  const std::size_t intrinsics = first + 56;
  refused(intrinsics, 0.5F, "intrinsics out of range");
  refused(intrinsics + 4, -1.0F, "intrinsics out of range");
  refused(intrinsics + 8, std::numeric_limits<float>::infinity(), "intrinsics out of range");
  refused(intrinsics + 12, 101.0F, "lens coefficient");
  refused(intrinsics + 28, std::numeric_limits<float>::quiet_NaN(), "lens coefficient");
  refused(intrinsics + 32, 0.0F, "lens radius");
  const std::size_t boards = first + 92;
  refused_u32(boards, 2, "neither 0 nor 3 to 8 points");
  refused_u32(boards, 9, "neither 0 nor 3 to 8 points");
  refused(boards + 4, std::numeric_limits<float>::quiet_NaN(), "outline point");
  refused(boards + 4 + 8, 2.0e4F, "outline point");
  // Board 0's spread, after its 4 points (version 16).
  for (const float v : {-0.01F, 0.8F, std::numeric_limits<float>::quiet_NaN()})
    refused(boards + 4 + 48, v, "bearing spread");
  {  // 0: the cells' spread, as a version 15 map written again has.
    std::vector<std::uint8_t> b = bytes;
    put_f32(b, boards + 4 + 48, 0.0F);
    fix_crc(b);
    ASSERT_FALSE(ha::decode_map(b.data(), b.size(), *out)) << decode_error(b);
    EXPECT_EQ(out->forward.projection.sigma_rad[0], 0.0F);
    EXPECT_FLOAT_EQ(out->forward.projection.sigma_rad[2], 0.004F);
  }
  // Board 0's feature per pixel, after its spread (version 17): 0 (the cells' areas) or up to
  // 1000.
  for (const float v : {-1e-6F, 1.5e3F, std::numeric_limits<float>::infinity()})
    refused(boards + 4 + 52, v, "feature per pixel");
  // Then its area noise: 0 (the map's sigma) or up to 1000.
  for (const float v : {-1e-6F, 1.5e3F, std::numeric_limits<float>::quiet_NaN()})
    refused(boards + 4 + 56, v, "area noise");
  {
    std::vector<std::uint8_t> b = bytes;
    put_f32(b, boards + 4 + 52, 2.0e-4F);
    put_f32(b, boards + 4 + 56, 0.5F);
    fix_crc(b);
    ASSERT_FALSE(ha::decode_map(b.data(), b.size(), *out)) << decode_error(b);
    EXPECT_FLOAT_EQ(out->forward.projection.area_per_px[0], 2.0e-4F);
    EXPECT_FLOAT_EQ(out->forward.projection.area_sigma[0], 0.5F);
    EXPECT_FLOAT_EQ(out->forward.projection.area_per_px[2], 3.25e-4F);
    EXPECT_FLOAT_EQ(out->forward.projection.area_sigma[2], 0.0125F);
  }
  for (const std::size_t length : {first + 2, boards + 6, bytes.size() - kAfterCalibration - 6}) {
    std::vector<std::uint8_t> cut(bytes.begin(),
                                  bytes.begin() + static_cast<std::ptrdiff_t>(length));
    EXPECT_FALSE(decode_error(cut).empty());
  }
  // Axes at right angles: down turned towards forward.
  {
    std::vector<std::uint8_t> b = bytes;
    put_f32(b, first + 32, 0.6F);   // down = (0.6, 0, -0.8): a unit vector, not at right angles
    put_f32(b, first + 40, -0.8F);  // with forward (1, 0, 0)
    fix_crc(b);
    EXPECT_NE(decode_error(b).find("not at right angles"), std::string::npos) << decode_error(b);
  }
  // An outline for board 3, whose bearings the map does not model; one without bearings; no
  // outline at all; a version 14 map.
  {
    auto other = make_map_with_bearings();
    other->forward.projection = p;
    other->forward.projection.points[3] = 4;
    const std::vector<std::uint8_t> b = ha::encode_map(*other);
    EXPECT_NE(decode_error(b).find("a board without bearings"), std::string::npos)
        << decode_error(b);
  }
  std::vector<std::uint8_t> b = bytes;
  b[kOffFlags] &= static_cast<std::uint8_t>(~2U);
  fix_crc(b);
  EXPECT_NE(decode_error(b).find("projected bearings but no bearings"), std::string::npos)
      << decode_error(b);
  b = bytes;
  put_u32(b, boards, 0);
  b.erase(b.begin() + static_cast<std::ptrdiff_t>(boards + 4),
          b.begin() + static_cast<std::ptrdiff_t>(boards + 4 + 48 + 12));
  put_u32(b, boards + 4 * 2, 0);
  b.erase(b.begin() + static_cast<std::ptrdiff_t>(boards + 12),
          b.begin() + static_cast<std::ptrdiff_t>(boards + 12 + 96 + 12));
  fix_crc(b);
  EXPECT_NE(decode_error(b).find("holds no outline"), std::string::npos) << decode_error(b);
  // A version 16 map: the outlines without their features per pixel and area noise (board 0's
  // after its 4 points and spread at 56, board 2's after its 8 and spread at 172), read as the
  // cells' areas (0).
  b = bytes;
  b.erase(b.begin() + static_cast<std::ptrdiff_t>(boards + 172),
          b.begin() + static_cast<std::ptrdiff_t>(boards + 180));
  b.erase(b.begin() + static_cast<std::ptrdiff_t>(boards + 56),
          b.begin() + static_cast<std::ptrdiff_t>(boards + 64));
  put_u32(b, kOffVersion, 16);
  fix_crc(b);
  ASSERT_FALSE(ha::decode_map(b.data(), b.size(), *out)) << decode_error(b);
  EXPECT_EQ(out->forward.projection.sigma_rad, p.sigma_rad);
  EXPECT_EQ(out->forward.projection.area_per_px, (std::array<float, ha::kMaxBoards>{}));
  EXPECT_EQ(out->forward.projection.area_sigma, (std::array<float, ha::kMaxBoards>{}));
  // A version 15 map: without the spreads too (board 0's at 52, board 2's at 160 in the version
  // 16 layout), read as the cells' spread (0).
  b.erase(b.begin() + static_cast<std::ptrdiff_t>(boards + 160),
          b.begin() + static_cast<std::ptrdiff_t>(boards + 164));
  b.erase(b.begin() + static_cast<std::ptrdiff_t>(boards + 52),
          b.begin() + static_cast<std::ptrdiff_t>(boards + 56));
  put_u32(b, kOffVersion, 15);
  fix_crc(b);
  ASSERT_FALSE(ha::decode_map(b.data(), b.size(), *out)) << decode_error(b);
  EXPECT_EQ(out->forward.projection.points, p.points);
  EXPECT_EQ(out->forward.projection.outline_m, p.outline_m);
  EXPECT_EQ(out->forward.projection.sigma_rad, (std::array<float, ha::kMaxBoards>{}));
  EXPECT_EQ(out->forward.projection.area_per_px, (std::array<float, ha::kMaxBoards>{}));
  b = bytes;
  put_u32(b, kOffVersion, 14);
  fix_crc(b);
  EXPECT_NE(decode_error(b).find("unknown bits"), std::string::npos) << decode_error(b);
  // Written only with bearings.
  map->forward.has_bearings = false;
  const std::vector<std::uint8_t> without = ha::encode_map(*map);
  ASSERT_FALSE(ha::decode_map(without.data(), without.size(), *out)) << decode_error(without);
  EXPECT_FALSE(out->forward.projection.present());
}
