#pragma once
/// @file Renders what the robot's camera sees: a room with a desk, upright colour boards (which
/// may be moved during the run) and occluders (people walking through), through a pinhole with the
/// radial distortion of seed 000 (x_d = x_u + k x_u r_u^2). Pixels outside the lens's image circle
/// (where the distortion folds back) are black.

#include <cstdint>
#include <vector>

#include "harmoloc/algorithms/geometry.hpp"
#include "harmoloc/algorithms/random.hpp"
#include "harmoloc/sim_host/scenario.hpp"

namespace harmoloc::sim_host {

/// The scene at one moment of the run: set_time() applies the board moves in effect and places
/// the occluders (upright cylinders) where their paths put them. A new renderer shows the scene
/// at time 0.
class SceneRenderer {
 public:
  /// Keeps its own copy of @p scenario.
  explicit SceneRenderer(const Scenario& scenario);

  /// Sets the run time (seconds from the start) the next renders and visible_board_pixels show.
  void set_time(double t_s);
  double time_s() const { return time_s_; }
  /// The boards as they stand at the current time (moves applied), in the scenario's order.
  const std::vector<BoardSpec>& boards() const { return boards_; }
  /// How many occluders are in the room at the current time.
  std::size_t occluders_present() const { return occluders_.size(); }

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
  struct PlacedOccluder {
    double x_m, y_m, radius_m, height_m;
    Rgb colour;
  };
  int trace(const double origin[3], const double dir[3], Rgb& colour) const;

  Scenario scenario_;
  std::vector<Ray> rays_;
  double time_s_ = 0.0;
  std::vector<BoardSpec> boards_;
  std::vector<PlacedOccluder> occluders_;
};

}  // namespace harmoloc::sim_host
