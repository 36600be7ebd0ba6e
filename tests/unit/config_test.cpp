// The firmware's TOML configuration: defaults, a full file read back, and one clear line for
// each kind of bad input.
#include "harmoloc/firmware/config.hpp"
#include "harmoloc/firmware/localization_cycle.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <string>

#include "test_support.hpp"

namespace hf = harmoloc::firmware;
namespace ha = harmoloc::algorithms;
namespace ht = harmoloc::test;

namespace {

// Loads @p text from a file in @p dir and expects a one-line message that names the file first
// and says what is wrong (@p what), at line @p line when that is given.
void expect_one_line_error(const ht::TempDir& dir, const std::string& text, const std::string& what,
                           int line = 0) {
  const std::string file = dir.write("harmoloc.toml", text);
  const std::string msg = ht::error_of([&] { hf::load_config(file); });
  ASSERT_NE(msg, ht::kNoException) << "accepted:\n" << text;
  ht::expect_one_line(msg, file + ": ", what);
  if (line > 0) {
    EXPECT_NE(msg.find("line " + std::to_string(line) + ":"), std::string::npos) << msg;
  }
}

}  // namespace

TEST(Config, DefaultsHaveSixBoards) {
  const hf::FirmwareConfig c = hf::default_config();
  ASSERT_EQ(c.thresholds.count, 6U);
  const char* names[] = {"red", "green", "blue", "yellow", "magenta", "cyan"};
  for (std::size_t i = 0; i < 6; ++i) {
    EXPECT_EQ(c.board_names.names[i], names[i]);
    const ha::ColourThreshold& t = c.thresholds.boards[i];
    EXPECT_LE(t.value_min, t.value_max) << i;
    EXPECT_GE(t.hue_min_deg, 0.0F);
    EXPECT_LE(t.hue_max_deg, 360.0F);
  }
  // Red wraps through 0.
  EXPECT_GT(c.thresholds.boards[0].hue_min_deg, c.thresholds.boards[0].hue_max_deg);
  EXPECT_DOUBLE_EQ(c.cycle.rate_hz, 30.0);
  EXPECT_DOUBLE_EQ(c.cycle.budget_ms, 15.0);
  EXPECT_EQ(c.cycle.pacing, hf::Pacing::kCamera);
  EXPECT_EQ(c.cycle.overrun_alarm_cycles, 3U);
  EXPECT_TRUE(ha::layout_valid(c.can_layout));
  EXPECT_FALSE(c.has_odometry_section);
  EXPECT_FALSE(c.has_can_section);
}

