#pragma once
/// @file Renders what the robot's camera sees: a room with a desk and upright colour boards,
/// through a pinhole with the radial distortion of seed 000 (x_d = x_u + k x_u r_u^2). Pixels
/// outside the lens's image circle (where the distortion folds back) are black.

#include <cstdint>
#include <vector>

#include "harmoloc/algorithms/geometry.hpp"
#include "harmoloc/algorithms/random.hpp"
#include "harmoloc/sim_host/scenario.hpp"

namespace harmoloc::sim_host {

class SceneRenderer {
 public:
  explicit SceneRenderer(const Scenario& scenario);

  /// Renders RGB24 (width * height * 3 bytes) for the robot at @p robot_pose.
  void render(const algorithms::Pose2& robot_pose, algorithms::Pcg32& rng,
              std::vector<std::uint8_t>& rgb) const;

  /// How many pixels of each board are visible (before noise): the true areas, for tests.
  std::vector<std::uint32_t> visible_board_pixels(const algorithms::Pose2& robot_pose) const;

 private:
  struct Ray {
    double x, y, z;  ///< camera frame: x right, y down, z forward
    bool valid;
  };
  int trace(const double origin[3], const double dir[3], Rgb& colour) const;

  const Scenario& scenario_;
  std::vector<Ray> rays_;
};

}  // namespace harmoloc::sim_host
