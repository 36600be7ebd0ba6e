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

/// A flat rectangular board standing upright, facing the direction @p facing_yaw_rad.
struct BoardSpec {
  std::string name;
  Rgb colour;
  double centre_x_m, centre_y_m, centre_z_m;
  double width_m, height_m;
  double facing_yaw_rad;  ///< direction the coloured face looks at (map frame yaw)
};

struct CameraSpec {
  std::uint32_t width_px = 320;
  std::uint32_t height_px = 240;
  double horizontal_fov_deg = 76.0;  ///< of the undistorted pinhole, across the width
  /// Radial distortion of seed 000: x_d = x_u + k x_u (x_u^2 + y_u^2), normalised coordinates.
  double radial_k = -0.15;
  double height_m = 0.35;          ///< optical centre above the floor
  double pitch_deg = 15.0;         ///< up is positive
  double mount_yaw_deg = 0.0;      ///< relative to the robot's forward axis
  double forward_offset_m = 0.10;  ///< ahead of the wheel axle centre
  double rate_hz = 30.0;
  double pixel_noise = 3.0;  ///< standard deviation per channel, 8-bit units
  double light_gain = 1.0;   ///< global brightness factor (lighting changes)
};

struct RouteSpec {
  std::vector<std::array<double, 2>> waypoints_m;  ///< the robot's axle centre passes these
  double speed_mps = 0.10;
  double acceleration_mps2 = 0.10;
  double pause_s = 0.5;    ///< standstill at each end of the route
  int laps = 1;            ///< forward then back is one lap
  double wander_m = 0.01;  ///< how far a run strays sideways from the route (smooth)
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
struct KidnapSpec {
  int count = 0;
  double first_s = 10.0;
  double interval_s = 8.0;
  double min_distance_m = 1.0;
};

struct Scenario {
  std::string name;
  std::string description;
  double floor_length_m = 4.2;  ///< along x
  double floor_width_m = 2.4;   ///< along y
  double desk_front_y_m = 2.4;
  double desk_height_m = 0.75;
  double wall_y_m = 3.0;
  std::vector<BoardSpec> boards;
  CameraSpec camera;
  RouteSpec route;
  EncoderSpec encoders;
  algorithms::DiffDriveGeometry robot;
  algorithms::EncoderFrameLayout can_layout;
  int labelled_frames = 64;
  double start_time_s = 1767225600.0;  ///< 2026-01-01T00:00:00Z, as a recorder's epoch clock
  // Events: a world that misbehaves (docs/scenarios.md). None by default.
  std::vector<OccluderSpec> occluders;
  std::vector<BoardMoveSpec> board_moves;
  KidnapSpec kidnaps;
};

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
