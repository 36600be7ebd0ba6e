#include "harmoloc/sim_host/random_scene.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "harmoloc/algorithms/geometry.hpp"
#include "harmoloc/algorithms/random.hpp"
#include "harmoloc/dataset/toml_writer.hpp"
#include "harmoloc/sim_host/lens.hpp"
#include "harmoloc/sim_host/route.hpp"
#include "harmoloc/sim_host/scenario_run.hpp"
#include "harmoloc/sim_host/scene_renderer.hpp"

namespace harmoloc::sim_host {

using algorithms::kPi;
using algorithms::Pcg32;
using algorithms::Pose2;

namespace {

constexpr double kDeg = kPi / 180.0;
constexpr int kMaxAttempts = 500;
constexpr double kCheckStep_m = 0.25;
constexpr std::uint32_t kProxyWidth_px = 320;
constexpr double kWallGap_m = 0.02;         // a wall board's face stands this far off the wall
constexpr double kStandClearance_m = 0.6;   // a stand keeps this far from the route
constexpr double kRouteWallMargin_m = 1.0;  // the route keeps this far from the walls
// The lighting the family allows over a run (and thresholds_for is set for): +-30%.
constexpr double kMinGain = 0.7;
constexpr double kMaxGain = 1.3;
// Stream numbers of the random draws (Pcg32's second argument).
constexpr std::uint64_t kAttemptStream = 1000;
constexpr std::uint64_t kKindStream = 999;
constexpr std::uint64_t kLightingStream = 77;
constexpr std::uint64_t kVariantStream = 91;

// Rounded to 1 / @p per_unit (a decimal that reads back as the same double).
double q(double x, double per_unit) {
  return std::round(x * per_unit) / per_unit;
}

class Draw {
 public:
  explicit Draw(Pcg32& rng) : rng_(rng) {}
  double u(double lo, double hi) { return rng_.uniform(lo, hi); }
  /// Whole number in [lo, hi].
  int i(int lo, int hi) {
    return lo +
           static_cast<int>(std::min<double>(hi - lo, std::floor(rng_.uniform() * (hi - lo + 1))));
  }
  bool chance(double p) { return rng_.uniform() < p; }
  std::uint32_t bits() { return rng_.next_u32(); }