TEST(Config, FullFileRoundTripsEveryValue) {
  ht::TempDir dir;
  const std::string path = dir.write("full.toml", R"(# a complete configuration
[cycle]
rate_hz = 25
budget_ms = 12.5
camera_timeout_ms = 300.0
encoder_timeout_ms = 400
pacing = "timer"
overrun_alarm_cycles = 5

[[board]]
name = "orange"
hue_deg = [10, 40.5]
saturation_min = 90
value_min = 40
value_max = 250

[[board]]
name = "violet"
hue_deg = [350.5, 20]
saturation_min = 0
value_min = 0
value_max = 255

[odometry]
wheel_radius_m = 0.0625
track_m = 0.42
ticks_per_rev = 16384
left_direction = -1
right_direction = 1

[can]
interface = "vcan0"
encoder_id = 0x201
length = 4
left_offset = 0
right_offset = 2
counter_bits = 16
byte_order = "big"

[filter]
particles = 512
seed = 42
alpha = [0.1, 0.2, 0.3, 0]
fix_sigma_m = 0.05
outlier_probability = 0.1
resample_threshold = 0.6
init_position_sigma_m = 0.2
vision_only_speed_mps = 0.5
map_margin_m = 2.5
nominal_spread_m = 0.2
nominal_resume_spread_m = 0.15
kld = true
kld_min_particles = 64
kld_epsilon = 0.1
kld_bin_m = 0.1
kld_bin_deg = 15
nearby_test = false
nearby_bound_nats = 35
nearby_frames = 90
nearby_radius_m = 0.3
nearby_levels = 2
nearby_hint_by_tables = false
seed_heading_from_boards = false
seed_from_search = false

[link]
system_id = 7
component_id = 100
baud = 57600
heartbeat_hz = 2
)");
  const hf::FirmwareConfig c = hf::load_config(path);
  EXPECT_EQ(c.source, path);
  EXPECT_DOUBLE_EQ(c.cycle.rate_hz, 25.0);
  EXPECT_DOUBLE_EQ(c.cycle.budget_ms, 12.5);
  EXPECT_DOUBLE_EQ(c.cycle.camera_timeout_ms, 300.0);
  EXPECT_DOUBLE_EQ(c.cycle.encoder_timeout_ms, 400.0);
  EXPECT_EQ(c.cycle.pacing, hf::Pacing::kTimer);
  EXPECT_EQ(c.cycle.overrun_alarm_cycles, 5U);

  ASSERT_EQ(c.thresholds.count, 2U);
  EXPECT_EQ(c.board_names.names[0], "orange");
  EXPECT_EQ(c.board_names.names[1], "violet");
  const ha::ColourThreshold& o = c.thresholds.boards[0];
  EXPECT_FLOAT_EQ(o.hue_min_deg, 10.0F);
  EXPECT_FLOAT_EQ(o.hue_max_deg, 40.5F);
  EXPECT_EQ(o.saturation_min, 90);
  EXPECT_EQ(o.value_min, 40);
  EXPECT_EQ(o.value_max, 250);
  EXPECT_FLOAT_EQ(c.thresholds.boards[1].hue_min_deg, 350.5F);
  EXPECT_FLOAT_EQ(c.thresholds.boards[1].hue_max_deg, 20.0F);
  EXPECT_EQ(c.thresholds.boards[1].saturation_min, 0);

  EXPECT_TRUE(c.has_odometry_section);
  EXPECT_DOUBLE_EQ(c.geometry.wheel_radius_m, 0.0625);
  EXPECT_DOUBLE_EQ(c.geometry.track_m, 0.42);
  EXPECT_DOUBLE_EQ(c.geometry.ticks_per_rev, 16384.0);
  EXPECT_EQ(c.geometry.left_direction, -1);
  EXPECT_EQ(c.geometry.right_direction, 1);

  EXPECT_TRUE(c.has_can_section);
  EXPECT_EQ(c.can_interface, "vcan0");
  EXPECT_EQ(c.can_layout.id, 0x201U);
  EXPECT_EQ(c.can_layout.length, 4);
  EXPECT_EQ(c.can_layout.left_offset, 0);
  EXPECT_EQ(c.can_layout.right_offset, 2);
  EXPECT_EQ(c.can_layout.counter_bits, 16);
  EXPECT_EQ(c.can_layout.byte_order, ha::ByteOrder::kBigEndian);

  EXPECT_EQ(c.filter.particles, 512U);
  EXPECT_EQ(c.filter.seed, 42U);
  EXPECT_DOUBLE_EQ(c.filter.noise.alpha1, 0.1);
  EXPECT_DOUBLE_EQ(c.filter.noise.alpha2, 0.2);
  EXPECT_DOUBLE_EQ(c.filter.noise.alpha3, 0.3);
  EXPECT_DOUBLE_EQ(c.filter.noise.alpha4, 0.0);
  EXPECT_DOUBLE_EQ(c.filter.fix_sigma_m, 0.05);
  EXPECT_DOUBLE_EQ(c.filter.outlier_probability, 0.1);
  EXPECT_DOUBLE_EQ(c.filter.resample_threshold, 0.6);
  EXPECT_DOUBLE_EQ(c.filter.init_position_sigma_m, 0.2);
  EXPECT_DOUBLE_EQ(c.filter.vision_only_speed_mps, 0.5);
  EXPECT_DOUBLE_EQ(c.filter.map_margin_m, 2.5);
  EXPECT_DOUBLE_EQ(c.filter.nominal_spread_m, 0.2);
  EXPECT_DOUBLE_EQ(c.filter.nominal_resume_spread_m, 0.15);
  EXPECT_EQ(c.filter.kld_mode, hf::KldMode::kOn);
  EXPECT_EQ(c.filter.kld.min_particles, 64U);
  EXPECT_DOUBLE_EQ(c.filter.kld.epsilon, 0.1);
  EXPECT_DOUBLE_EQ(c.filter.kld.bin_xy_m, 0.1);
  EXPECT_NEAR(c.filter.kld.bin_yaw_rad, 15.0 * 3.14159265358979323846 / 180.0, 1e-12);
  EXPECT_FALSE(c.filter.nearby_test);
  EXPECT_DOUBLE_EQ(c.filter.nearby.bound_nats, 35.0);
  EXPECT_EQ(c.filter.nearby.max_frames, 90U);
  EXPECT_DOUBLE_EQ(c.filter.nearby.search_radius_m, 0.3);
  EXPECT_EQ(c.filter.nearby.search_levels, 2);
  EXPECT_FALSE(c.filter.nearby.hint_by_tables);
  EXPECT_FALSE(c.filter.seed_heading_from_boards);
  EXPECT_FALSE(c.filter.seed_from_search);

  EXPECT_EQ(c.link.system_id, 7);
  EXPECT_EQ(c.link.component_id, 100);
  EXPECT_EQ(c.link.baud, 57600U);
  EXPECT_DOUBLE_EQ(c.link.heartbeat_hz, 2.0);
}

