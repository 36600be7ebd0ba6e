// The scenario simulator: scenarios and scenario files, the robot's motion along the route (closed
// laps, heading bound, wheel travel that integrates back to the pose), the scene renderer, scenario
// events (occluders, board moves, kidnaps), runs in memory (ScenarioRun, SimCamera) and the
// datasets simulate_dataset writes from them.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "harmoloc/algorithms/can_encoder_layout.hpp"
#include "harmoloc/algorithms/geometry.hpp"
#include "harmoloc/algorithms/odometry.hpp"
#include "harmoloc/algorithms/random.hpp"
#include "harmoloc/algorithms/segmentation.hpp"
#include "harmoloc/dataset/candump_log.hpp"
#include "harmoloc/dataset/metadata.hpp"
#include "harmoloc/dataset/tum.hpp"
#include "harmoloc/host/file_camera.hpp"
#include "harmoloc/host/log_encoders.hpp"
#include "harmoloc/sim_host/route.hpp"
#include "harmoloc/sim_host/scenario.hpp"
#include "harmoloc/sim_host/scenario_run.hpp"
#include "harmoloc/sim_host/scene_renderer.hpp"
#include "harmoloc/sim_host/sim_camera.hpp"
#include "harmoloc/sim_host/simulate.hpp"
#include "test_support.hpp"

