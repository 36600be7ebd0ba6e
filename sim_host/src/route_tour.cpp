// A tour (RouteShape::kTour): poses visited in turn by turning on the spot and driving straight
// legs, as a floor's coverage run or a test run off the trained route is driven.
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "harmoloc/sim_host/route.hpp"
#include "route_parts.hpp"

namespace harmoloc::sim_host::route_detail {

using algorithms::kPi;
using algorithms::Pose2;
using algorithms::wrap_angle_rad;

namespace {

constexpr double kDeg = algorithms::kPi / 180.0;

// The angular acceleration of a turn: the turn rate reached in the time the speed is.
double turn_acceleration(const RouteSpec& r) {
  return r.turn_rate_dps * kDeg * r.acceleration_mps2 / r.speed_mps;
}

}  // namespace

std::vector<TourSegment> tour_segments(const RouteSpec& r, double t0_s) {
  const std::size_t n = r.waypoints_m.size();
  if (n < 2) throw std::runtime_error("a tour needs at least 2 waypoints");
  if (r.heading_deg.size() != n) {
    std::ostringstream m;
    m << "a tour needs a heading at every waypoint ([x, y, heading_deg]): " << r.heading_deg.size()
      << " headings for " << n << " waypoints";
    throw std::runtime_error(m.str());
  }
  if (!(r.speed_mps > 0.0 && r.acceleration_mps2 > 0.0 && r.turn_rate_dps > 0.0))
    throw std::runtime_error("a tour needs a positive speed, acceleration and turn rate");
  std::vector<TourSegment> out;
  double t = t0_s;
  std::size_t target = 1;
  Pose2 at{r.waypoints_m[0][0], r.waypoints_m[0][1], r.heading_deg[0] * kDeg};
  const auto add = [&](TourSegment::Kind kind, double duration, const Pose2& to) {
    TourSegment s;
    s.kind = kind;
    s.t0_s = t;
    s.duration_s = duration;
    s.from = at;
    s.to = to;
    s.target = target;
    out.push_back(s);
    t += duration;
    at = to;
  };
  const double omega = r.turn_rate_dps * kDeg, alpha = turn_acceleration(r);
  const auto turn_by = [&](double angle) {
    if (std::fabs(angle) < 1e-9) return;
    double duration = 0.0;
    leg_distance(0.0, std::fabs(angle), omega, alpha, duration);
    add(TourSegment::Kind::kTurn, duration, Pose2{at.x_m, at.y_m, at.yaw_rad + angle});
  };
  if (r.pause_s > 0.0) add(TourSegment::Kind::kPause, r.pause_s, at);
  for (int lap = 0; lap < r.laps; ++lap) {
    for (std::size_t j = lap == 0 ? 1 : 0; j < n; ++j) {
      target = j;
      const double x = r.waypoints_m[j][0], y = r.waypoints_m[j][1];
      const double heading = r.heading_deg[j] * kDeg;
      const double length = std::hypot(x - at.x_m, y - at.y_m);
      if (length > 1e-6) {
        // Forward or reversing, whichever turns less before and after the leg.
        const double ahead = std::atan2(y - at.y_m, x - at.x_m);
        const double f1 = wrap_angle_rad(ahead - at.yaw_rad), f2 = wrap_angle_rad(heading - ahead);
        const double r1 = wrap_angle_rad(ahead + kPi - at.yaw_rad),
                     r2 = wrap_angle_rad(heading - ahead - kPi);
        turn_by(std::fabs(f1) + std::fabs(f2) <= std::fabs(r1) + std::fabs(r2) ? f1 : r1);
        double duration = 0.0;
        leg_distance(0.0, length, r.speed_mps, r.acceleration_mps2, duration);
        add(TourSegment::Kind::kDrive, duration, Pose2{x, y, at.yaw_rad});
      }
      turn_by(wrap_angle_rad(heading - at.yaw_rad));
    }
  }
  if (r.pause_s > 0.0) add(TourSegment::Kind::kPause, r.pause_s, at);
  if (out.empty()) add(TourSegment::Kind::kPause, 0.0, at);
  return out;
}

Pose2 tour_pose(const std::vector<TourSegment>& tour, const RouteSpec& r, double t_s) {
  const auto it = std::upper_bound(tour.begin(), tour.end(), t_s,
                                   [](double t, const TourSegment& s) { return t < s.t0_s; });
  const TourSegment& s = it == tour.begin() ? tour.front() : *(it - 1);
  const double dt = std::clamp(t_s - s.t0_s, 0.0, s.duration_s);
  double duration = 0.0;
  Pose2 p = s.from;
  switch (s.kind) {
    case TourSegment::Kind::kPause:
      break;
    case TourSegment::Kind::kTurn: {
      const double angle = s.to.yaw_rad - s.from.yaw_rad;
      const double done = leg_distance(dt, std::fabs(angle), r.turn_rate_dps * kDeg,
                                       turn_acceleration(r), duration);
      p.yaw_rad = s.from.yaw_rad + std::copysign(done, angle);
      break;
    }
    case TourSegment::Kind::kDrive: {
      const double length = std::hypot(s.to.x_m - s.from.x_m, s.to.y_m - s.from.y_m);
      const double u =
          length > 0.0
              ? leg_distance(dt, length, r.speed_mps, r.acceleration_mps2, duration) / length
              : 1.0;
      p.x_m = s.from.x_m + u * (s.to.x_m - s.from.x_m);
      p.y_m = s.from.y_m + u * (s.to.y_m - s.from.y_m);
      break;
    }
  }
  p.yaw_rad = wrap_angle_rad(p.yaw_rad);
  return p;
}

}  // namespace harmoloc::sim_host::route_detail

namespace harmoloc::sim_host {

std::vector<algorithms::Pose2> tour_places(const RouteSpec& route, double step_m, double step_deg) {
  using namespace route_detail;
  const std::vector<TourSegment> tour = tour_segments(route);
  std::vector<Pose2> out;
  out.push_back(tour.front().from);
  for (const TourSegment& s : tour) {
    double pieces = 1.0;
    if (s.kind == TourSegment::Kind::kDrive)
      pieces = std::ceil(std::hypot(s.to.x_m - s.from.x_m, s.to.y_m - s.from.y_m) / step_m);
    else if (s.kind == TourSegment::Kind::kTurn)
      pieces = std::ceil(std::fabs(s.to.yaw_rad - s.from.yaw_rad) / (step_deg * kDeg));
    if (s.kind == TourSegment::Kind::kPause) continue;
    const int n = std::max(1, static_cast<int>(pieces));
    // Sampled in the segment's own time: the trapezoid only changes when, not where.
    for (int k = 1; k <= n; ++k) {
      const double u = static_cast<double>(k) / n;
      Pose2 p = s.from;
      p.x_m += u * (s.to.x_m - s.from.x_m);
      p.y_m += u * (s.to.y_m - s.from.y_m);
      p.yaw_rad = wrap_angle_rad(s.from.yaw_rad + u * (s.to.yaw_rad - s.from.yaw_rad));
      out.push_back(p);
    }
  }
  return out;
}

}  // namespace harmoloc::sim_host
