#pragma once
/// @file The wire protocol's outbound mapping (docs/wire-protocol.md): what the published pose and
/// its health become in HEARTBEAT, STATUSTEXT and ODOMETRY. Pure functions of the plain
/// PoseOutput, as PX4 keeps its ODOMETRY mapping in one stream: the cycle only decides when each
/// message goes out.

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
/// @p off_map: invalid because the pose lies outside the mapped region, said in its own words.
HealthText health_text(Health health, bool off_map);

/// @p pose as ODOMETRY stamped @p time_ns. Map frame (x, y on the floor, z up, yaw
/// counter-clockwise) -> MAV_FRAME_LOCAL_FRD (z down): y and yaw change sign; body velocity in
/// MAV_FRAME_BODY_FRD. Quality from the position's spread (100 at 0, 0 at 10 cm), -1 when the
/// pose is invalid.
mavlink::Odometry odometry_message(const PoseOutput& pose, std::uint64_t time_ns,
                                   std::uint8_t reset_counter);

}  // namespace harmoloc::firmware
