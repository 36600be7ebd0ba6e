#pragma once
/// @file The firmware's configuration (TOML): cycle rate and budget, colour thresholds, robot
/// geometry, CAN frame layout, filter and link settings. Every field has a default; the
/// documented example is docs/examples/harmoloc.toml and the schema docs/config-format.md.

#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "harmoloc/algorithms/board_observation.hpp"
#include "harmoloc/algorithms/can_encoder_layout.hpp"
#include "harmoloc/algorithms/kidnap_detector.hpp"
#include "harmoloc/algorithms/nearby_pose_test.hpp"
#include "harmoloc/algorithms/odometry.hpp"
#include "harmoloc/algorithms/particle_filter.hpp"
#include "harmoloc/algorithms/segmentation.hpp"

namespace harmoloc::firmware {

/// What starts a cycle (firmware/cycle_pacer.hpp; docs/architecture.md, "Pacing and overruns").
enum class Pacing : std::uint8_t {
  kCamera,  ///< the arrival of a frame (acquire waits at most one period)
  kTimer,   ///< an absolute grid of the monotonic clock; the newest ready frame, or none
};

struct CycleConfig {
  double rate_hz = 30.0;
  double budget_ms = 15.0;            ///< compute budget per cycle; a cycle over it is an overrun
  double camera_timeout_ms = 250.0;   ///< no usable frame for this long: odometry only
  double encoder_timeout_ms = 250.0;  ///< no encoder data for this long: vision only
  Pacing pacing = Pacing::kCamera;
  /// This many overruns in a row raise the overrun alarm (STATUSTEXT, HEARTBEAT CRITICAL); as
  /// many cycles in a row within the budget clear it.
  std::uint32_t overrun_alarm_cycles = 3;
};

/// Whether the filter adapts its particle count by KLD-sampling (filter.kld).
enum class KldMode : std::uint8_t {
  kAuto,  ///< on for a floor map, off for a route map (kld_on)
  kOn,
  kOff,
};

struct FilterConfig {
  std::size_t particles = 1024;  ///< the capacity; with KLD-sampling the most it uses
  /// Adaptive particle count within `particles`: on for a floor map, where the 30-floor sweep
  /// backs it, off for a route map, where no sweep has yet (docs/filter.md). kld_on() decides;
  /// `kld.enabled` is set from it at start-up.
  KldMode kld_mode = KldMode::kAuto;
  algorithms::KldSampling kld;  ///< its parameters
  std::uint64_t seed = 1;
  algorithms::MotionNoise noise;
  /// Standard deviation given to each harmonic fix. Far above the localizer's own error (5-9 cm):
  /// 30 fixes a second share most of their error, so each must count as a small part of the
  /// evidence, or the particles collapse onto a wrong heading within the first centimetres.
  double fix_sigma_m = 0.4;
  double outlier_probability = 0.05;  ///< chance that a fix is wrong altogether
  double resample_threshold = 0.5;    ///< resample when N_eff < this fraction of particles
  double init_position_sigma_m = 0.05;
  double vision_only_speed_mps = 0.3;  ///< how fast the robot may move when odometry is missing
  /// How far beyond the mapped region (the box around the map's training positions and its
  /// forward map) a pose may lie and still be published as more than invalid.
  double map_margin_m = 1.0;
  /// A pose whose cloud spreads this far (the root of the mean of the x and y variances, as the
  /// published quality takes it: 0 at 10 cm) is not nominal: odometry only
  /// (HealthCause::kSpreadWide) until the spread is back under nominal_resume_spread_m. The
  /// boards then do not pin the pose to the map's accuracy, whatever the inputs' freshness says.
  double nominal_spread_m = 0.10;
  double nominal_resume_spread_m = 0.07;
  /// On a floor map with bearings (route terms off): the sequential test between the estimate
  /// and the best pose near it that draws particles there when the boards keep preferring it
  /// (algorithms/nearby_pose_test.hpp, docs/filter.md "The nearby pose test").
  bool nearby_test = true;
  algorithms::NearbyPoseParams nearby;
  /// On a floor map with bearings (route terms off): a seed (at start-up, after a kidnap) takes
  /// its heading from the boards' bearings at its place (algorithms/floor_search.hpp) with the
  /// kidnap's yaw spread, instead of the training run's mean heading there with the spread of
  /// its passes (docs/filter.md, "The seed's heading on a floor").
  bool seed_heading_from_boards = true;
  /// On a floor map with the floor search (kidnap.floor_search): the first seed waits, at most
  /// a second, for the search's first pass over the floor and starts half the cloud on its pose
  /// (as a floor kidnap's re-seed does) and half on the harmonic fix, init_position_sigma_m wide
  /// (docs/filter.md, "The first seed on a floor from the search"). Off: all of it around the
  /// first known-place fix.
  bool seed_from_search = true;
};

/// What the particles are weighed by.
enum class ObservationModel : std::uint8_t {
  kBoards,  ///< every board against the map's forward model (robust; needs a version 3 map)
  kFix,     ///< a Gaussian around the harmonic localizer's fix (maps without a forward model)
};

/// Whether the particles are held to the training run's passes (the route term and the route
/// heading term of BoardModelParams).
enum class RouteTerms : std::uint8_t {
  kAuto,  ///< on for a route map, off for a floor map (algorithms::is_floor_map)
  kOn,    ///< on, as configured, whatever the map
  kOff,   ///< off
};

/// Whether the harmonic fix weighs the particles besides the boards (observation.fix_term).
enum class FixTerm : std::uint8_t {
  kAuto,  ///< on for a route map, off for a floor map (fix_term_on)
  kOn,    ///< on, whatever the map
  kOff,   ///< off
};

struct ObservationConfig {
  ObservationModel model = ObservationModel::kBoards;
  RouteTerms route_terms = RouteTerms::kAuto;
  /// With the per-board model, also weigh the particles by the harmonic fix (a version 4 map's
  /// calibration gives its width).
  FixTerm fix_term = FixTerm::kAuto;
  /// Check the fix's boards one a frame by leaving each out (algorithms/fix_board_check.hpp);
  /// needs a version 4 map's calibration.
  bool fix_board_check = true;
  algorithms::BoardModelParams boards;
};

/// Where the particles go when the filter is re-seeded (a kidnap, the relocalize command).
enum class ReseedStrategy : std::uint8_t {
  kAroundFix,  ///< around the harmonic localizer's global fix (Yang et al. 2021 with our global
               ///< guess)
  kUniform,    ///< uniformly over the mapped region, any heading (AMCL-style; the baseline)
};

struct KidnapConfig {
  bool enabled = true;
  algorithms::KidnapParams detector;
  ReseedStrategy reseed = ReseedStrategy::kAroundFix;
  double position_sigma_m = 0.04;  ///< spread around the fix
  /// Spread of the heading around the training run's heading at the fix (uniform when the map
  /// has no heading).
  double yaw_sigma_deg = 15.0;
  /// On a floor map with bearings (route terms off): the evidence and the re-seed come from a
  /// search over the whole floor (algorithms/floor_search.hpp) instead of the harmonic fix, and
  /// the re-seed goes to its pose (and to the fix, where that is a known place apart from it).
  /// On since 2026-12-04: on the 30 random floors it held the position RMSE's median and cut its
  /// 90th percentile and worst scene, and brought back more kidnaps (docs/filter.md, "The floor
  /// search"). Off: the harmonic fix, as on a route.
  bool floor_search = true;
};

struct LinkConfig {
  std::uint8_t system_id = 1;
  std::uint8_t component_id = 197;  ///< MAV_COMP_ID_VISUAL_INERTIAL_ODOMETRY
  unsigned baud = 115200;
  double heartbeat_hz = 1.0;
  /// Commands are taken only from a system and a component in these lists (both must match;
  /// an empty list takes none). Default: a ground station (QGroundControl, Mission Planner).
  std::vector<std::uint8_t> accept_system_ids{255};
  std::vector<std::uint8_t> accept_component_ids{190};
  /// MAVLink 2 signing: with a key, commands must be signed with it (and not replayed), and
  /// every frame sent is signed. The key file holds 32 bytes, raw or as 64 hex digits.
  std::string signing_key_file;  ///< as written in the config ("" = no signing)
  bool has_signing_key = false;
  std::array<std::uint8_t, 32> signing_key{};
  std::uint8_t link_id = 0;  ///< link id in the signatures of the frames sent
  /// Where the signing state (the replay protection's high-water mark and streams) survives a
  /// restart; required with a key. Resolved against the config file's folder.
  std::string signing_state_file;
  /// How far ahead of the local signing clock a signed frame may be dated.
  double signing_max_ahead_s = 60.0;
  /// A board without a real-time clock: the first signed frame accepted sets the signing clock
  /// (link.signing_clock = "peer"); else the wall clock is trusted ("wall").
  bool signing_peer_clock = false;
  /// Serial device of the Linux board (its --link overrides it; the host board ignores it).
  std::string device = "/dev/serial0";
};

/// Real-time set-up of the cycle's thread (applied where permitted; see
/// drivers/realtime_setup.hpp).
struct RealtimeConfig {
  bool enabled = true;
  int priority = 80;
  int cpu = -1;
  bool lock_memory = true;
  std::size_t prefault_stack_kb = 256;
};

// ---- Devices of the Linux board ([camera], [encoders]; docs/drivers.md) ----

/// The camera of the Linux board.
struct CameraDeviceConfig {
  std::string driver = "v4l2";  ///< "v4l2" or "libcamera"
  /// v4l2: the device node; libcamera: the camera id ("" = the first camera found).
  std::string device = "/dev/video0";
  std::uint32_t width_px = 320;
  std::uint32_t height_px = 240;
  std::string format = "auto";              ///< "auto" (YUYV, else RGB24), "yuyv" or "rgb24"
  std::uint32_t buffers = 4;                ///< mmap buffers / libcamera requests, 2..8
  std::uint32_t reopen_interval_ms = 1000;  ///< v4l2: retry a failed device this often
  /// The camera's mounting (metres; NaN: not given): its optical centre above the floor and its
  /// offset ahead of the wheel axle's centre. The cycle does not use them; `harmoloc --record`
  /// writes them into the recording's metadata.toml for the trainer (docs/training.md).
  double mount_height_m = std::numeric_limits<double>::quiet_NaN();
  double mount_forward_m = std::numeric_limits<double>::quiet_NaN();
};

/// The wheel encoders of the Linux board: SocketCAN (layout in [can]) or GPIO quadrature.
struct EncoderDeviceConfig {
  std::string driver = "can";     ///< "can" or "gpio"
  bool can_kernel_filter = true;  ///< false: every frame reaches the driver (foreign IDs counted)
  std::string gpio_chip = "gpiochip0";
  std::array<unsigned, 2> left_lines{0, 1};   ///< A, B line offsets
  std::array<unsigned, 2> right_lines{2, 3};  ///< A, B line offsets
  std::uint32_t debounce_us = 0;
  std::string gpio_reader = "thread";  ///< "thread" or "cycle"
};

struct BoardNames {
  std::array<std::string, algorithms::kMaxBoards> names;
};

struct FirmwareConfig {
  CycleConfig cycle;
  algorithms::ThresholdSet thresholds;
  BoardNames board_names;
  algorithms::DiffDriveGeometry geometry;
  /// Apply the odometry calibration a map carries (odometry.map_calibration): the wheels as the
  /// training run measured them, on top of the configured geometry.
  bool use_map_odometry_calibration = true;
  algorithms::EncoderFrameLayout can_layout;
  std::string can_interface = "can0";
  FilterConfig filter;
  ObservationConfig observation;
  KidnapConfig kidnap;
  LinkConfig link;
  RealtimeConfig realtime;
  CameraDeviceConfig camera;
  EncoderDeviceConfig encoders;
  /// Whether the file set these sections itself (else the host board may take them from the
  /// dataset's metadata, which describes the recorded robot).
  bool has_odometry_section = false;
  bool has_can_section = false;
  std::string source = "built-in defaults";
};

/// Defaults: the simulator's robot and its six boards (red, green, blue, yellow, magenta, cyan).
FirmwareConfig default_config();

/// Reads and validates a config file on top of the defaults. Throws std::runtime_error with one
/// line "FILE: [line N:] what is wrong" for anything unreadable, unknown or out of range.
FirmwareConfig load_config(const std::string& path);

/// Reads a MAVLink signing key file: exactly 32 raw bytes, or 64 hex digits (surrounding
/// whitespace allowed); a regular file only. Returns an empty string on success, else what is
/// wrong. (The config's link.signing_key_file is read with it; so is harmoloc-monitor's --key.)
std::string read_signing_key_file(const std::string& path, std::array<std::uint8_t, 32>& key);

}  // namespace harmoloc::firmware