TEST(Config, EmptyFileGivesDefaultsAndPartialSectionsKeepTheRest) {
  ht::TempDir dir;
  const hf::FirmwareConfig d = hf::default_config();
  hf::FirmwareConfig c = hf::load_config(dir.write("empty.toml", ""));
  EXPECT_TRUE(c.thresholds == d.thresholds);
  EXPECT_EQ(c.filter.particles, d.filter.particles);
  EXPECT_FALSE(c.has_odometry_section);
  c = hf::load_config(
      dir.write("partial.toml", "[filter]\nparticles = 256\n[odometry]\ntrack_m = 0.5\n"));
  EXPECT_EQ(c.filter.particles, 256U);
  EXPECT_DOUBLE_EQ(c.filter.fix_sigma_m, d.filter.fix_sigma_m);
  EXPECT_TRUE(c.has_odometry_section);
  EXPECT_DOUBLE_EQ(c.geometry.track_m, 0.5);
  EXPECT_DOUBLE_EQ(c.geometry.wheel_radius_m, d.geometry.wheel_radius_m);
  EXPECT_TRUE(c.thresholds == d.thresholds);  // no [[board]]: the defaults stay
}

TEST(Config, UnknownKey) {
  ht::TempDir dir;
  expect_one_line_error(dir, "[cycle]\nrate_hz = 30\nbudget = 12\n", "unknown key 'cycle.budget'",
                        3);
  expect_one_line_error(dir, "[[board]]\nname = \"x\"\nhue_deg = [1, 2]\nsat_min = 3\n",
                        "board[0].sat_min", 4);
}

TEST(Config, TypoInSectionName) {
  ht::TempDir dir;
  expect_one_line_error(dir, "\n[filtr]\nparticles = 100\n", "unknown key 'filtr'", 2);
  expect_one_line_error(dir, "verbose = true\n", "unknown key 'verbose'", 1);
}

TEST(Config, WrongType) {
  ht::TempDir dir;
  expect_one_line_error(dir, "[cycle]\nrate_hz = \"fast\"\n", "cycle.rate_hz must be a number", 2);
  expect_one_line_error(dir, "[filter]\nparticles = 512.0\n",
                        "filter.particles must be a whole number", 2);
  expect_one_line_error(dir, "[can]\ninterface = 0\n", "can.interface must be a string", 2);
  expect_one_line_error(dir, "cycle = 5\n", "[cycle] must be a table", 1);
  expect_one_line_error(dir, "[board]\nname = \"x\"\n", "[[board]]");
}

TEST(Config, OutOfRange) {
  ht::TempDir dir;
  expect_one_line_error(dir, "[filter]\nparticles = 10\n",
                        "filter.particles = 10 is outside 16..4096", 2);
  expect_one_line_error(dir, "[filter]\nparticles = 5000\n", "outside", 2);
  expect_one_line_error(dir, "[cycle]\n\nrate_hz = 0.5\n", "cycle.rate_hz", 3);
  expect_one_line_error(dir, "[link]\nbaud = 1200\n", "link.baud", 2);
  expect_one_line_error(dir, "[link]\nsystem_id = 0\n", "link.system_id", 2);
  expect_one_line_error(dir, "[filter]\noutlier_probability = 1.0\n", "filter.outlier_probability",
                        2);
  expect_one_line_error(dir, "[cycle]\nrate_hz = nan\n", "cycle.rate_hz", 2);
  expect_one_line_error(dir, "[odometry]\nleft_direction = 0\n", "direction");
  expect_one_line_error(dir, "[can]\nbyte_order = \"middle\"\n", "byte_order", 2);
  expect_one_line_error(dir, "[cycle]\nrate_hz = 30\npacing = \"frame\"\n",
                        "cycle.pacing must be \"camera\" or \"timer\"", 3);
  expect_one_line_error(dir, "[cycle]\npacing = 1\n", "cycle.pacing must be a string", 2);
  expect_one_line_error(dir, "[cycle]\novverrun_alarm_cycles = 0\n", "unknown key", 2);
  expect_one_line_error(dir, "[cycle]\noverrun_alarm_cycles = 0\n",
                        "cycle.overrun_alarm_cycles = 0 is outside 1..1000", 2);
  std::string boards;
  for (int i = 0; i < 9; ++i) boards += "[[board]]\nhue_deg = [1, 2]\n";
  expect_one_line_error(dir, boards, "1 to 8");
}

TEST(Config, HueOutsideCircle) {
  ht::TempDir dir;
  expect_one_line_error(dir, "[[board]]\nname = \"x\"\nhue_deg = [10, 400]\n", "0..360", 3);
  expect_one_line_error(dir, "[[board]]\nname = \"x\"\nhue_deg = [-1, 40]\n", "0..360", 3);
  expect_one_line_error(dir, "[[board]]\nname = \"x\"\nhue_deg = [10]\n",
                        "hue_deg must be [min, max]", 3);
  expect_one_line_error(dir, "[[board]]\nname = \"x\"\n", "hue_deg must be [min, max]");
  expect_one_line_error(dir, "[[board]]\nname = \"x\"\nhue_deg = [\"a\", 3]\n",
                        "hue_deg values must be numbers", 3);
}

