// The scenario simulator: scenarios and scenario files, the robot's motion along the route (closed
// laps, heading bound, wheel travel that integrates back to the pose), and the scene renderer.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "harmoloc/algorithms/geometry.hpp"
#include "harmoloc/algorithms/odometry.hpp"
#include "harmoloc/algorithms/random.hpp"
#include "harmoloc/algorithms/segmentation.hpp"
#include "harmoloc/sim_host/route.hpp"
#include "harmoloc/sim_host/scenario.hpp"
#include "harmoloc/sim_host/scene_renderer.hpp"
#include "test_support.hpp"

namespace hs = harmoloc::sim_host;
namespace ha = harmoloc::algorithms;
namespace ht = harmoloc::test;
using ha::kPi;

namespace {

std::string scenario_error(const std::string& name_or_file) {
  return ht::error_of([&] { hs::load_scenario(name_or_file); });
}

}  // namespace

// --- scenarios ---------------------------------------------------------------------------------

TEST(Scenario, BuiltInTiny) {
  const hs::Scenario s = hs::load_scenario("tiny");
  EXPECT_EQ(s.name, "tiny");
  EXPECT_EQ(s.camera.width_px, 160U);
  EXPECT_EQ(s.camera.height_px, 120U);
  EXPECT_EQ(s.boards.size(), 6U);
  EXPECT_EQ(s.route.waypoints_m.size(), 3U);
  EXPECT_TRUE(ha::layout_valid(s.can_layout));
  const hs::Scenario w = hs::load_scenario("tiny-wrap16");
  EXPECT_EQ(w.can_layout.counter_bits, 16);
  EXPECT_TRUE(ha::layout_valid(w.can_layout));
  EXPECT_GT(w.encoders.initial_left, 60000U);
  const auto list = hs::builtin_scenarios();
  ASSERT_EQ(list.size(), 6U);  // four desk routes, tiny, tiny-wrap16
  for (const auto& [name, text] : list) {
    EXPECT_FALSE(text.empty()) << name;
    EXPECT_EQ(hs::load_scenario(name).name, name);
  }
}

TEST(Scenario, UnknownNameListsTheBuiltIns) {
  const std::string msg = scenario_error("no-such-scenario");
  EXPECT_NE(msg.find("no-such-scenario"), std::string::npos) << msg;
  for (const char* name : {"desk-shuttle", "tiny", "tiny-wrap16"})
    EXPECT_NE(msg.find(name), std::string::npos) << msg;
  EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
}

TEST(Scenario, FileOverridesWhatItNames) {
  ht::TempDir dir;
  const std::string path = dir.write("mine.toml", R"(base = "tiny"
name = "mine"
labelled_frames = 10

[camera]
width_px = 96
height_px = 64
pixel_noise = 0

[route]
waypoints = [[1.0, 0.5], [1.5, 1.0]]
laps = 2

[encoders]
counter_bits = 16
initial_left = 65530

[[boards]]
name = "only"
colour = [10, 200, 30]
centre = [1.5, 2.5, 0.9]
size = [0.4, 0.3]
facing_deg = -90
)");
  const hs::Scenario s = hs::load_scenario(path);
  const hs::Scenario tiny = hs::load_scenario("tiny");
  EXPECT_EQ(s.name, "mine");
  EXPECT_EQ(s.labelled_frames, 10);
  EXPECT_EQ(s.camera.width_px, 96U);
  EXPECT_EQ(s.camera.height_px, 64U);
  EXPECT_EQ(s.camera.pixel_noise, 0.0);
  EXPECT_EQ(s.camera.horizontal_fov_deg,
            tiny.camera.horizontal_fov_deg);  // not named: from the base
  ASSERT_EQ(s.route.waypoints_m.size(), 2U);
  EXPECT_DOUBLE_EQ(s.route.waypoints_m[1][0], 1.5);
  EXPECT_DOUBLE_EQ(s.route.waypoints_m[1][1], 1.0);
  EXPECT_EQ(s.route.laps, 2);
  EXPECT_DOUBLE_EQ(s.route.pause_s, tiny.route.pause_s);
  EXPECT_EQ(s.can_layout.counter_bits, 16);
  EXPECT_EQ(s.encoders.initial_left, 65530U);
  EXPECT_TRUE(ha::layout_valid(s.can_layout));  // the frame shrinks to fit two 16-bit counters
  ASSERT_EQ(s.boards.size(), 1U);
  EXPECT_EQ(s.boards[0].name, "only");
  EXPECT_EQ(s.boards[0].colour.g, 200);
  EXPECT_DOUBLE_EQ(s.boards[0].width_m, 0.4);
  EXPECT_NEAR(s.boards[0].facing_yaw_rad, -kPi / 2.0, 1e-12);
}

