// The built-in scenarios, and loading a scenario by name or file.
#include <filesystem>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "harmoloc/sim_host/scenario.hpp"
#include "scenario_parts.hpp"

namespace harmoloc::sim_host {

using scenario_detail::kDeg;
using scenario_detail::load_scenario_at_depth;

namespace {

// Wu & Qin's setting: six single-colour boards of different sizes on a desk, the robot on a
// 420 x 240 cm floor in front of it, 10 cm/s, 30 Hz, a camera with strong radial distortion.
Scenario desk_shuttle() {
  Scenario s;
  s.name = "desk-shuttle";
  s.description =
      "Wu & Qin's desk: 6 boards, 320x240 distorted camera, S-shaped route driven forth and back";
  const double face = -90.0 * kDeg;  // boards look at the robot (towards -y)
  s.boards = {
      {"red", {220, 30, 30}, 1.55, 2.55, 0.95, 0.30, 0.40, face + 15.0 * kDeg},
      {"green", {30, 180, 40}, 1.85, 2.85, 1.05, 0.45, 0.30, face},
      {"blue", {30, 60, 220}, 2.10, 2.50, 0.87, 0.18, 0.24, face - 10.0 * kDeg},
      {"yellow", {230, 210, 30}, 2.38, 2.75, 1.05, 0.35, 0.55, face},
      {"magenta", {200, 40, 190}, 2.62, 2.55, 0.84, 0.24, 0.18, face + 10.0 * kDeg},
      {"cyan", {30, 190, 200}, 2.88, 2.85, 1.00, 0.50, 0.35, face - 15.0 * kDeg},
  };
  s.route.waypoints_m = {{2.10, 0.35}, {2.03, 0.70}, {2.17, 1.05}, {2.05, 1.40}, {2.10, 1.60}};
  return s;
}

// The same desk seen from three more routes, so accuracy is not a property of one path.
Scenario desk_route(const char* name, const char* description,
                    std::vector<std::array<double, 2>> waypoints) {
  Scenario s = desk_shuttle();
  s.name = name;
  s.description = description;
  s.route.waypoints_m = std::move(waypoints);
  return s;
}

Scenario desk_left() {
  return desk_route("desk-left", "Wu & Qin's desk, a diagonal route from the front left",
                    {{1.40, 0.40}, {1.55, 0.80}, {1.80, 1.20}, {1.95, 1.55}});
}

Scenario desk_right() {
  return desk_route("desk-right", "Wu & Qin's desk, a diagonal route from the front right",
                    {{2.90, 0.40}, {2.75, 0.80}, {2.50, 1.20}, {2.30, 1.55}});
}

Scenario desk_slalom() {
  return desk_route("desk-slalom", "Wu & Qin's desk, a slalom across the middle",
                    {{2.10, 0.40}, {2.25, 0.80}, {1.95, 1.20}, {2.10, 1.60}});
}

Scenario tiny() {
  Scenario s = desk_shuttle();
  s.name = "tiny";
  s.description = "small and quick (160x120, short route): for tests";
  s.camera.width_px = 160;
  s.camera.height_px = 120;
  s.route.waypoints_m = {{2.10, 0.70}, {2.04, 1.00}, {2.14, 1.30}};
  s.route.pause_s = 0.3;
  s.labelled_frames = 24;
  return s;
}

Scenario wrap_test() {
  Scenario s = tiny();
  s.name = "tiny-wrap16";
  s.description = "tiny, with 16-bit encoder counters that start just below the wrap";
  s.can_layout.counter_bits = 16;
  s.can_layout.length = 4;
  s.can_layout.left_offset = 0;
  s.can_layout.right_offset = 2;
  s.encoders.initial_left = 65000;
  s.encoders.initial_right = 65500;
  return s;
}

// Events on the desk-shuttle route (docs/scenarios.md gives the facts each was designed to).

// A person walks in along the desk and stands 3 s in front of the green board, the board with
// the least noise for its size (what the filter leans on most), while the robot drives towards
// the desk; blue, beside green's line of sight, is mostly hidden too.
Scenario desk_occlusion() {
  Scenario s = desk_shuttle();
  s.name = "desk-occlusion";
  s.description =
      "desk-shuttle, 2 laps; halfway a person stands in front of the green board for 3 s";
  s.route.laps = 2;
  OccluderSpec person;
  person.name = "person";
  person.radius_m = 0.20;
  person.path = {{28.7, 0.20, 2.15}, {30.1, 1.93, 2.15}, {33.1, 1.93, 2.15}, {34.5, 0.20, 2.15}};
  s.occluders.push_back(person);
  return s;
}

// Someone moves the yellow board (the largest) 30 cm to the left along the desk halfway through
// two laps (while the robot stands at the start of its route). There it stands partly behind
// blue and in front of part of green, so three boards' areas change: yellow's most.
Scenario desk_moved_board() {
  Scenario s = desk_shuttle();
  s.name = "desk-moved-board";
  s.description = "desk-shuttle, 2 laps; halfway the yellow board is moved 30 cm along the desk";
  s.route.laps = 2;
  BoardMoveSpec move;
  move.board = "yellow";
  move.at_s = 29.7;
  move.offset_m = {-0.30, 0.0, 0.0};
  s.board_moves.push_back(move);
  return s;
}

// The robot is lifted and put down at least 1 m away, 10 times, 15 s apart. Only the 0.2-0.25 m
// at each end of the 1.32 m route are 1 m from anywhere (the ends are 1.25 m apart), and the robot
// stays there 5-6 s a visit: kidnaps 1 m long need the robot near an end at every kidnap time,
// which holds for intervals up to ~3.5 s or of 12-18 s (about half a lap, 14.7 s), not 5-10 s.
Scenario desk_kidnap() {
  Scenario s = desk_shuttle();
  s.name = "desk-kidnap";
  s.description = "desk-shuttle, 6 laps; the robot is kidnapped 10 times 15 s apart, each >= 1 m";
  s.route.laps = 6;
  s.kidnaps.count = 10;
  s.kidnaps.first_s = 15.0;
  s.kidnaps.interval_s = 15.0;
  s.kidnaps.min_distance_m = 1.0;
  return s;
}

// Ten simulated minutes of the nominal desk-shuttle (false alarms of kidnap and moved-board
// tests).
Scenario desk_long() {
  Scenario s = desk_shuttle();
  s.name = "desk-long";
  s.description = "desk-shuttle for 10 minutes (21 laps), nothing happens";
  s.route.laps = 21;
  return s;
}

using ScenarioFactory = Scenario (*)();
constexpr ScenarioFactory kBuiltIns[] = {desk_shuttle,   desk_left,        desk_right,  desk_slalom,
                                         desk_occlusion, desk_moved_board, desk_kidnap, desk_long,
                                         tiny,           wrap_test};

}  // namespace

std::vector<std::pair<std::string, std::string>> builtin_scenarios() {
  std::vector<std::pair<std::string, std::string>> out;
  for (const ScenarioFactory make : kBuiltIns) {
    const Scenario s = make();
    out.emplace_back(s.name, s.description);
  }
  return out;
}

Scenario load_scenario(const std::string& name_or_file) {
  return load_scenario_at_depth(name_or_file, 0);
}

namespace scenario_detail {

Scenario load_scenario_at_depth(const std::string& name_or_file, int depth) {
  constexpr int kMaxBaseDepth = 8;
  if (depth > kMaxBaseDepth) {
    throw std::runtime_error(
        name_or_file + ": more than 8 scenario files chained by 'base' (does one name itself?)");
  }
  for (const ScenarioFactory make : kBuiltIns) {
    Scenario s = make();
    if (s.name == name_or_file) return s;
  }
  // A file that is not a regular one (a folder, a FIFO) is refused by from_file, by name.
  if (std::filesystem::exists(name_or_file)) return from_file(name_or_file, depth);
  std::string names;
  for (const auto& [name, text] : builtin_scenarios()) names += (names.empty() ? "" : ", ") + name;
  throw std::runtime_error("unknown scenario '" + name_or_file + "' (built-in: " + names +
                           "; or a .toml file)");
}

}  // namespace scenario_detail

}  // namespace harmoloc::sim_host