TEST(Config, ValueMinAboveValueMax) {
  ht::TempDir dir;
  expect_one_line_error(
      dir, "[[board]]\nname = \"x\"\nhue_deg = [10, 40]\nvalue_min = 200\nvalue_max = 100\n",
      "value_min is above value_max");
}

// The health's spread bounds: without its own value the resume bound keeps the defaults' ratio
// (0.07 to 0.10); one beyond the spread bound would never let the health resume.
TEST(Config, TheSpreadResumeBoundFollowsTheSpreadBound) {
  ht::TempDir dir;
  const hf::FirmwareConfig c =
      hf::load_config(dir.write("spread.toml", "[filter]\nnominal_spread_m = 0.2\n"));
  EXPECT_DOUBLE_EQ(c.filter.nominal_resume_spread_m, 0.7 * 0.2);
  expect_one_line_error(dir, "[filter]\nnominal_spread_m = 0.05\nnominal_resume_spread_m = 0.06\n",
                        "filter.nominal_resume_spread_m must not exceed filter.nominal_spread_m",
                        3);
}

TEST(Config, CanLayoutThatDoesNotFit) {
  ht::TempDir dir;
  expect_one_line_error(dir, "[can]\nlength = 4\n", "fit");       // two 32-bit counters in 4 bytes
  expect_one_line_error(dir, "[can]\nleft_offset = 2\n", "fit");  // overlaps the right counter at 4
  expect_one_line_error(dir, "[can]\ncounter_bits = 16\nlength = 4\nright_offset = 1\n", "fit");
}

TEST(Config, AlphaOfWrongLength) {
  ht::TempDir dir;
  expect_one_line_error(dir, "[filter]\nalpha = [0.1, 0.2]\n",
                        "filter.alpha must be [alpha1, alpha2, alpha3, alpha4]", 2);
  expect_one_line_error(dir, "[filter]\nalpha = [0.1, 0.2, 0.3, 0.4, 0.5]\n", "filter.alpha", 2);
  expect_one_line_error(dir, "[filter]\nalpha = 0.1\n", "filter.alpha", 2);
  expect_one_line_error(dir, "[filter]\nalpha = [0.1, 0.2, -0.3, 0.4]\n", "filter.alpha values", 2);
  expect_one_line_error(dir, "[filter]\nalpha = [0.1, 0.2, \"x\", 0.4]\n", "filter.alpha values",
                        2);
}

TEST(Config, MissingFile) {
  ht::TempDir dir;
  const std::string path = dir.path("does-not-exist.toml");
  const std::string msg = ht::error_of([&] { hf::load_config(path); });
  ASSERT_NE(msg, ht::kNoException);
  ht::expect_one_line(msg, path + ": ");
  // There is no line in a file that is not there.
  EXPECT_EQ(msg.find("line 0"), std::string::npos) << msg;
}

// Anything that cannot be read and parsed as a config stops start-up: before, a directory or
// /dev/zero as --config ran on the built-in defaults (no signing key: unsigned commands obeyed).
TEST(Config, WhatIsNotARegularFileIsRefused) {
  ht::TempDir dir;
  const std::string fifo = dir.path("harmoloc.fifo");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  for (const std::string& path :
       {dir.dir(), std::string("/dev/zero"), std::string("/dev/null"), fifo}) {
    const std::string msg = ht::error_of([&] { hf::load_config(path); });
    ASSERT_NE(msg, ht::kNoException) << path << " was read as a config";
    ht::expect_one_line(msg, path + ": ", "not a regular file");
  }
}

// A config of 50,000 dotted-key parts (100 KB) overflowed toml++'s stack (SIGSEGV); its nesting
// is now checked before parsing. And a file far beyond any config's size is refused unread.
TEST(Config, DeepOrHugeTomlIsRefusedBeforeParsing) {
  ht::TempDir dir;
  std::string deep;
  for (int i = 0; i < 50000; ++i) deep += "a.";
  expect_one_line_error(dir, deep + "a = 1\n", "nested 50001 deep", 1);
  std::string tables;
  for (int i = 0; i < 20000; ++i) tables += "[";
  expect_one_line_error(dir, "x = " + tables + "\n", "nested", 1);
  std::string inline_tables = "x = ";
  for (int i = 0; i < 20000; ++i) inline_tables += "{a=";
  expect_one_line_error(dir, inline_tables + "\n", "nested", 1);
  // Within the bound, a dotted key works as before.
  const std::string ok = dir.write("ok.toml", "cycle.rate_hz = 25\n");
  EXPECT_EQ(hf::load_config(ok).cycle.rate_hz, 25.0);
  expect_one_line_error(dir, "# " + std::string(300 * 1024, 'x') + "\n", "more than the 262144");
}

