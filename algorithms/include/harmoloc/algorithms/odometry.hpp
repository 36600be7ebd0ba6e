#pragma once
/// @file Differential-drive odometry from wheel encoder counters (Guo & Li's motion model).
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
  /// Each wheel's travel per tick as a multiple of the nominal 2 pi r / ticks_per_rev: the
  /// trainer's odometry calibration (two wheels are never exactly alike), 1 without one.
  double left_scale = 1.0;
  double right_scale = 1.0;
};

/// Multipliers on a configured geometry (odometry_calibration.hpp measures them): each wheel's
/// travel per tick and the track.
struct OdometryScale {
  double left = 1.0;
  double right = 1.0;
  double track = 1.0;
};

/// @p geometry with @p scale applied (wheel scales multiply, the track is scaled).
DiffDriveGeometry calibrated(const DiffDriveGeometry& geometry, const OdometryScale& scale);

/// Metres each wheel travels per tick, direction and calibration included.
double left_metres_per_tick(const DiffDriveGeometry& geometry);
double right_metres_per_tick(const DiffDriveGeometry& geometry);

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