TEST(Scenario, BadFilesGiveOneLine) {
  ht::TempDir dir;
  struct Case {
    const char* name;
    const char* text;
    const char* what;
  };
  const Case cases[] = {
      {"small", "[camera]\nwidth_px = 5\n", "camera.width_px"},
      {"odd", "[camera]\nwidth_px = 97\n", "even"},
      {"type", "[route]\nspeed_mps = \"fast\"\n", "route.speed_mps"},
      {"parse", "[camera]\nwidth_px = = 3\n", "line 2"},
      {"waypoint3", "[route]\nwaypoints = [[1, 2, 3], [2, 3]]\n", "waypoints"},
      {"waypoint1", "[route]\nwaypoints = [[1, 2]]\n", "at least 2"},
      {"colour", "[[boards]]\ncolour = [300, 0, 0]\ncentre = [1, 2, 1]\nsize = [0.1, 0.1]\n",
       "colour"},
      {"size", "[[boards]]\ncolour = [3, 0, 0]\ncentre = [1, 2, 1]\nsize = [0.1, -0.1]\n", "size"},
      {"centre", "[[boards]]\ncolour = [3, 0, 0]\nsize = [0.1, 0.1]\n", "centre"},
      {"laps", "[route]\nlaps = 0\n", "route.laps"},
      {"bits", "[encoders]\ncounter_bits = 40\n", "counter_bits"},
  };
  for (const Case& c : cases) {
    const std::string path = dir.write(std::string(c.name) + ".toml", c.text);
    SCOPED_TRACE(c.name);
    ht::expect_one_line(scenario_error(path), path + ": ", c.what);
  }
  const std::string path = dir.write("base.toml", "base = \"nope\"\n");
  const std::string msg = scenario_error(path);
  EXPECT_NE(msg.find("nope"), std::string::npos) << msg;
  EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
}