TEST(Config, UnparsableToml) {
  ht::TempDir dir;
  expect_one_line_error(dir, "[cycle]\nrate_hz = = 3\n", "", 2);
  expect_one_line_error(dir, "[cycle\nrate_hz = 3\n", "", 1);
  expect_one_line_error(dir, "[cycle]\nrate_hz = 30\nrate_hz = 31\n", "", 3);  // duplicate key
  expect_one_line_error(dir, "# ok\n\n[link]\nbaud = 115200\nname = \"unterminated\n", "", 5);
}

TEST(Config, ObservationAndKidnapSections) {
  ht::TempDir dir;
  const std::string path = dir.write("filter.toml", R"([observation]
model = "fix"
robust = false
fix_board_check = false
sigma_scale = 2.5
tempering = 12
outlier_floor = 0.001
dcs_phi = 2
consensus_chi2 = 16
consensus_fraction = 0.6
motion_index_rate = 0.1
motion_index_rise_rate = 0.02
motion_index_min = 0.05
motion_index_max = 0.9
route_free_m = 0.05
route_sigma_m = 0
route_terms = "off"
implausible_ratio = 3.5
cut_board_width = 0

[kidnap]
enabled = false
change_threshold = 0.7
confirm = false
window_frames = 10
evidence_frames = 4
fix_distance_m = 0.5
divergence_frames = 60
divergence_gap_frames = 0
lost_frames = 120
reseed = "uniform"
position_sigma_m = 0.1
yaw_sigma_deg = 30
floor_search = false
)");
  const hf::FirmwareConfig c = hf::load_config(path);
  EXPECT_EQ(c.observation.model, hf::ObservationModel::kFix);
  EXPECT_FALSE(c.observation.fix_board_check);
  const auto& b = c.observation.boards;
  EXPECT_FALSE(b.robust);
  EXPECT_DOUBLE_EQ(b.sigma_scale, 2.5);
  EXPECT_DOUBLE_EQ(b.tempering, 12.0);
  EXPECT_DOUBLE_EQ(b.outlier_floor, 0.001);
  EXPECT_DOUBLE_EQ(b.dcs_phi, 2.0);
  EXPECT_DOUBLE_EQ(b.consensus_chi2, 16.0);
  EXPECT_DOUBLE_EQ(b.consensus_fraction, 0.6);
  EXPECT_DOUBLE_EQ(b.motion_index_rate, 0.1);
  EXPECT_DOUBLE_EQ(b.motion_index_rise_rate, 0.02);
  EXPECT_DOUBLE_EQ(b.motion_index_min, 0.05);
  EXPECT_DOUBLE_EQ(b.motion_index_max, 0.9);
  EXPECT_DOUBLE_EQ(b.route_free_m, 0.05);
  EXPECT_DOUBLE_EQ(b.route_sigma_m, 0.0);
  EXPECT_EQ(c.observation.route_terms, hf::RouteTerms::kOff);
  EXPECT_DOUBLE_EQ(b.implausible_ratio, 3.5);
  EXPECT_DOUBLE_EQ(b.cut_board_width, 0.0);
  const auto& k = c.kidnap;
  EXPECT_FALSE(k.enabled);
  EXPECT_DOUBLE_EQ(k.detector.change_threshold, 0.7);
  EXPECT_FALSE(k.detector.confirm);
  EXPECT_EQ(k.detector.window_frames, 10);
  EXPECT_EQ(k.detector.evidence_frames, 4);
  EXPECT_DOUBLE_EQ(k.detector.fix_distance_m, 0.5);
  EXPECT_EQ(k.detector.divergence_frames, 60);
  EXPECT_EQ(k.detector.divergence_gap_frames, 0);
  EXPECT_EQ(k.detector.lost_frames, 120);
  EXPECT_EQ(k.reseed, hf::ReseedStrategy::kUniform);
  EXPECT_DOUBLE_EQ(k.position_sigma_m, 0.1);
  EXPECT_DOUBLE_EQ(k.yaw_sigma_deg, 30.0);
  EXPECT_FALSE(k.floor_search);

  // Defaults: the robust per-board model, kidnap test on, re-seed around the fix.
  const hf::FirmwareConfig d = hf::default_config();
  EXPECT_EQ(d.observation.model, hf::ObservationModel::kBoards);
  EXPECT_EQ(d.observation.route_terms, hf::RouteTerms::kAuto);
  EXPECT_TRUE(d.kidnap.floor_search);
  EXPECT_EQ(hf::load_config(dir.write("on.toml", "[observation]\nroute_terms = \"on\"\n"))
                .observation.route_terms,
            hf::RouteTerms::kOn);
  EXPECT_TRUE(d.observation.boards.robust);
  EXPECT_TRUE(d.observation.fix_board_check);
  EXPECT_TRUE(d.kidnap.enabled);
  EXPECT_TRUE(d.kidnap.detector.confirm);
  EXPECT_EQ(d.kidnap.reseed, hf::ReseedStrategy::kAroundFix);
}

