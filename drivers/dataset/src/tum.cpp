#include "harmoloc/dataset/tum.hpp"

#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "recording_text.hpp"

namespace harmoloc::dataset {

using algorithms::Pose2;

double yaw_from_quaternion(double qx, double qy, double qz, double qw) {
  return std::atan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz));
}

std::vector<StampedPose> read_tum(const std::string& path) {
  const std::string content = detail::read_recording_text(path);
  std::istringstream in(content);
  std::vector<StampedPose> out;
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream fields(line);
    double v[8];
    for (double& x : v) {
      if (!(fields >> x))
        throw std::runtime_error(path + ":" + std::to_string(line_no) +
                                 ": expected 8 numbers (t x y z qx qy qz qw)");
      if (!std::isfinite(x))
        throw std::runtime_error(path + ":" + std::to_string(line_no) + ": value is not finite");
    }
    std::string extra;
    if (fields >> extra)
      throw std::runtime_error(path + ":" + std::to_string(line_no) + ": more than 8 fields");
    StampedPose p;
    p.t_s = v[0];
    const double norm = std::sqrt(v[4] * v[4] + v[5] * v[5] + v[6] * v[6] + v[7] * v[7]);
    if (!(norm > 0.5 && norm < 2.0)) {
      throw std::runtime_error(path + ":" + std::to_string(line_no) +
                               ": quaternion is not a rotation (norm " + std::to_string(norm) +
                               ")");
    }
    p.pose =
        Pose2{v[1], v[2], yaw_from_quaternion(v[4] / norm, v[5] / norm, v[6] / norm, v[7] / norm)};
    if (!out.empty() && p.t_s <= out.back().t_s) {
      throw std::runtime_error(path + ":" + std::to_string(line_no) + ": timestamps must increase");
    }
    out.push_back(p);
  }
  return out;
}

int format_tum_line(char* buffer, std::size_t size, double t_s, const Pose2& pose) {
  const double half = 0.5 * pose.yaw_rad;
  return std::snprintf(buffer, size, "%.6f %.6f %.6f 0 0 0 %.9f %.9f\n", t_s, pose.x_m, pose.y_m,
                       std::sin(half), std::cos(half));
}

void write_tum(const std::string& path, const std::vector<StampedPose>& poses) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path + ": cannot write");
  char line[160];
  for (const StampedPose& p : poses) {
    format_tum_line(line, sizeof line, p.t_s, p.pose);
    out << line;
  }
  if (!out) throw std::runtime_error(path + ": write failed");
}

bool interpolate(const std::vector<StampedPose>& trajectory, double t_s, Pose2& pose) {
  if (trajectory.empty() || t_s < trajectory.front().t_s || t_s > trajectory.back().t_s)
    return false;
  std::size_t lo = 0, hi = trajectory.size() - 1;
  while (hi - lo > 1) {
    const std::size_t mid = (lo + hi) / 2;
    (trajectory[mid].t_s <= t_s ? lo : hi) = mid;
  }
  const StampedPose& a = trajectory[lo];
  const StampedPose& b = trajectory[hi];
  const double span = b.t_s - a.t_s;
  const double u = span > 0.0 ? (t_s - a.t_s) / span : 0.0;
  pose.x_m = a.pose.x_m + u * (b.pose.x_m - a.pose.x_m);
  pose.y_m = a.pose.y_m + u * (b.pose.y_m - a.pose.y_m);
  pose.yaw_rad = algorithms::wrap_angle_rad(
      a.pose.yaw_rad + u * algorithms::wrap_angle_rad(b.pose.yaw_rad - a.pose.yaw_rad));
  return true;
}

}  // namespace harmoloc::dataset