TEST(Scenario, WrittenScenarioIsAValidScenarioFileWithTheSameContents) {
  ht::TempDir dir;
  for (const char* name : {"tiny", "tiny-wrap16", "desk-shuttle"}) {
    const hs::Scenario a = hs::load_scenario(name);
    const hs::Scenario b =
        hs::load_scenario(dir.write(std::string(name) + ".toml", hs::scenario_to_toml(a)));
    SCOPED_TRACE(name);
    EXPECT_EQ(b.name, a.name);
    EXPECT_EQ(b.description, a.description);
    EXPECT_EQ(b.labelled_frames, a.labelled_frames);
    EXPECT_NEAR(b.start_time_s, a.start_time_s, 1e-3);
    EXPECT_EQ(b.camera.width_px, a.camera.width_px);
    EXPECT_EQ(b.camera.height_px, a.camera.height_px);
    EXPECT_NEAR(b.camera.radial_k, a.camera.radial_k, 1e-12);
    EXPECT_NEAR(b.camera.pitch_deg, a.camera.pitch_deg, 1e-12);
    EXPECT_NEAR(b.camera.horizontal_fov_deg, a.camera.horizontal_fov_deg, 1e-12);
    ASSERT_EQ(b.route.waypoints_m.size(), a.route.waypoints_m.size());
    for (std::size_t i = 0; i < a.route.waypoints_m.size(); ++i) {
      EXPECT_NEAR(b.route.waypoints_m[i][0], a.route.waypoints_m[i][0], 1e-12);
      EXPECT_NEAR(b.route.waypoints_m[i][1], a.route.waypoints_m[i][1], 1e-12);
    }
    EXPECT_DOUBLE_EQ(b.route.pause_s, a.route.pause_s);
    EXPECT_DOUBLE_EQ(b.route.wander_m, a.route.wander_m);
    EXPECT_EQ(b.encoders.initial_left, a.encoders.initial_left);
    EXPECT_EQ(b.encoders.initial_right, a.encoders.initial_right);
    EXPECT_NEAR(b.encoders.left_scale_error, a.encoders.left_scale_error, 1e-15);
    EXPECT_EQ(b.can_layout.counter_bits, a.can_layout.counter_bits);
    EXPECT_EQ(b.can_layout.length, a.can_layout.length);
    EXPECT_EQ(b.can_layout.left_offset, a.can_layout.left_offset);
    EXPECT_EQ(b.can_layout.right_offset, a.can_layout.right_offset);
    EXPECT_EQ(b.can_layout.id, a.can_layout.id);
    EXPECT_DOUBLE_EQ(b.robot.wheel_radius_m, a.robot.wheel_radius_m);
    EXPECT_DOUBLE_EQ(b.robot.ticks_per_rev, a.robot.ticks_per_rev);
    ASSERT_EQ(b.boards.size(), a.boards.size());
    for (std::size_t i = 0; i < a.boards.size(); ++i) {
      EXPECT_EQ(b.boards[i].name, a.boards[i].name);
      EXPECT_EQ(b.boards[i].colour.r, a.boards[i].colour.r);
      EXPECT_NEAR(b.boards[i].centre_y_m, a.boards[i].centre_y_m, 1e-12);
      EXPECT_NEAR(b.boards[i].height_m, a.boards[i].height_m, 1e-12);
      EXPECT_NEAR(b.boards[i].facing_yaw_rad, a.boards[i].facing_yaw_rad, 1e-9);
    }
  }
}

// --- motion ------------------------------------------------------------------------------------

namespace {

std::vector<hs::MotionSample> motion_of(const hs::Scenario& s, double step, std::uint64_t seed,
                                        hs::RouteStats* stats) {
  ha::Pcg32 rng(seed);
  return hs::simulate_motion(s, step, rng, stats);
}

}  // namespace

TEST(Motion, LapEndsWhereItStartedWithoutWander) {
  hs::Scenario s = hs::load_scenario("tiny");
  s.route.wander_m = 0.0;
  hs::RouteStats stats;
  const auto m = motion_of(s, 0.01, 1, &stats);
  ASSERT_GT(m.size(), 100U);
  const ha::Pose2& a = m.front().pose;
  const ha::Pose2& b = m.back().pose;
  EXPECT_NEAR(a.x_m, s.route.waypoints_m.front()[0], 1e-9);
  EXPECT_NEAR(a.y_m, s.route.waypoints_m.front()[1], 1e-9);
  EXPECT_NEAR(b.x_m, a.x_m, 1e-9);
  EXPECT_NEAR(b.y_m, a.y_m, 1e-9);
  EXPECT_LT(std::fabs(ha::wrap_angle_rad(b.yaw_rad - a.yaw_rad)), 1.0 * kPi / 180.0);
  // Halfway through the lap it stands at the last waypoint.
  const auto& mid = m[m.size() / 2].pose;
  EXPECT_NEAR(mid.x_m, s.route.waypoints_m.back()[0], 1e-6);
  EXPECT_NEAR(mid.y_m, s.route.waypoints_m.back()[1], 1e-6);
  // Duration: pause, leg, pause, leg back, final pause.
  EXPECT_NEAR(m.back().t_s, stats.duration_s, 0.011);
  // Total path: the route twice; never faster than the speed limit.
  double travelled = 0.0, fastest = 0.0;
  for (std::size_t i = 1; i < m.size(); ++i) {
    const double d =
        std::hypot(m[i].pose.x_m - m[i - 1].pose.x_m, m[i].pose.y_m - m[i - 1].pose.y_m);
    travelled += d;
    fastest = std::max(fastest, d / 0.01);
  }
  EXPECT_NEAR(travelled, 2.0 * stats.length_m, 0.01 * stats.length_m);
  EXPECT_LE(fastest, s.route.speed_mps * 1.01);
  const double chord = std::hypot(s.route.waypoints_m[2][0] - s.route.waypoints_m[0][0],
                                  s.route.waypoints_m[2][1] - s.route.waypoints_m[0][1]);
  EXPECT_GT(stats.length_m, chord);
  EXPECT_LT(stats.length_m, 1.2 * chord);
}