 private:
  Pcg32& rng_;
};

Rgb hsv_to_rgb(double hue_deg, double s, double v) {
  hue_deg = std::fmod(std::fmod(hue_deg, 360.0) + 360.0, 360.0);
  const double c = v * s;
  const double x = c * (1.0 - std::fabs(std::fmod(hue_deg / 60.0, 2.0) - 1.0));
  const double m = v - c;
  double r = 0, g = 0, b = 0;
  switch (static_cast<int>(hue_deg / 60.0)) {
    case 0:
      r = c, g = x;
      break;
    case 1:
      r = x, g = c;
      break;
    case 2:
      g = c, b = x;
      break;
    case 3:
      g = x, b = c;
      break;
    case 4:
      r = x, b = c;
      break;
    default:
      r = c, b = x;
      break;
  }
  const auto byte = [m](double t) {
    return static_cast<std::uint8_t>(std::clamp(std::lround(t + m), 0L, 255L));
  };
  return Rgb{byte(r), byte(g), byte(b)};
}

// A desaturated colour: 8-bit HSV saturation s8, value v8.
Rgb grey(double hue_deg, double s8, double v8) {
  return hsv_to_rgb(hue_deg, s8 / 255.0, v8);
}

double saturation_of(const Rgb& c) {
  double h = 0, s = 0, v = 0;
  hsv_of(c, h, s, v);
  return s;
}

std::string hue_name(double h) {
  struct Band {
    double upto;
    const char* name;
  };
  static const Band bands[] = {{12, "red"},     {40, "orange"},   {68, "yellow"}, {100, "lime"},
                               {150, "green"},  {190, "cyan"},    {225, "azure"}, {255, "blue"},
                               {285, "violet"}, {320, "magenta"}, {345, "pink"},  {361, "crimson"}};
  for (const Band& b : bands) {
    if (h < b.upto) return b.name;
  }
  return "red";
}

// Where the camera would be along the route: the route's own places every kCheckStep_m with the
// heading of the curve (driven forward; a shuttle's way back is the same places reversing).
std::vector<Pose2> route_places(const RouteSpec& route) {
  const auto pts = route_curve(route, kCheckStep_m);
  std::vector<Pose2> out;
  const bool loop = route.shape == RouteShape::kLoop;
  const std::size_t n = loop ? pts.size() - 1 : pts.size();  // a loop's last point is its first
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t a = i == 0 ? (loop ? pts.size() - 2 : 0) : i - 1;
    const std::size_t b = i + 1 < pts.size() ? i + 1 : i;
    const double yaw = std::atan2(pts[b][1] - pts[a][1], pts[b][0] - pts[a][0]);
    out.push_back(Pose2{pts[i][0], pts[i][1], yaw});
  }
  return out;
}

// The scene with its camera scaled to kProxyWidth_px (same field, lens and aspect): the
// feasibility check and the board placement look through it.
Scenario proxy_of(const Scenario& s) {
  Scenario p = s;
  CameraSpec& c = p.camera;
  const double scale = static_cast<double>(kProxyWidth_px) / c.width_px;
  c.height_px =
      std::max<std::uint32_t>(16, static_cast<std::uint32_t>(std::lround(c.height_px * scale)));
  c.width_px = kProxyWidth_px;
  c.principal_offset_x_px *= scale;
  c.principal_offset_y_px *= scale;
  p.occluders.clear();
  p.board_moves.clear();
  p.kidnaps = KidnapSpec{};
  return p;
}

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

// ---- drawing a scene ---------------------------------------------------------------------------

struct Wall {
  double x0, y0, x1, y1;  // along the wall
  double nx, ny;          // into the room
};

std::vector<Wall> walls_of(const RoomSpec& r) {
  return {{r.x_m[0], r.y_m[0], r.x_m[1], r.y_m[0], 0.0, 1.0},
          {r.x_m[0], r.y_m[1], r.x_m[1], r.y_m[1], 0.0, -1.0},
          {r.x_m[0], r.y_m[0], r.x_m[0], r.y_m[1], 1.0, 0.0},
          {r.x_m[1], r.y_m[0], r.x_m[1], r.y_m[1], -1.0, 0.0}};
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

// ---- board placement ---------------------------------------------------------------------------

// The view of the route the placement works with: the proxy camera at the route's places.
struct Views {
  Scenario proxy;
  LensModel lens;
  std::vector<Pose2> places;
  std::vector<CameraFrame> frames;
  double frame_px = 0.0;
  double usable_px = 0.0;
  double focal_px = 0.0;
  double half_vfov_rad = 0.0;
  double half_hfov_rad = 0.0;  // of the true view (with the lens) across the width
};

Views views_of(const Scenario& s) {
  Views v;
  v.proxy = proxy_of(s);
  v.lens = LensModel(v.proxy.camera);
  v.places = route_places(s.route);
  for (const Pose2& p : v.places) v.frames.push_back(camera_frame_of(v.proxy.camera, p));
  const CameraSpec& c = v.proxy.camera;
  v.frame_px = static_cast<double>(c.width_px) * c.height_px;
  v.usable_px = std::max(60.0, kUsableBoardShare * v.frame_px);
  const Intrinsics in = intrinsics_of(c);
  v.focal_px = in.focal_px;
  double x = 0, y = 0;
  v.half_hfov_rad = v.lens.undistort(0.5 * c.width_px / in.focal_px, 0.0, x, y)
                        ? std::atan(x)
                        : std::atan(v.lens.max_radius());
  v.half_vfov_rad = v.lens.undistort(0.0, 0.5 * c.height_px / in.focal_px, x, y)
                        ? std::atan(y)
                        : std::atan(v.lens.max_radius());
  return v;
}

// The area of polygon (x, y) clipped to the rectangle [0, w] x [0, h] (Sutherland-Hodgman).
double clipped_area(std::vector<std::array<double, 2>> poly, double w, double h) {
  const auto clip = [&poly](int axis, double bound, bool keep_below) {
    std::vector<std::array<double, 2>> out;
    const auto in = [&](const std::array<double, 2>& p) {
      return keep_below ? p[static_cast<std::size_t>(axis)] <= bound
                        : p[static_cast<std::size_t>(axis)] >= bound;
    };
    for (std::size_t i = 0; i < poly.size(); ++i) {
      const auto& a = poly[i];
      const auto& b = poly[(i + 1) % poly.size()];
      if (in(a)) out.push_back(a);
      if (in(a) != in(b)) {
        const auto ax = static_cast<std::size_t>(axis);
        const double t = (bound - a[ax]) / (b[ax] - a[ax]);
        out.push_back({a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])});
      }
    }
    poly = std::move(out);
  };
  clip(0, 0.0, false);
  clip(0, w, true);
  clip(1, 0.0, false);
  clip(1, h, true);
  double area = 0.0;
  for (std::size_t k = 0; k < poly.size(); ++k) {
    const auto& a = poly[k];
    const auto& b = poly[(k + 1) % poly.size()];
    area += a[0] * b[1] - b[0] * a[1];
  }
  return 0.5 * std::fabs(area);
}

// A board's approximate area (pixels) from the camera at @p f: its outline's corners projected
// through the lens, clipped to the frame; 0 unless it faces the camera and every corner projects.
double approx_area(const Views& v, const CameraFrame& f, const BoardSpec& b) {
  const double cy = std::cos(b.facing_yaw_rad), sy = std::sin(b.facing_yaw_rad);
  const double ct = std::cos(b.tilt_rad), st = std::sin(b.tilt_rad);
  const double n[3] = {cy * ct, sy * ct, st};
  const double c[3] = {b.centre_x_m, b.centre_y_m, b.centre_z_m};
  const double to_cam =
      (f.origin[0] - c[0]) * n[0] + (f.origin[1] - c[1]) * n[1] + (f.origin[2] - c[2]) * n[2];
  if (to_cam <= 0.05) return 0.0;
  const double u[3] = {-sy, cy, 0.0}, w[3] = {-cy * st, -sy * st, ct};
  const CameraSpec& cam = v.proxy.camera;
  std::vector<std::array<double, 2>> quad(4);
  const double su[4] = {-1, 1, 1, -1}, sv[4] = {-1, -1, 1, 1};
  for (std::size_t k = 0; k < 4; ++k) {
    double p[3];
    for (int i = 0; i < 3; ++i)
      p[i] = c[i] + su[k] * 0.5 * b.width_m * u[i] + sv[k] * 0.5 * b.height_m * w[i];
    if (!project_point(cam, v.lens, f, p, quad[k][0], quad[k][1])) return 0.0;
  }
  const double area = clipped_area(quad, cam.width_px, cam.height_px);
  return b.shape == BoardShape::kEllipse ? area * kPi / 4.0 : area;
}