TEST(Config, ObservationAndKidnapValuesAreChecked) {
  ht::TempDir dir;
  const std::pair<const char*, const char*> bad[] = {
      {"[observation]\nmodel = \"magic\"\n", "observation.model"},
      {"[observation]\nroute_terms = \"floor\"\n", "observation.route_terms must be"},
      {"[observation]\nroute_terms = true\n", "observation.route_terms"},
      {"[observation]\ntempering = 0.5\n", "observation.tempering"},
      {"[observation]\nrobust = 1\n", "observation.robust must be true or false"},
      {"[observation]\nimplausible_ratio = 0.5\n", "observation.implausible_ratio"},
      {"[observation]\ncut_board_width = -1\n", "observation.cut_board_width"},
      {"[observation]\nimplausible_ratio = -1\n", "observation.implausible_ratio"},
      {"[observation]\nmotion_index_min = 0.9\nmotion_index_max = 0.5\n", "motion_index_min"},
      {"[observation]\nmotion_index_rise_rate = 1.5\n", "observation.motion_index_rise_rate"},
      {"[observation]\nsigma = 3\n", "unknown key 'observation.sigma'"},
      {"[kidnap]\nreseed = \"random\"\n", "kidnap.reseed"},
      {"[kidnap]\nwindow_frames = 2\nevidence_frames = 3\n", "evidence_frames"},
      {"[kidnap]\nchange_threshold = 1.5\n", "kidnap.change_threshold"},
      {"[kidnap]\nlost_frames = 0\n", "kidnap.lost_frames"},
      {"[kidnap]\ndivergence_gap_frames = -1\n", "kidnap.divergence_gap_frames"},
      {"[kidnap]\nfloor_search = \"on\"\n", "kidnap.floor_search must be true or false"},
      {"[filter]\nkld = \"yes\"\n", "filter.kld must be true, false or \"auto\""},
      {"[filter]\nkld = 1\n", "filter.kld must be true, false or \"auto\""},
      {"[filter]\nkld_min_particles = 8\n", "filter.kld_min_particles"},
      {"[filter]\nkld_epsilon = 0\n", "filter.kld_epsilon"},
      {"[filter]\nkld_bin_m = 2\n", "filter.kld_bin_m"},
      {"[filter]\nkld_bin_deg = 0.5\n", "filter.kld_bin_deg"},
      {"[filter]\nnearby_test = 1\n", "filter.nearby_test must be true or false"},
      {"[filter]\nnearby_bound_nats = 0.5\n", "filter.nearby_bound_nats"},
      {"[filter]\nnearby_frames = 0\n", "filter.nearby_frames"},
      {"[filter]\nnearby_radius_m = 0.01\n", "filter.nearby_radius_m"},
      {"[filter]\nnearby_levels = 5\n", "filter.nearby_levels"},
      {"[filter]\nnearby_hint_by_tables = 1\n",
       "filter.nearby_hint_by_tables must be true or false"},
      {"[observation]\nfix_term = \"yes\"\n",
       "observation.fix_term must be true, false or \"auto\""},
      {"[observation]\nfix_term = 1\n", "observation.fix_term must be true, false or \"auto\""},
      {"[filter]\nseed_heading_from_boards = \"yes\"\n",
       "filter.seed_heading_from_boards must be true or false"},
  };
  for (const auto& [text, want] : bad) {
    const std::string path = dir.write("bad.toml", text);
    const std::string why = ht::error_of([&] { hf::load_config(path); });
    ht::expect_one_line(why, path + ": ", want);
  }
}

// kidnap.fix_distance_m = "auto": six times the fix's RMS error the trainer measured, at most
// 1 m and at least 25 cm (a lighting drift biases the fix beyond what cross-validation sees);
// 25 cm for maps without a calibration. A number in the config is taken as it is.
TEST(Config, AutoKidnapDistanceFollowsTheMapCalibrationWithin25cmAnd1m) {
  const harmoloc::algorithms::KidnapParams automatic = hf::default_config().kidnap.detector;
  ASSERT_LT(automatic.fix_distance_m, 0.0) << "the default is auto";
  harmoloc::algorithms::MapCalibration c;
  c.present = true;
  const auto distance = [&](float rmse_x_m, float rmse_y_m) {
    c.fix_rmse_x_m = rmse_x_m;
    c.fix_rmse_y_m = rmse_y_m;
    return hf::derived_kidnap_params(automatic, c).fix_distance_m;
  };
  EXPECT_DOUBLE_EQ(distance(0.01F, 0.0F), 0.25);    // 6 cm: the floor
  EXPECT_NEAR(distance(0.03F, 0.04F), 0.30, 1e-6);  // 6 x 5 cm
  EXPECT_DOUBLE_EQ(distance(0.3F, 0.0F), 1.0);      // the ceiling
  EXPECT_DOUBLE_EQ(
      hf::derived_kidnap_params(automatic, harmoloc::algorithms::MapCalibration{}).fix_distance_m,
      0.25);
  harmoloc::algorithms::KidnapParams fixed = automatic;
  fixed.fix_distance_m = 0.12;
  EXPECT_DOUBLE_EQ(hf::derived_kidnap_params(fixed, c).fix_distance_m, 0.12);
}

