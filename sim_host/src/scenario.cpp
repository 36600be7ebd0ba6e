#include "harmoloc/sim_host/scenario.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include <toml++/toml.h>

#include "harmoloc/dataset/toml_writer.hpp"
#include "harmoloc/drivers/input_file.hpp"
#include "harmoloc/sim_host/route.hpp"

namespace harmoloc::sim_host {

namespace {

constexpr double kDeg = algorithms::kPi / 180.0;
constexpr double kMaxEventTime_s = 1e6;
constexpr double kMaxCoordinate_m = 100.0;
constexpr double kMaxKidnaps = 10000;
// An occluder colour is taken for a board when it is saturated (8-bit HSV S >= 80), not dark
// (V >= 40) and within 30 degrees of a board colour's hue.
constexpr double kOccluderMaxSaturation = 80.0;
constexpr double kOccluderMaxValue = 40.0;
constexpr double kOccluderMinHueDistance_deg = 30.0;

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

[[noreturn]] void fail(const std::string& file, const std::string& what) {
  throw std::runtime_error(file + ": " + what);
}

double num(const toml::node& n, const std::string& file, const std::string& key) {
  if (auto i = n.value_exact<std::int64_t>()) return static_cast<double>(*i);
  if (auto d = n.value_exact<double>()) return *d;
  fail(file, key + " must be a number");
}

void set_num(const toml::table& t, const char* key, double& out, const std::string& file,
             const std::string& section, double lo, double hi) {
  if (const toml::node* n = t.get(key)) {
    const double v = num(*n, file, section + key);
    if (!(v >= lo && v <= hi)) {
      std::ostringstream s;
      s << section << key << " = " << v << " is outside " << lo << ".." << hi;
      fail(file, s.str());
    }
    out = v;
  }
}

template <typename T>
void set_int(const toml::table& t, const char* key, T& out, const std::string& file,
             const std::string& section, double lo, double hi) {
  double v = static_cast<double>(out);
  set_num(t, key, v, file, section, lo, hi);
  out = static_cast<T>(v);
}

// A scenario file is checked as strictly as the firmware config: a typo must not fall back to a
// default silently.
void only(const toml::table& t, const std::string& file, const std::string& where,
          std::initializer_list<const char*> keys) {
  for (const auto& [key, node] : t) {
    bool known = false;
    for (const char* k : keys) known = known || key.str() == k;
    if (!known) fail(file, "unknown key '" + where + std::string(key.str()) + "'");
  }
}

std::vector<double> numbers(const toml::node* n, std::size_t count, const std::string& file,
                            const std::string& key) {
  const toml::array* a = n != nullptr ? n->as_array() : nullptr;
  if (a == nullptr || a->size() != count)
    fail(file, key + " must be an array of " + std::to_string(count) + " numbers");
  std::vector<double> out;
  for (const toml::node& e : *a) out.push_back(num(e, file, key));
  return out;
}

// A number that must be present and within lo..hi.
double required_num(const toml::table& t, const char* key, const std::string& file,
                    const std::string& section, double lo, double hi) {
  if (t.get(key) == nullptr) fail(file, section + key + " is required");
  double v = 0.0;
  set_num(t, key, v, file, section, lo, hi);
  return v;
}

Rgb colour_of(const toml::table& t, const std::string& file, const std::string& key) {
  const auto c = numbers(t.get("colour"), 3, file, key);
  for (double v : c) {
    if (!(v >= 0 && v <= 255)) fail(file, key + " values must be 0..255");
  }
  return Rgb{static_cast<std::uint8_t>(c[0]), static_cast<std::uint8_t>(c[1]),
             static_cast<std::uint8_t>(c[2])};
}

bool boolean(const toml::table& t, const char* key, bool fallback, const std::string& file,
             const std::string& section) {
  const toml::node* n = t.get(key);
  if (n == nullptr) return fallback;
  const auto v = n->value_exact<bool>();
  if (!v) fail(file, section + key + " must be true or false");
  return *v;
}

// A colour under @p key (not "colour"): [r, g, b], 0..255 each.
void set_colour(const toml::table& t, const char* key, Rgb& out, const std::string& file,
                const std::string& section) {
  const toml::node* n = t.get(key);
  if (n == nullptr) return;
  const auto c = numbers(n, 3, file, section + key);
  for (double v : c) {
    if (!(v >= 0 && v <= 255)) fail(file, section + key + " values must be 0..255");
  }
  out = Rgb{static_cast<std::uint8_t>(c[0]), static_cast<std::uint8_t>(c[1]),
            static_cast<std::uint8_t>(c[2])};
}

// An interval [lo, hi] with lo < hi, both within +-@p bound.
void set_interval(const toml::table& t, const char* key, std::array<double, 2>& out,
                  const std::string& file, const std::string& section, double bound) {
  const toml::node* n = t.get(key);
  if (n == nullptr) return;
  const auto v = numbers(n, 2, file, section + key);
  if (!(std::fabs(v[0]) <= bound && std::fabs(v[1]) <= bound && v[0] < v[1])) {
    std::ostringstream m;
    m << section << key << " must be [min, max] with min < max, within +-" << bound;
    fail(file, m.str());
  }
  out = {v[0], v[1]};
}

void read_room(const toml::table& t, const std::string& file, Scenario& s) {
  if (const toml::node* n = t.get("room")) {
    const toml::table* r = n->as_table();
    if (r == nullptr) fail(file, "room must be a table ([room])");
    only(*r, file, "room.",
         {"x_m", "y_m", "height_m", "floor_colour", "floor_tile_colour", "tile_m", "wall_colour",
          "side_wall_colour", "ceiling_colour"});
    set_interval(*r, "x_m", s.room.x_m, file, "room.", kMaxCoordinate_m);
    set_interval(*r, "y_m", s.room.y_m, file, "room.", kMaxCoordinate_m);
    set_num(*r, "height_m", s.room.height_m, file, "room.", 0.5, 20);
    set_colour(*r, "floor_colour", s.room.floor_colour, file, "room.");
    set_colour(*r, "floor_tile_colour", s.room.floor_tile_colour, file, "room.");
    set_num(*r, "tile_m", s.room.tile_m, file, "room.", 0, 10);
    set_colour(*r, "wall_colour", s.room.wall_colour, file, "room.");
    set_colour(*r, "side_wall_colour", s.room.side_wall_colour, file, "room.");
    set_colour(*r, "ceiling_colour", s.room.ceiling_colour, file, "room.");
  }
  if (const toml::node* n = t.get("desk")) {
    const toml::table* d = n->as_table();
    if (d == nullptr) fail(file, "desk must be a table ([desk])");
    only(*d, file, "desk.", {"present", "x_m", "front_y_m", "height_m", "colour", "top_colour"});
    s.desk.present = boolean(*d, "present", s.desk.present, file, "desk.");
    set_interval(*d, "x_m", s.desk.x_m, file, "desk.", kMaxCoordinate_m);
    set_num(*d, "front_y_m", s.desk.front_y_m, file, "desk.", -kMaxCoordinate_m, kMaxCoordinate_m);
    set_num(*d, "height_m", s.desk.height_m, file, "desk.", 0.05, 5);
    set_colour(*d, "colour", s.desk.colour, file, "desk.");
    set_colour(*d, "top_colour", s.desk.top_colour, file, "desk.");
  }
  if (!(s.desk.front_y_m < s.room.y_m[1]))
    fail(file, "desk.front_y_m must be before the wall at room.y_m[1]");
  if (const toml::node* n = t.get("lighting")) {
    const toml::table* l = n->as_table();
    if (l == nullptr) fail(file, "lighting must be a table ([lighting])");
    only(*l, file, "lighting.", {"drift_amplitude", "drift_period_s", "drift_phase_deg", "steps"});
    set_num(*l, "drift_amplitude", s.lighting.drift_amplitude, file, "lighting.", 0, 0.9);
    set_num(*l, "drift_period_s", s.lighting.drift_period_s, file, "lighting.", 1, kMaxEventTime_s);
    set_num(*l, "drift_phase_deg", s.lighting.drift_phase_deg, file, "lighting.", -360, 360);
    if (const toml::node* st = l->get("steps")) {
      const toml::array* a = st->as_array();
      if (a == nullptr) fail(file, "lighting.steps must be an array of [t_s, gain]");
      s.lighting.steps.clear();
      for (const toml::node& e : *a) {
        const auto v = numbers(&e, 2, file, "lighting.steps[]");
        if (!(v[0] >= 0.0 && v[0] <= kMaxEventTime_s))
          fail(file, "lighting.steps times must be 0..1e6 s");
        if (!(v[1] >= 0.1 && v[1] <= 3.0)) fail(file, "lighting.steps gains must be 0.1..3");
        if (!s.lighting.steps.empty() && !(v[0] > s.lighting.steps.back()[0]))
          fail(file, "lighting.steps times must increase");
        s.lighting.steps.push_back({v[0], v[1]});
      }
    }
  }
}

// An occluder whose colour a board's colour window could take for the board would add to that
// board's area instead of hiding it: rejected. Saturated, not dark, within 30 degrees of hue.
bool looks_like_a_board(const Rgb& occluder, const std::vector<BoardSpec>& boards,
                        std::string& which) {
  double h = 0.0, sat = 0.0, val = 0.0;
  hsv_of(occluder, h, sat, val);
  if (sat < kOccluderMaxSaturation || val < kOccluderMaxValue) return false;
  for (const BoardSpec& b : boards) {
    double bh = 0.0, bs = 0.0, bv = 0.0;
    hsv_of(b.colour, bh, bs, bv);
    const double d = std::fabs(std::remainder(h - bh, 360.0));
    if (d <= kOccluderMinHueDistance_deg) {
      which = b.name;
      return true;
    }
  }
  return false;
}

void read_events(const toml::table& t, const std::string& file, Scenario& s) {
  if (const toml::node* n = t.get("occluders")) {
    const toml::array* list = n->as_array();
    if (list == nullptr) fail(file, "occluders must be an array of tables ([[occluders]])");
    s.occluders.clear();
    for (const toml::node& e : *list) {
      const toml::table* o = e.as_table();
      if (o == nullptr) fail(file, "[[occluders]] entries must be tables");
      only(*o, file, "occluders.", {"name", "colour", "radius_m", "height_m", "path"});
      OccluderSpec spec;
      if (const toml::node* name = o->get("name")) {
        const auto v = name->value_exact<std::string>();
        if (!v) fail(file, "occluders.name must be a string");
        spec.name = *v;
      }
      if (o->get("colour") != nullptr) spec.colour = colour_of(*o, file, "occluders.colour");
      set_num(*o, "radius_m", spec.radius_m, file, "occluders.", 0.01, 5);
      set_num(*o, "height_m", spec.height_m, file, "occluders.", 0.01, 5);
      const toml::array* path = (*o)["path"].as_array();
      if (path == nullptr || path->empty())
        fail(file, "occluders.path must be an array of [t_s, x_m, y_m] keyframes");
      for (const toml::node& k : *path) {
        const auto p = numbers(&k, 3, file, "occluders.path[]");
        if (!(p[0] >= 0.0 && p[0] <= kMaxEventTime_s))
          fail(file, "occluders.path times must be 0.." + std::to_string(kMaxEventTime_s) + " s");
        if (!(std::fabs(p[1]) <= kMaxCoordinate_m && std::fabs(p[2]) <= kMaxCoordinate_m))
          fail(file, "occluders.path positions must be within +-100 m");
        if (!spec.path.empty() && !(p[0] > spec.path.back()[0]))
          fail(file, "occluders.path times must increase");
        spec.path.push_back({p[0], p[1], p[2]});
      }
      s.occluders.push_back(spec);
    }
  }
  if (const toml::node* n = t.get("board_moves")) {
    const toml::array* list = n->as_array();
    if (list == nullptr) fail(file, "board_moves must be an array of tables ([[board_moves]])");
    s.board_moves.clear();
    for (const toml::node& e : *list) {
      const toml::table* m = e.as_table();
      if (m == nullptr) fail(file, "[[board_moves]] entries must be tables");
      only(*m, file, "board_moves.", {"board", "at_s", "offset_m", "turn_deg"});
      BoardMoveSpec spec;
      const auto board = (*m)["board"].value_exact<std::string>();
      if (!board) fail(file, "board_moves.board (a board's name) is required");
      spec.board = *board;
      spec.at_s = required_num(*m, "at_s", file, "board_moves.", 0, kMaxEventTime_s);
      if (const toml::node* off = m->get("offset_m")) {
        const auto v = numbers(off, 3, file, "board_moves.offset_m");
        for (std::size_t i = 0; i < 3; ++i) {
          if (!(std::fabs(v[i]) <= kMaxCoordinate_m))
            fail(file, "board_moves.offset_m must be within +-100 m");
          spec.offset_m[i] = v[i];
        }
      }
      set_num(*m, "turn_deg", spec.turn_deg, file, "board_moves.", -360, 360);
      s.board_moves.push_back(spec);
    }
  }
  if (const toml::node* n = t.get("kidnaps")) {
    const toml::table* k = n->as_table();
    if (k == nullptr) fail(file, "kidnaps must be a table ([kidnaps])");
    only(*k, file, "kidnaps.", {"count", "first_s", "interval_s", "min_distance_m"});
    set_int(*k, "count", s.kidnaps.count, file, "kidnaps.", 0, kMaxKidnaps);
    set_num(*k, "first_s", s.kidnaps.first_s, file, "kidnaps.", 0, kMaxEventTime_s);
    set_num(*k, "interval_s", s.kidnaps.interval_s, file, "kidnaps.", 0.1, kMaxEventTime_s);
    set_num(*k, "min_distance_m", s.kidnaps.min_distance_m, file, "kidnaps.", 0, kMaxCoordinate_m);
  }
  // Checked against the final boards: a file may replace the base's boards.
  for (const BoardMoveSpec& m : s.board_moves) {
    bool found = false;
    for (const BoardSpec& b : s.boards) found = found || b.name == m.board;
    if (!found) fail(file, "board_moves.board '" + m.board + "' is not a board of this scenario");
  }
  for (const OccluderSpec& o : s.occluders) {
    std::string which;
    if (looks_like_a_board(o.colour, s.boards, which)) {
      fail(file, "occluder '" + o.name + "': its colour is too close to board '" + which +
                     "' (segmentation would count it as that board)");
    }
  }
}

Scenario load_scenario_at_depth(const std::string& name_or_file, int depth);

Scenario from_file(const std::string& file, int depth) {
  std::string content;
  if (const std::string e =
          drivers::read_regular_file(file, drivers::input_limits::kTomlBytes, content);
      !e.empty()) {
    fail(file, e);
  }
  if (const std::string e = drivers::check_toml_nesting(content); !e.empty()) fail(file, e);
  toml::table t;
  try {
    t = toml::parse(content, file);
  } catch (const toml::parse_error& e) {
    std::ostringstream s;
    s << "line " << e.source().begin.line << ": " << e.description();
    fail(file, s.str());
  }
  only(t, file, "",
       {"base", "name", "description", "labelled_frames", "labels_with_heading", "start_time_s",
        "room", "desk", "lighting", "camera", "route", "encoders", "robot", "boards", "occluders",
        "board_moves", "kidnaps"});
  const std::string base = t["base"].value_or(std::string("desk-shuttle"));
  Scenario s;
  try {
    s = load_scenario_at_depth(base, depth + 1);
  } catch (const std::runtime_error& e) {
    fail(file, std::string("base: ") + e.what());
  }
  s.name = t["name"].value_or(std::filesystem::path(file).stem().string());
  s.description = t["description"].value_or(std::string("from ") + file);
  set_int(t, "labelled_frames", s.labelled_frames, file, "", 2, 4096);
  set_num(t, "start_time_s", s.start_time_s, file, "", 0, 4e9);
  s.labels_with_heading = boolean(t, "labels_with_heading", s.labels_with_heading, file, "");
  read_room(t, file, s);
  if (const toml::table* c = t["camera"].as_table()) {
    only(*c, file, "camera.",
         {"width_px", "height_px", "horizontal_fov_deg", "radial_k", "k1", "k2", "k3", "p1", "p2",
          "principal_offset_px", "vignetting", "height_m", "pitch_deg", "mount_yaw_deg",
          "forward_offset_m", "rate_hz", "pixel_noise", "light_gain"});
    set_int(*c, "width_px", s.camera.width_px, file, "camera.", 16, 4096);
    set_int(*c, "height_px", s.camera.height_px, file, "camera.", 16, 4096);
    set_num(*c, "horizontal_fov_deg", s.camera.horizontal_fov_deg, file, "camera.", 10, 150);
    if (c->get("radial_k") != nullptr && c->get("k1") != nullptr)
      fail(file, "camera.radial_k and camera.k1 are the same coefficient: give one");
    set_num(*c, "radial_k", s.camera.k1, file, "camera.", -1, 1);
    set_num(*c, "k1", s.camera.k1, file, "camera.", -1, 1);
    set_num(*c, "k2", s.camera.k2, file, "camera.", -1, 1);
    set_num(*c, "k3", s.camera.k3, file, "camera.", -1, 1);
    set_num(*c, "p1", s.camera.p1, file, "camera.", -0.1, 0.1);
    set_num(*c, "p2", s.camera.p2, file, "camera.", -0.1, 0.1);
    if (const toml::node* pp = c->get("principal_offset_px")) {
      const auto v = numbers(pp, 2, file, "camera.principal_offset_px");
      s.camera.principal_offset_x_px = v[0];
      s.camera.principal_offset_y_px = v[1];
    }
    set_num(*c, "vignetting", s.camera.vignetting, file, "camera.", 0, 1);
    set_num(*c, "height_m", s.camera.height_m, file, "camera.", 0.01, 5);
    set_num(*c, "pitch_deg", s.camera.pitch_deg, file, "camera.", -60, 60);
    set_num(*c, "mount_yaw_deg", s.camera.mount_yaw_deg, file, "camera.", -180, 180);
    set_num(*c, "forward_offset_m", s.camera.forward_offset_m, file, "camera.", -2, 2);
    set_num(*c, "rate_hz", s.camera.rate_hz, file, "camera.", 1, 240);
    set_num(*c, "pixel_noise", s.camera.pixel_noise, file, "camera.", 0, 50);
    set_num(*c, "light_gain", s.camera.light_gain, file, "camera.", 0.1, 3);
  }
  if (const toml::table* r = t["route"].as_table()) {
    only(*r, file, "route.",
         {"shape", "waypoints", "speed_mps", "acceleration_mps2", "pause_s", "laps", "wander_m"});
    if (const toml::node* shape = r->get("shape")) {
      const auto v = shape->value_exact<std::string>();
      if (v && *v == "shuttle")
        s.route.shape = RouteShape::kShuttle;
      else if (v && *v == "loop")
        s.route.shape = RouteShape::kLoop;
      else
        fail(file, "route.shape must be \"shuttle\" or \"loop\"");
    }
    if (const toml::array* w = (*r)["waypoints"].as_array()) {
      s.route.waypoints_m.clear();
      for (const toml::node& p : *w) {
        const auto xy = numbers(&p, 2, file, "route.waypoints[]");
        s.route.waypoints_m.push_back({xy[0], xy[1]});
      }
      if (s.route.waypoints_m.size() < 2) fail(file, "route.waypoints needs at least 2 points");
    }
    if (s.route.shape == RouteShape::kLoop && s.route.waypoints_m.size() < 3)
      fail(file, "route.waypoints needs at least 3 points for a loop");
    set_num(*r, "speed_mps", s.route.speed_mps, file, "route.", 0.01, 2);
    set_num(*r, "acceleration_mps2", s.route.acceleration_mps2, file, "route.", 0.01, 10);
    set_num(*r, "pause_s", s.route.pause_s, file, "route.", 0, 60);
    set_int(*r, "laps", s.route.laps, file, "route.", 1, 1000);
    set_num(*r, "wander_m", s.route.wander_m, file, "route.", 0, 0.5);
  }
  if (const toml::table* e = t["encoders"].as_table()) {
    only(*e, file, "encoders.",
         {"rate_hz", "slip_sigma", "left_scale_error", "right_scale_error", "initial_left",
          "initial_right", "counter_bits"});
    set_num(*e, "rate_hz", s.encoders.rate_hz, file, "encoders.", 1, 2000);
    set_num(*e, "slip_sigma", s.encoders.slip_sigma, file, "encoders.", 0, 0.5);
    set_num(*e, "left_scale_error", s.encoders.left_scale_error, file, "encoders.", -0.5, 0.5);
    set_num(*e, "right_scale_error", s.encoders.right_scale_error, file, "encoders.", -0.5, 0.5);
    set_int(*e, "initial_left", s.encoders.initial_left, file, "encoders.", 0, 4294967295.0);
    set_int(*e, "initial_right", s.encoders.initial_right, file, "encoders.", 0, 4294967295.0);
    set_int(*e, "counter_bits", s.can_layout.counter_bits, file, "encoders.", 8, 32);
  }
  if (const toml::table* b = t["robot"].as_table()) {
    only(*b, file, "robot.", {"wheel_radius_m", "track_m", "ticks_per_rev"});
    set_num(*b, "wheel_radius_m", s.robot.wheel_radius_m, file, "robot.", 0.005, 1);
    set_num(*b, "track_m", s.robot.track_m, file, "robot.", 0.05, 3);
    set_num(*b, "ticks_per_rev", s.robot.ticks_per_rev, file, "robot.", 1, 1e7);
  }
  if (const toml::array* boards = t["boards"].as_array()) {
    s.boards.clear();
    for (const toml::node& n : *boards) {
      const toml::table* b = n.as_table();
      if (b == nullptr) fail(file, "[[boards]] entries must be tables");
      only(*b, file, "boards.",
           {"name", "colour", "centre", "size", "facing_deg", "shape", "tilt_deg", "stand"});
      BoardSpec spec;
      spec.name = (*b)["name"].value_or(std::string("board") + std::to_string(s.boards.size() + 1));
      const auto c = numbers(b->get("colour"), 3, file, "boards.colour");
      for (double v : c) {
        if (v < 0 || v > 255) fail(file, "boards.colour values must be 0..255");
      }
      spec.colour = Rgb{static_cast<std::uint8_t>(c[0]), static_cast<std::uint8_t>(c[1]),
                        static_cast<std::uint8_t>(c[2])};
      const auto centre = numbers(b->get("centre"), 3, file, "boards.centre");
      const auto size = numbers(b->get("size"), 2, file, "boards.size");
      if (size[0] <= 0 || size[1] <= 0) fail(file, "boards.size must be positive");
      spec.centre_x_m = centre[0];
      spec.centre_y_m = centre[1];
      spec.centre_z_m = centre[2];
      spec.width_m = size[0];
      spec.height_m = size[1];
      double facing = -90.0;
      set_num(*b, "facing_deg", facing, file, "boards.", -360, 360);
      spec.facing_yaw_rad = facing * kDeg;
      if (const toml::node* shape = b->get("shape")) {
        const auto v = shape->value_exact<std::string>();
        if (v && *v == "rectangle")
          spec.shape = BoardShape::kRectangle;
        else if (v && *v == "ellipse")
          spec.shape = BoardShape::kEllipse;
        else
          fail(file, "boards.shape must be \"rectangle\" or \"ellipse\"");
      }
      double tilt = 0.0;
      set_num(*b, "tilt_deg", tilt, file, "boards.", -60, 60);
      spec.tilt_rad = tilt * kDeg;
      spec.stand = boolean(*b, "stand", false, file, "boards.");
      s.boards.push_back(spec);
    }
    if (s.boards.empty() || s.boards.size() > 8) fail(file, "1 to 8 boards");
  }
  read_events(t, file, s);
  const std::uint8_t bytes = static_cast<std::uint8_t>((s.can_layout.counter_bits + 7) / 8);
  s.can_layout.left_offset = 0;
  s.can_layout.right_offset = bytes;
  s.can_layout.length = static_cast<std::uint8_t>(2 * bytes);
  if (s.camera.width_px % 2 != 0) fail(file, "camera.width_px must be even");
  if (!(std::fabs(s.camera.principal_offset_x_px) <= 0.5 * s.camera.width_px &&
        std::fabs(s.camera.principal_offset_y_px) <= 0.5 * s.camera.height_px))
    fail(file, "camera.principal_offset_px must be within half the image size");
  if (s.route.shape == RouteShape::kLoop) {
    std::string why;
    if (route_crosses_itself(s.route, &why)) fail(file, "route: " + why);
  }
  return s;
}

}  // namespace

void hsv_of(const Rgb& c, double& hue_deg, double& saturation, double& value) {
  const double r = c.r, g = c.g, b = c.b;
  const double hi = std::max({r, g, b}), lo = std::min({r, g, b});
  value = hi;
  saturation = hi > 0.0 ? 255.0 * (hi - lo) / hi : 0.0;
  hue_deg = 0.0;
  if (hi > lo) {
    if (hi == r)
      hue_deg = 60.0 * (g - b) / (hi - lo);
    else if (hi == g)
      hue_deg = 120.0 + 60.0 * (b - r) / (hi - lo);
    else
      hue_deg = 240.0 + 60.0 * (r - g) / (hi - lo);
    if (hue_deg < 0.0) hue_deg += 360.0;
  }
}

double light_gain_at(const Scenario& s, double t_s) {
  const LightingSpec& l = s.lighting;
  double gain = s.camera.light_gain;
  if (l.drift_amplitude != 0.0) {
    gain *= 1.0 + l.drift_amplitude * std::sin(2.0 * algorithms::kPi * t_s / l.drift_period_s +
                                               l.drift_phase_deg * kDeg);
  }
  double step = 1.0;
  for (const auto& st : l.steps) {
    if (st[0] <= t_s) step = st[1];
  }
  return gain * step;
}

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

namespace {

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

}  // namespace

namespace {

// Degrees computed from radians: 12 significant digits, so that -75 stays -75 (a scenario's
// angles are whole or decimal degrees; they read back to the same radians).
double degrees(double rad) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.12g", rad / kDeg);
  return std::strtod(buf, nullptr);
}

toml::array rgb(const Rgb& c) {
  return toml::array{int{c.r}, int{c.g}, int{c.b}};
}

}  // namespace