namespace hs = harmoloc::sim_host;
namespace hd = harmoloc::dataset;
namespace hh = harmoloc::host;
namespace ha = harmoloc::algorithms;
namespace ht = harmoloc::test;
namespace hal = harmoloc::hal;
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
  // four desk routes, four with events on the desk-shuttle route, tiny, tiny-wrap16
  ASSERT_EQ(list.size(), 10U);
  for (const auto& [name, text] : list) {
    EXPECT_FALSE(text.empty()) << name;
    EXPECT_EQ(hs::load_scenario(name).name, name);
  }
  for (const char* name : {"desk-shuttle", "desk-left", "tiny", "tiny-wrap16", "desk-long"}) {
    const hs::Scenario e = hs::load_scenario(name);
    EXPECT_TRUE(e.occluders.empty() && e.board_moves.empty() && e.kidnaps.count == 0) << name;
    EXPECT_EQ(hs::describe_events(e), "no events");
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
    EXPECT_NEAR(b.camera.k1, a.camera.k1, 1e-12);
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

namespace {

// A tour in the tiny scenario's room: @p poses [x, y, heading_deg].
hs::Scenario tour_of(const std::vector<std::array<double, 3>>& poses) {
  hs::Scenario s = hs::load_scenario("tiny");
  s.route.shape = hs::RouteShape::kTour;
  s.route.waypoints_m.clear();
  s.route.heading_deg.clear();
  for (const auto& p : poses) {
    s.route.waypoints_m.push_back({p[0], p[1]});
    s.route.heading_deg.push_back(p[2]);
  }
  return s;
}

}  // namespace

TEST(Motion, TourTurnsOnTheSpotAndDrivesStraightLegs) {
  hs::Scenario s = tour_of({{1.0, 1.0, 0.0}, {2.0, 1.0, 0.0}, {2.0, 1.0, 90.0}, {2.0, 1.6, 150.0}});
  s.route.turn_rate_dps = 60.0;
  hs::RouteStats stats;
  const double step = 0.001;
  const auto m = motion_of(s, step, 1, &stats);
  ASSERT_GT(m.size(), 1000U);
  EXPECT_NEAR(stats.length_m, 1.6, 1e-9);
  EXPECT_NEAR(m.back().t_s, stats.duration_s, step);
  EXPECT_NEAR(hs::run_duration_s(s), stats.duration_s, 1e-9);
  EXPECT_NEAR(m.front().pose.x_m, 1.0, 1e-12);
  EXPECT_NEAR(m.back().pose.x_m, 2.0, 1e-9);
  EXPECT_NEAR(m.back().pose.y_m, 1.6, 1e-9);
  EXPECT_NEAR(m.back().pose.yaw_rad, 150.0 * kPi / 180.0, 1e-9);
  double fastest = 0.0, fastest_turn = 0.0;
  for (std::size_t i = 1; i < m.size(); ++i) {
    const ha::Pose2 &a = m[i - 1].pose, &b = m[i].pose;
    const double moved = std::hypot(b.x_m - a.x_m, b.y_m - a.y_m);
    const double turned = std::fabs(ha::wrap_angle_rad(b.yaw_rad - a.yaw_rad));
    fastest = std::max(fastest, moved / step);
    fastest_turn = std::max(fastest_turn, turned / step);
    // Either it turns on the spot or it drives straight, never both.
    ASSERT_FALSE(moved > 1e-12 && turned > 1e-12) << "t " << m[i].t_s;
    // On the legs: y = 1 from x 1 to 2, then x = 2 up to y 1.6.
    const bool first_leg =
        std::fabs(b.y_m - 1.0) < 1e-9 && b.x_m > 1.0 - 1e-9 && b.x_m < 2.0 + 1e-9;
    const bool second_leg =
        std::fabs(b.x_m - 2.0) < 1e-9 && b.y_m > 1.0 - 1e-9 && b.y_m < 1.6 + 1e-9;
    ASSERT_TRUE(first_leg || second_leg) << b.x_m << ", " << b.y_m;
    // Driving the second leg the camera faces +y: forward (90 degrees) needs no turn before it.
    if (second_leg && b.y_m > 1.0 + 1e-6 && b.y_m < 1.6 - 1e-6) {
      ASSERT_NEAR(b.yaw_rad, 0.5 * kPi, 1e-9);
    }
  }
  EXPECT_LE(fastest, s.route.speed_mps * 1.001);
  EXPECT_LE(fastest_turn, 60.0 * kPi / 180.0 * 1.001);
  EXPECT_GT(fastest_turn, 0.5 * 60.0 * kPi / 180.0);
  // The wheels' travel integrates back to the pose.
  ha::Pose2 dead = m.front().pose;
  double worst = 0.0;
  for (std::size_t i = 1; i < m.size(); ++i) {
    const double dl = m[i].left_m - m[i - 1].left_m, dr = m[i].right_m - m[i - 1].right_m;
    dead = ha::apply_arc(dead, ha::OdometryDelta{0.5 * (dl + dr), (dr - dl) / s.robot.track_m});
    worst = std::max(worst, std::hypot(dead.x_m - m[i].pose.x_m, dead.y_m - m[i].pose.y_m));
  }
  EXPECT_LT(worst, 0.002);
}

TEST(Motion, TourReversesWhereThatTurnsLess) {
  // Back along the camera's axis: reversing, no turn at all.
  const hs::Scenario back = tour_of({{2.0, 1.0, 0.0}, {1.0, 1.0, 0.0}});
  const auto m = motion_of(back, 0.01, 1, nullptr);
  double widest = 0.0;
  for (const auto& x : m) widest = std::max(widest, std::fabs(x.pose.yaw_rad));
  EXPECT_LT(widest, 1e-12);
  EXPECT_NEAR(m.back().pose.x_m, 1.0, 1e-9);
  EXPECT_LT(m.back().left_m, -0.99);  // the wheels turned backwards
  // The tour's places: both ends and the legs between, every 10 cm.
  const auto places = hs::tour_places(back.route, 0.1, 10.0);
  ASSERT_EQ(places.size(), 11U);
  EXPECT_NEAR(places.back().x_m, 1.0, 1e-12);
}

TEST(Motion, ToursRefuseWhatTheyCannotDrive) {
  hs::Scenario s = tour_of({{1.0, 1.0, 0.0}, {2.0, 1.0, 0.0}});
  s.route.heading_deg.pop_back();
  EXPECT_NE(ht::error_of([&] { motion_of(s, 0.01, 1, nullptr); }).find("heading"),
            std::string::npos);
  hs::Scenario k = tour_of({{1.0, 1.0, 0.0}, {2.0, 1.0, 0.0}});
  k.kidnaps.count = 1;
  ha::Pcg32 rng(1), kidnap_rng(2);
  EXPECT_NE(ht::error_of([&] {
              hs::simulate_motion(k, 0.01, rng, nullptr, &kidnap_rng);
            }).find("kidnaps.poses"),
            std::string::npos);
  k.kidnaps.poses = {{1.5, 1.5, 0.0}};
  k.kidnaps.first_s = 1000.0;
  EXPECT_NE(ht::error_of([&] {
              hs::simulate_motion(k, 0.01, rng, nullptr, &kidnap_rng);
            }).find("after the end of the tour"),
            std::string::npos);
}

TEST(Motion, TourKidnapPutsTheRobotDownAndDrivesOnToItsNextWaypoint) {
  hs::Scenario s = tour_of({{1.0, 1.0, 0.0}, {2.0, 1.0, 0.0}, {2.0, 1.8, 90.0}});
  s.kidnaps.count = 1;
  s.kidnaps.first_s = 3.0;
  s.kidnaps.poses = {{1.2, 1.9, -90.0}};
  ha::Pcg32 rng(1);
  std::vector<hs::KidnapEvent> events;
  hs::RouteStats stats;
  const auto m = hs::simulate_motion(s, 0.01, rng, &stats, nullptr, &events);
  ASSERT_EQ(events.size(), 1U);
  EXPECT_NEAR(events[0].t_s, 3.0, 0.011);
  EXPECT_NEAR(events[0].from.y_m, 1.0, 1e-9);  // on the first leg
  EXPECT_NEAR(events[0].to.x_m, 1.2, 1e-9);
  EXPECT_NEAR(events[0].to.y_m, 1.9, 1e-9);
  EXPECT_NEAR(events[0].to.yaw_rad, -0.5 * kPi, 1e-9);
  // From there to the waypoint it was heading for (2, 1), then on to the last one.
  EXPECT_NEAR(m.back().pose.x_m, 2.0, 1e-9);
  EXPECT_NEAR(m.back().pose.y_m, 1.8, 1e-9);
  bool passed_second = false;
  std::size_t jump = 0;
  for (std::size_t i = 0; i < m.size(); ++i) {
    if (m[i].t_s > 3.0 && std::hypot(m[i].pose.x_m - 2.0, m[i].pose.y_m - 1.0) < 1e-6)
      passed_second = true;
    if (jump == 0 && i > 0 &&
        std::hypot(m[i].pose.x_m - m[i - 1].pose.x_m, m[i].pose.y_m - m[i - 1].pose.y_m) > 0.5)
      jump = i;
  }
  EXPECT_TRUE(passed_second);
  ASSERT_GT(jump, 0U);
  // The wheels do not turn across the jump.
  EXPECT_EQ(m[jump].left_m, m[jump - 1].left_m);
  EXPECT_EQ(m[jump].right_m, m[jump - 1].right_m);
  EXPECT_NEAR(stats.duration_s, m.back().t_s, 0.01);
  EXPECT_LE(stats.duration_s, m.back().t_s + 1e-9);
}

TEST(Scenario, TourFilesReadAndWriteThePoses) {
  ht::TempDir dir;
  const std::string path =
      dir.write("tour.toml",
                "base = \"tiny\"\n[route]\nshape = \"tour\"\nturn_rate_dps = 30\n"
                "waypoints = [[1.0, 1.0, 90], [1.5, 1.2, 45.5]]\n");
  const hs::Scenario s = hs::load_scenario(path);
  ASSERT_EQ(s.route.shape, hs::RouteShape::kTour);
  ASSERT_EQ(s.route.heading_deg.size(), 2U);
  EXPECT_EQ(s.route.heading_deg[1], 45.5);
  EXPECT_EQ(s.route.turn_rate_dps, 30.0);
  const std::string again = dir.write("again.toml", hs::scenario_to_toml(s));
  EXPECT_EQ(hs::scenario_to_toml(hs::load_scenario(again)), hs::scenario_to_toml(s));
  const std::string kidnapped = dir.write(
      "kidnapped.toml", hs::scenario_to_toml(s) +
                            "\n[kidnaps]\nfirst_s = 2\nposes = [[1.2, 1.3, 10], [1.1, 1.0, 0]]\n");
  const hs::Scenario k = hs::load_scenario(kidnapped);
  EXPECT_EQ(k.kidnaps.count, 2);
  ASSERT_EQ(k.kidnaps.poses.size(), 2U);
  EXPECT_EQ(k.kidnaps.poses[0][2], 10.0);
  const std::string k_again = dir.write("k_again.toml", hs::scenario_to_toml(k));
  EXPECT_EQ(hs::scenario_to_toml(hs::load_scenario(k_again)), hs::scenario_to_toml(k));
  const std::string bad =
      dir.write("bad.toml", "[route]\nshape = \"tour\"\nwaypoints = [[1.0, 1.0], [1.5, 1.2]]\n");
  ht::expect_one_line(scenario_error(bad), bad + ": ", "heading_deg");
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

// --- scenario events: occluders, board moves, kidnaps --------------------------------------------

namespace {

// A person standing at (x, y) from t = 1 s to t = 2 s.
hs::OccluderSpec standing_person(double x, double y) {
  hs::OccluderSpec o;
  o.path = {{1.0, x, y}, {2.0, x, y}};
  return o;
}

std::size_t board_index(const hs::Scenario& s, const std::string& name) {
  for (std::size_t i = 0; i < s.boards.size(); ++i) {
    if (s.boards[i].name == name) return i;
  }
  ADD_FAILURE() << "no board " << name;
  return 0;
}

// On the line from the camera to the board's centre, @p fraction of the way, on the floor plan.
void on_line_of_sight(const hs::Scenario& s, const ha::Pose2& robot, const hs::BoardSpec& b,
                      double fraction, double& x, double& y) {
  const double cx = robot.x_m + s.camera.forward_offset_m * std::cos(robot.yaw_rad);
  const double cy = robot.y_m + s.camera.forward_offset_m * std::sin(robot.yaw_rad);
  x = cx + fraction * (b.centre_x_m - cx);
  y = cy + fraction * (b.centre_y_m - cy);
}

}  // namespace

TEST(SceneEvents, OccluderHidesABoardWhileItStandsThere) {
  hs::Scenario s = hs::load_scenario("tiny");
  const ha::Pose2 pose = motion_of(s, 0.01, 1, nullptr).front().pose;
  const std::size_t yellow = board_index(s, "yellow");
  const std::vector<std::uint32_t> before = hs::SceneRenderer(s).visible_board_pixels(pose);
  ASSERT_GT(before[yellow], 300U);
  double x = 0.0, y = 0.0;
  on_line_of_sight(s, pose, s.boards[yellow], 0.6, x, y);
  s.occluders.push_back(standing_person(x, y));
  hs::SceneRenderer renderer(s);
  EXPECT_EQ(renderer.visible_board_pixels(pose), before);  // time 0: nobody there yet
  renderer.set_time(0.99);
  EXPECT_EQ(renderer.occluders_present(), 0U);
  EXPECT_EQ(renderer.visible_board_pixels(pose), before);
  renderer.set_time(1.5);
  EXPECT_EQ(renderer.occluders_present(), 1U);
  const std::vector<std::uint32_t> during = renderer.visible_board_pixels(pose);
  EXPECT_EQ(during[yellow], 0U);
  for (std::size_t b = 0; b < before.size(); ++b) EXPECT_LE(during[b], before[b]);
  renderer.set_time(2.01);
  EXPECT_EQ(renderer.visible_board_pixels(pose), before);

  // Rendered, the occluder's dark colour is no board's: segmentation counts what is visible.
  s.camera.pixel_noise = 0.0;
  hs::SceneRenderer clean(s);
  clean.set_time(1.5);
  std::vector<std::uint8_t> rgb;
  ha::Pcg32 rng(1);
  clean.render(pose, rng, rgb);
  ha::AreaVector areas;
  ha::segment_rgb24(rgb.data(), s.camera.width_px, s.camera.height_px, s.camera.width_px * 3U,
                    ht::board_windows(), areas);
  for (std::size_t b = 0; b < before.size(); ++b)
    EXPECT_EQ(areas.pixels[b], during[b]) << s.boards[b].name;
  // Its pixels are there: the frame differs from the one without the person.
  clean.set_time(0.5);
  std::vector<std::uint8_t> empty_room;
  clean.render(pose, rng, empty_room);
  std::size_t changed = 0;
  for (std::size_t i = 0; i < rgb.size(); i += 3) changed += rgb[i] != empty_room[i] ? 1U : 0U;
  EXPECT_GT(changed, static_cast<std::size_t>(s.camera.width_px) * s.camera.height_px / 20U);
}

TEST(SceneEvents, WalkingOccluderFollowsItsKeyframes) {
  hs::Scenario s = hs::load_scenario("tiny");
  const ha::Pose2 pose = motion_of(s, 0.01, 1, nullptr).front().pose;
  const std::size_t yellow = board_index(s, "yellow");
  const std::uint32_t full = hs::SceneRenderer(s).visible_board_pixels(pose)[yellow];
  double x = 0.0, y = 0.0;
  on_line_of_sight(s, pose, s.boards[yellow], 0.6, x, y);
  hs::OccluderSpec walker;  // 1 m/s along the desk, from x = 0.5 at t = 10 s to 4.0 at 13.5 s
  walker.path = {{10.0, 0.5, y}, {11.0, 1.5, y}, {13.5, 4.0, y}};
  s.occluders.push_back(walker);
  hs::SceneRenderer renderer(s);
  const double t_crossing = 10.0 + (x - 0.5);
  renderer.set_time(t_crossing);
  EXPECT_EQ(renderer.visible_board_pixels(pose)[yellow], 0U) << "at " << t_crossing << " s";
  for (const double dt : {-1.0, 1.0}) {
    renderer.set_time(t_crossing + dt);
    EXPECT_EQ(renderer.visible_board_pixels(pose)[yellow], full) << dt;
  }
  renderer.set_time(9.9);  // not yet in the room
  EXPECT_EQ(renderer.occluders_present(), 0U);
  renderer.set_time(13.6);  // gone
  EXPECT_EQ(renderer.occluders_present(), 0U);
  // Standing on the camera: the far side of the cylinder hides every board.
  hs::Scenario on_robot = hs::load_scenario("tiny");
  on_robot.occluders.push_back(standing_person(pose.x_m, pose.y_m));
  hs::SceneRenderer blind(on_robot);
  blind.set_time(1.5);
  for (std::uint32_t v : blind.visible_board_pixels(pose)) EXPECT_EQ(v, 0U);
}

TEST(SceneEvents, BoardMoveChangesThatBoardOnlyFromItsTime) {
  hs::Scenario s = hs::load_scenario("tiny");
  const ha::Pose2 pose = motion_of(s, 0.01, 1, nullptr)[300].pose;
  const std::vector<std::uint32_t> base = hs::SceneRenderer(s).visible_board_pixels(pose);
  const std::size_t yellow = board_index(s, "yellow"), cyan = board_index(s, "cyan");
  hs::BoardMoveSpec up;  // yellow is lifted 10 cm at 1 s...
  up.board = "yellow";
  up.at_s = 1.0;
  up.offset_m = {0.0, 0.0, 0.10};
  hs::BoardMoveSpec turn;  // ...cyan turned 40 degrees at 2 s...
  turn.board = "cyan";
  turn.at_s = 2.0;
  turn.turn_deg = 40.0;
  hs::BoardMoveSpec again = up;  // ...and yellow lifted 10 cm more at 3 s: moves add up
  again.at_s = 3.0;
  s.board_moves = {up, turn, again};
  hs::SceneRenderer renderer(s);
  renderer.set_time(0.9);
  EXPECT_EQ(renderer.visible_board_pixels(pose), base);
  renderer.set_time(1.0);
  EXPECT_NEAR(renderer.boards()[yellow].centre_z_m, s.boards[yellow].centre_z_m + 0.10, 1e-12);
  const std::vector<std::uint32_t> lifted = renderer.visible_board_pixels(pose);
  EXPECT_NE(lifted[yellow], base[yellow]);
  for (std::size_t b = 0; b < base.size(); ++b) {
    if (b != yellow) {
      EXPECT_EQ(lifted[b], base[b]) << s.boards[b].name;
    }
  }
  renderer.set_time(2.5);
  const std::vector<std::uint32_t> turned = renderer.visible_board_pixels(pose);
  EXPECT_EQ(turned[yellow], lifted[yellow]);
  EXPECT_LT(turned[cyan], base[cyan] * 0.9);  // seen more from the side
  for (std::size_t b = 0; b < base.size(); ++b) {
    if (b != yellow && b != cyan) {
      EXPECT_EQ(turned[b], base[b]) << s.boards[b].name;
    }
  }
  EXPECT_NEAR(renderer.boards()[cyan].facing_yaw_rad,
              s.boards[cyan].facing_yaw_rad + 40.0 * kPi / 180, 1e-12);
  renderer.set_time(3.0);
  EXPECT_NEAR(renderer.boards()[yellow].centre_z_m, s.boards[yellow].centre_z_m + 0.20, 1e-12);
  EXPECT_NE(renderer.visible_board_pixels(pose)[yellow], lifted[yellow]);
  renderer.set_time(0.0);  // and back: set_time is not a one-way street
  EXPECT_EQ(renderer.visible_board_pixels(pose), base);
}

namespace {

hs::Scenario tiny_with_kidnaps() {
  hs::Scenario s = hs::load_scenario("tiny");
  s.route.laps = 3;
  s.kidnaps.count = 4;
  s.kidnaps.first_s = 1.0;
  s.kidnaps.interval_s = 3.0;
  s.kidnaps.min_distance_m = 0.4;
  return s;
}

}  // namespace

TEST(Kidnaps, JumpFarWithoutWheelTravelAndWithTheRoutesHeading) {
  const hs::Scenario s = tiny_with_kidnaps();
  const double step = 0.001;
  for (const std::uint64_t seed : {1U, 2U, 3U}) {
    SCOPED_TRACE(seed);
    ha::Pcg32 rng(seed, 1), kidnap_rng(seed, 5);
    std::vector<hs::KidnapEvent> kidnaps;
    const auto m = hs::simulate_motion(s, step, rng, nullptr, &kidnap_rng, &kidnaps);
    ASSERT_EQ(kidnaps.size(), 4U);
    double max_jump_elsewhere = 0.0;
    std::size_t next = 0;
    for (std::size_t i = 1; i < m.size(); ++i) {
      const double moved =
          std::hypot(m[i].pose.x_m - m[i - 1].pose.x_m, m[i].pose.y_m - m[i - 1].pose.y_m);
      if (next < kidnaps.size() && m[i].t_s == kidnaps[next].t_s) {
        const hs::KidnapEvent& k = kidnaps[next];
        EXPECT_NEAR(k.t_s, s.kidnaps.first_s + static_cast<double>(next) * s.kidnaps.interval_s,
                    step);
        EXPECT_EQ(k.timestamp_ns, hs::dataset_time_ns(s.start_time_s, k.t_s));
        EXPECT_EQ(k.from.x_m, m[i - 1].pose.x_m);
        EXPECT_EQ(k.to.x_m, m[i].pose.x_m);
        EXPECT_EQ(k.to.yaw_rad, m[i].pose.yaw_rad);
        EXPECT_GE(moved, s.kidnaps.min_distance_m);
        // The wheels do not turn while the robot is carried.
        EXPECT_EQ(m[i].left_m, m[i - 1].left_m);
        EXPECT_EQ(m[i].right_m, m[i - 1].right_m);
        // Put down driving along the route: the heading carries on smoothly from there, and the
        // robot moves along it (forward or backing up).
        EXPECT_LT(std::fabs(ha::wrap_angle_rad(m[i + 1].pose.yaw_rad - k.to.yaw_rad)), 0.01);
        const ha::Pose2& later = m[i + 200].pose;
        const double along = (later.x_m - k.to.x_m) * std::cos(k.to.yaw_rad) +
                             (later.y_m - k.to.y_m) * std::sin(k.to.yaw_rad);
        const double across = -(later.x_m - k.to.x_m) * std::sin(k.to.yaw_rad) +
                              (later.y_m - k.to.y_m) * std::cos(k.to.yaw_rad);
        EXPECT_GT(std::fabs(along), 0.005);
        EXPECT_LT(std::fabs(across), 0.2 * std::fabs(along));
        EXPECT_NE(m[i].route_t_s, m[i].t_s);
        ++next;
      } else {
        max_jump_elsewhere = std::max(max_jump_elsewhere, moved);
      }
    }
    EXPECT_EQ(next, kidnaps.size());
    EXPECT_LT(max_jump_elsewhere, 2.0 * s.route.speed_mps * step);
  }
}

TEST(Kidnaps, EncodersCountOnlyTheDrivingAcrossAJump) {
  const hs::Scenario s = tiny_with_kidnaps();
  hs::ScenarioRun run(s, 4);
  ASSERT_EQ(run.kidnaps().size(), 4U);
  std::vector<std::uint64_t> stamps;
  std::vector<std::int64_t> left_delta, right_delta;
  std::uint32_t last_left = 0, last_right = 0;
  for (const ha::CanFrame& f : run.encoder_frames()) {
    if (f.id != s.can_layout.id) continue;
    std::uint32_t left = 0, right = 0;
    ASSERT_EQ(ha::decode_encoder_frame(s.can_layout, f, left, right), ha::CanDecode::kOk);
    if (!stamps.empty()) {
      left_delta.push_back(static_cast<std::int32_t>(left - last_left));
      right_delta.push_back(static_cast<std::int32_t>(right - last_right));
    }
    stamps.push_back(f.timestamp_ns);
    last_left = left;
    last_right = right;
  }
  // A jump of 0.4 m or more would be 5000 ticks or more. Elsewhere the robot drives 1 mm in 10 ms
  // (13 ticks) and turns a few degrees on the spot where it reverses (up to ~300 ticks).
  for (std::size_t j = 0; j < left_delta.size(); ++j) {
    EXPECT_LT(std::abs(left_delta[j]), 500) << stamps[j + 1];
    EXPECT_LT(std::abs(right_delta[j]), 500) << stamps[j + 1];
  }
  // The 10 ms that hold a jump count the driving before and after it, not the jump.
  for (const hs::KidnapEvent& k : run.kidnaps()) {
    const auto j = static_cast<std::size_t>(
        std::lower_bound(stamps.begin(), stamps.end(), k.timestamp_ns) - stamps.begin());
    ASSERT_GT(j, 0U);
    ASSERT_LT(j, stamps.size());
    EXPECT_LT(std::abs(left_delta[j - 1]), 30) << k.t_s;
    EXPECT_LT(std::abs(right_delta[j - 1]), 30) << k.t_s;
  }
  // Dead reckoning from the true wheel travel carries on across the jump from the new place.
  const auto& m = run.motion();
  const hs::KidnapEvent& k = run.kidnaps()[1];
  const auto i = static_cast<std::size_t>(std::llround(k.t_s / hs::ScenarioRun::kMotionStep_s));
  ASSERT_EQ(m[i].t_s, k.t_s);
  ha::Pose2 dead = m[i].pose;
  for (std::size_t j = i + 1; j < i + 2000; ++j) {
    const double dl = m[j].left_m - m[j - 1].left_m, dr = m[j].right_m - m[j - 1].right_m;
    dead = ha::apply_arc(dead, ha::OdometryDelta{0.5 * (dl + dr), (dr - dl) / s.robot.track_m});
  }
  EXPECT_LT(std::hypot(dead.x_m - m[i + 1999].pose.x_m, dead.y_m - m[i + 1999].pose.y_m), 0.003);
}

TEST(Kidnaps, ImpossibleKidnapsAreOneLineErrors) {
  hs::Scenario far = tiny_with_kidnaps();
  far.kidnaps.min_distance_m = 2.0;  // the tiny route is 0.62 m long
  std::string msg = ht::error_of([&] { hs::ScenarioRun run(far, 1); });
  ht::expect_one_line(msg, "kidnap 1 at 1 s", "min_distance_m");
  hs::Scenario late = tiny_with_kidnaps();
  late.kidnaps.count = 40;
  msg = ht::error_of([&] { hs::ScenarioRun run(late, 1); });
  ht::expect_one_line(msg, "kidnap 16 of 40", "route.laps");
  ha::Pcg32 rng(1);
  EXPECT_THROW(hs::simulate_motion(tiny_with_kidnaps(), 0.01, rng, nullptr), std::invalid_argument);
}

TEST(Kidnaps, BuiltInDeskKidnapKeepsAMetreEveryTime) {
  const hs::Scenario s = hs::load_scenario("desk-kidnap");
  EXPECT_EQ(s.kidnaps.count, 10);
  EXPECT_EQ(hs::describe_events(s), "10 kidnaps");
  for (const std::uint64_t seed : {1U, 2U, 3U}) {
    hs::ScenarioRun run(s, seed);
    ASSERT_EQ(run.kidnaps().size(), 10U) << seed;
    for (const hs::KidnapEvent& k : run.kidnaps()) {
      EXPECT_GE(std::hypot(k.to.x_m - k.from.x_m, k.to.y_m - k.from.y_m), 1.0)
          << "seed " << seed << " at " << k.t_s;
    }
    // The last kidnap leaves at least 20 s to relocalize.
    EXPECT_GT(run.route().duration_s - run.kidnaps().back().t_s, 20.0);
  }
}

// --- events in scenario files -------------------------------------------------------------------

namespace {

const char* const kEventsToml = R"(base = "tiny"
name = "events"

[[occluders]]
name = "walker"
colour = [40, 40, 40]
radius_m = 0.2
height_m = 1.6
path = [[1.0, 0.5, 2.0], [3.5, 3.0, 2.0]]

[[occluders]]
path = [[0.5, 2.2, 2.1]]

[[board_moves]]
board = "red"
at_s = 2.0
offset_m = [-0.3, 0.05, 0.0]
turn_deg = 12.5

[kidnaps]
count = 2
first_s = 1.5
interval_s = 4.0
min_distance_m = 0.35
)";

}  // namespace

TEST(Scenario, EventsFromAFile) {
  ht::TempDir dir;
  const hs::Scenario s = hs::load_scenario(dir.write("events.toml", kEventsToml));
  ASSERT_EQ(s.occluders.size(), 2U);
  EXPECT_EQ(s.occluders[0].name, "walker");
  EXPECT_EQ(s.occluders[0].colour.r, 40);
  EXPECT_DOUBLE_EQ(s.occluders[0].radius_m, 0.2);
  EXPECT_DOUBLE_EQ(s.occluders[0].height_m, 1.6);
  ASSERT_EQ(s.occluders[0].path.size(), 2U);
  EXPECT_DOUBLE_EQ(s.occluders[0].path[1][1], 3.0);
  const hs::OccluderSpec defaults;
  EXPECT_EQ(s.occluders[1].name, defaults.name);
  EXPECT_EQ(s.occluders[1].colour.b, defaults.colour.b);
  EXPECT_DOUBLE_EQ(s.occluders[1].radius_m, defaults.radius_m);
  ASSERT_EQ(s.board_moves.size(), 1U);
  EXPECT_EQ(s.board_moves[0].board, "red");
  EXPECT_DOUBLE_EQ(s.board_moves[0].offset_m[1], 0.05);
  EXPECT_DOUBLE_EQ(s.board_moves[0].turn_deg, 12.5);
  EXPECT_EQ(s.kidnaps.count, 2);
  EXPECT_DOUBLE_EQ(s.kidnaps.first_s, 1.5);
  EXPECT_DOUBLE_EQ(s.kidnaps.interval_s, 4.0);
  EXPECT_DOUBLE_EQ(s.kidnaps.min_distance_m, 0.35);
  EXPECT_EQ(hs::describe_events(s), "2 kidnaps, 1 board move, 2 occluders");
  // A file based on a scenario with events keeps them unless it names them; an empty array
  // removes them.
  const hs::Scenario kept =
      hs::load_scenario(dir.write("kept.toml", "base = \"desk-occlusion\"\n"));
  EXPECT_EQ(kept.occluders.size(), 1U);
  const hs::Scenario cleared =
      hs::load_scenario(dir.write("cleared.toml", "base = \"desk-occlusion\"\noccluders = []\n"));
  EXPECT_TRUE(cleared.occluders.empty());
}

TEST(Scenario, BadEventsGiveOneLine) {
  ht::TempDir dir;
  struct Case {
    const char* name;
    const char* text;
    const char* what;
  };
  const Case cases[] = {
      {"occ-key", "[[occluders]]\npath = [[1, 2, 2]]\nradius = 0.2\n",
       "unknown key 'occluders.radius'"},
      {"occ-table", "occluders = 3\n", "occluders must be an array"},
      {"occ-nopath", "[[occluders]]\nname = \"x\"\n", "occluders.path"},
      {"occ-path3", "[[occluders]]\npath = [[1, 2]]\n", "occluders.path[]"},
      {"occ-order", "[[occluders]]\npath = [[2, 1, 1], [1, 2, 2]]\n", "increase"},
      {"occ-same", "[[occluders]]\npath = [[2, 1, 1], [2, 2, 2]]\n", "increase"},
      {"occ-time", "[[occluders]]\npath = [[-1, 1, 1]]\n", "times"},
      {"occ-radius", "[[occluders]]\npath = [[1, 1, 1]]\nradius_m = 0\n", "occluders.radius_m"},
      {"occ-height", "[[occluders]]\npath = [[1, 1, 1]]\nheight_m = -2\n", "occluders.height_m"},
      {"occ-name", "[[occluders]]\npath = [[1, 1, 1]]\nname = 3\n", "occluders.name"},
      {"occ-colour", "[[occluders]]\npath = [[1, 1, 1]]\ncolour = [1, 2]\n", "occluders.colour"},
      {"occ-red",
       "[[occluders]]\nname = \"red shirt\"\npath = [[1, 1, 1]]\ncolour = [200, 40, 50]\n",
       "too close to board 'red'"},
      {"occ-far", "[[occluders]]\npath = [[1, 1, 1e9]]\n", "positions"},
      {"move-board", "[[board_moves]]\nboard = \"purple\"\nat_s = 1\n", "'purple' is not a board"},
      {"move-noboard", "[[board_moves]]\nat_s = 1\n", "board_moves.board"},
      {"move-noat", "[[board_moves]]\nboard = \"red\"\n", "board_moves.at_s is required"},
      {"move-key", "[[board_moves]]\nboard = \"red\"\nat_s = 1\noffset = [1, 0, 0]\n",
       "unknown key 'board_moves.offset'"},
      {"move-offset", "[[board_moves]]\nboard = \"red\"\nat_s = 1\noffset_m = [1, 0]\n",
       "board_moves.offset_m"},
      {"move-turn", "[[board_moves]]\nboard = \"red\"\nat_s = 1\nturn_deg = 400\n",
       "board_moves.turn_deg"},
      {"move-time", "[[board_moves]]\nboard = \"red\"\nat_s = -1\n", "board_moves.at_s"},
      {"kid-key", "[kidnaps]\ncount = 1\nevery_s = 3\n", "unknown key 'kidnaps.every_s'"},
      {"kid-table", "[[kidnaps]]\ncount = 1\n", "kidnaps must be a table"},
      {"kid-count", "[kidnaps]\ncount = -1\n", "kidnaps.count"},
      {"kid-interval", "[kidnaps]\ncount = 2\ninterval_s = 0\n", "kidnaps.interval_s"},
      {"kid-distance", "[kidnaps]\nmin_distance_m = -1\n", "kidnaps.min_distance_m"},
      {"kid-type", "[kidnaps]\nfirst_s = \"soon\"\n", "kidnaps.first_s"},
  };
  for (const Case& c : cases) {
    const std::string path = dir.write(std::string(c.name) + ".toml", c.text);
    SCOPED_TRACE(c.name);
    ht::expect_one_line(scenario_error(path), path + ": ", c.what);
  }
  // A board move must name a board of the final scenario, also when the file replaces the boards.
  const std::string path = dir.write("replaced.toml", R"(base = "desk-moved-board"
[[boards]]
name = "only"
colour = [10, 200, 30]
centre = [1.5, 2.5, 0.9]
size = [0.4, 0.3]
)");
  ht::expect_one_line(scenario_error(path), path + ": ", "'yellow' is not a board");
}

TEST(Scenario, EventsSurviveTheWrittenScenarioFile) {
  ht::TempDir dir;
  std::vector<hs::Scenario> scenarios = {hs::load_scenario(dir.write("e.toml", kEventsToml))};
  for (const char* name : {"desk-occlusion", "desk-moved-board", "desk-kidnap"})
    scenarios.push_back(hs::load_scenario(name));
  for (const hs::Scenario& a : scenarios) {
    SCOPED_TRACE(a.name);
    const hs::Scenario b =
        hs::load_scenario(dir.write(a.name + ".out.toml", hs::scenario_to_toml(a)));
    ASSERT_EQ(b.occluders.size(), a.occluders.size());
    for (std::size_t i = 0; i < a.occluders.size(); ++i) {
      EXPECT_EQ(b.occluders[i].name, a.occluders[i].name);
      EXPECT_EQ(b.occluders[i].colour.g, a.occluders[i].colour.g);
      EXPECT_DOUBLE_EQ(b.occluders[i].radius_m, a.occluders[i].radius_m);
      EXPECT_DOUBLE_EQ(b.occluders[i].height_m, a.occluders[i].height_m);
      ASSERT_EQ(b.occluders[i].path.size(), a.occluders[i].path.size());
      for (std::size_t k = 0; k < a.occluders[i].path.size(); ++k) {
        for (std::size_t d = 0; d < 3; ++d)
          EXPECT_NEAR(b.occluders[i].path[k][d], a.occluders[i].path[k][d], 1e-9);
      }
    }
    ASSERT_EQ(b.board_moves.size(), a.board_moves.size());
    for (std::size_t i = 0; i < a.board_moves.size(); ++i) {
      EXPECT_EQ(b.board_moves[i].board, a.board_moves[i].board);
      EXPECT_NEAR(b.board_moves[i].at_s, a.board_moves[i].at_s, 1e-9);
      for (std::size_t d = 0; d < 3; ++d)
        EXPECT_NEAR(b.board_moves[i].offset_m[d], a.board_moves[i].offset_m[d], 1e-12);
      EXPECT_NEAR(b.board_moves[i].turn_deg, a.board_moves[i].turn_deg, 1e-9);
    }
    EXPECT_EQ(b.kidnaps.count, a.kidnaps.count);
    if (a.kidnaps.count > 0) {
      EXPECT_NEAR(b.kidnaps.first_s, a.kidnaps.first_s, 1e-9);
      EXPECT_NEAR(b.kidnaps.interval_s, a.kidnaps.interval_s, 1e-9);
      EXPECT_NEAR(b.kidnaps.min_distance_m, a.kidnaps.min_distance_m, 1e-12);
    }
    EXPECT_EQ(b.route.laps, a.route.laps);
    EXPECT_EQ(hs::describe_events(b), hs::describe_events(a));
  }
  // Without events, nothing about them is written (scenario.toml stays what it was).
  const std::string plain = hs::scenario_to_toml(hs::load_scenario("tiny"));
  for (const char* word : {"occluders", "board_moves", "kidnaps"})
    EXPECT_EQ(plain.find(word), std::string::npos) << word;
}

// --- runs in memory and datasets -----------------------------------------------------------------

namespace {

// FNV-1a 64 over every file of a folder, in the order of their relative paths: path, a 0 byte,
// contents.
std::uint64_t folder_hash(const std::string& dir, std::size_t* files = nullptr) {
  namespace fs = std::filesystem;
  std::vector<std::string> names;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (e.is_regular_file()) names.push_back(fs::relative(e.path(), dir).generic_string());
  }
  std::sort(names.begin(), names.end());
  std::uint64_t h = 0xcbf29ce484222325ULL;
  const auto add = [&h](std::uint8_t byte) {
    h ^= byte;
    h *= 0x100000001b3ULL;
  };
  for (const std::string& n : names) {
    for (const char c : n) add(static_cast<std::uint8_t>(c));
    add(0);
    for (const std::uint8_t b : ht::read_bytes((fs::path(dir) / n).string())) add(b);
  }
  if (files != nullptr) *files = names.size();
  return h;
}

// tiny with every kind of event, at 10 frames a second (a quick run: 154 frames).
hs::Scenario tiny_with_events() {
  hs::Scenario s = hs::load_scenario("tiny");
  s.name = "tiny-events";
  s.camera.rate_hz = 10.0;
  s.kidnaps.count = 1;
  s.kidnaps.first_s = 1.0;
  s.kidnaps.min_distance_m = 0.4;
  hs::OccluderSpec walker;
  walker.path = {{3.0, 0.6, 1.9}, {6.5, 3.8, 1.9}};
  s.occluders.push_back(walker);
  hs::BoardMoveSpec move;
  move.board = "green";
  move.at_s = 8.0;
  move.offset_m = {0.0, 0.0, 0.15};
  s.board_moves.push_back(move);
  return s;
}

}  // namespace

