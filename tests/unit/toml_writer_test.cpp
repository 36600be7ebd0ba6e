// The TOML files the project writes (dataset/toml_writer.hpp): numbers short and exact, keys in
// the order set, strings escaped; metadata.toml, scenario.toml and a random scene's harmoloc.toml
// read back by the project's own readers to the same values, every double bit for bit.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <toml++/toml.h>

#include "harmoloc/dataset/metadata.hpp"
#include "harmoloc/dataset/toml_writer.hpp"
#include "harmoloc/firmware/config.hpp"
#include "harmoloc/sim_host/random_scene.hpp"
#include "harmoloc/sim_host/scenario.hpp"
#include "test_support.hpp"

namespace hd = harmoloc::dataset;
namespace hs = harmoloc::sim_host;
namespace ht = harmoloc::test;

namespace {

// The same double, bit for bit (0.0 and -0.0 differ).
bool same_bits(double a, double b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

#define EXPECT_SAME_DOUBLE(a, b) \
  EXPECT_TRUE(same_bits((a), (b))) << #a " = " << (a) << ", " #b " = " << (b)

double read_number(const toml::table& t, const char* key) {
  const toml::node* n = t.get(key);
  if (n == nullptr) return std::nan("");
  if (auto i = n->value_exact<std::int64_t>()) return static_cast<double>(*i);
  return n->value_exact<double>().value_or(std::nan(""));
}

std::string read_text(const std::string& path) {
  const std::vector<std::uint8_t> bytes = ht::read_bytes(path);
  return std::string(bytes.begin(), bytes.end());
}

bool has_line(const std::string& text, const std::string& line) {
  return ("\n" + text).find("\n" + line + "\n") != std::string::npos;
}

}  // namespace

// --- the writer ------------------------------------------------------------------------------

TEST(TomlWriter, NumbersAreShortWhereExactAndReadBackExactly) {
  const double cases[] = {0.05,
                          0.1 + 0.2,
                          1.0 / 3.0,
                          16384.0,
                          0.0,
                          -0.0,
                          -75.0,
                          1e-5,
                          2.5e-300,
                          5e-324,
                          1e300,
                          1.5e22,
                          -2.75,
                          9007199254740992.0,
                          9007199254740994.0,
                          1767225600.0,
                          std::numeric_limits<double>::max(),
                          std::numeric_limits<double>::infinity()};
  hd::TomlWriter w;
  for (std::size_t i = 0; i < std::size(cases); ++i) w.set("n" + std::to_string(i), cases[i]);
  const std::string text = w.text();
  EXPECT_TRUE(has_line(text, "n0 = 0.05")) << text;
  EXPECT_TRUE(has_line(text, "n1 = 0.30000000000000004")) << text;
  EXPECT_TRUE(has_line(text, "n3 = 16384")) << text;  // whole: an integer, as before
  EXPECT_TRUE(has_line(text, "n4 = 0")) << text;
  EXPECT_TRUE(has_line(text, "n5 = -0.0")) << text;  // the sign is kept
  EXPECT_TRUE(has_line(text, "n6 = -75")) << text;
  EXPECT_TRUE(has_line(text, "n7 = 1e-05")) << text;
  EXPECT_TRUE(has_line(text, "n14 = 9007199254740994.0")) << text;  // beyond 2^53: a float
  EXPECT_TRUE(has_line(text, "n17 = inf")) << text;
  const toml::table back = toml::parse(text);
  EXPECT_EQ(back, w.document());
  for (std::size_t i = 0; i < std::size(cases); ++i) {
    SCOPED_TRACE(i);
    EXPECT_SAME_DOUBLE(read_number(back, ("n" + std::to_string(i)).c_str()), cases[i]);
  }
}

TEST(TomlWriter, AnyFiniteDoubleReadsBackBitForBit) {
  std::mt19937_64 rng(17);
  hd::TomlWriter w;
  std::vector<double> values;
  while (values.size() < 3000) {
    const std::uint64_t bits = rng();
    double v = 0.0;
    std::memcpy(&v, &bits, sizeof v);
    if (!std::isfinite(v)) continue;
    // Every third a number of everyday size.
    if (values.size() % 3 == 0) v = std::ldexp(std::fmod(v, 1.0), -static_cast<int>(rng() % 20));
    w.set("v" + std::to_string(values.size()), v);
    values.push_back(v);
  }
  const toml::table back = toml::parse(w.text());
  for (std::size_t i = 0; i < values.size(); ++i)
    EXPECT_SAME_DOUBLE(read_number(back, ("v" + std::to_string(i)).c_str()), values[i]);
}

TEST(TomlWriter, FloatsWrittenAsTheirShortestDecimal) {
  hd::TomlWriter w;
  toml::array hue;
  hd::push_number(hue, hd::decimal_of(37.3F));
  hd::push_number(hue, hd::decimal_of(350.0F));
  w.set("hue_deg", hue).set("gain", 0.1F);
  const std::string text = w.text();
  EXPECT_TRUE(has_line(text, "hue_deg = [37.3, 350]")) << text;
  EXPECT_TRUE(has_line(text, "gain = 0.1")) << text;
  const toml::table back = toml::parse(text);
  EXPECT_EQ(static_cast<float>(*back["hue_deg"][0].value<double>()), 37.3F);
  EXPECT_EQ(static_cast<float>(*back["gain"].value<double>()), 0.1F);
}

TEST(TomlWriter, KeysInTheOrderSetTablesAndStringsEscaped) {
  hd::TomlWriter w("first line\nsecond, with a\x01 control character\n\nafter an empty line");
  w.set("zeta", 1).set("alpha", "plain").set("quote", "say \"hi\" \\ it's").set("yes", true);
  w.set("lines", "a\nb\tc\x01\x7F")
      .set("unicode",
           "K\xC3\xBC"
           "che");
  w.table("camera").set("width_px", 320U).set("height_px", 240U).set_hex("can_id", 0x18FF0001);
  w.array_table("boards").set("name", "a").set("size", hd::number_array<2>({0.4, 0.3}));
  w.array_table("boards").set("name", "b").set("size", toml::array{});
  w.table("odd key").set("key with space", 1.5).set("width_px", 7);
  w.set("width_px", 8);  // set again: the first place, the last value
  const std::string text = w.text();
  EXPECT_EQ(text.rfind("# first line\n# second, with a  control character\n#\n"
                       "# after an empty line\nzeta = 1\nalpha = \"plain\"\n",
                       0),
            0U)
      << text;
  EXPECT_TRUE(has_line(text, "quote = \"say \\\"hi\\\" \\\\ it's\"")) << text;
  EXPECT_TRUE(has_line(text,
                       "unicode = \"K\xC3\xBC"
                       "che\""))
      << text;
  EXPECT_NE(text.find("\n\n[camera]\nwidth_px = 320\nheight_px = 240\ncan_id = 0x18FF0001\n"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("\n\n[[boards]]\nname = \"a\"\nsize = [0.4, 0.3]\n\n[[boards]]\nname = "
                      "\"b\"\nsize = []\n"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("\n\n[\"odd key\"]\n\"key with space\" = 1.5\nwidth_px = 8\n"),
            std::string::npos)
      << text;
  const toml::table back = toml::parse(text);
  EXPECT_EQ(back, w.document());
  EXPECT_EQ(back["lines"].value<std::string>(), "a\nb\tc\x01\x7F");
  EXPECT_EQ(back["quote"].value<std::string>(), "say \"hi\" \\ it's");
}

TEST(TomlWriter, ANumberTooLargeForTomlIsRefused) {
  hd::TomlWriter w;
  EXPECT_NO_THROW(w.set("seed", std::uint64_t{INT64_MAX}));
  EXPECT_THROW(w.set("seed", std::uint64_t{INT64_MAX} + 1), std::runtime_error);
  // A dataset's seed above it: write_metadata says so (the reader would refuse the file).
  ht::TempDir dir;
  hd::DatasetMetadata m;
  m.image_width_px = 16;
  m.image_height_px = 16;
  m.seed = std::uint64_t{INT64_MAX} + 1;
  try {
    hd::write_metadata(dir.dir(), m);
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    ht::expect_one_line(e.what(), dir.path("metadata.toml") + ": seed = 9223372036854775808");
  }
}

// --- metadata.toml ---------------------------------------------------------------------------

TEST(TomlFiles, MetadataReadsBackExactly) {
  ht::TempDir dir;
  hd::DatasetMetadata m;
  m.name = "odd \"name\" \\ with\na line break";
  m.seed = 9007199254740993ULL;  // beyond a double's integers
  m.image_width_px = 322;
  m.image_height_px = 241;
  m.pixel_format = harmoloc::hal::PixelFormat::kRgb24;
  m.frame_rate_hz = 29.97;
  m.frames_index = "frames/index.csv";
  m.encoder_source = hd::EncoderSource::kGpio;
  m.encoder_log = "enc \"gpio\".csv";
  m.ground_truth = "truth.tum";
  m.can_interface = "vcan0";
  m.geometry.wheel_radius_m = 0.05;
  m.geometry.track_m = 0.1 + 0.2;
  m.geometry.ticks_per_rev = 2048.5;
  m.geometry.left_direction = 1;
  m.geometry.right_direction = -1;
  m.encoder_layout.id = 0x1ABCDEF0;
  m.encoder_layout.length = 8;
  m.encoder_layout.left_offset = 4;
  m.encoder_layout.right_offset = 0;
  m.encoder_layout.counter_bits = 32;
  m.encoder_layout.byte_order = harmoloc::algorithms::ByteOrder::kBigEndian;
  hd::write_metadata(dir.dir(), m);
  const std::string text = read_text(dir.path("metadata.toml"));
  EXPECT_TRUE(has_line(text, "wheel_radius_m = 0.05")) << text;
  EXPECT_TRUE(has_line(text, "track_m = 0.30000000000000004")) << text;
  EXPECT_TRUE(has_line(text, "can_id = 0x1ABCDEF0")) << text;
  EXPECT_EQ(text.rfind("# harmoloc dataset metadata (schema: docs/dataset-format.md)\n"
                       "format_version = 1\n",
                       0),
            0U)
      << text;

  const hd::DatasetMetadata r = hd::read_metadata(dir.dir());
  EXPECT_EQ(r.name, m.name);
  EXPECT_EQ(r.seed, m.seed);
  EXPECT_EQ(r.image_width_px, m.image_width_px);
  EXPECT_EQ(r.image_height_px, m.image_height_px);
  EXPECT_EQ(r.pixel_format, m.pixel_format);
  EXPECT_SAME_DOUBLE(r.frame_rate_hz, m.frame_rate_hz);
  EXPECT_EQ(r.frames_index, m.frames_index);
  EXPECT_EQ(r.encoder_source, m.encoder_source);
  EXPECT_EQ(r.encoder_log, m.encoder_log);
  EXPECT_EQ(r.ground_truth, m.ground_truth);
  EXPECT_EQ(r.can_interface, m.can_interface);
  EXPECT_SAME_DOUBLE(r.geometry.wheel_radius_m, m.geometry.wheel_radius_m);
  EXPECT_SAME_DOUBLE(r.geometry.track_m, m.geometry.track_m);
  EXPECT_SAME_DOUBLE(r.geometry.ticks_per_rev, m.geometry.ticks_per_rev);
  EXPECT_EQ(r.geometry.left_direction, m.geometry.left_direction);
  EXPECT_EQ(r.geometry.right_direction, m.geometry.right_direction);
  EXPECT_EQ(r.encoder_layout.id, m.encoder_layout.id);
  EXPECT_EQ(r.encoder_layout.length, m.encoder_layout.length);
  EXPECT_EQ(r.encoder_layout.left_offset, m.encoder_layout.left_offset);
  EXPECT_EQ(r.encoder_layout.right_offset, m.encoder_layout.right_offset);
  EXPECT_EQ(r.encoder_layout.counter_bits, m.encoder_layout.counter_bits);
  EXPECT_EQ(r.encoder_layout.byte_order, m.encoder_layout.byte_order);
  // Written again from what was read: the same file.
  EXPECT_EQ(hd::metadata_toml(r), text);
}

// --- scenario.toml ---------------------------------------------------------------------------

namespace {

void expect_same_rgb(const hs::Rgb& a, const hs::Rgb& b) {
  EXPECT_EQ(a.r, b.r);
  EXPECT_EQ(a.g, b.g);
  EXPECT_EQ(a.b, b.b);
}

template <std::size_t N>
void expect_same_array(const std::array<double, N>& a, const std::array<double, N>& b) {
  for (std::size_t i = 0; i < N; ++i) EXPECT_SAME_DOUBLE(a[i], b[i]);
}

template <std::size_t N>
void expect_same_list(const std::vector<std::array<double, N>>& a,
                      const std::vector<std::array<double, N>>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) expect_same_array(a[i], b[i]);
}

// Every field scenario.toml holds.
void expect_same_scenario(const hs::Scenario& a, const hs::Scenario& b, bool exact_angles) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.description, b.description);
  EXPECT_EQ(a.labelled_frames, b.labelled_frames);
  EXPECT_EQ(a.labels_with_heading, b.labels_with_heading);
  EXPECT_SAME_DOUBLE(a.start_time_s, b.start_time_s);
  expect_same_array(a.room.x_m, b.room.x_m);
  expect_same_array(a.room.y_m, b.room.y_m);
  EXPECT_SAME_DOUBLE(a.room.height_m, b.room.height_m);
  expect_same_rgb(a.room.floor_colour, b.room.floor_colour);
  expect_same_rgb(a.room.floor_tile_colour, b.room.floor_tile_colour);
  EXPECT_SAME_DOUBLE(a.room.tile_m, b.room.tile_m);
  expect_same_rgb(a.room.wall_colour, b.room.wall_colour);
  expect_same_rgb(a.room.side_wall_colour, b.room.side_wall_colour);
  expect_same_rgb(a.room.ceiling_colour, b.room.ceiling_colour);
  EXPECT_EQ(a.desk.present, b.desk.present);
  expect_same_array(a.desk.x_m, b.desk.x_m);
  EXPECT_SAME_DOUBLE(a.desk.front_y_m, b.desk.front_y_m);
  EXPECT_SAME_DOUBLE(a.desk.height_m, b.desk.height_m);
  expect_same_rgb(a.desk.colour, b.desk.colour);
  expect_same_rgb(a.desk.top_colour, b.desk.top_colour);
  const hs::CameraSpec &c = a.camera, &d = b.camera;
  EXPECT_EQ(c.width_px, d.width_px);
  EXPECT_EQ(c.height_px, d.height_px);
  for (const auto field :
       {&hs::CameraSpec::horizontal_fov_deg, &hs::CameraSpec::k1, &hs::CameraSpec::k2,
        &hs::CameraSpec::k3, &hs::CameraSpec::p1, &hs::CameraSpec::p2,
        &hs::CameraSpec::principal_offset_x_px, &hs::CameraSpec::principal_offset_y_px,
        &hs::CameraSpec::vignetting, &hs::CameraSpec::height_m, &hs::CameraSpec::pitch_deg,
        &hs::CameraSpec::mount_yaw_deg, &hs::CameraSpec::forward_offset_m, &hs::CameraSpec::rate_hz,
        &hs::CameraSpec::pixel_noise, &hs::CameraSpec::light_gain})
    EXPECT_SAME_DOUBLE(c.*field, d.*field);
  EXPECT_SAME_DOUBLE(a.lighting.drift_amplitude, b.lighting.drift_amplitude);
  EXPECT_SAME_DOUBLE(a.lighting.drift_period_s, b.lighting.drift_period_s);
  EXPECT_SAME_DOUBLE(a.lighting.drift_phase_deg, b.lighting.drift_phase_deg);
  expect_same_list(a.lighting.steps, b.lighting.steps);
  EXPECT_EQ(a.route.shape, b.route.shape);
  expect_same_list(a.route.waypoints_m, b.route.waypoints_m);
  EXPECT_SAME_DOUBLE(a.route.speed_mps, b.route.speed_mps);
  EXPECT_SAME_DOUBLE(a.route.acceleration_mps2, b.route.acceleration_mps2);
  EXPECT_SAME_DOUBLE(a.route.pause_s, b.route.pause_s);
  EXPECT_EQ(a.route.laps, b.route.laps);
  EXPECT_SAME_DOUBLE(a.route.wander_m, b.route.wander_m);
  EXPECT_SAME_DOUBLE(a.encoders.rate_hz, b.encoders.rate_hz);
  EXPECT_SAME_DOUBLE(a.encoders.slip_sigma, b.encoders.slip_sigma);
  EXPECT_SAME_DOUBLE(a.encoders.left_scale_error, b.encoders.left_scale_error);
  EXPECT_SAME_DOUBLE(a.encoders.right_scale_error, b.encoders.right_scale_error);
  EXPECT_EQ(a.encoders.initial_left, b.encoders.initial_left);
  EXPECT_EQ(a.encoders.initial_right, b.encoders.initial_right);
  EXPECT_EQ(a.can_layout.counter_bits, b.can_layout.counter_bits);
  EXPECT_SAME_DOUBLE(a.robot.wheel_radius_m, b.robot.wheel_radius_m);
  EXPECT_SAME_DOUBLE(a.robot.track_m, b.robot.track_m);
  EXPECT_SAME_DOUBLE(a.robot.ticks_per_rev, b.robot.ticks_per_rev);
  ASSERT_EQ(a.boards.size(), b.boards.size());
  for (std::size_t i = 0; i < a.boards.size(); ++i) {
    const hs::BoardSpec &x = a.boards[i], &y = b.boards[i];
    EXPECT_EQ(x.name, y.name);
    expect_same_rgb(x.colour, y.colour);
    for (const auto field :
         {&hs::BoardSpec::centre_x_m, &hs::BoardSpec::centre_y_m, &hs::BoardSpec::centre_z_m,
          &hs::BoardSpec::width_m, &hs::BoardSpec::height_m})
      EXPECT_SAME_DOUBLE(x.*field, y.*field);
    // Angles are radians in memory and degrees in the file (12 digits, so that -105 stays -105):
    // a built-in board at `face - 15 * kDeg` reads back as -105 * kDeg, an ulp away. A random
    // scene's angles are whole tenths of a degree times kDeg and read back exactly (below).
    for (const auto field : {&hs::BoardSpec::facing_yaw_rad, &hs::BoardSpec::tilt_rad}) {
      EXPECT_LE(std::fabs(x.*field - y.*field),
                2.0 * std::numeric_limits<double>::epsilon() * std::fabs(x.*field));
      if (exact_angles) {
        EXPECT_SAME_DOUBLE(x.*field, y.*field);
      }
    }
    EXPECT_EQ(x.shape, y.shape);
    EXPECT_EQ(x.stand, y.stand);
  }
  ASSERT_EQ(a.occluders.size(), b.occluders.size());
  for (std::size_t i = 0; i < a.occluders.size(); ++i) {
    EXPECT_EQ(a.occluders[i].name, b.occluders[i].name);
    expect_same_rgb(a.occluders[i].colour, b.occluders[i].colour);
    EXPECT_SAME_DOUBLE(a.occluders[i].radius_m, b.occluders[i].radius_m);
    EXPECT_SAME_DOUBLE(a.occluders[i].height_m, b.occluders[i].height_m);
    expect_same_list(a.occluders[i].path, b.occluders[i].path);
  }
  ASSERT_EQ(a.board_moves.size(), b.board_moves.size());
  for (std::size_t i = 0; i < a.board_moves.size(); ++i) {
    EXPECT_EQ(a.board_moves[i].board, b.board_moves[i].board);
    EXPECT_SAME_DOUBLE(a.board_moves[i].at_s, b.board_moves[i].at_s);
    expect_same_array(a.board_moves[i].offset_m, b.board_moves[i].offset_m);
    EXPECT_SAME_DOUBLE(a.board_moves[i].turn_deg, b.board_moves[i].turn_deg);
  }
  EXPECT_EQ(a.kidnaps.count, b.kidnaps.count);
  if (a.kidnaps.count > 0) {
    EXPECT_SAME_DOUBLE(a.kidnaps.first_s, b.kidnaps.first_s);
    EXPECT_SAME_DOUBLE(a.kidnaps.interval_s, b.kidnaps.interval_s);
    EXPECT_SAME_DOUBLE(a.kidnaps.min_distance_m, b.kidnaps.min_distance_m);
  }
}

}  // namespace

