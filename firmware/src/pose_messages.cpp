#include "harmoloc/firmware/pose_messages.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

namespace harmoloc::firmware {

std::uint8_t heartbeat_status(Health health, bool overrun_alarm) {
  std::uint8_t status = mavlink::kMavStateStandby;
  switch (health) {
    case Health::kNotInitialized:
      status = mavlink::kMavStateStandby;
      break;
    case Health::kNominal:
      status = mavlink::kMavStateActive;
      break;
    case Health::kOdometryOnly:
    case Health::kVisionOnly:
      status = mavlink::kMavStateCritical;
      break;
    case Health::kInvalid:
      status = mavlink::kMavStateEmergency;
      break;
  }
  if (overrun_alarm && (health == Health::kNominal || health == Health::kNotInitialized))
    status = mavlink::kMavStateCritical;
  return status;
}

HealthText health_text(Health health, bool off_map) {
  static constexpr const char* kText[] = {
      "harmoloc: waiting for a first fix", "harmoloc: pose nominal",
      "harmoloc: odometry only (no camera fix)", "harmoloc: vision only (no encoder data)",
      "harmoloc: pose invalid (no camera, no encoders)"};
  const std::uint8_t severity = health == Health::kNominal   ? mavlink::kSeverityInfo
                                : health == Health::kInvalid ? mavlink::kSeverityCritical
                                                             : mavlink::kSeverityWarning;
  return HealthText{severity, off_map ? "harmoloc: pose invalid (outside the mapped region)"
                                      : kText[static_cast<std::size_t>(health)]};
}

mavlink::Odometry odometry_message(const PoseOutput& pose, std::uint64_t time_ns,
                                   std::uint8_t reset_counter) {
  mavlink::Odometry m;
  m.time_usec = time_ns / 1000U;
  m.x = static_cast<float>(pose.pose.x_m);
  m.y = static_cast<float>(-pose.pose.y_m);
  m.z = 0.0F;
  const double half_yaw = -0.5 * pose.pose.yaw_rad;
  m.q = {static_cast<float>(std::cos(half_yaw)), 0.0F, 0.0F,
         static_cast<float>(std::sin(half_yaw))};
  m.vx = static_cast<float>(pose.speed_mps);
  m.yawspeed = static_cast<float>(-pose.yaw_rate_rps);
  const auto& c = pose.covariance;
  m.pose_covariance.fill(0.0F);
  m.pose_covariance[0] = static_cast<float>(c(0, 0));   // x x
  m.pose_covariance[1] = static_cast<float>(-c(0, 1));  // x y
  m.pose_covariance[5] = static_cast<float>(-c(0, 2));  // x yaw
  m.pose_covariance[6] = static_cast<float>(c(1, 1));   // y y
  m.pose_covariance[10] = static_cast<float>(c(1, 2));  // y yaw (both signs flip)
  m.pose_covariance[20] = static_cast<float>(c(2, 2));  // yaw yaw
  m.velocity_covariance.fill(0.0F);
  m.velocity_covariance[0] = std::numeric_limits<float>::quiet_NaN();  // not estimated
  m.reset_counter = reset_counter;
  if (pose.health == Health::kInvalid) {
    m.quality = -1;
  } else {
    const double sigma_m = std::sqrt(std::max(0.0, 0.5 * (c(0, 0) + c(1, 1))));
    m.quality =
        static_cast<std::int8_t>(std::lround(std::clamp(100.0 - 1000.0 * sigma_m, 0.0, 100.0)));
  }
  return m;
}

}  // namespace harmoloc::firmware