TEST(Dataset, WithoutNoiseTheFramesAreThoseOfTheRendererBeforeTheFastRenderer) {
  // Noise-free frames and true areas of tiny and desk-occlusion (with its person) at 20 poses, as
  // the renderer drew them before it was made fast (tiled culling, the box exit in one step,
  // the polynomial lens model): the FNV-1a hash printed by that renderer. Geometry (rays, lens,
  // room, desk, boards, occluders, motion) must not change; only the noise source did.
  std::uint64_t h = 0xcbf29ce484222325ULL;
  const auto add = [&h](std::uint8_t b) {
    h ^= b;
    h *= 0x100000001b3ULL;
  };
  for (const char* name : {"tiny", "desk-occlusion"}) {
    hs::Scenario s = hs::load_scenario(name);
    s.camera.pixel_noise = 0.0;
    const auto motion = motion_of(s, 0.01, 1, nullptr);
    hs::SceneRenderer r(s);
    for (std::size_t k = 0; k < 20; ++k) {
      const hs::MotionSample& m = motion[k * (motion.size() - 1) / 19];
      r.set_time(m.t_s);
      ha::Pcg32 n(1);
      std::vector<std::uint8_t> rgb;
      r.render(m.pose, n, rgb);
      for (const std::uint8_t b : rgb) add(b);
      for (const std::uint32_t c : r.visible_board_pixels(m.pose)) {
        for (int i = 0; i < 4; ++i) add(static_cast<std::uint8_t>(c >> (8 * i)));
      }
    }
  }
  EXPECT_EQ(h, 0x600c0d2ba6e57667ULL);
}