// With the floor search as the kidnap test's evidence, "auto" ignores the harmonic fix's error:
// the search's pose is good to centimetres, so 25 cm far and 15 cm consistent, as without a
// calibration; numbers in the config are still taken as they are.
TEST(Config, AutoKidnapDistancesForTheFloorSearchIgnoreTheFixCalibration) {
  const harmoloc::algorithms::KidnapParams automatic = hf::default_config().kidnap.detector;
  harmoloc::algorithms::MapCalibration c;
  c.present = true;
  c.fix_rmse_x_m = 0.12F;
  c.fix_rmse_y_m = 0.09F;
  const auto fix = hf::derived_kidnap_params(automatic, c, hf::KidnapEvidence::kHarmonicFix);
  EXPECT_NEAR(fix.fix_distance_m, 0.9, 1e-6);  // 6 x 15 cm
  EXPECT_NEAR(fix.consistency_m, 0.5, 1e-6);   // 4 x 15 cm + 3 cm, at most 50 cm
  const auto search = hf::derived_kidnap_params(automatic, c, hf::KidnapEvidence::kFloorSearch);
  EXPECT_DOUBLE_EQ(search.fix_distance_m, 0.25);
  EXPECT_DOUBLE_EQ(search.consistency_m, 0.15);
  harmoloc::algorithms::KidnapParams fixed = automatic;
  fixed.fix_distance_m = 0.4;
  fixed.consistency_m = 0.2;
  const auto kept = hf::derived_kidnap_params(fixed, c, hf::KidnapEvidence::kFloorSearch);
  EXPECT_DOUBLE_EQ(kept.fix_distance_m, 0.4);
  EXPECT_DOUBLE_EQ(kept.consistency_m, 0.2);
}

// The map's odometry calibration scales the configured wheels and track, unless the config
// turns it off; a map without one leaves the configured geometry as it is.
TEST(Config, OdometryRunsOnTheMapsCalibrationUnlessTurnedOff) {
  ht::TempDir dir;
  hf::FirmwareConfig c = hf::load_config(dir.write(
      "odometry.toml", "[odometry]\nwheel_radius_m = 0.05\ntrack_m = 0.3\nticks_per_rev = 1000\n"));
  EXPECT_TRUE(c.use_map_odometry_calibration) << "on by default";
  harmoloc::algorithms::MapCalibration cal;
  EXPECT_EQ(hf::effective_geometry(c, cal).track_m, 0.3);
  EXPECT_EQ(hf::odometry_summary(c, cal), "");
  cal.odometry_present = true;
  cal.left_wheel_scale = 0.99F;
  cal.right_wheel_scale = 1.01F;
  cal.track_scale = 1.1F;
  const harmoloc::algorithms::DiffDriveGeometry g = hf::effective_geometry(c, cal);
  EXPECT_NEAR(g.track_m, 0.33, 1e-6);
  const harmoloc::algorithms::OdometryDelta d =
      harmoloc::algorithms::odometry_from_ticks(g, 1000, 1000);
  EXPECT_NEAR(d.distance_m, 2.0 * 3.14159265358979 * 0.05, 1e-6);
  EXPECT_NEAR(d.yaw_rad, 0.02 * 2.0 * 3.14159265358979 * 0.05 / 0.33, 1e-6);
  EXPECT_NE(hf::odometry_summary(c, cal).find("with the map's calibration"), std::string::npos);
  c = hf::load_config(dir.write("off.toml", "[odometry]\nmap_calibration = false\n"));
  EXPECT_FALSE(c.use_map_odometry_calibration);
  EXPECT_EQ(hf::effective_geometry(c, cal).track_m, c.geometry.track_m);
  EXPECT_EQ(hf::effective_geometry(c, cal).left_scale, 1.0);
  EXPECT_NE(hf::odometry_summary(c, cal).find("map_calibration = false"), std::string::npos);
}

