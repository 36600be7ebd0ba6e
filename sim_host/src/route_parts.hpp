#pragma once
/// @file What the pieces of the route (route*.cpp) share: the sampled curve through the waypoints
/// and the trapezoidal speed profile of a leg. Private to sim_host/src.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <vector>

#include "harmoloc/algorithms/geometry.hpp"
#include "harmoloc/sim_host/scenario.hpp"

namespace harmoloc::sim_host::route_detail {

struct Polyline {
  std::vector<double> x, y, s;  // s: cumulative arc length
  bool closed = false;          // a loop: arc lengths wrap round
  double length() const { return s.back(); }
  /// Fills s from x and y.
  void measure() {
    s.assign(x.size(), 0.0);
    for (std::size_t k = 1; k < x.size(); ++k)
      s[k] = s[k - 1] + std::hypot(x[k] - x[k - 1], y[k] - y[k - 1]);
  }
  void at(double si, double& px, double& py, double& tx, double& ty) const {
    if (closed && (si < 0.0 || si > length())) {
      si = std::fmod(si, length());
      if (si < 0.0) si += length();
    }
    si = std::clamp(si, 0.0, length());
    const auto it = std::upper_bound(s.begin(), s.end(), si);
    std::size_t k = static_cast<std::size_t>(std::max<std::ptrdiff_t>(1, it - s.begin()));
    if (k >= s.size()) k = s.size() - 1;
    const double seg = s[k] - s[k - 1];
    const double u = seg > 0.0 ? (si - s[k - 1]) / seg : 0.0;
    px = x[k - 1] + u * (x[k] - x[k - 1]);
    py = y[k - 1] + u * (y[k] - y[k - 1]);
    tx = (x[k] - x[k - 1]) / seg;
    ty = (y[k] - y[k - 1]) / seg;
  }
};

// Catmull-Rom through the waypoints, densely sampled (@p steps points a segment): end points
// repeated, or closed (back to the first waypoint, neighbours taken round the loop).
Polyline make_path(const std::vector<std::array<double, 2>>& w, bool closed, int steps = 400);

// Distance covered after time t on a leg of length L with a trapezoidal speed profile.
double leg_distance(double t, double length, double v, double a, double& duration);

// One piece of a tour (RouteShape::kTour): standing still, turning on the spot or driving a
// straight leg (forward or reversing: the heading is held either way).
struct TourSegment {
  enum class Kind { kPause, kTurn, kDrive };
  Kind kind = Kind::kPause;
  double t0_s = 0.0;
  double duration_s = 0.0;
  algorithms::Pose2 from;  // a turn's yaw is not wrapped: to.yaw_rad - from.yaw_rad is the turn
  algorithms::Pose2 to;
  std::size_t target = 0;  // the waypoint this segment is on the way to (or turning at)
};

// The tour's pieces in time order, from its start pause to its end pause, starting at
// @p t0_s. Throws std::runtime_error when the waypoints and headings do not make a tour.
std::vector<TourSegment> tour_segments(const RouteSpec& route, double t0_s = 0.0);

// Where the tour puts the robot at run time @p t_s (the start pose before, the end pose after).
algorithms::Pose2 tour_pose(const std::vector<TourSegment>& tour, const RouteSpec& route,
                            double t_s);

}  // namespace harmoloc::sim_host::route_detail