TEST(Motion, LapsAndWander) {
  hs::Scenario s = hs::load_scenario("tiny");
  s.route.laps = 2;
  hs::RouteStats one, two;
  hs::Scenario single = s;
  single.route.laps = 1;
  motion_of(single, 0.01, 3, &one);
  const auto m = motion_of(s, 0.01, 3, &two);
  EXPECT_NEAR(two.duration_s, 2.0 * one.duration_s - s.route.pause_s, 1e-9);
  // With wander the robot strays sideways but ends near its start (the offsets are smooth sines of
  // amplitude <= 0.6 wander each).
  EXPECT_LT(
      std::hypot(m.back().pose.x_m - m.front().pose.x_m, m.back().pose.y_m - m.front().pose.y_m),
      2.0 * 3.0 * 0.6 * s.route.wander_m + 1e-9);
  // Seeds change the wander, and only the wander.
  const auto again = motion_of(s, 0.01, 3, nullptr);
  const auto other = motion_of(s, 0.01, 4, nullptr);
  ASSERT_EQ(again.size(), m.size());
  ASSERT_EQ(other.size(), m.size());
  double max_same = 0.0, max_other = 0.0;
  for (std::size_t i = 0; i < m.size(); ++i) {
    max_same = std::max(max_same, std::fabs(again[i].pose.x_m - m[i].pose.x_m) +
                                      std::fabs(again[i].left_m - m[i].left_m));
    max_other = std::max(max_other, std::hypot(other[i].pose.x_m - m[i].pose.x_m,
                                               other[i].pose.y_m - m[i].pose.y_m));
  }
  EXPECT_EQ(max_same, 0.0);
  EXPECT_GT(max_other, 0.001);
  EXPECT_LT(max_other, 2.0 * 3.0 * 0.6 * s.route.wander_m + 1e-9);
}

TEST(Motion, HeadingStaysWithinTheStatedBound) {
  const hs::Scenario s = hs::load_scenario("tiny");
  hs::RouteStats stats;
  const auto m = motion_of(s, 0.01, 7, &stats);
  double ss = 0.0, sc = 0.0;
  for (const auto& x : m) {
    ss += std::sin(x.pose.yaw_rad);
    sc += std::cos(x.pose.yaw_rad);
  }
  const double mean = std::atan2(ss, sc);
  double worst = 0.0;
  for (const auto& x : m)
    worst = std::max(worst, std::fabs(ha::wrap_angle_rad(x.pose.yaw_rad - mean)));
  EXPECT_NEAR(stats.max_heading_offset_deg, worst * 180.0 / kPi, 1e-9);
  // The route runs towards the desk (+y) and back in reverse: the camera keeps facing the desk.
  EXPECT_NEAR(ha::wrap_angle_rad(mean - kPi / 2.0), 0.0, 0.2);
  EXPECT_LT(stats.max_heading_offset_deg, 35.0);
  EXPECT_GT(stats.max_heading_offset_deg, 1.0);  // an S-curve does turn
  // No jumps: consecutive headings differ by little.
  for (std::size_t i = 1; i < m.size(); ++i) {
    ASSERT_LT(std::fabs(ha::wrap_angle_rad(m[i].pose.yaw_rad - m[i - 1].pose.yaw_rad)), 0.05)
        << "t " << m[i].t_s;
  }
}

