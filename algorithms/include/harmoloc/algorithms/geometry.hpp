#pragma once
/// @file Planar poses and angles. Map frame: x and y on the floor, z up, yaw counter-clockwise
/// from +x (right-handed). Units are in the names.

#include <cmath>

namespace harmoloc::algorithms {

constexpr double kPi = 3.14159265358979323846;

/// Wraps an angle to [-pi, pi).
inline double wrap_angle_rad(double angle_rad) {
  double a = std::fmod(angle_rad + kPi, 2.0 * kPi);
  if (a < 0.0) a += 2.0 * kPi;
  return a - kPi;
}

/// One turn towards [-pi, pi]: exact for an angle within a turn and a half of it (the difference
/// of two wrapped angles), and without fmod, for the per-particle loops.
inline double wrap_once_rad(double angle_rad) {
  return angle_rad > kPi ? angle_rad - 2.0 * kPi
                         : (angle_rad < -kPi ? angle_rad + 2.0 * kPi : angle_rad);
}

struct Pose2 {
  double x_m = 0.0;
  double y_m = 0.0;
  double yaw_rad = 0.0;
};

/// 3x3 covariance of (x, y, yaw), row-major.
struct PoseCovariance {
  double m[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  double operator()(int r, int c) const { return m[r * 3 + c]; }
  double& operator()(int r, int c) { return m[r * 3 + c]; }
};

}  // namespace harmoloc::algorithms
