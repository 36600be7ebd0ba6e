#pragma once
/// @file A simulated scenario: the room, the landmark boards, the camera and its mount, the robot
/// and the route it repeats. Built-in scenarios are listed by `harmoloc-sim --list`; a scenario
/// file (TOML, docs/scenarios.md) starts from a built-in one and overrides what it names.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "harmoloc/algorithms/can_encoder_layout.hpp"
#include "harmoloc/algorithms/odometry.hpp"

namespace harmoloc::sim_host {

struct Rgb {
  std::uint8_t r, g, b;
};

enum class BoardShape : std::uint8_t {
  kRectangle = 0,
  kEllipse = 1,  ///< inscribed in width x height
};

/// A flat board facing the direction @p facing_yaw_rad (upright, or tilted about its horizontal
/// axis by @p tilt_rad), on a wall, on the desk or on a stand of its own.
struct BoardSpec {
  std::string name;
  Rgb colour;
  double centre_x_m, centre_y_m, centre_z_m;
  double width_m, height_m;
  double facing_yaw_rad;  ///< direction the coloured face looks at (map frame yaw)
  BoardShape shape = BoardShape::kRectangle;
  double tilt_rad = 0.0;  ///< about the board's horizontal axis; positive: the face looks upwards
  bool stand = false;     ///< on a thin grey pole from the floor up to its lower edge
};

struct CameraSpec {
  std::uint32_t width_px = 320;
  std::uint32_t height_px = 240;
  /// Of the undistorted pinhole, across the width: the focal length is
  /// 0.5 width_px / tan(horizontal_fov_deg / 2) pixels (the lens then widens the view).
  double horizontal_fov_deg = 76.0;
  /// OpenCV's lens model in normalised coordinates (x, y), r^2 = x^2 + y^2:
  ///   x_d = x (1 + k1 r^2 + k2 r^4 + k3 r^6) + 2 p1 x y + p2 (r^2 + 2 x^2)
  ///   y_d = y (1 + k1 r^2 + k2 r^4 + k3 r^6) + p1 (r^2 + 2 y^2) + 2 p2 x y
  /// Wu & Qin's x_d = x_u + k x_u r_u^2 is k1 = k with the others 0 (scenario files: radial_k).
  double k1 = -0.15;
  double k2 = 0.0;
  double k3 = 0.0;
  double p1 = 0.0;
  double p2 = 0.0;
  /// Principal point offset from the image centre ((width - 1) / 2, (height - 1) / 2), pixels.
  double principal_offset_x_px = 0.0;
  double principal_offset_y_px = 0.0;
  /// Relative illumination 1 - vignetting (1 - cos^4 theta), theta the angle between a pixel's
  /// ray and the optical axis (0: none; 1: the natural cos^4 fall-off).
  double vignetting = 0.0;
  double height_m = 0.35;          ///< optical centre above the floor
  double pitch_deg = 15.0;         ///< up is positive
  double mount_yaw_deg = 0.0;      ///< relative to the robot's forward axis
  double forward_offset_m = 0.10;  ///< ahead of the wheel axle centre
  double rate_hz = 30.0;
  double pixel_noise = 3.0;  ///< standard deviation per channel, 8-bit units
  double light_gain = 1.0;   ///< global brightness factor (lighting changes)
};

/// Brightness over the run: the camera's light_gain times (1 + drift_amplitude
/// sin(2 pi t / drift_period_s + drift_phase_deg)) times the gain of the last step at or before t
/// (1 before the first).
struct LightingSpec {
  double drift_amplitude = 0.0;
  double drift_period_s = 60.0;
  double drift_phase_deg = 0.0;
  std::vector<std::array<double, 2>> steps;  ///< [t_s, gain], t_s strictly increasing
};

/// The room: a box with the floor at z = 0 (tiled in two colours), four walls and a ceiling. The
/// robot drives inside it.
struct RoomSpec {
  std::array<double, 2> x_m{-0.6, 4.8};  ///< walls at x = x_m[0] and x_m[1]
  std::array<double, 2> y_m{-0.6, 3.0};  ///< walls at y = y_m[0] and y_m[1]
  double height_m = 2.6;                 ///< the ceiling
  Rgb floor_colour{112, 112, 108};
  Rgb floor_tile_colour{96, 96, 93};    ///< every other tile
  double tile_m = 0.3;                  ///< tile size; 0: a plain floor
  Rgb wall_colour{200, 198, 188};       ///< walls at y = const
  Rgb side_wall_colour{190, 190, 182};  ///< walls at x = const
  Rgb ceiling_colour{215, 215, 212};
};

/// A desk against the wall at y = room.y_m[1]: a box from x_m[0] to x_m[1], from its front face
/// at front_y_m to the wall, height_m high.
struct DeskSpec {
  bool present = true;
  std::array<double, 2> x_m{1.1, 3.3};
  double front_y_m = 2.4;
  double height_m = 0.75;
  Rgb colour{118, 84, 54};  ///< front face
  Rgb top_colour{150, 110, 70};
};

enum class RouteShape : std::uint8_t {
  /// Forward along the curve through the waypoints to the last one, then back in reverse (the
  /// camera keeps facing one way); a pause at each end. Forth and back is one lap.
  kShuttle = 0,
  /// A closed curve through the waypoints (back to the first), driven forward only, heading in
  /// the direction of travel, laps times round without stopping; a pause at the start and end.
  kLoop = 1,
  /// Poses visited in turn, as a floor's coverage run or a test run off any route is driven:
  /// from each waypoint the robot turns on the spot towards the next (or away from it, to
  /// reverse, whichever turns less overall), drives the straight leg, and turns on the spot to
  /// the waypoint's heading (heading_deg); a pause at the start and end. No wander. A tour may
  /// cross itself. Laps > 1 drive back to the first waypoint and repeat.
  kTour = 2,
};

struct RouteSpec {
  RouteShape shape = RouteShape::kShuttle;
  std::vector<std::array<double, 2>> waypoints_m;  ///< the robot's axle centre passes these
  double speed_mps = 0.10;
  double acceleration_mps2 = 0.10;
  double pause_s = 0.5;    ///< standstill at each end of the route (loop: at the start and end)
  int laps = 1;            ///< shuttle: forward then back is one lap; loop: once round
  double wander_m = 0.01;  ///< how far a run strays sideways from the route (smooth)
  /// kTour only: the heading at each waypoint (degrees, map frame), one per waypoint.
  std::vector<double> heading_deg;
  /// kTour only: how fast the robot turns on the spot (degrees per second, reached with the
  /// same ramp time as speed_mps).
  double turn_rate_dps = 45.0;
};

struct EncoderSpec {
  double rate_hz = 100.0;
  double slip_sigma = 0.01;         ///< random relative error of each wheel's travel, per step
  double left_scale_error = 0.003;  ///< systematic relative error (wheel radius mismatch)
  double right_scale_error = -0.002;
  std::uint32_t initial_left = 0;  ///< first counter values (set near the wrap to test wrap)
  std::uint32_t initial_right = 0;
};

/// Something that walks through the room, e.g. a person between the robot and the desk: an upright
/// cylinder standing on the floor that hides what is behind it.
struct OccluderSpec {
  std::string name = "person";
  Rgb colour{45, 45, 55};  ///< must not be a board colour (dark clothing); checked on load
  double radius_m = 0.22;
  double height_m = 1.75;
  /// Keyframes [t_s, x_m, y_m] (run time, strictly increasing), linear in between; the occluder
  /// is not in the room before the first keyframe or after the last.
  std::vector<std::array<double, 3>> path;
};

/// Someone moves a board during the run: from @p at_s on, the board stands @p offset_m further
/// (map frame) and is turned by @p turn_deg. Moves of one board add up.
struct BoardMoveSpec {
  std::string board;  ///< a board's name
  double at_s = 0.0;
  std::array<double, 3> offset_m{0.0, 0.0, 0.0};
  double turn_deg = 0.0;  ///< added to the board's facing
};

/// The robot is lifted and put down elsewhere on its route (a kidnap), @p count times: at run
/// times first_s + k interval_s, each new place at least @p min_distance_m from the old one.
/// On a tour the places are given (poses, one per kidnap): from each the robot drives on to the
/// waypoint it was heading for and on along its tour.
struct KidnapSpec {
  int count = 0;
  double first_s = 10.0;
  double interval_s = 8.0;
  double min_distance_m = 1.0;
  std::vector<std::array<double, 3>> poses;  ///< a tour's: [x, y, heading_deg] per kidnap
};

struct Scenario {
  std::string name;
  std::string description;
  RoomSpec room;
  DeskSpec desk;
  std::vector<BoardSpec> boards;
  CameraSpec camera;
  LightingSpec lighting;
  RouteSpec route;
  EncoderSpec encoders;
  algorithms::DiffDriveGeometry robot;
  algorithms::EncoderFrameLayout can_layout;
  int labelled_frames = 64;
  /// Labels carry the true heading (an overhead camera that sees the robot's heading), or yaw 0
  /// (a position-only reference, e.g. a total station, writes 0 for the heading it lacks).
  bool labels_with_heading = true;
  double start_time_s = 1767225600.0;  ///< 2026-01-01T00:00:00Z, as a recorder's epoch clock
  // Events: a world that misbehaves (docs/scenarios.md). None by default.
  std::vector<OccluderSpec> occluders;
  std::vector<BoardMoveSpec> board_moves;
  KidnapSpec kidnaps;
};

/// The brightness factor at run time @p t_s (camera.light_gain and the lighting's drift and steps).
double light_gain_at(const Scenario& scenario, double t_s);

/// Hue (degrees, 0..360), saturation and value (0..255) of a colour as the firmware's 8-bit HSV
/// segmentation sees them (before its 2-degree hue steps).
void hsv_of(const Rgb& colour, double& hue_deg, double& saturation, double& value);

/// Names and one-line descriptions of the built-in scenarios.
std::vector<std::pair<std::string, std::string>> builtin_scenarios();

/// A built-in scenario by name, or one loaded from a TOML file (when @p name_or_file names an
/// existing file). Throws std::runtime_error with one line on an unknown name or a bad file.
Scenario load_scenario(const std::string& name_or_file);

/// "10 kidnaps, 1 board move, 1 occluder", or "no events".
std::string describe_events(const Scenario& scenario);

/// The scenario as a TOML scenario file (what the simulator writes beside the dataset).
std::string scenario_to_toml(const Scenario& scenario);

}  // namespace harmoloc::sim_host