TEST(Motion, WheelTravelIntegratesBackToThePose) {
  for (const char* name : {"tiny", "desk-shuttle"}) {
    SCOPED_TRACE(name);
    const hs::Scenario s = hs::load_scenario(name);
    const auto m = motion_of(s, 0.001, 11, nullptr);
    ha::Pose2 dead = m.front().pose;
    double worst = 0.0, worst_yaw = 0.0;
    for (std::size_t i = 1; i < m.size(); ++i) {
      const double dl = m[i].left_m - m[i - 1].left_m, dr = m[i].right_m - m[i - 1].right_m;
      dead = ha::apply_arc(dead, ha::OdometryDelta{0.5 * (dl + dr), (dr - dl) / s.robot.track_m});
      worst = std::max(worst, std::hypot(dead.x_m - m[i].pose.x_m, dead.y_m - m[i].pose.y_m));
      worst_yaw =
          std::max(worst_yaw, std::fabs(ha::wrap_angle_rad(dead.yaw_rad - m[i].pose.yaw_rad)));
    }
    EXPECT_LT(worst, 0.003) << "dead reckoning from the true wheel travel drifts " << worst << " m";
    EXPECT_LT(worst_yaw, 0.2 * kPi / 180.0);
    // Driving back in reverse: the wheels' net travel over a lap is (nearly) zero.
    EXPECT_NEAR(m.back().left_m, 0.0, 0.01);
    EXPECT_NEAR(m.back().right_m, 0.0, 0.01);
  }
}

// --- renderer ----------------------------------------------------------------------------------

TEST(SceneRenderer, AllBoardsVisibleFromTheStartAndNoneFacingAway) {
  const hs::Scenario s = hs::load_scenario("tiny");
  const hs::SceneRenderer renderer(s);
  const ha::Pose2 start = motion_of(s, 0.01, 1, nullptr).front().pose;
  const std::vector<std::uint32_t> seen = renderer.visible_board_pixels(start);
  ASSERT_EQ(seen.size(), 6U);
  std::uint32_t total = 0;
  for (std::size_t b = 0; b < 6; ++b) {
    EXPECT_GT(seen[b], 0U) << s.boards[b].name;
    total += seen[b];
  }
  EXPECT_LT(total, s.camera.width_px * s.camera.height_px / 2U);
  ha::Pose2 away = start;
  away.yaw_rad = ha::wrap_angle_rad(start.yaw_rad + kPi);
  for (std::uint32_t v : renderer.visible_board_pixels(away)) EXPECT_EQ(v, 0U);
  // Closer to the desk, the boards look bigger.
  ha::Pose2 closer = start;
  closer.y_m += 0.5;
  const std::vector<std::uint32_t> near = renderer.visible_board_pixels(closer);
  std::uint32_t near_total = 0;
  for (std::uint32_t v : near) near_total += v;
  EXPECT_GT(near_total, total);
}

TEST(SceneRenderer, RenderIsDeterministicAndSegmentsToTheVisibleAreas) {
  hs::Scenario s = hs::load_scenario("tiny");
  const hs::SceneRenderer renderer(s);
  const ha::Pose2 pose = motion_of(s, 0.01, 1, nullptr)[300].pose;
  std::vector<std::uint8_t> a, b, c;
  ha::Pcg32 r1(5), r2(5), r3(6);
  renderer.render(pose, r1, a);
  renderer.render(pose, r2, b);
  renderer.render(pose, r3, c);
  ASSERT_EQ(a.size(), static_cast<std::size_t>(s.camera.width_px) * s.camera.height_px * 3U);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);  // pixel noise follows the seed

  // Without noise, threshold segmentation counts exactly the board pixels the renderer reports.
  s.camera.pixel_noise = 0.0;
  const hs::SceneRenderer clean(s);
  std::vector<std::uint8_t> rgb;
  ha::Pcg32 r4(1);
  clean.render(pose, r4, rgb);
  ha::AreaVector areas;
  ha::segment_rgb24(rgb.data(), s.camera.width_px, s.camera.height_px, s.camera.width_px * 3U,
                    ht::board_windows(), areas);
  const std::vector<std::uint32_t> truth = clean.visible_board_pixels(pose);
  for (std::size_t k = 0; k < 6; ++k) {
    EXPECT_EQ(areas.pixels[k], truth[k]) << s.boards[k].name;
    EXPECT_GT(truth[k], 0U) << s.boards[k].name;
  }
}