TEST(Dataset, TinyDatasetBytesArePinned) {
  // The hash of `harmoloc-sim --scenario tiny --seed 1`. It last changed with the fast renderer
  // (its noise table and counter-based noise stream) and the scenario file's new keys; the
  // geometry is pinned by the test above. A scenario without events gives the same dataset as
  // before events existed (same random streams, drawn in the same order). Then with metadata.toml
  // written by toml_writer.hpp: `wheel_radius_m = 0.05` and `track_m = 0.3` instead of
  // 0.050000000000000003 and 0.29999999999999999 (the same doubles; every other byte as before).
  // Then with the camera's offset in metadata.toml (camera.forward_offset_m = 0.1), then its
  // height (camera.height_m = 0.35).
  ht::TempDir dir;
  const hs::SimulationSummary sum =
      hs::simulate_dataset(hs::load_scenario("tiny"), 1, dir.dir(), nullptr);
  EXPECT_EQ(sum.frames, 462U);
  EXPECT_EQ(sum.kidnaps, 0U);
  std::size_t files = 0;
  EXPECT_EQ(folder_hash(dir.dir(), &files), 0x5416c3130e043b4fULL);
  EXPECT_EQ(files, 468U);  // 462 frames, frames.csv, encoders.log, 2 TUM files, 2 TOML files
  EXPECT_FALSE(std::filesystem::exists(dir.path("kidnaps.csv")));
}

