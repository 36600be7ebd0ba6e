#include "harmoloc/firmware/pose_messages.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
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

HealthText health_text(Health health, HealthCause cause) {
  static constexpr const char* kText[] = {
      "harmoloc: waiting for a first fix", "harmoloc: pose nominal",
      "harmoloc: odometry only (no camera fix)", "harmoloc: vision only (no encoder data)",
      "harmoloc: pose invalid (no camera, no encoders)"};
  const std::uint8_t severity = health == Health::kNominal   ? mavlink::kSeverityInfo
                                : health == Health::kInvalid ? mavlink::kSeverityCritical
                                                             : mavlink::kSeverityWarning;
  if (health == Health::kInvalid && cause == HealthCause::kOffMap)
    return HealthText{severity, "harmoloc: pose invalid (outside the mapped region)"};
  if (cause == HealthCause::kHeadingNotCovered) {
    if (health == Health::kOdometryOnly)
      return HealthText{severity, "harmoloc: odometry only (heading not mapped here)"};
    if (health == Health::kInvalid)  // no encoder data either
      return HealthText{severity, "harmoloc: pose invalid (heading not mapped here)"};
  }
  if (cause == HealthCause::kBoardsDisagree) {
    if (health == Health::kOdometryOnly)
      return HealthText{severity, "harmoloc: odometry only (boards disagree)"};
    if (health == Health::kInvalid)
      return HealthText{severity, "harmoloc: pose invalid (boards disagree)"};
  }
  if (cause == HealthCause::kSpreadWide && health == Health::kOdometryOnly)
    return HealthText{severity, "harmoloc: odometry only (pose spread too wide)"};
  return HealthText{severity, kText[static_cast<std::size_t>(health)]};
}

int quality_of_spread(double sigma_m) {
  return static_cast<int>(std::lround(std::clamp(100.0 - 1000.0 * sigma_m, 0.0, 100.0)));
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
  } else if (pose.cause == HealthCause::kHeadingNotCovered ||
             pose.cause == HealthCause::kBoardsDisagree) {
    m.quality = 0;
  } else {
    m.quality = static_cast<std::int8_t>(
        quality_of_spread(std::sqrt(std::max(0.0, 0.5 * (c(0, 0) + c(1, 1))))));
  }
  return m;
}

namespace {

float f32_at(const std::uint8_t* p, std::size_t at) {
  std::uint32_t u = 0;
  for (std::size_t i = 0; i < 4; ++i) u |= static_cast<std::uint32_t>(p[at + i]) << (8U * i);
  float f = 0.0F;
  std::memcpy(&f, &u, 4);
  return f;
}

}  // namespace

mavlink::Odometry decode_odometry(const std::uint8_t* p) {
  // Wire order: time_usec, x y z, q[4], vx vy vz, roll/pitch/yawspeed, the two covariances (21
  // floats each), frame_id, child_frame_id, reset_counter, estimator_type, quality (extension).
  mavlink::Odometry m;
  m.time_usec = 0;
  for (std::size_t i = 0; i < 8; ++i) m.time_usec |= static_cast<std::uint64_t>(p[i]) << (8U * i);
  m.x = f32_at(p, 8);
  m.y = f32_at(p, 12);
  m.z = f32_at(p, 16);
  for (std::size_t i = 0; i < 4; ++i) m.q[i] = f32_at(p, 20 + 4 * i);
  m.vx = f32_at(p, 36);
  m.vy = f32_at(p, 40);
  m.vz = f32_at(p, 44);
  m.rollspeed = f32_at(p, 48);
  m.pitchspeed = f32_at(p, 52);
  m.yawspeed = f32_at(p, 56);
  for (std::size_t i = 0; i < 21; ++i) m.pose_covariance[i] = f32_at(p, 60 + 4 * i);
  for (std::size_t i = 0; i < 21; ++i) m.velocity_covariance[i] = f32_at(p, 144 + 4 * i);
  m.frame_id = p[228];
  m.child_frame_id = p[229];
  m.reset_counter = p[230];
  m.estimator_type = p[231];
  m.quality = static_cast<std::int8_t>(p[232]);
  return m;
}

MapPose map_pose(const mavlink::Odometry& m) {
  MapPose out;
  out.t_s = static_cast<double>(m.time_usec) / 1e6;
  out.x_m = static_cast<double>(m.x);
  out.y_m = -static_cast<double>(m.y);
  // Yaw-only quaternion (w, 0, 0, z) about the downward axis.
  const double yaw_frd = 2.0 * std::atan2(static_cast<double>(m.q[3]), static_cast<double>(m.q[0]));
  out.yaw_rad = std::remainder(-yaw_frd, 6.283185307179586);  // wrapped to [-pi, pi]
  const double var =
      0.5 * (static_cast<double>(m.pose_covariance[0]) + static_cast<double>(m.pose_covariance[6]));
  out.sigma_m = std::sqrt(std::max(0.0, var));
  out.quality = m.quality;
  out.reset_counter = m.reset_counter;
  return out;
}

bool health_of_text(const char* text, std::size_t size, Health& health) {
  const std::size_t n = ::strnlen(text, size);
  for (const Health h : {Health::kNotInitialized, Health::kNominal, Health::kOdometryOnly,
                         Health::kVisionOnly, Health::kInvalid}) {
    for (const HealthCause cause :
         {HealthCause::kInputs, HealthCause::kOffMap, HealthCause::kHeadingNotCovered,
          HealthCause::kBoardsDisagree, HealthCause::kSpreadWide}) {
      const char* t = health_text(h, cause).text;
      if (std::strlen(t) == n && std::strncmp(t, text, n) == 0) {
        health = h;
        return true;
      }
    }
  }
  return false;
}

bool health_of_heartbeat(std::uint8_t system_status, Health& health) {
  switch (system_status) {
    case mavlink::kMavStateStandby:
      health = Health::kNotInitialized;
      return true;
    case mavlink::kMavStateActive:
      health = Health::kNominal;
      return true;
    case mavlink::kMavStateEmergency:
      health = Health::kInvalid;
      return true;
    default:
      return false;
  }
}

}  // namespace harmoloc::firmware
