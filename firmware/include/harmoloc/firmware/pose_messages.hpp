#pragma once
/// @file The wire protocol's outbound mapping (docs/wire-protocol.md): what the published pose and
/// its health become in HEARTBEAT, STATUSTEXT and ODOMETRY. Pure functions of the plain
/// PoseOutput, as PX4 keeps its ODOMETRY mapping in one stream: the cycle only decides when each
/// message goes out.

#include <cstddef>
#include <cstdint>

#include "harmoloc/firmware/mavlink_v2.hpp"
#include "harmoloc/firmware/pose_output.hpp"

namespace harmoloc::firmware {

/// HEARTBEAT's system status (MAV_STATE) for @p health; at least CRITICAL while the overrun alarm
/// is raised (the pose comes late or not every cycle).
std::uint8_t heartbeat_status(Health health, bool overrun_alarm);

/// The STATUSTEXT that announces a change of health.
struct HealthText {
  std::uint8_t severity;  ///< MAV_SEVERITY
  const char* text;
};
/// A cause other than the inputs is said in its own words (kOffMap with kInvalid,
/// kHeadingNotCovered and kBoardsDisagree with kOdometryOnly or kInvalid; with any other health
/// the cause is ignored).
HealthText health_text(Health health, HealthCause cause);

/// ODOMETRY's quality for a pose that is neither invalid nor facing a heading the map does not
/// cover: 100 - 1000 x the position spread @p sigma_m (metres), rounded, within 0..100 (0 from a
/// spread of 9.95 cm).
int quality_of_spread(double sigma_m);

/// @p pose as ODOMETRY stamped @p time_ns. Map frame (x, y on the floor, z up, yaw
/// counter-clockwise) -> MAV_FRAME_LOCAL_FRD (z down): y and yaw change sign; body velocity in
/// MAV_FRAME_BODY_FRD. Quality from the position's spread (100 at 0, 0 at 10 cm), -1 when the
/// pose is invalid, 0 ("unknown" in MAVLink's words) while the map does not cover the estimate's
/// heading at its place (the spread is then the cloud's, and the cloud was weighed against a view
/// the map only guesses) or while the boards disagree with the pose (the cloud's spread says
/// nothing of how far off it is).
mavlink::Odometry odometry_message(const PoseOutput& pose, std::uint64_t time_ns,
                                   std::uint8_t reset_counter);

// ---- the other way: what a peer reads back (harmoloc-monitor, tests) ------------------------

/// An ODOMETRY payload (zero-restored to its full length, as the frame parser gives it).
mavlink::Odometry decode_odometry(const std::uint8_t* payload);

/// ODOMETRY back in the map frame, as the TUM files have it.
struct MapPose {
  double t_s = 0.0;      ///< time_usec in seconds
  double x_m = 0.0;      ///< x_map = x
  double y_m = 0.0;      ///< y_map = -y
  double yaw_rad = 0.0;  ///< yaw_map = -yaw_frd
  double sigma_m = 0.0;  ///< sqrt of the mean of the x and y variances
  int quality = 0;       ///< -1: invalid
  std::uint8_t reset_counter = 0;
};
MapPose map_pose(const mavlink::Odometry& odometry);

/// The health a STATUSTEXT of health_text() announces: true and @p health, or false for any
/// other text (up to 50 characters, not necessarily terminated).
bool health_of_text(const char* text, std::size_t size, Health& health);

/// The health HEARTBEAT's system status says at least: STANDBY not initialised, ACTIVE nominal,
/// EMERGENCY invalid; CRITICAL is one of the degraded modes (or an overrun): false.
bool health_of_heartbeat(std::uint8_t system_status, Health& health);

}  // namespace harmoloc::firmware