TEST(Dataset, EventsAreDeterministicAndFollowTheSeed) {
  const hs::Scenario s = tiny_with_events();
  ht::TempDir a, b, c;
  const hs::SimulationSummary sum = hs::simulate_dataset(s, 5, a.dir(), nullptr);
  hs::simulate_dataset(s, 5, b.dir(), nullptr);
  hs::simulate_dataset(s, 6, c.dir(), nullptr);
  EXPECT_EQ(sum.kidnaps, 1U);
  EXPECT_EQ(folder_hash(a.dir()), folder_hash(b.dir()));
  EXPECT_NE(folder_hash(a.dir()), folder_hash(c.dir()));
  EXPECT_EQ(ht::read_bytes(a.path("kidnaps.csv")), ht::read_bytes(b.path("kidnaps.csv")));
  EXPECT_NE(ht::read_bytes(a.path("kidnaps.csv")), ht::read_bytes(c.path("kidnaps.csv")));
  // kidnaps.csv: a header and one line a kidnap, on the dataset's clock.
  hs::ScenarioRun run(s, 5);
  ASSERT_EQ(run.kidnaps().size(), 1U);
  const hs::KidnapEvent& k = run.kidnaps()[0];
  char expected[256];
  std::snprintf(expected, sizeof expected,
                "t_s,from_x_m,from_y_m,from_yaw_rad,to_x_m,to_y_m,to_yaw_rad\n"
                "1767225601.000000000,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f\n",
                k.from.x_m, k.from.y_m, k.from.yaw_rad, k.to.x_m, k.to.y_m, k.to.yaw_rad);
  const std::vector<std::uint8_t> csv = ht::read_bytes(a.path("kidnaps.csv"));
  EXPECT_EQ(std::string(csv.begin(), csv.end()), expected);
  // The scenario beside the dataset has the events and simulates to the same bytes.
  ht::TempDir again;
  hs::simulate_dataset(hs::load_scenario(a.path("scenario.toml")), 5, again.dir(), nullptr);
  EXPECT_EQ(folder_hash(again.dir()), folder_hash(a.dir()));
  // Writing into a folder with an old kidnaps.csv removes it when the run has none.
  hs::Scenario calm = s;
  calm.kidnaps.count = 0;
  hs::simulate_dataset(calm, 5, a.dir(), nullptr);
  EXPECT_FALSE(std::filesystem::exists(a.path("kidnaps.csv")));
}

