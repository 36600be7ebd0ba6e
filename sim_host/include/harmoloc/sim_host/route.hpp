#pragma once
/// @file The robot's motion along a scenario's route: a smooth curve through the waypoints, either
/// driven forward and then backward (a shuttle: a differential-drive robot keeps the desk in view
/// that way) or round a closed curve forward only (a loop), with a trapezoidal speed profile; or
/// a tour of poses joined by turns on the spot and straight legs (a floor's coverage run, a test
/// run off the route). Sampled at a fine fixed step.

#include <array>
#include <cstdint>
#include <string>
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
  double route_t_s;  ///< the route clock: equal to t_s until a kidnap moves the robot
};

/// The robot lifted at @p from and put down at @p to (ground truth of a kidnap).
struct KidnapEvent {
  double t_s;  ///< run time of the jump: the first motion sample at or after the scheduled time
  algorithms::Pose2 from;      ///< the last pose before the jump
  algorithms::Pose2 to;        ///< the first pose after it
  std::uint64_t timestamp_ns;  ///< t_s on the dataset's clock (the scenario's start_time_s epoch)
};

struct RouteStats {
  double length_m = 0.0;
  double duration_s = 0.0;
  double max_heading_offset_deg = 0.0;  ///< largest |heading - mean heading|
};

/// Samples the whole run at @p step_s. @p rng draws this run's smooth sideways wander.
///
/// With scenario.kidnaps.count > 0 the robot is lifted at the scheduled times and put down on the
/// route elsewhere: the route clock jumps to a place drawn from @p kidnap_rng (required then) that
/// is at least kidnaps.min_distance_m away, where the robot drives, and from where the remaining
/// kidnaps can keep that distance too. The wheels do not turn during a jump: the samples' wheel
/// travel does not change at the jump sample. Kidnaps are listed in @p kidnaps (if given).
/// Throws std::runtime_error when a kidnap falls after the run's end or no place on the route is
/// far enough, std::invalid_argument when kidnaps are asked for without @p kidnap_rng.
std::vector<MotionSample> simulate_motion(const Scenario& scenario, double step_s,
                                          algorithms::Pcg32& rng, RouteStats* stats,
                                          algorithms::Pcg32* kidnap_rng = nullptr,
                                          std::vector<KidnapEvent>* kidnaps = nullptr);

/// The route's curve (Catmull-Rom through the waypoints; closed for a loop, ending at its start;
/// a tour's straight legs, once) sampled about every @p step_m metres: [x, y] points.
std::vector<std::array<double, 2>> route_curve(const RouteSpec& route, double step_m);

/// How long a run of @p scenario lasts (seconds): its laps with their pauses, as simulate_motion
/// samples it.
double run_duration_s(const Scenario& scenario);

/// The curve's length (a loop: once round; a tour: its legs, once).
double route_length_m(const RouteSpec& route);

/// The poses a tour (RouteShape::kTour) passes through as driven: about every @p step_m along
/// its legs and every @p step_deg of its turns on the spot, each waypoint's pose included.
std::vector<algorithms::Pose2> tour_places(const RouteSpec& route, double step_m, double step_deg);

/// True when the route's curve crosses or touches itself (closer than 5 cm between parts that are
/// not neighbours along it); @p why (if given) then says where. Never for a tour.
bool route_crosses_itself(const RouteSpec& route, std::string* why = nullptr);

/// A run time (seconds from the start) on the dataset's clock: @p start_time_s (whole
/// microseconds) plus @p t_s, in nanoseconds.
std::uint64_t dataset_time_ns(double start_time_s, double t_s);

}  // namespace harmoloc::sim_host
