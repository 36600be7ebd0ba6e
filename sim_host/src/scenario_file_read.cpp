// Reading a scenario file (docs/scenarios.md): its base, then each section over it.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <toml++/toml.h>

#include "harmoloc/drivers/input_file.hpp"
#include "harmoloc/sim_host/route.hpp"
#include "harmoloc/sim_host/scenario.hpp"
#include "scenario_parts.hpp"

namespace harmoloc::sim_host::scenario_detail {

namespace {

constexpr double kMaxEventTime_s = 1e6;
constexpr double kMaxCoordinate_m = 100.0;
constexpr double kMaxKidnaps = 10000;
// An occluder colour is taken for a board when it is saturated (8-bit HSV S >= 80), not dark
// (V >= 40) and within 30 degrees of a board colour's hue.
constexpr double kOccluderMaxSaturation = 80.0;
constexpr double kOccluderMaxValue = 40.0;
constexpr double kOccluderMinHueDistance_deg = 30.0;

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
    only(*k, file, "kidnaps.", {"count", "first_s", "interval_s", "min_distance_m", "poses"});
    set_int(*k, "count", s.kidnaps.count, file, "kidnaps.", 0, kMaxKidnaps);
    if (const toml::array* poses = (*k)["poses"].as_array()) {
      s.kidnaps.poses.clear();
      for (const toml::node& p : *poses) {
        const auto v = numbers(&p, 3, file, "kidnaps.poses[] ([x, y, heading_deg])");
        s.kidnaps.poses.push_back({v[0], v[1], v[2]});
      }
      if (s.kidnaps.poses.size() > static_cast<std::size_t>(kMaxKidnaps))
        fail(file, "kidnaps.poses: too many");
      if (k->get("count") == nullptr) s.kidnaps.count = static_cast<int>(s.kidnaps.poses.size());
    }
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

}  // namespace

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
         {"shape", "waypoints", "speed_mps", "acceleration_mps2", "pause_s", "laps", "wander_m",
          "turn_rate_dps"});
    if (const toml::node* shape = r->get("shape")) {
      const auto v = shape->value_exact<std::string>();
      if (v && *v == "shuttle")
        s.route.shape = RouteShape::kShuttle;
      else if (v && *v == "loop")
        s.route.shape = RouteShape::kLoop;
      else if (v && *v == "tour")
        s.route.shape = RouteShape::kTour;
      else
        fail(file, "route.shape must be \"shuttle\", \"loop\" or \"tour\"");
    }
    const bool tour = s.route.shape == RouteShape::kTour;
    if (const toml::array* w = (*r)["waypoints"].as_array()) {
      s.route.waypoints_m.clear();
      s.route.heading_deg.clear();
      for (const toml::node& p : *w) {
        // A tour's waypoints are poses: [x, y, heading_deg].
        const auto xy = numbers(
            &p, tour ? 3 : 2, file,
            tour ? "route.waypoints[] (a tour's: [x, y, heading_deg])" : "route.waypoints[]");
        s.route.waypoints_m.push_back({xy[0], xy[1]});
        if (tour) s.route.heading_deg.push_back(xy[2]);
      }
      if (s.route.waypoints_m.size() < 2) fail(file, "route.waypoints needs at least 2 points");
    }
    if (tour && s.route.heading_deg.size() != s.route.waypoints_m.size())
      fail(file, "route.waypoints of a tour are [x, y, heading_deg]");
    if (s.route.shape == RouteShape::kLoop && s.route.waypoints_m.size() < 3)
      fail(file, "route.waypoints needs at least 3 points for a loop");
    set_num(*r, "turn_rate_dps", s.route.turn_rate_dps, file, "route.", 1, 720);
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

}  // namespace harmoloc::sim_host::scenario_detail