double bounding_radius(const BoardSpec& b) {
  return 0.5 * std::hypot(b.width_m, b.height_m);
}

// A candidate board in view of place @p k: on the wall ahead, or on a stand in front of it.
std::optional<BoardSpec> candidate(Draw& d, const Scenario& s, const Views& v, std::size_t k,
                                   const std::vector<BoardSpec>& placed) {
  BoardSpec b{};
  b.width_m = q(d.u(0.15, 0.6), 1000.0);
  b.height_m = q(std::clamp(b.width_m * d.u(0.6, 1.6), 0.15, 0.6), 1000.0);
  b.shape = d.chance(0.4) ? BoardShape::kEllipse : BoardShape::kRectangle;
  const Pose2& place = v.places[k];
  const CameraFrame& f = v.frames[k];
  const double ox = f.origin[0], oy = f.origin[1];
  const double dir = place.yaw_rad + d.u(-0.6, 0.6) * v.half_hfov_rad;
  const double dx = std::cos(dir), dy = std::sin(dir);
  // The farthest a board of this size stays usable (3 times the usable area, seen head-on).
  const double fill = b.shape == BoardShape::kEllipse ? kPi / 4.0 : 1.0;
  const double reach = v.focal_px * std::sqrt(b.width_m * b.height_m * fill / (3.0 * v.usable_px));
  // The wall ahead.
  double wall_t = 1e9;
  const Wall* wall = nullptr;
  const std::vector<Wall> walls = walls_of(s.room);
  for (const Wall& w : walls) {
    const double denom = dx * w.nx + dy * w.ny;
    if (denom >= -1e-9) continue;
    const double t = ((w.x0 - ox) * w.nx + (w.y0 - oy) * w.ny) / denom;
    if (t > 0.0 && t < wall_t) {
      wall_t = t;
      wall = &w;
    }
  }
  if (wall == nullptr || reach < 0.8) return std::nullopt;
  const bool on_wall = wall_t <= reach && d.chance(0.7);
  double cx = 0, cy = 0, facing = 0, horizontal = 0;
  if (on_wall) {
    const double hx = ox + wall_t * dx, hy = oy + wall_t * dy;
    const double normal = std::atan2(wall->ny, wall->nx);
    const double to_cam = std::atan2(oy - hy, ox - hx);
    const double turn =
        std::clamp(algorithms::wrap_angle_rad(to_cam - normal) + d.u(-5.0, 5.0) * kDeg,
                   -20.0 * kDeg, 20.0 * kDeg);
    facing = normal + turn;
    const double off = kWallGap_m + 0.5 * b.width_m * std::fabs(std::sin(turn)) + 0.01;
    cx = hx + wall->nx * off;
    cy = hy + wall->ny * off;
    // Wholly on its wall, clear of the corners.
    const double along = wall->nx != 0.0 ? cy : cx;
    const double lo = wall->nx != 0.0 ? s.room.y_m[0] : s.room.x_m[0];
    const double hi = wall->nx != 0.0 ? s.room.y_m[1] : s.room.x_m[1];
    if (along - 0.5 * b.width_m < lo + 0.1 || along + 0.5 * b.width_m > hi - 0.1)
      return std::nullopt;
    horizontal = wall_t;
  } else {
    const double most = std::min(reach, wall_t - 0.4);
    if (most < 0.9) return std::nullopt;
    horizontal = d.u(0.9, most);
    cx = ox + horizontal * dx;
    cy = oy + horizontal * dy;
    facing = std::atan2(oy - cy, ox - cx) + d.u(-20.0, 20.0) * kDeg;
    b.stand = true;
  }
  // Height: within the middle of the view from that place, on the wall or stand's range.
  const double pitch = s.camera.pitch_deg * kDeg;
  const double elevation = pitch + d.u(-0.5, 0.5) * v.half_vfov_rad;
  double z = s.camera.height_m + horizontal * std::tan(elevation);
  const double half_h = 0.5 * b.height_m;
  double z_lo = half_h + 0.05, z_hi = s.room.height_m - half_h - 0.1;
  if (b.stand) z_hi = std::min(z_hi, 1.8);
  if (on_wall && s.desk.present && wall->ny < 0.0 && cx + 0.5 * b.width_m > s.desk.x_m[0] - 0.05 &&
      cx - 0.5 * b.width_m < s.desk.x_m[1] + 0.05)
    z_lo = std::max(z_lo, s.desk.height_m + half_h + 0.05);  // above the desk
  if (z_lo > z_hi) return std::nullopt;
  z = std::clamp(z, z_lo, z_hi);
  // A slight tilt now and then, towards the camera's height.
  if (d.chance(0.3)) {
    const double tilt =
        std::clamp(std::atan2(s.camera.height_m - z, horizontal), -10.0 * kDeg, 10.0 * kDeg);
    b.tilt_rad = q(tilt / kDeg, 10.0) * kDeg;
  }
  b.centre_x_m = q(cx, 1000.0);
  b.centre_y_m = q(cy, 1000.0);
  b.centre_z_m = q(z, 1000.0);
  b.facing_yaw_rad = q(algorithms::wrap_angle_rad(facing) / kDeg, 10.0) * kDeg;
  // Clear of the other boards, the walls (a stand), the desk and the route.
  const double radius = bounding_radius(b);
  for (const BoardSpec& o : placed) {
    const double gap = std::sqrt(std::pow(o.centre_x_m - b.centre_x_m, 2) +
                                 std::pow(o.centre_y_m - b.centre_y_m, 2) +
                                 std::pow(o.centre_z_m - b.centre_z_m, 2));
    if (gap < radius + bounding_radius(o) + 0.05) return std::nullopt;
  }
  if (b.stand) {
    if (cx < s.room.x_m[0] + radius + 0.1 || cx > s.room.x_m[1] - radius - 0.1 ||
        cy < s.room.y_m[0] + radius + 0.1 || cy > s.room.y_m[1] - radius - 0.1)
      return std::nullopt;
    if (s.desk.present && cx > s.desk.x_m[0] - radius && cx < s.desk.x_m[1] + radius &&
        cy > s.desk.front_y_m - radius)
      return std::nullopt;
    for (const Pose2& p : v.places) {
      if (std::hypot(p.x_m - cx, p.y_m - cy) < kStandClearance_m + radius) return std::nullopt;
    }
  }
  return b;
}