TEST(ScenarioRun, FramesRenderInOrderOnly) {
  hs::Scenario s = hs::load_scenario("tiny");
  s.camera.rate_hz = 2.0;
  hs::ScenarioRun run(s, 1);
  ASSERT_GT(run.frame_count(), 3U);
  EXPECT_EQ(run.frame_timestamp_ns(0), 1767225600000000000ULL);
  EXPECT_EQ(run.frame_timestamp_ns(3), 1767225601500000000ULL);
  std::vector<std::uint8_t> rgb;
  EXPECT_THROW(run.render(1, rgb), std::logic_error);
  run.render(0, rgb);
  EXPECT_EQ(rgb.size(), 160U * 120U * 3U);
  EXPECT_THROW(run.render(0, rgb), std::logic_error);
  EXPECT_THROW(run.render(2, rgb), std::logic_error);
  run.render(1, rgb);
  EXPECT_EQ(run.next_frame(), 2U);
  // The true areas are there in any order and do not disturb the image noise.
  EXPECT_EQ(run.visible_board_pixels(run.frame_count() - 1).size(), 6U);
  hs::ScenarioRun twin(s, 1);
  std::vector<std::uint8_t> a, b;
  for (std::size_t k = 0; k < 3; ++k) twin.render(k, a);
  run.render(2, b);
  EXPECT_EQ(a, b);
  for (std::size_t k = 3; k < run.frame_count(); ++k) run.render(k, b);
  EXPECT_THROW(run.render(run.frame_count(), b), std::logic_error);
  // A scenario the run cannot use is a one-line error.
  hs::Scenario none = s;
  none.boards.clear();
  EXPECT_EQ(ht::error_of([&] { hs::ScenarioRun r(none, 1); }), "scenario has no boards");
}