TEST(TomlFiles, ScenarioReadsBackExactly) {
  ht::TempDir dir;
  std::vector<hs::Scenario> scenarios;
  for (const auto& [name, what] : hs::builtin_scenarios())
    scenarios.push_back(hs::load_scenario(name));
  for (std::uint64_t seed = 1; seed <= 8; ++seed) scenarios.push_back(hs::random_scenario(seed));
  scenarios.push_back(hs::kidnap_variant(hs::random_scenario(3), 2));
  hs::Scenario odd = hs::load_scenario("tiny");
  odd.name = "tiny \"quoted\" \\ name";
  odd.description = "two\nlines";
  odd.robot.wheel_radius_m = 0.05;
  odd.robot.track_m = 0.1 + 0.2;
  scenarios.push_back(odd);
  for (const hs::Scenario& s : scenarios) {
    SCOPED_TRACE(s.name);
    const std::string text = hs::scenario_to_toml(s);
    const hs::Scenario back = hs::load_scenario(dir.write("scene.toml", text));
    expect_same_scenario(back, s, s.name.rfind("random", 0) == 0);
    EXPECT_EQ(hs::scenario_to_toml(back), text);
  }
  EXPECT_TRUE(has_line(hs::scenario_to_toml(odd), "wheel_radius_m = 0.05"));
  // The sections in the documented order, not sorted.
  const std::string text = hs::scenario_to_toml(odd);
  std::size_t at = 0;
  for (const char* section : {"\n[room]\n", "\n[desk]\n", "\n[camera]\n", "\n[lighting]\n",
                              "\n[route]\n", "\n[encoders]\n", "\n[robot]\n", "\n[[boards]]\n"}) {
    const std::size_t next = text.find(section, at);
    EXPECT_NE(next, std::string::npos) << section << "\n" << text;
    at = next;
  }
}