// Places @p count boards greedily: each where it serves the places with the fewest boards in view
// best (by the approximate areas). Empty when some place is left with fewer than 2.
std::optional<std::vector<BoardSpec>> place_boards(Draw& d, const Scenario& s, const Views& v,
                                                   int count) {
  constexpr int kCandidates = 30;
  const std::size_t n = v.places.size();
  std::vector<int> cover(n, 0);
  std::vector<BoardSpec> boards;
  std::vector<char> sees(n), best_sees(n);
  // @p count boards, and more (up to 8) while some place sees fewer than 2.
  for (int b = 0; b < count || (b < 8 && *std::min_element(cover.begin(), cover.end()) < 2); ++b) {
    const int least = *std::min_element(cover.begin(), cover.end());
    std::vector<std::size_t> needy;
    for (std::size_t k = 0; k < n; ++k) {
      if (cover[k] == least) needy.push_back(k);
    }
    double best_score = 0.0;
    std::optional<BoardSpec> best;
    for (int c = 0; c < kCandidates; ++c) {
      const std::size_t k =
          needy[static_cast<std::size_t>(d.i(0, static_cast<int>(needy.size()) - 1))];
      const std::optional<BoardSpec> cand = candidate(d, s, v, k, boards);
      if (!cand) continue;
      double score = 0.0;
      bool too_big = false;
      for (std::size_t j = 0; j < n; ++j) {
        const double area = approx_area(v, v.frames[j], *cand);
        too_big = too_big || area > 0.3 * v.frame_px;
        sees[j] = area >= 2.0 * v.usable_px ? 1 : 0;
        if (sees[j])
          score += cover[j] == 0 ? 100.0 : cover[j] == 1 ? 30.0 : cover[j] == 2 ? 3.0 : 0.3;
      }
      if (too_big || score <= best_score) continue;
      best_score = score;
      best = cand;
      best_sees = sees;
    }
    if (!best) return std::nullopt;
    for (std::size_t j = 0; j < n; ++j) cover[j] += best_sees[j];
    boards.push_back(*best);
  }
  if (*std::min_element(cover.begin(), cover.end()) < 2) return std::nullopt;
  return boards;
}

// Hues spread evenly round the circle from a random start (jittered by up to 10% of the
// spacing), assigned in random order; saturated colours.
void colour_boards(Draw& d, std::vector<BoardSpec>& boards) {
  const std::size_t n = boards.size();
  const double spacing = 360.0 / static_cast<double>(n);
  const double start = d.u(0.0, 360.0);
  std::vector<double> hues;
  for (std::size_t k = 0; k < n; ++k)
    hues.push_back(std::fmod(
        start + static_cast<double>(k) * spacing + d.u(-0.1, 0.1) * spacing + 360.0, 360.0));
  for (std::size_t k = n; k > 1; --k)
    std::swap(hues[k - 1], hues[static_cast<std::size_t>(d.i(0, static_cast<int>(k) - 1))]);
  std::vector<std::string> names;
  for (std::size_t k = 0; k < n; ++k) {
    boards[k].colour = hsv_to_rgb(hues[k], d.u(0.75, 1.0), d.u(165.0, 200.0));
    double h = 0, sat = 0, val = 0;
    hsv_of(boards[k].colour, h, sat, val);
    std::string name = hue_name(h);
    const auto same = std::count(names.begin(), names.end(), name);
    names.push_back(name);
    boards[k].name = same == 0 ? name : name + std::to_string(same + 1);
  }
}