// The route terms: on for a route map (its passes run one way), off for a floor map (its passes
// 10 degrees or more apart in heading) unless the config says otherwise; a line says so.
TEST(Config, FloorMapsDropTheRouteTermsUnlessConfiguredOtherwise) {
  ht::TempDir dir;
  hf::FirmwareConfig c = hf::default_config();
  harmoloc::algorithms::MapCalibration cal;
  EXPECT_TRUE(hf::route_terms_on(c, cal)) << "a map without the measure is a route map";
  EXPECT_EQ(hf::route_terms_summary(c, cal), "");
  const double deg = 3.14159265358979 / 180.0;
  cal.pass_heading_spread_rad = static_cast<float>(3.0 * deg);  // a route's passes
  EXPECT_TRUE(hf::route_terms_on(c, cal));
  cal.pass_heading_spread_rad = static_cast<float>(21.0 * deg);  // lanes at several headings
  EXPECT_FALSE(hf::route_terms_on(c, cal));
  EXPECT_NE(hf::route_terms_summary(c, cal).find("a floor map (its training passes 21 deg apart)"),
            std::string::npos)
      << hf::route_terms_summary(c, cal);
  c = hf::load_config(dir.write("on.toml", "[observation]\nroute_terms = \"on\"\n"));
  EXPECT_TRUE(hf::route_terms_on(c, cal));
  EXPECT_EQ(hf::route_terms_summary(c, cal), "");
  c = hf::load_config(dir.write("off.toml", "[observation]\nroute_terms = \"off\"\n"));
  cal.pass_heading_spread_rad = 0.0F;
  EXPECT_FALSE(hf::route_terms_on(c, cal));
  EXPECT_NE(hf::route_terms_summary(c, cal).find("route_terms = \"off\""), std::string::npos);
}

// The fix term: on for a route map, off for a floor map, unless the config says true or false.
TEST(Config, TheFixTermIsOffOnAFloorMapUnlessConfigured) {
  ht::TempDir dir;
  hf::FirmwareConfig c = hf::default_config();
  EXPECT_EQ(c.observation.fix_term, hf::FixTerm::kAuto);
  harmoloc::algorithms::MapFile map;
  EXPECT_TRUE(hf::fix_term_on(c, map)) << "a route map";
  const double deg = 3.14159265358979 / 180.0;
  map.calibration.pass_heading_spread_rad = static_cast<float>(21.0 * deg);
  EXPECT_FALSE(hf::fix_term_on(c, map));
  EXPECT_NE(hf::fix_term_summary(c, map).find("the harmonic fix does not weigh the particles"),
            std::string::npos);
  map.calibration.pass_heading_spread_rad = static_cast<float>(3.0 * deg);
  EXPECT_TRUE(hf::fix_term_on(c, map)) << "a route map";
  EXPECT_EQ(hf::fix_term_summary(c, map), "");
  map.calibration.pass_heading_spread_rad = static_cast<float>(21.0 * deg);
  c = hf::load_config(dir.write("on.toml", "[observation]\nfix_term = true\n"));
  EXPECT_TRUE(hf::fix_term_on(c, map));
  EXPECT_EQ(hf::fix_term_summary(c, map), "");
  c = hf::load_config(dir.write("off.toml", "[observation]\nfix_term = false\n"));
  map.calibration.pass_heading_spread_rad = 0.0F;
  EXPECT_FALSE(hf::fix_term_on(c, map));
  c = hf::load_config(dir.write("auto.toml", "[observation]\nfix_term = \"auto\"\n"));
  EXPECT_EQ(c.observation.fix_term, hf::FixTerm::kAuto);
}

// KLD-sampling: on for a floor map, off for a route map, unless the config says true or false.
TEST(Config, KldSamplingIsOnForAFloorMapUnlessConfigured) {
  ht::TempDir dir;
  hf::FirmwareConfig c = hf::default_config();
  EXPECT_EQ(c.filter.kld_mode, hf::KldMode::kAuto);
  harmoloc::algorithms::MapFile map;
  EXPECT_FALSE(hf::kld_on(c, map)) << "a route map";
  EXPECT_EQ(hf::kld_summary(c, map), "");
  const double deg = 3.14159265358979 / 180.0;
  map.calibration.pass_heading_spread_rad = static_cast<float>(21.0 * deg);
  EXPECT_TRUE(hf::kld_on(c, map));
  EXPECT_NE(hf::kld_summary(c, map).find("the particle count adapts between 256 and 1024"),
            std::string::npos)
      << hf::kld_summary(c, map);
  c = hf::load_config(dir.write("off.toml", "[filter]\nkld = false\n"));
  EXPECT_FALSE(hf::kld_on(c, map));
  EXPECT_EQ(hf::kld_summary(c, map), "");
  c = hf::load_config(dir.write("on.toml", "[filter]\nkld = true\n"));
  map.calibration.pass_heading_spread_rad = 0.0F;
  EXPECT_TRUE(hf::kld_on(c, map));
  EXPECT_EQ(hf::kld_summary(c, map), "") << "configured, not decided by the map";
  c = hf::load_config(dir.write("auto.toml", "[filter]\nkld = \"auto\"\n"));
  EXPECT_EQ(c.filter.kld_mode, hf::KldMode::kAuto);
}