std::string scenario_to_toml(const Scenario& s) {
  using dataset::number_array;
  using dataset::number_arrays;
  dataset::TomlWriter w("Scenario as simulated (format: docs/scenarios.md)");
  w.set("name", s.name)
      .set("description", s.description)
      .set("labelled_frames", s.labelled_frames)
      .set("labels_with_heading", s.labels_with_heading)
      .set("start_time_s", s.start_time_s);
  w.table("room")
      .set("x_m", number_array(s.room.x_m))
      .set("y_m", number_array(s.room.y_m))
      .set("height_m", s.room.height_m)
      .set("floor_colour", rgb(s.room.floor_colour))
      .set("floor_tile_colour", rgb(s.room.floor_tile_colour))
      .set("tile_m", s.room.tile_m)
      .set("wall_colour", rgb(s.room.wall_colour))
      .set("side_wall_colour", rgb(s.room.side_wall_colour))
      .set("ceiling_colour", rgb(s.room.ceiling_colour));
  w.table("desk")
      .set("present", s.desk.present)
      .set("x_m", number_array(s.desk.x_m))
      .set("front_y_m", s.desk.front_y_m)
      .set("height_m", s.desk.height_m)
      .set("colour", rgb(s.desk.colour))
      .set("top_colour", rgb(s.desk.top_colour));
  const CameraSpec& c = s.camera;
  w.table("camera")
      .set("width_px", c.width_px)
      .set("height_px", c.height_px)
      .set("horizontal_fov_deg", c.horizontal_fov_deg)
      .set("k1", c.k1)
      .set("k2", c.k2)
      .set("k3", c.k3)
      .set("p1", c.p1)
      .set("p2", c.p2)
      .set("principal_offset_px",
           number_array(std::array<double, 2>{c.principal_offset_x_px, c.principal_offset_y_px}))
      .set("vignetting", c.vignetting)
      .set("height_m", c.height_m)
      .set("pitch_deg", c.pitch_deg)
      .set("mount_yaw_deg", c.mount_yaw_deg)
      .set("forward_offset_m", c.forward_offset_m)
      .set("rate_hz", c.rate_hz)
      .set("pixel_noise", c.pixel_noise)
      .set("light_gain", c.light_gain);
  w.table("lighting")
      .set("drift_amplitude", s.lighting.drift_amplitude)
      .set("drift_period_s", s.lighting.drift_period_s)
      .set("drift_phase_deg", s.lighting.drift_phase_deg)
      .set("steps", number_arrays(s.lighting.steps));
  w.table("route")
      .set("shape", s.route.shape == RouteShape::kLoop ? "loop" : "shuttle")
      .set("waypoints", number_arrays(s.route.waypoints_m))
      .set("speed_mps", s.route.speed_mps)
      .set("acceleration_mps2", s.route.acceleration_mps2)
      .set("pause_s", s.route.pause_s)
      .set("laps", s.route.laps)
      .set("wander_m", s.route.wander_m);
  w.table("encoders")
      .set("rate_hz", s.encoders.rate_hz)
      .set("slip_sigma", s.encoders.slip_sigma)
      .set("left_scale_error", s.encoders.left_scale_error)
      .set("right_scale_error", s.encoders.right_scale_error)
      .set("initial_left", s.encoders.initial_left)
      .set("initial_right", s.encoders.initial_right)
      .set("counter_bits", int{s.can_layout.counter_bits});
  w.table("robot")
      .set("wheel_radius_m", s.robot.wheel_radius_m)
      .set("track_m", s.robot.track_m)
      .set("ticks_per_rev", s.robot.ticks_per_rev);
  for (const BoardSpec& b : s.boards) {
    w.array_table("boards")
        .set("name", b.name)
        .set("colour", rgb(b.colour))
        .set("centre",
             number_array(std::array<double, 3>{b.centre_x_m, b.centre_y_m, b.centre_z_m}))
        .set("size", number_array(std::array<double, 2>{b.width_m, b.height_m}))
        .set("facing_deg", degrees(b.facing_yaw_rad))
        .set("shape", b.shape == BoardShape::kEllipse ? "ellipse" : "rectangle")
        .set("tilt_deg", degrees(b.tilt_rad))
        .set("stand", b.stand);
  }
  // Events only when there are any.
  for (const OccluderSpec& oc : s.occluders) {
    w.array_table("occluders")
        .set("name", oc.name)
        .set("colour", rgb(oc.colour))
        .set("radius_m", oc.radius_m)
        .set("height_m", oc.height_m)
        .set("path", number_arrays(oc.path));
  }
  for (const BoardMoveSpec& m : s.board_moves) {
    w.array_table("board_moves")
        .set("board", m.board)
        .set("at_s", m.at_s)
        .set("offset_m", number_array(m.offset_m))
        .set("turn_deg", m.turn_deg);
  }
  if (s.kidnaps.count > 0) {
    w.table("kidnaps")
        .set("count", s.kidnaps.count)
        .set("first_s", s.kidnaps.first_s)
        .set("interval_s", s.kidnaps.interval_s)
        .set("min_distance_m", s.kidnaps.min_distance_m);
  }
  return w.text();
}

std::string describe_events(const Scenario& s) {
  std::string out;
  const auto add = [&out](std::size_t n, const char* what) {
    if (n == 0) return;
    out += (out.empty() ? "" : ", ") + std::to_string(n) + " " + what + (n == 1 ? "" : "s");
  };
  add(static_cast<std::size_t>(std::max(0, s.kidnaps.count)), "kidnap");
  add(s.board_moves.size(), "board move");
  add(s.occluders.size(), "occluder");
  return out.empty() ? "no events" : out;
}

}  // namespace harmoloc::sim_host