// One attempt at a scene. The route's shape and the labels' kind are the seed's (drawn once
// from their own stream), so that redrawn attempts keep the family's mix.
std::optional<Scenario> draw_scene(std::uint64_t seed, Draw& d) {
  Scenario s;
  s.name = "random-" + std::to_string(seed);
  Pcg32 kind_rng(seed, kKindStream);
  const RouteShape shape = kind_rng.uniform() < 0.5 ? RouteShape::kLoop : RouteShape::kShuttle;
  s.labels_with_heading = kind_rng.uniform() < 0.5;
  const std::optional<RouteSpec> route = draw_route(d, shape);
  if (!route) return std::nullopt;
  s.route = *route;
  const bool loop = s.route.shape == RouteShape::kLoop;
  // A loop turns the camera all round: it takes a wider view and more boards to keep two in
  // view everywhere.
  draw_camera(d, loop ? 80.0 : 60.0, s.camera);
  draw_room(d, s);
  if (route_crosses_itself(s.route)) return std::nullopt;
  draw_robot(d, s);
  s.labelled_frames = 64;
  const Views v = views_of(s);
  const int count = loop ? d.i(6, 8) : d.i(3, 8);
  std::optional<std::vector<BoardSpec>> boards = place_boards(d, s, v, count);
  if (!boards) return std::nullopt;
  colour_boards(d, *boards);
  s.boards = std::move(*boards);
  draw_lighting(d, run_duration_s(s), s);
  return s;
}

std::string describe(const Scenario& s, int attempt, const FeasibilityReport& f) {
  std::ostringstream o;
  o.precision(3);
  const CameraSpec& c = s.camera;
  std::size_t ellipses = 0, stands = 0;
  for (const BoardSpec& b : s.boards) {
    ellipses += b.shape == BoardShape::kEllipse ? 1 : 0;
    stands += b.stand ? 1 : 0;
  }
  o << "random scene: " << (s.route.shape == RouteShape::kLoop ? "loop" : "shuttle") << " route "
    << route_length_m(s.route) << " m at " << s.route.speed_mps << " m/s in a "
    << s.room.x_m[1] - s.room.x_m[0] << " x " << s.room.y_m[1] - s.room.y_m[0] << " m room"
    << (s.desk.present ? " with a desk" : "") << "; " << s.boards.size() << " boards (" << ellipses
    << " ellipses, " << stands << " on stands); " << c.width_px << "x" << c.height_px << ", k1 "
    << c.k1 << ", noise " << c.pixel_noise << "; labels "
    << (s.labels_with_heading ? "with heading" : "yaw 0") << "; feasible at attempt " << attempt + 1
    << " (>= " << f.min_boards_in_view << " boards in view at " << f.points << " places, 3+ at "
    << std::lround(100.0 * f.share_with_three) << "%)";
  return o.str();
}

std::uint64_t name_hash(const std::string& text) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (const char c : text) {
    h ^= static_cast<unsigned char>(c);
    h *= 0x100000001b3ULL;
  }
  return h;
}

// Keeps the lighting steps at the same share of a run that now lasts @p to_s instead of @p from_s.
void stretch_lighting(Scenario& s, double from_s, double to_s) {
  for (auto& st : s.lighting.steps) st[0] = q(st[0] * to_s / from_s, 10.0);
}

}  // namespace

FeasibilityReport check_feasibility(const Scenario& s) {
  FeasibilityReport r;
  const Scenario proxy = proxy_of(s);
  const SceneRenderer renderer(proxy);
  const double frame_px =
      static_cast<double>(proxy.camera.width_px) * static_cast<double>(proxy.camera.height_px);
  const double usable = std::max(60.0, kUsableBoardShare * frame_px);
  const std::vector<Pose2> places = route_places(s.route);
  r.points = places.size();
  r.min_boards_in_view = s.boards.size();
  std::size_t three = 0;
  for (const Pose2& p : places) {
    const std::vector<std::uint32_t> counts = renderer.visible_board_pixels(p);
    std::size_t in_view = 0;
    for (const std::uint32_t c : counts) {
      in_view += c >= usable ? 1 : 0;
      r.max_board_share = std::max(r.max_board_share, c / frame_px);
    }
    r.min_boards_in_view = std::min(r.min_boards_in_view, in_view);
    three += in_view >= 3 ? 1 : 0;
  }
  r.share_with_three =
      places.empty() ? 0.0 : static_cast<double>(three) / static_cast<double>(places.size());
  std::ostringstream why;
  if (r.min_boards_in_view < 2) {
    why << "a place on the route sees only " << r.min_boards_in_view << " usable boards";
  } else if (r.max_board_share > kMaxBoardShare) {
    why << "a board fills " << std::lround(100.0 * r.max_board_share) << "% of the frame";
  }
  r.reason = why.str();
  r.feasible = r.reason.empty();
  return r;
}

Scenario random_scenario(std::uint64_t seed) {
  for (int attempt = 0; attempt < kMaxAttempts; ++attempt) {
    Pcg32 rng(seed, kAttemptStream + static_cast<std::uint64_t>(attempt));
    Draw d(rng);
    std::optional<Scenario> s = draw_scene(seed, d);
    if (!s) continue;
    const FeasibilityReport f = check_feasibility(*s);
    if (!f.feasible) continue;
    s->description = describe(*s, attempt, f);
    return *s;
  }
  throw std::runtime_error("random scene " + std::to_string(seed) + ": no feasible draw in " +
                           std::to_string(kMaxAttempts) + " attempts");
}

