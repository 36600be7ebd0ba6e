#pragma once
/// @file Differential-drive odometry from wheel encoder counters (seed 001's motion model).
/// Sign convention: ticks count up when a wheel drives the robot forward (after the per-wheel
/// direction in the geometry); yaw is counter-clockwise, so a right wheel that turns more than
/// the left turns the robot left (positive yaw).

#include <cstdint>

#include "harmoloc/algorithms/geometry.hpp"

namespace harmoloc::algorithms {

/// Difference of two readings of a counter that wraps at 2^bits (1..32), as a signed number in
/// [-2^(bits-1), 2^(bits-1)). Counters may be signed or unsigned on the wire: modulo 2^bits
/// the difference is the same.
std::int64_t wrapped_delta(std::uint32_t previous, std::uint32_t current, std::uint8_t bits);

struct DiffDriveGeometry {
  double wheel_radius_m = 0.05;
  double track_m = 0.30;          ///< distance between the wheel contact points
  double ticks_per_rev = 4096.0;  ///< counter increments per wheel turn (after any 4x decoding)
  int left_direction = 1;         ///< +1, or -1 when that wheel counts down going forward
  int right_direction = 1;
};

/// Motion over one step in the robot frame: distance along the mean heading and yaw change.
struct OdometryDelta {
  double distance_m = 0.0;
  double yaw_rad = 0.0;
};

OdometryDelta odometry_from_ticks(const DiffDriveGeometry& geometry, std::int64_t left_ticks,
                                  std::int64_t right_ticks);

/// Moves @p pose along the circular arc of @p delta (exact for constant wheel speeds).
Pose2 apply_arc(const Pose2& pose, const OdometryDelta& delta);

}  // namespace harmoloc::algorithms