// --- a random scene's harmoloc.toml ----------------------------------------------------------

TEST(TomlFiles, SceneConfigReadsBackExactly) {
  ht::TempDir dir;
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    SCOPED_TRACE(seed);
    hs::Scenario s = hs::random_scenario(seed);
    if (seed == 1) s.robot.wheel_radius_m = 0.05;
    const std::string text = hs::firmware_config_toml(s);
    if (seed == 1) {
      EXPECT_TRUE(has_line(text, "wheel_radius_m = 0.05")) << text;
    }
    const auto config = harmoloc::firmware::load_config(dir.write("harmoloc.toml", text));
    EXPECT_SAME_DOUBLE(config.geometry.wheel_radius_m, s.robot.wheel_radius_m);
    EXPECT_SAME_DOUBLE(config.geometry.track_m, s.robot.track_m);
    EXPECT_SAME_DOUBLE(config.geometry.ticks_per_rev, s.robot.ticks_per_rev);
    EXPECT_EQ(config.can_layout.id, s.can_layout.id);
    EXPECT_EQ(config.can_layout.length, s.can_layout.length);
    EXPECT_EQ(config.can_layout.left_offset, s.can_layout.left_offset);
    EXPECT_EQ(config.can_layout.right_offset, s.can_layout.right_offset);
    EXPECT_EQ(config.can_layout.counter_bits, s.can_layout.counter_bits);
    const auto windows = hs::thresholds_for(s);
    ASSERT_EQ(config.thresholds.count, windows.size());
    for (std::size_t b = 0; b < windows.size(); ++b) {
      EXPECT_EQ(config.board_names.names[b], windows[b].first);
      EXPECT_EQ(config.thresholds.boards[b], windows[b].second);
    }
  }
}