std::vector<std::pair<std::string, algorithms::ColourThreshold>> thresholds_for(const Scenario& s) {
  std::vector<std::pair<std::string, algorithms::ColourThreshold>> out;
  // Saturation: between the most saturated thing in the room that is not a board and the least
  // saturated board. People walking through are not counted (they come and go; the variants'
  // people are dressed at most as saturated as the walls), so that a scene and its derived runs
  // share one set of windows, and a map trained on the one serves the others.
  double room_s = 0.0;
  for (const Rgb& c : {s.room.floor_colour, s.room.floor_tile_colour, s.room.wall_colour,
                       s.room.side_wall_colour, s.room.ceiling_colour, Rgb{80, 80, 80}})
    room_s = std::max(room_s, saturation_of(c));
  if (s.desk.present)
    room_s = std::max({room_s, saturation_of(s.desk.colour), saturation_of(s.desk.top_colour)});
  double board_s = 255.0, board_v = 255.0;
  std::vector<double> hues;
  for (const BoardSpec& b : s.boards) {
    double h = 0, sat = 0, val = 0;
    hsv_of(b.colour, h, sat, val);
    hues.push_back(h);
    board_s = std::min(board_s, sat);
    board_v = std::min(board_v, val);
  }
  double sat_min = room_s + 0.45 * (board_s - room_s);
  sat_min = std::clamp(sat_min, std::min(room_s + 30.0, board_s - 30.0), board_s - 30.0);
  // Value: the darkest a board can look (its face turned away: 0.8; the vignetting's darkest
  // corner; the lighting at -30%), with room to spare for the noise.
  const double widest = widest_ray_rad(s.camera);
  const double vignette = 1.0 - s.camera.vignetting * (1.0 - std::pow(std::cos(widest), 4.0));
  const double darkest = board_v * 0.8 * vignette * kMinGain;
  const double value_min = std::max(15.0, std::floor(0.55 * darkest));
  for (std::size_t k = 0; k < s.boards.size(); ++k) {
    double gap = 180.0;
    for (std::size_t j = 0; j < hues.size(); ++j) {
      if (j != k) gap = std::min(gap, std::fabs(std::remainder(hues[k] - hues[j], 360.0)));
    }
    const double half = std::clamp(0.5 * gap - 4.0, 5.0, 20.0);
    double lo = hues[k] - half, hi = hues[k] + half;
    if (lo < 0.0) lo += 360.0;
    if (hi >= 360.0) hi -= 360.0;
    algorithms::ColourThreshold t;
    t.hue_min_deg = static_cast<float>(q(lo, 10.0));
    t.hue_max_deg = static_cast<float>(q(hi, 10.0));
    t.saturation_min = static_cast<std::uint8_t>(std::lround(sat_min));
    t.value_min = static_cast<std::uint8_t>(value_min);
    t.value_max = 255;
    out.emplace_back(s.boards[k].name, t);
  }
  return out;
}

algorithms::ThresholdSet threshold_set(
    const std::vector<std::pair<std::string, algorithms::ColourThreshold>>& windows) {
  algorithms::ThresholdSet set;
  set.count = std::min(windows.size(), algorithms::kMaxBoards);
  for (std::size_t k = 0; k < set.count; ++k) set.boards[k] = windows[k].second;
  return set;
}

std::string firmware_config_toml(const Scenario& s) {
  dataset::TomlWriter w("harmoloc firmware configuration for the simulated scene '" + s.name +
                        "' (docs/config-format.md):\nthe robot's nominal geometry, its encoder "
                        "frames and a colour window per board.");
  w.table("odometry")
      .set("wheel_radius_m", s.robot.wheel_radius_m)
      .set("track_m", s.robot.track_m)
      .set("ticks_per_rev", s.robot.ticks_per_rev);
  w.table("can")
      .set("encoder_id", s.can_layout.id)
      .set("length", int{s.can_layout.length})
      .set("left_offset", int{s.can_layout.left_offset})
      .set("right_offset", int{s.can_layout.right_offset})
      .set("counter_bits", int{s.can_layout.counter_bits});
  for (const auto& [name, t] : thresholds_for(s)) {
    toml::array hue;
    dataset::push_number(hue, dataset::decimal_of(t.hue_min_deg));
    dataset::push_number(hue, dataset::decimal_of(t.hue_max_deg));
    w.array_table("board")
        .set("name", name)
        .set("hue_deg", hue)
        .set("saturation_min", int{t.saturation_min})
        .set("value_min", int{t.value_min})
        .set("value_max", int{t.value_max});
  }
  return w.text();
}

Scenario with_other_lighting(const Scenario& s, std::uint64_t seed) {
  Scenario out = s;
  Pcg32 rng(seed, kLightingStream);
  Draw d(rng);
  draw_lighting(d, run_duration_s(out), out);
  out.name = s.name + "-light" + std::to_string(seed);
  return out;
}

Scenario long_variant(const Scenario& s, double minutes) {
  Scenario out = s;
  const double before = run_duration_s(s);
  out.route.laps = 1;
  while (run_duration_s(out) < minutes * 60.0 && out.route.laps < 100000) ++out.route.laps;
  stretch_lighting(out, before, run_duration_s(out));
  out.name = s.name + "-long";
  out.description = s.description + "; driven " + std::to_string(out.route.laps) + " laps";
  return out;
}

