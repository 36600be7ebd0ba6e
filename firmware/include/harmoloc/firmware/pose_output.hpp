#pragma once
/// @file What the cycle publishes each period: the fused pose, its covariance and velocity, and
/// how far it can be trusted. Plain data: the wire protocol (pose_messages.hpp), the trajectory
/// writers and the tools read it.

#include <cstdint>

#include "harmoloc/algorithms/geometry.hpp"

namespace harmoloc::firmware {

/// What the pose can be trusted for.
enum class Health : std::uint8_t {
  kNotInitialized = 0,  ///< no fix yet since start-up
  kNominal = 1,         ///< camera and encoders both contribute
  kOdometryOnly = 2,    ///< no usable frame lately: dead reckoning, covariance grows
  kVisionOnly = 3,      ///< no encoder data lately: fixes only, motion unknown
  kInvalid = 4,         ///< neither input lately: pose flagged invalid
};
const char* health_name(Health health);

/// Why the health is what it is, where the inputs alone do not say it.
enum class HealthCause : std::uint8_t {
  kInputs = 0,  ///< the camera's and the encoders' timeouts (the health's own words)
  kOffMap = 1,  ///< invalid: the pose lies outside the mapped region
  /// Odometry only (or invalid, without encoder data) although frames arrive: the map's heading
  /// coverage does not hold the estimate's heading at its place (a floor map faced a way its
  /// training run never drove there), so what the boards show cannot be compared with what the
  /// map expects.
  kHeadingNotCovered = 2,
  /// Odometry only (or invalid, without encoder data) although frames arrive: most boards
  /// disagree with the estimate (BoardAssessment::consensus), and no fix the filter weighs
  /// vouches for it. The robot was carried, or the cloud stands where the boards say it is not.
  kBoardsDisagree = 3,
  /// Odometry only although frames arrive and vouch for the estimate: the cloud's position
  /// spread has reached `filter.nominal_spread_m` (10 cm, where the published quality is 0) and
  /// not yet come back under `filter.nominal_resume_spread_m`. The boards do not pin the pose to
  /// the map's accuracy (a frame with one board in view, a cloud just seeded).
  kSpreadWide = 4,
};

struct PoseOutput {
  std::uint64_t data_time_ns = 0;
  algorithms::Pose2 pose;
  algorithms::PoseCovariance covariance;
  double speed_mps = 0.0;
  double yaw_rate_rps = 0.0;
  Health health = Health::kNotInitialized;
  HealthCause cause = HealthCause::kInputs;
  bool valid = false;  ///< a pose exists (filter initialised)
};

}  // namespace harmoloc::firmware
