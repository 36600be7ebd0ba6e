#include "harmoloc/algorithms/odometry.hpp"

#include <cmath>

namespace harmoloc::algorithms {

std::int64_t wrapped_delta(std::uint32_t previous, std::uint32_t current, std::uint8_t bits) {
  if (bits == 0 || bits > 32) bits = 32;
  const std::uint64_t modulus = 1ULL << bits;
  const std::uint64_t mask = modulus - 1U;
  const std::uint64_t diff = (static_cast<std::uint64_t>(current) - previous) & mask;
  const auto half = static_cast<std::int64_t>(modulus >> 1U);
  const auto d = static_cast<std::int64_t>(diff);
  return d >= half ? d - static_cast<std::int64_t>(modulus) : d;
}

DiffDriveGeometry calibrated(const DiffDriveGeometry& geometry, const OdometryScale& scale) {
  DiffDriveGeometry g = geometry;
  g.left_scale *= scale.left;
  g.right_scale *= scale.right;
  g.track_m *= scale.track;
  return g;
}

double left_metres_per_tick(const DiffDriveGeometry& geometry) {
  return 2.0 * kPi * geometry.wheel_radius_m / geometry.ticks_per_rev *
         static_cast<double>(geometry.left_direction) * geometry.left_scale;
}

double right_metres_per_tick(const DiffDriveGeometry& geometry) {
  return 2.0 * kPi * geometry.wheel_radius_m / geometry.ticks_per_rev *
         static_cast<double>(geometry.right_direction) * geometry.right_scale;
}

OdometryDelta odometry_from_ticks(const DiffDriveGeometry& geometry, std::int64_t left_ticks,
                                  std::int64_t right_ticks) {
  const double left_m = static_cast<double>(left_ticks) * left_metres_per_tick(geometry);
  const double right_m = static_cast<double>(right_ticks) * right_metres_per_tick(geometry);
  return OdometryDelta{0.5 * (left_m + right_m), (right_m - left_m) / geometry.track_m};
}

Pose2 apply_arc(const Pose2& pose, const OdometryDelta& delta) {
  Pose2 out = pose;
  if (std::fabs(delta.yaw_rad) < 1e-9) {
    const double mid = pose.yaw_rad + 0.5 * delta.yaw_rad;
    out.x_m += delta.distance_m * std::cos(mid);
    out.y_m += delta.distance_m * std::sin(mid);
  } else {
    const double radius = delta.distance_m / delta.yaw_rad;
    const double yaw_end = pose.yaw_rad + delta.yaw_rad;
    out.x_m += radius * (std::sin(yaw_end) - std::sin(pose.yaw_rad));
    out.y_m += -radius * (std::cos(yaw_end) - std::cos(pose.yaw_rad));
  }
  out.yaw_rad = wrap_angle_rad(pose.yaw_rad + delta.yaw_rad);
  return out;
}

}  // namespace harmoloc::algorithms