Scenario kidnap_variant(const Scenario& s, int kidnaps) {
  if (kidnaps < 1) throw std::runtime_error("kidnap_variant: at least 1 kidnap");
  Scenario out = s;
  out.name = s.name + "-kidnap";
  out.occluders.clear();
  out.board_moves.clear();
  // The route's span: kidnaps keep 1 m, or half the span on routes too small for that.
  const auto curve = route_curve(s.route, 0.05);
  double span = 0.0;
  for (std::size_t i = 0; i < curve.size(); i += 2) {
    for (std::size_t j = i + 1; j < curve.size(); j += 2)
      span = std::max(span, std::hypot(curve[i][0] - curve[j][0], curve[i][1] - curve[j][1]));
  }
  out.kidnaps.count = kidnaps;
  out.kidnaps.min_distance_m = q(std::min(1.0, 0.5 * span), 100.0);
  const double before = run_duration_s(s);
  // Try schedules about 15 s apart (the robot needs time to recover between kidnaps) until one
  // works for a few runs of the scene (the kidnap planner throws when none does).
  static const double intervals[] = {15, 14, 16, 13, 17, 12, 18, 20, 22, 25, 30, 11, 10};
  static const double firsts[] = {15, 12, 18, 10, 20, 25, 30};
  std::string last_error;
  for (const double interval : intervals) {
    for (const double first : firsts) {
      out.kidnaps.first_s = first;
      out.kidnaps.interval_s = interval;
      out.route.laps = 1;
      const double need = first + (kidnaps - 1) * interval + 30.0;
      while (run_duration_s(out) < need && out.route.laps < 100000) ++out.route.laps;
      bool ok = true;
      for (std::uint64_t seed = 1; seed <= 3 && ok; ++seed) {
        try {
          Pcg32 motion_rng(seed, 1), kidnap_rng(seed, 5);
          simulate_motion(out, ScenarioRun::kMotionStep_s, motion_rng, nullptr, &kidnap_rng);
        } catch (const std::runtime_error& e) {
          ok = false;
          last_error = e.what();
        }
      }
      if (!ok) continue;
      stretch_lighting(out, before, run_duration_s(out));
      std::ostringstream desc;
      desc << s.description << "; " << kidnaps << " kidnaps (>= " << out.kidnaps.min_distance_m
           << " m) every " << interval << " s from " << first << " s, " << out.route.laps
           << " laps";
      out.description = desc.str();
      return out;
    }
  }
  throw std::runtime_error(s.name + ": no kidnap schedule fits this route (" + last_error + ")");
}