TEST(SimCamera, ReplaysExactlyWhatTheDatasetHolds) {
  const hs::Scenario s = tiny_with_events();
  ht::TempDir dir;
  hs::simulate_dataset(s, 9, dir.dir(), nullptr);
  const hd::DatasetMetadata meta = hd::read_metadata(dir.dir());
  hh::FileCamera files(dir.dir(), meta);
  hh::LogEncoders logged(dir.path("encoders.log"), meta.encoder_layout);

  hs::ScenarioRun run(s, 9);
  hs::SimCamera camera(run);
  hh::LogEncoders in_memory(run.encoder_frames(), s.can_layout);
  ASSERT_EQ(camera.frame_count(), files.frame_count());
  EXPECT_EQ(camera.first_timestamp_ns(), files.first_timestamp_ns());
  EXPECT_EQ(camera.last_timestamp_ns(), files.last_timestamp_ns());
  EXPECT_EQ(in_memory.frame_count(), logged.frame_count());
  EXPECT_EQ(in_memory.first_timestamp_ns(), logged.first_timestamp_ns());
  EXPECT_EQ(in_memory.last_timestamp_ns(), logged.last_timestamp_ns());
  EXPECT_EQ(hd::read_candump_log(dir.path("encoders.log")).size(), run.encoder_frames().size());

  const std::vector<hd::StampedPose> truth = hd::read_tum(dir.path("groundtruth.tum"));
  ASSERT_EQ(truth.size(), run.frame_count());
  const std::uint8_t* first_buffer = nullptr;
  std::size_t frames = 0, encoder_reads = 0;
  for (;;) {
    ASSERT_EQ(camera.next_timestamp_ns(), files.next_timestamp_ns());
    hal::FrameView a{}, b{};
    const hal::CameraStatus sa = camera.acquire(a, 0);
    const hal::CameraStatus sb = files.acquire(b, 0);
    ASSERT_EQ(sa, sb);
    if (sa == hal::CameraStatus::kEnded) break;
    ASSERT_EQ(sa, hal::CameraStatus::kFrame);
    ASSERT_EQ(a.timestamp_ns, b.timestamp_ns);
    ASSERT_EQ(a.sequence, b.sequence);
    ASSERT_EQ(a.width_px, b.width_px);
    ASSERT_EQ(a.height_px, b.height_px);
    ASSERT_EQ(a.stride_bytes, b.stride_bytes);
    ASSERT_EQ(a.format, b.format);
    ASSERT_EQ(std::memcmp(a.data, b.data, std::size_t{a.stride_bytes} * a.height_px), 0)
        << "frame " << frames;
    if (first_buffer == nullptr) first_buffer = a.data;
    EXPECT_EQ(a.data, first_buffer);  // one buffer, reused
    EXPECT_NEAR(truth[frames].pose.x_m, run.truth(frames).x_m, 1e-6);
    EXPECT_NEAR(truth[frames].pose.y_m, run.truth(frames).y_m, 1e-6);
    camera.release();
    files.release();
    // The encoders as the cycle reads them at this frame's time.
    hal::EncoderCounts ca{}, cb{};
    const hal::EncoderStatus ea = in_memory.read(a.timestamp_ns, ca);
    const hal::EncoderStatus eb = logged.read(a.timestamp_ns, cb);
    ASSERT_EQ(ea, eb);
    if (ea == hal::EncoderStatus::kFresh) {
      ASSERT_EQ(ca.left_ticks, cb.left_ticks);
      ASSERT_EQ(ca.right_ticks, cb.right_ticks);
      ASSERT_EQ(ca.timestamp_ns, cb.timestamp_ns);
      ++encoder_reads;
    }
    ++frames;
  }
  EXPECT_EQ(frames, run.frame_count());
  EXPECT_GT(encoder_reads, frames / 2);
  EXPECT_EQ(camera.counters().frames, frames);
  EXPECT_EQ(camera.next_timestamp_ns(), 0U);
  hal::FrameView after{};
  EXPECT_EQ(camera.acquire(after, 0), hal::CameraStatus::kEnded);
  EXPECT_EQ(in_memory.counters().ignored_id, logged.counters().ignored_id);
  EXPECT_THROW(hs::SimCamera second(run), std::logic_error);  // a camera needs a fresh run
}

