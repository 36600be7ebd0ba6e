#pragma once
/// @file TUM trajectory files: `t x y z qx qy qz qw` a line, seconds and metres. Planar poses
/// are written with z = 0 and a yaw-only quaternion.

#include <cstdio>
#include <string>
#include <vector>

#include "harmoloc/algorithms/geometry.hpp"

namespace harmoloc::dataset {

struct StampedPose {
  double t_s = 0.0;
  algorithms::Pose2 pose;
};

/// Reads a TUM file. Comment lines (#) and blank lines are skipped. Throws std::runtime_error
/// with "FILE:LINE: reason" on a malformed line or a non-monotonic timestamp.
std::vector<StampedPose> read_tum(const std::string& path);

/// Formats one pose as a TUM line (with newline) into @p buffer; returns the length.
/// No allocation: the firmware uses it in its cycle.
int format_tum_line(char* buffer, std::size_t size, double t_s, const algorithms::Pose2& pose);

void write_tum(const std::string& path, const std::vector<StampedPose>& poses);

/// Yaw of a quaternion (rotation about z).
double yaw_from_quaternion(double qx, double qy, double qz, double qw);

/// Linear interpolation of a trajectory at @p t_s (yaw along the shorter arc). Returns false
/// when @p t_s is outside the trajectory's time span.
bool interpolate(const std::vector<StampedPose>& trajectory, double t_s, algorithms::Pose2& pose);

}  // namespace harmoloc::dataset
