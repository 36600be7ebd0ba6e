#pragma once
/// @file The robot's motion along a scenario's route: a smooth curve through the waypoints,
/// driven forward and then backward (a differential-drive robot keeps the desk in view that
/// way), with a trapezoidal speed profile. Sampled at a fine fixed step.

#include <vector>

#include "harmoloc/algorithms/geometry.hpp"
#include "harmoloc/algorithms/random.hpp"
#include "harmoloc/sim_host/scenario.hpp"

namespace harmoloc::sim_host {

struct MotionSample {
  double t_s;              ///< from the start of the run
  algorithms::Pose2 pose;  ///< axle centre, heading
  double left_m;           ///< cumulative true travel of each wheel (signed)
  double right_m;
};

struct RouteStats {
  double length_m = 0.0;
  double duration_s = 0.0;
  double max_heading_offset_deg = 0.0;  ///< largest |heading - mean heading|
};

/// Samples the whole run at @p step_s. @p rng draws this run's smooth sideways wander.
std::vector<MotionSample> simulate_motion(const Scenario& scenario, double step_s,
                                          algorithms::Pcg32& rng, RouteStats* stats);

}  // namespace harmoloc::sim_host