// --- the built-in scenarios with events do what docs/scenarios.md says
// ----------------------------

TEST(BuiltInEvents, DeskOcclusionHidesGreenFor93FramesWhileTheRobotDrives) {
  const hs::Scenario s = hs::load_scenario("desk-occlusion");
  EXPECT_EQ(hs::describe_events(s), "1 occluder");
  hs::ScenarioRun run(s, 1);
  hs::Scenario nobody = s;
  nobody.occluders.clear();
  hs::ScenarioRun clean(nobody, 1);
  const std::size_t green = board_index(s, "green"), blue = board_index(s, "blue"),
                    red = board_index(s, "red");
  // Green fully hidden in frames 902..994 (30.07-33.13 s); checked on every third frame and the
  // edges. Blue, beside green's line of sight, loses most of its pixels; red a little; the
  // others nothing.
  for (std::size_t k = 897; k <= 999; ++k) {
    if (k % 3 != 0 && k != 901 && k != 902 && k != 994 && k != 995) continue;
    SCOPED_TRACE(k);
    const std::vector<std::uint32_t> seen = run.visible_board_pixels(k);
    const std::vector<std::uint32_t> all = clean.visible_board_pixels(k);
    ASSERT_GT(all[green], 700U);
    if (k >= 902 && k <= 994) {
      EXPECT_EQ(seen[green], 0U);
      EXPECT_LT(seen[blue], all[blue] * 0.6);
      for (std::size_t b = 0; b < all.size(); ++b) {
        if (b != red && b != green && b != blue) {
          EXPECT_EQ(seen[b], all[b]) << s.boards[b].name;
        }
      }
      // The robot drives meanwhile (it starts from the start of its route at 29.92 s).
      EXPECT_GT(std::hypot(run.truth(k).x_m - run.truth(k - 1).x_m,
                           run.truth(k).y_m - run.truth(k - 1).y_m),
                1e-5);
    } else {
      EXPECT_GT(seen[green], 0U);
    }
  }
}

TEST(BuiltInEvents, DeskMovedBoardChangesYellowHalfway) {
  const hs::Scenario s = hs::load_scenario("desk-moved-board");
  EXPECT_EQ(hs::describe_events(s), "1 board move");
  hs::ScenarioRun run(s, 1);
  hs::Scenario still = s;
  still.board_moves.clear();
  hs::ScenarioRun clean(still, 1);
  const std::size_t yellow = board_index(s, "yellow"), green = board_index(s, "green");
  const double half = run.route().duration_s / 2.0;
  for (std::size_t k = 0; k < run.frame_count(); k += 97) {
    SCOPED_TRACE(k);
    const std::vector<std::uint32_t> seen = run.visible_board_pixels(k);
    const std::vector<std::uint32_t> all = clean.visible_board_pixels(k);
    if (run.frame_time_s(k) < s.board_moves[0].at_s) {
      EXPECT_EQ(seen, all);
      continue;
    }
    EXPECT_GT(run.frame_time_s(k), half - 0.5);
    // Yellow, now partly behind blue, loses a quarter or more; it hides part of green.
    EXPECT_LT(seen[yellow], all[yellow] * 0.8);
    EXPECT_LT(seen[green], all[green]);
    for (std::size_t b = 0; b < all.size(); ++b) {
      if (b != yellow && b != green) {
        EXPECT_EQ(seen[b], all[b]) << s.boards[b].name;
      }
    }
  }
}

TEST(BuiltInEvents, DeskLongRunsTenMinutes) {
  const hs::Scenario s = hs::load_scenario("desk-long");
  hs::ScenarioRun run(s, 1);
  EXPECT_GE(run.route().duration_s, 600.0);
  EXPECT_LT(run.route().duration_s, 630.0);
  EXPECT_TRUE(run.kidnaps().empty());
  EXPECT_EQ(run.frame_count(), static_cast<std::size_t>(run.route().duration_s * 30.0) + 1U);
}
