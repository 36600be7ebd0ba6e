// Drawing a random scene: its camera, lighting, route, room and robot.
#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include "harmoloc/sim_host/lens.hpp"
#include "harmoloc/sim_host/route.hpp"
#include "random_scene_parts.hpp"

namespace harmoloc::sim_host::random_scene_detail {

namespace {

constexpr double kRouteWallMargin_m = 1.0;  // the route keeps this far from the walls

}  // namespace

// The angle between the optical axis and the ray of the frame's farthest pixel that has one.
double widest_ray_rad(const CameraSpec& c) {
  const LensModel lens(c);
  const Intrinsics in = intrinsics_of(c);
  double widest = 0.0;
  for (const double fx : {0.0, 1.0}) {
    for (const double fy : {0.0, 1.0}) {
      const double xd = (fx * (c.width_px - 1) - in.cx_px) / in.focal_px;
      const double yd = (fy * (c.height_px - 1) - in.cy_px) / in.focal_px;
      double x = 0, y = 0;
      const double r = lens.undistort(xd, yd, x, y) ? std::hypot(x, y) : lens.max_radius();
      widest = std::max(widest, std::atan(std::min(r, 1e3)));
    }
  }
  return widest;
}

void draw_camera(Draw& d, double min_fov_deg, CameraSpec& c) {
  static const std::uint32_t sizes[3][2] = {{320, 240}, {640, 480}, {1280, 720}};
  const int res = d.i(0, 2);
  c.width_px = sizes[res][0];
  c.height_px = sizes[res][1];
  const double true_fov = d.u(min_fov_deg, 100.0);
  const double x_edge = std::tan(0.5 * true_fov * kDeg);
  // The lens: k1 from -0.05 to -0.4 with a small k2, p1, p2, monotonic (slope >= 0.3) out to
  // the horizontal edge of the frame (the corners may fall outside the image circle).
  c.k1 = -0.05;
  c.k2 = c.p1 = c.p2 = 0.0;
  for (int tries = 0; tries < 64; ++tries) {
    const double k1 = d.u(-0.4, -0.05), k2 = d.u(-0.02, 0.06);
    const double x2 = x_edge * x_edge;
    if (1.0 + 3.0 * k1 * x2 + 5.0 * k2 * x2 * x2 >= 0.3) {
      c.k1 = q(k1, 1e4);
      c.k2 = q(k2, 1e4);
      break;
    }
  }
  c.k3 = 0.0;
  c.p1 = q(d.u(-0.002, 0.002), 1e5);
  c.p2 = q(d.u(-0.002, 0.002), 1e5);
  const double x2 = x_edge * x_edge;
  const double xd_edge = x_edge * (1.0 + c.k1 * x2 + c.k2 * x2 * x2);
  c.horizontal_fov_deg = q(2.0 * std::atan(xd_edge) / kDeg, 100.0);
  c.principal_offset_x_px = q(d.u(-0.02, 0.02) * c.width_px, 10.0);
  c.principal_offset_y_px = q(d.u(-0.02, 0.02) * c.height_px, 10.0);
  c.pitch_deg = q(d.u(0.0, 20.0), 10.0);
  c.height_m = q(d.u(0.15, 0.5), 1000.0);
  c.forward_offset_m = q(d.u(0.05, 0.2), 1000.0);
  c.mount_yaw_deg = 0.0;
  c.rate_hz = 30.0;
  c.pixel_noise = q(d.u(1.0, 6.0), 100.0);
  // Vignetting: the corners keep at least 65% of the light.
  const double widest = widest_ray_rad(c);
  const double c4 = std::pow(std::cos(widest), 4.0);
  const double most = std::min(0.4, 0.35 / std::max(1e-6, 1.0 - c4));
  c.vignetting = q(d.u(0.0, most), 1000.0);
  c.light_gain = 1.0;
}

// Draws the lighting of a run of @p duration_s: global gain, drift, 0-3 steps; the gain stays
// within [kMinGain, kMaxGain] over the run.
void draw_lighting(Draw& d, double duration_s, Scenario& s) {
  for (int tries = 0; tries < 32; ++tries) {
    s.camera.light_gain = q(d.u(0.9, 1.1), 1000.0);
    LightingSpec l;
    if (d.chance(0.7)) {
      l.drift_amplitude = q(d.u(0.03, 0.15), 1000.0);
      l.drift_period_s = q(d.u(60.0, 600.0), 10.0);
      l.drift_phase_deg = q(d.u(-180.0, 180.0), 10.0);
    }
    const int steps = d.i(0, 3);
    std::vector<double> times;
    for (int k = 0; k < steps; ++k) times.push_back(q(d.u(0.05, 0.95) * duration_s, 10.0));
    std::sort(times.begin(), times.end());
    for (int k = 0; k < steps; ++k) {
      const double gain = q(d.u(0.75, 1.25), 1000.0);
      if (!l.steps.empty() && !(times[static_cast<std::size_t>(k)] > l.steps.back()[0])) continue;
      l.steps.push_back({times[static_cast<std::size_t>(k)], gain});
    }
    s.lighting = l;
    bool ok = true;
    for (double t = 0.0; t <= duration_s + 0.5 && ok; t += 0.5) {
      const double g = light_gain_at(s, t);
      ok = g >= kMinGain && g <= kMaxGain;
    }
    if (ok) return;
  }
  s.camera.light_gain = 1.0;
  s.lighting = LightingSpec{};
}

// The route, in a frame of its own (translated into the room later). Empty when it crosses itself.
std::optional<RouteSpec> draw_route(Draw& d, RouteShape shape) {
  RouteSpec r;
  r.shape = shape;
  const double length = d.u(2.0, 15.0);
  r.speed_mps = q(d.u(0.08, 0.3), 1000.0);
  r.acceleration_mps2 = q(d.u(0.1, 0.4), 1000.0);
  r.pause_s = q(d.u(0.3, 1.5), 100.0);
  r.wander_m = q(d.u(0.0, 0.02), 1e4);
  // Every place at least twice in the training run: forth and back, or twice round a loop
  // (the trainer checks each frame against the other passes).
  r.laps = shape == RouteShape::kLoop ? 2 : 1;
  if (r.shape == RouteShape::kLoop) {
    // A perturbed ellipse, either way round.
    const double aspect = d.u(1.5, 3.5);
    const int n = d.i(8, 12);
    const double turn = d.chance(0.5) ? 1.0 : -1.0;
    const double gamma = d.u(0.0, kPi);
    for (int k = 0; k < n; ++k) {
      const double th = turn * (2.0 * kPi * k / n + d.u(-0.2, 0.2) * 2.0 * kPi / n);
      const double rad = 1.0 + d.u(-0.08, 0.08);
      const double x = aspect * std::cos(th) * rad, y = std::sin(th) * rad;
      r.waypoints_m.push_back(
          {x * std::cos(gamma) - y * std::sin(gamma), x * std::sin(gamma) + y * std::cos(gamma)});
    }
  } else {
    const int n = d.i(3, 6);
    double th = d.u(0.0, 2.0 * kPi), x = 0.0, y = 0.0;
    r.waypoints_m.push_back({x, y});
    for (int k = 1; k < n; ++k) {
      th += d.u(-0.5, 0.5);
      x += std::cos(th);
      y += std::sin(th);
      r.waypoints_m.push_back({x, y});
    }
  }
  const double scale = length / route_length_m(r);
  for (auto& w : r.waypoints_m) w = {w[0] * scale, w[1] * scale};
  if (route_crosses_itself(r)) return std::nullopt;
  return r;
}

// The room around the route (1 to 2.5 m beyond it on every side), the route moved into it, and
// maybe a desk against the far wall (y max).
void draw_room(Draw& d, Scenario& s) {
  const auto curve = route_curve(s.route, 0.05);
  double x0 = 1e9, x1 = -1e9, y0 = 1e9, y1 = -1e9;
  for (const auto& p : curve) {
    x0 = std::min(x0, p[0]);
    x1 = std::max(x1, p[0]);
    y0 = std::min(y0, p[1]);
    y1 = std::max(y1, p[1]);
  }
  const double left = d.u(kRouteWallMargin_m, 2.5), right = d.u(kRouteWallMargin_m, 2.5);
  const double front = d.u(kRouteWallMargin_m, 2.5), back = d.u(kRouteWallMargin_m, 2.5);
  // Whole millimetres keep the route's points exact when moved.
  const double dx = q(left - x0, 1000.0), dy = q(front - y0, 1000.0);
  for (auto& w : s.route.waypoints_m) w = {q(w[0] + dx, 1000.0), q(w[1] + dy, 1000.0)};
  RoomSpec& room = s.room;
  room.x_m = {0.0, q(x1 - x0 + left + right, 100.0)};
  room.y_m = {0.0, q(y1 - y0 + front + back, 100.0)};
  room.height_m = q(d.u(2.4, 3.2), 100.0);
  const double wall_hue = d.u(0.0, 360.0);
  room.wall_colour = grey(wall_hue, d.u(4.0, 28.0), d.u(150.0, 225.0));
  room.side_wall_colour = grey(wall_hue + d.u(-25.0, 25.0), d.u(4.0, 28.0), d.u(140.0, 220.0));
  room.ceiling_colour = grey(d.u(0.0, 360.0), d.u(0.0, 12.0), d.u(200.0, 235.0));
  const double floor_hue = d.u(0.0, 360.0), floor_s = d.u(4.0, 30.0), floor_v = d.u(110.0, 170.0);
  room.floor_colour = grey(floor_hue, floor_s, floor_v);
  room.floor_tile_colour = grey(floor_hue, floor_s, floor_v * d.u(0.8, 0.94));
  room.tile_m = d.chance(0.3) ? 0.0 : q(d.u(0.25, 0.6), 100.0);
  // A desk against the wall at y max, where the route keeps 0.5 m from it.
  DeskSpec& desk = s.desk;
  desk.present = false;
  if (d.chance(0.3)) {
    const double width = std::min(d.u(1.2, 2.4), room.x_m[1] - 0.4);
    desk.x_m[0] = q(d.u(0.2, room.x_m[1] - width - 0.2), 1000.0);
    desk.x_m[1] = q(desk.x_m[0] + width, 1000.0);
    desk.front_y_m = q(room.y_m[1] - d.u(0.6, 0.8), 1000.0);
    desk.height_m = q(d.u(0.72, 0.78), 1000.0);
    const double hue = d.u(15.0, 45.0), sat = d.u(10.0, 35.0), val = d.u(90.0, 140.0);
    desk.colour = grey(hue, sat, val);
    desk.top_colour = grey(hue, sat, std::min(230.0, val * 1.25));
    bool clear = true;
    for (const auto& p : route_curve(s.route, 0.05)) {
      if (p[0] > desk.x_m[0] - 0.5 && p[0] < desk.x_m[1] + 0.5 && p[1] > desk.front_y_m - 0.5)
        clear = false;
    }
    desk.present = clear;
  }
}

void draw_robot(Draw& d, Scenario& s) {
  s.robot.wheel_radius_m = q(d.u(0.03, 0.10), 1e4);
  s.robot.track_m = q(d.u(0.15, 0.50), 1e4);
  s.robot.ticks_per_rev = std::round(std::exp(d.u(std::log(360.0), std::log(8192.0))));
  s.robot.left_direction = s.robot.right_direction = 1;
  EncoderSpec& e = s.encoders;
  e.rate_hz = d.i(20, 200);
  e.slip_sigma = q(d.u(0.005, 0.02), 1e5);
  e.left_scale_error = q(d.u(-0.005, 0.005), 1e5);
  e.right_scale_error = q(d.u(-0.005, 0.005), 1e5);
  const int bits = d.chance(0.5) ? 16 : 32;
  const std::uint32_t mask = bits == 16 ? 0xFFFFU : 0xFFFFFFFFU;
  e.initial_left = d.bits() & mask;
  e.initial_right = d.bits() & mask;
  algorithms::EncoderFrameLayout& l = s.can_layout;
  l.counter_bits = static_cast<std::uint8_t>(bits);
  const auto bytes = static_cast<std::uint8_t>(bits / 8);
  l.left_offset = 0;
  l.right_offset = bytes;
  l.length = static_cast<std::uint8_t>(2 * bytes);
}

}  // namespace harmoloc::sim_host::random_scene_detail
