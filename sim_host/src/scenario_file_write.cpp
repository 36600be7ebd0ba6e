// Writing a scenario as a scenario file (docs/scenarios.md): every field, so that it reads back
// the same.
#include <array>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <toml++/toml.h>

#include "harmoloc/dataset/toml_writer.hpp"
#include "harmoloc/sim_host/scenario.hpp"
#include "scenario_parts.hpp"

namespace harmoloc::sim_host {

using scenario_detail::kDeg;

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
  const bool tour = s.route.shape == RouteShape::kTour;
  std::vector<std::array<double, 3>> poses;
  for (std::size_t i = 0; tour && i < s.route.waypoints_m.size(); ++i)
    poses.push_back({s.route.waypoints_m[i][0], s.route.waypoints_m[i][1],
                     i < s.route.heading_deg.size() ? s.route.heading_deg[i] : 0.0});
  auto& route = w.table("route").set("shape", tour                                 ? "tour"
                                              : s.route.shape == RouteShape::kLoop ? "loop"
                                                                                   : "shuttle");
  if (tour)
    route.set("waypoints", number_arrays(poses)).set("turn_rate_dps", s.route.turn_rate_dps);
  else
    route.set("waypoints", number_arrays(s.route.waypoints_m));
  route.set("speed_mps", s.route.speed_mps)
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
    if (!s.kidnaps.poses.empty()) w.set("poses", number_arrays(s.kidnaps.poses));
  }
  return w.text();
}

}  // namespace harmoloc::sim_host