Scenario dynamic_variant(const Scenario& s) {
  Scenario out = s;
  out.name = s.name + "-dynamic";
  out.occluders.clear();
  out.board_moves.clear();
  out.kidnaps = KidnapSpec{};
  const double before = run_duration_s(s);
  out.route.laps = std::max(2, s.route.laps);
  const double duration = run_duration_s(out);
  stretch_lighting(out, before, duration);
  Pcg32 rng(name_hash(s.name), kVariantStream);
  Draw d(rng);
  const ScenarioRun run(out, 1);
  const Scenario proxy = proxy_of(out);
  const auto curve = route_curve(out.route, 0.05);
  const auto clear_of_route = [&](double x, double y, double margin) {
    for (const auto& p : curve) {
      if (std::hypot(p[0] - x, p[1] - y) < margin) return false;
    }
    return true;
  };
  const RoomSpec& room = out.room;
  const auto inside = [&](double x, double y, double margin) {
    return x > room.x_m[0] + margin && x < room.x_m[1] - margin && y > room.y_m[0] + margin &&
           y < room.y_m[1] - margin;
  };
  // The person: stands 3.5 s on the line of sight to a board well in view, near the board (so
  // that the board stays hidden while the robot moves on), clear of the route; walks in and out
  // at 1 m/s from 2.5 m to the side.
  constexpr double kStand_s = 3.5, kWalk_mps = 1.0, kAside_m = 2.5;
  bool placed = false;
  std::size_t hidden_board = out.boards.size();
  std::ostringstream what;
  const double fractions[] = {0.35, 0.45, 0.3, 0.5, 0.4, 0.25, 0.55, 0.6, 0.2, 0.65};
  for (int tries = 0; tries < 3 && !placed; ++tries) {
    for (const double fraction : fractions) {
      if (placed) break;
      const double t_mid = q(fraction * duration + d.u(-2.0, 2.0), 10.0);
      if (t_mid < 5.0 || t_mid > duration - 5.0) continue;
      const auto frame = static_cast<std::size_t>(std::lround(t_mid * out.camera.rate_hz));
      if (frame >= run.frame_count()) continue;
      SceneRenderer clean(proxy);
      clean.set_time(t_mid);
      const Pose2 pose = run.truth(frame);
      const std::vector<std::uint32_t> seen = clean.visible_board_pixels(pose);
      std::vector<std::size_t> order(seen.size());
      for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
      std::stable_sort(order.begin(), order.end(),
                       [&](std::size_t a, std::size_t b) { return seen[a] > seen[b]; });
      const CameraFrame cam = camera_frame_of(out.camera, pose);
      for (std::size_t rank = 0; rank < std::min<std::size_t>(3, order.size()) && !placed; ++rank) {
        const BoardSpec& board = out.boards[order[rank]];
        if (seen[order[rank]] < 150) break;
        const double bx = board.centre_x_m, by = board.centre_y_m;
        const double dist = std::hypot(cam.origin[0] - bx, cam.origin[1] - by);
        for (const double near : {0.6, 0.9, 0.45, 1.2}) {
          if (near > dist - 0.6) continue;
          const double ux = (cam.origin[0] - bx) / dist, uy = (cam.origin[1] - by) / dist;
          const double px = q(bx + near * ux, 1000.0), py = q(by + near * uy, 1000.0);
          if (!inside(px, py, 0.3) || !clear_of_route(px, py, 0.6)) continue;
          // Walk in from the side that stays in the room.
          double ex = px - uy * kAside_m, ey = py + ux * kAside_m;
          if (!inside(ex, ey, 0.3)) {
            ex = px + uy * kAside_m;
            ey = py - ux * kAside_m;
          }
          ex = q(std::clamp(ex, room.x_m[0] + 0.3, room.x_m[1] - 0.3), 1000.0);
          ey = q(std::clamp(ey, room.y_m[0] + 0.3, room.y_m[1] - 0.3), 1000.0);
          const double walk = q(std::hypot(ex - px, ey - py) / kWalk_mps, 10.0);
          const double t0 = q(t_mid - 0.4 * kStand_s, 10.0);
          OccluderSpec person;
          person.name = "person";
          person.colour = grey(d.u(200.0, 250.0), d.u(10.0, 30.0), d.u(70.0, 110.0));
          person.radius_m = q(d.u(0.2, 0.25), 1000.0);
          person.height_m = q(d.u(1.65, 1.85), 1000.0);
          person.path = {{q(t0 - walk, 10.0), ex, ey},
                         {t0, px, py},
                         {q(t0 + kStand_s, 10.0), px, py},
                         {q(t0 + kStand_s + walk, 10.0), ex, ey}};
          if (person.path.front()[0] < 0.0) continue;
          // Hidden (under 30% of its pixels) in every frame of 2.5 s while the person stands?
          Scenario trial = proxy;
          trial.occluders = {person};
          SceneRenderer with(trial), without(proxy);
          bool hidden = true;
          for (double t = t0 + 0.5; t <= t0 + 3.0 && hidden; t += 0.25) {
            const auto k = static_cast<std::size_t>(std::lround(t * out.camera.rate_hz));
            if (k >= run.frame_count()) {
              hidden = false;
              break;
            }
            with.set_time(t);
            without.set_time(t);
            const double a = with.visible_board_pixels(run.truth(k))[order[rank]];
            const double b = without.visible_board_pixels(run.truth(k))[order[rank]];
            hidden = b >= 50.0 && a <= 0.3 * b;
          }
          if (!hidden) continue;
          out.occluders.push_back(person);
          hidden_board = order[rank];
          what << "a person hides " << board.name << " from " << t0 << " s for " << kStand_s
               << " s";
          placed = true;
          break;
        }
      }
    }
  }
  if (!placed) throw std::runtime_error(s.name + ": no place for a person to hide a board");
  // A board moved 30 cm along its wall (a stand's: along its width) halfway through the run: the
  // one most often in view.
  std::vector<double> total(out.boards.size(), 0.0);
  {
    SceneRenderer clean(proxy);
    for (std::size_t k = 0; k < run.frame_count();
         k += std::max<std::size_t>(1, run.frame_count() / 40)) {
      const auto counts = clean.visible_board_pixels(run.truth(k));
      for (std::size_t b = 0; b < counts.size(); ++b) total[b] += counts[b];
    }
  }
  std::vector<std::size_t> order(total.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return total[a] > total[b]; });
  // Another board than the one the person hides, when there is one that can move.
  std::stable_partition(order.begin(), order.end(),
                        [&](std::size_t b) { return b != hidden_board; });
  bool moved = false;
  for (const std::size_t b : order) {
    const BoardSpec& board = out.boards[b];
    double ax = -std::sin(board.facing_yaw_rad), ay = std::cos(board.facing_yaw_rad);
    if (!board.stand) {
      // Along the nearest wall.
      const double to_x = std::min(board.centre_x_m - room.x_m[0], room.x_m[1] - board.centre_x_m);
      const double to_y = std::min(board.centre_y_m - room.y_m[0], room.y_m[1] - board.centre_y_m);
      ax = to_y < to_x ? 1.0 : 0.0;
      ay = to_y < to_x ? 0.0 : 1.0;
    }
    const double half = 0.5 * board.width_m + 0.1;
    const double first = d.chance(0.5) ? 1.0 : -1.0;
    for (const double sg : {first, -first}) {
      const double dx = q(0.3 * sg * ax, 1000.0), dy = q(0.3 * sg * ay, 1000.0);
      const double nx = board.centre_x_m + dx, ny = board.centre_y_m + dy;
      const bool fits =
          board.stand ? inside(nx, ny, half) && clear_of_route(nx, ny, kStandClearance_m + half)
                      : (ax != 0.0 ? nx > room.x_m[0] + half && nx < room.x_m[1] - half
                                   : ny > room.y_m[0] + half && ny < room.y_m[1] - half);
      if (!fits) continue;
      BoardMoveSpec m;
      m.board = board.name;
      m.at_s = q(0.55 * duration, 10.0);
      m.offset_m = {dx, dy, 0.0};
      out.board_moves.push_back(m);
      what << "; " << board.name << " moved 30 cm at " << m.at_s << " s";
      moved = true;
      break;
    }
    if (moved) break;
  }
  if (!moved) throw std::runtime_error(s.name + ": no board can move 30 cm along its wall");
  out.description = s.description + "; " + std::to_string(out.route.laps) + " laps; " + what.str();
  return out;
}

}  // namespace harmoloc::sim_host
