#include "harmoloc/sim_host/route.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <sstream>
#include <stdexcept>

#include "route_kidnap_planner.hpp"
#include "route_parts.hpp"

namespace harmoloc::sim_host {

using algorithms::kPi;
using algorithms::Pose2;
using algorithms::wrap_angle_rad;
using namespace route_detail;

namespace {

constexpr double kLegMargin_s = 0.1;  // "driving": this far inside a leg

// Wheel travel from the pose increments (standard differential drive); none across a jump (the
// samples @p jump_at, ascending).
void add_wheel_travel(const Scenario& scenario, const std::vector<std::size_t>& jump_at,
                      std::vector<MotionSample>& out) {
  const double half_track = 0.5 * scenario.robot.track_m;
  std::size_t next_jump = 0;
  for (std::size_t i = 0; i < out.size(); ++i) {
    if (i == 0) {
      out[i].left_m = out[i].right_m = 0.0;
      continue;
    }
    if (next_jump < jump_at.size() && i == jump_at[next_jump]) {
      ++next_jump;
      out[i].left_m = out[i - 1].left_m;
      out[i].right_m = out[i - 1].right_m;
      continue;
    }
    const Pose2& p0 = out[i - 1].pose;
    const Pose2& p1 = out[i].pose;
    const double dyaw = wrap_angle_rad(p1.yaw_rad - p0.yaw_rad);
    const double mid = p0.yaw_rad + 0.5 * dyaw;
    const double ds = (p1.x_m - p0.x_m) * std::cos(mid) + (p1.y_m - p0.y_m) * std::sin(mid);
    out[i].left_m = out[i - 1].left_m + ds - dyaw * half_track;
    out[i].right_m = out[i - 1].right_m + ds + dyaw * half_track;
  }
}

// The largest |heading - mean heading| over the run (degrees).
double max_heading_offset_deg(const std::vector<MotionSample>& out) {
  double mean_sin = 0.0, mean_cos = 0.0;
  for (const MotionSample& m : out) {
    mean_sin += std::sin(m.pose.yaw_rad);
    mean_cos += std::cos(m.pose.yaw_rad);
  }
  const double mean = std::atan2(mean_sin, mean_cos);
  double worst = 0.0;
  for (const MotionSample& m : out)
    worst = std::max(worst, std::fabs(wrap_angle_rad(m.pose.yaw_rad - mean)));
  return worst * 180.0 / kPi;
}

}  // namespace

std::uint64_t dataset_time_ns(double start_time_s, double t_s) {
  const auto start_ns = static_cast<std::uint64_t>(std::llround(start_time_s * 1e6)) * 1000ULL;
  return start_ns + static_cast<std::uint64_t>(std::llround(t_s * 1e9));
}

std::vector<MotionSample> simulate_motion(const Scenario& scenario, double step_s,
                                          algorithms::Pcg32& rng, RouteStats* stats,
                                          algorithms::Pcg32* kidnap_rng,
                                          std::vector<KidnapEvent>* kidnaps) {
  const RouteSpec& r = scenario.route;
  if (r.shape == RouteShape::kTour) {
    // Kidnaps on a tour: at each kidnap time the robot is put down at the kidnap's pose and
    // drives on from there to the waypoint it was heading for, and on along the tour.
    const KidnapSpec& ks = scenario.kidnaps;
    if (ks.count > 0 && ks.poses.size() != static_cast<std::size_t>(ks.count))
      throw std::runtime_error(
          "a tour's kidnaps need a pose each (kidnaps.poses [x, y, heading_deg])");
    if (ks.count > 0 && r.laps != 1)
      throw std::runtime_error("kidnaps on a tour need route.laps = 1");
    RouteSpec leg = r;
    std::vector<TourSegment> tour = tour_segments(leg);
    std::vector<MotionSample> out;
    std::vector<std::size_t> jump_at;
    std::vector<KidnapEvent> events;
    for (std::size_t i = 0;; ++i) {
      const double t = static_cast<double>(i) * step_s;
      const std::size_t k = events.size();
      if (k < static_cast<std::size_t>(ks.count) &&
          t >= ks.first_s + static_cast<double>(k) * ks.interval_s - 1e-9 && i > 0) {
        // The rest of the tour from the kidnap's pose.
        const auto it = std::upper_bound(tour.begin(), tour.end(), t,
                                         [](double v, const TourSegment& s) { return v < s.t0_s; });
        const std::size_t next = (it == tour.begin() ? tour.front() : *(it - 1)).target;
        const std::array<double, 3>& to = ks.poses[k];
        RouteSpec rest = r;
        rest.waypoints_m = {{to[0], to[1]}};
        rest.heading_deg = {to[2]};
        for (std::size_t j = std::min(next, r.waypoints_m.size() - 1); j < r.waypoints_m.size();
             ++j) {
          rest.waypoints_m.push_back(r.waypoints_m[j]);
          rest.heading_deg.push_back(r.heading_deg[j]);
        }
        if (rest.waypoints_m.size() < 2) {  // nothing left to drive: stand there
          rest.waypoints_m.push_back(rest.waypoints_m.front());
          rest.heading_deg.push_back(rest.heading_deg.front());
        }
        tour = tour_segments(rest, t);
        // No standstill before driving on: drop the start pause.
        if (!tour.empty() && tour.front().kind == TourSegment::Kind::kPause) {
          const double shift = tour.front().duration_s;
          tour.erase(tour.begin());
          for (TourSegment& s : tour) s.t0_s -= shift;
        }
        leg = rest;
        jump_at.push_back(i);
        const Pose2 put = tour_pose(tour, leg, t);
        events.push_back(
            KidnapEvent{t, out.back().pose, put, dataset_time_ns(scenario.start_time_s, t)});
      }
      // Samples up to the first at or after the tour's end (as a route's: ceil(total / step) + 1).
      if (!out.empty() && out.back().t_s >= tour.back().t0_s + tour.back().duration_s - 1e-9) break;
      MotionSample m;
      m.t_s = t;
      m.route_t_s = t;
      m.pose = tour_pose(tour, leg, t);
      out.push_back(m);
    }
    const double total_s = tour.back().t0_s + tour.back().duration_s;
    if (ks.count > 0 && events.size() < static_cast<std::size_t>(ks.count)) {
      std::ostringstream msg;
      msg << "kidnap " << events.size() + 1 << " of " << ks.count << " at "
          << ks.first_s + static_cast<double>(events.size()) * ks.interval_s
          << " s is after the end of the tour (" << total_s << " s)";
      throw std::runtime_error(msg.str());
    }
    add_wheel_travel(scenario, jump_at, out);
    if (stats != nullptr) {
      stats->length_m = route_length_m(r);
      stats->duration_s = total_s;
      stats->max_heading_offset_deg = max_heading_offset_deg(out);
    }
    if (kidnaps != nullptr) *kidnaps = std::move(events);
    return out;
  }
  const bool loop = r.shape == RouteShape::kLoop;
  const Polyline path = make_path(r.waypoints_m, loop);
  const double length = path.length();
  // A shuttle drives one leg forth and one back a lap, pausing at each end; a loop drives one leg
  // of laps x its length round the closed curve, pausing at the start and at the end.
  const double leg_length = loop ? r.laps * length : length;
  double leg_s = 0.0;
  leg_distance(0.0, leg_length, r.speed_mps, r.acceleration_mps2, leg_s);
  const double lap_s = loop ? length / r.speed_mps : 2.0 * (r.pause_s + leg_s);
  const double total_s = loop ? leg_s + 2.0 * r.pause_s : r.laps * lap_s + r.pause_s;
  // A loop's cruise: from cruise_begin to cruise_end the robot drives at speed_mps, and the route
  // clock tau puts it at arc distance speed_mps (tau - cruise_origin).
  double cruise_begin = 0.0, cruise_end = 0.0, cruise_origin = 0.0;
  if (loop) {
    const double t_acc = std::min(r.speed_mps / r.acceleration_mps2, 0.5 * leg_s);
    const double d_acc = 0.5 * r.acceleration_mps2 * t_acc * t_acc;
    cruise_begin = r.pause_s + t_acc;
    cruise_end = r.pause_s + leg_s - t_acc;
    cruise_origin = cruise_begin - d_acc / r.speed_mps;
  }

  // Smooth sideways wander as a function of distance travelled (so a stopped robot stays put).
  double amp[3], wavelength[3], phase[3];
  for (int k = 0; k < 3; ++k) {
    amp[k] = r.wander_m * rng.uniform(0.3, 0.6);
    wavelength[k] = rng.uniform(1.0, 2.5);
    phase[k] = rng.uniform(0.0, 2.0 * kPi);
  }
  auto wander = [&](double travelled) {
    double w = 0.0;
    for (int k = 0; k < 3; ++k)
      w += amp[k] * std::sin(2.0 * kPi * travelled / wavelength[k] + phase[k]);
    return w;
  };

  auto position = [&](double s_m, double travelled_m, double& x, double& y) {
    double px, py, tx, ty;
    path.at(s_m, px, py, tx, ty);
    const double w = wander(travelled_m);
    x = px - ty * w;
    y = py + tx * w;
  };

  // Where the route clock @p tau puts the robot: arc length along the route, the distance driven
  // along it since the start of the run (@p along: the shuttle's arc length, a loop's distance
  // round), and the direction of travel (0 while it stands: the pauses and after the last lap).
  auto route_at = [&](double tau, double& s, double& along, int& dir) {
    double leg = 0.0;
    s = 0.0;
    dir = 0;
    if (loop) {
      along = 0.0;
      if (tau >= r.pause_s + leg_s) {
        along = leg_length;
      } else if (tau > r.pause_s) {
        along = leg_distance(tau - r.pause_s, leg_length, r.speed_mps, r.acceleration_mps2, leg);
        dir = 1;
      }
      s = std::fmod(along, length);
      return;
    }
    const double in_lap = std::fmod(tau, lap_s);
    const bool done = tau >= r.laps * lap_s;
    if (done || in_lap < r.pause_s) {
      s = 0.0;
    } else if (in_lap < r.pause_s + leg_s) {
      s = leg_distance(in_lap - r.pause_s, length, r.speed_mps, r.acceleration_mps2, leg);
      dir = 1;
    } else if (in_lap < 2.0 * r.pause_s + leg_s) {
      s = length;
    } else {
      s = length - leg_distance(in_lap - 2.0 * r.pause_s - leg_s, length, r.speed_mps,
                                r.acceleration_mps2, leg);
      dir = -1;
    }
    along = s;
  };

  // The kidnap planner's view of the route: phases within a lap, where the robot drives at a
  // phase, where a phase puts it, which route clock to jump to, and the phase of a route clock.
  const KidnapPlanner::DrivingFn driving = [&](double phi) {
    if (loop) return true;
    const bool forward = phi > r.pause_s + kLegMargin_s && phi < r.pause_s + leg_s - kLegMargin_s;
    const bool back = phi > 2.0 * r.pause_s + leg_s + kLegMargin_s && phi < lap_s - kLegMargin_s;
    return forward || back;
  };
  const auto phase_s_m = [&](double phi) {
    if (loop) return std::fmod(r.speed_mps * phi, length);
    double s = 0.0, along = 0.0;
    int dir = 0;
    route_at(phi, s, along, dir);
    return s;
  };
  const KidnapPlanner::TauFn tau_for = [&](double phi, double t_s) {
    if (!loop) {
      // The latest lap that puts the route clock at or before the run time, so that the rest of
      // the run fits in the route; in the first lap that is not always possible, and the robot
      // then finishes its route early and waits at its start.
      const double lap =
          std::clamp(std::floor((t_s - phi) / lap_s), 0.0, static_cast<double>(r.laps - 1));
      return lap * lap_s + phi;
    }
    // The latest lap of the cruise at or before the run time, else the first after it.
    const double lo = cruise_begin + kLegMargin_s, hi = cruise_end - kLegMargin_s;
    double tau = cruise_origin + phi + std::floor((t_s - cruise_origin - phi) / lap_s) * lap_s;
    if (tau > hi) tau -= lap_s * std::ceil((tau - hi) / lap_s);
    if (tau < lo) tau += lap_s * std::ceil((lo - tau) / lap_s);
    return tau >= lo && tau <= hi ? tau : -1.0;
  };
  const KidnapPlanner::PhaseFn phase_of = [&](double tau) {
    if (!loop) return tau >= r.laps * lap_s ? 0.0 : std::fmod(tau, lap_s);
    if (tau < cruise_begin || tau > cruise_end) return 0.0;
    return std::fmod(tau - cruise_origin, lap_s);
  };

  const auto count = static_cast<std::size_t>(std::ceil(total_s / step_s)) + 1;

  // Kidnaps: the samples where the route clock jumps, and which places on the route (by phase
  // within a lap) can be jumped to so that every later kidnap still finds a far enough place.
  const KidnapSpec& ks = scenario.kidnaps;
  std::vector<std::size_t> jump_at;
  KidnapPlanner planner;
  if (ks.count > 0) {
    if (kidnap_rng == nullptr)
      throw std::invalid_argument("simulate_motion: kidnaps need their random stream");
    for (int k = 0; k < ks.count; ++k) {
      const double t_k = ks.first_s + k * ks.interval_s;
      const auto i =
          std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil((t_k - 1e-9) / step_s)));
      if (i >= count) {
        std::ostringstream msg;
        msg << "kidnap " << k + 1 << " of " << ks.count << " at " << t_k
            << " s is after the end of the run (" << static_cast<double>(count - 1) * step_s
            << " s): raise route.laps, or lower kidnaps.count or kidnaps.interval_s";
        throw std::runtime_error(msg.str());
      }
      jump_at.push_back(i);
    }
    double wander_bound = 0.0;
    for (double a : amp) wander_bound += std::fabs(a);
    planner.plan(lap_s, driving, ks, wander_bound, [&](double phi, double& x, double& y) {
      double tx, ty;
      path.at(phase_s_m(phi), x, y, tx, ty);
    });
  }

  std::vector<MotionSample> out(count);
  std::vector<KidnapEvent> events;
  double travelled = 0.0, last_along = 0.0;
  double heading = 0.0;
  {
    double px, py, tx, ty;
    path.at(0.0, px, py, tx, ty);
    heading = std::atan2(ty, tx);
  }
  double shift_s = 0.0;  // route clock minus run time
  constexpr double kProbe_m = 0.005;
  for (std::size_t i = 0; i < count; ++i) {
    const double t = static_cast<double>(i) * step_s;
    const bool jump = events.size() < jump_at.size() && i == jump_at[events.size()];
    if (jump) {
      const std::size_t k = events.size();
      const double next_gap_s =
          k + 1 < jump_at.size() ? static_cast<double>(jump_at[k + 1] - i) * step_s : -1.0;
      const Pose2& from = out[i - 1].pose;
      const double tau = planner.choose(
          k, t, next_gap_s, from, *kidnap_rng,
          [&](double phi, double& x, double& y) { position(phase_s_m(phi), travelled, x, y); },
          tau_for, phase_of);
      shift_s = tau - t;
    }
    const double tau = t + shift_s;
    double s = 0.0, along = 0.0;
    int dir = 0;
    route_at(tau, s, along, dir);
    if (!jump) travelled += std::fabs(along - last_along);  // the wander carries on across a jump
    last_along = along;
    double x, y;
    position(s, travelled, x, y);
    if (dir != 0) {
      // Heading follows the direction of motion, probed a few mm ahead and behind along the route
      // (reversed when backing up); held while stopped.
      double xf, yf, xb, yb;
      position(s + dir * kProbe_m, travelled + kProbe_m, xf, yf);
      position(s - dir * kProbe_m, travelled - kProbe_m, xb, yb);
      heading = std::atan2(yf - yb, xf - xb) + (dir < 0 ? kPi : 0.0);
    }
    out[i].t_s = t;
    out[i].pose = Pose2{x, y, wrap_angle_rad(heading)};
    out[i].route_t_s = tau;
    if (jump) {
      events.push_back(
          KidnapEvent{t, out[i - 1].pose, out[i].pose, dataset_time_ns(scenario.start_time_s, t)});
    }
  }
  add_wheel_travel(scenario, jump_at, out);
  if (stats != nullptr) {
    stats->length_m = length;
    stats->duration_s = total_s;
    stats->max_heading_offset_deg = max_heading_offset_deg(out);
  }
  if (kidnaps != nullptr) *kidnaps = std::move(events);
  return out;
}

double run_duration_s(const Scenario& scenario) {
  const RouteSpec& r = scenario.route;
  if (r.shape == RouteShape::kTour) {
    const std::vector<TourSegment> tour = tour_segments(r);
    return tour.back().t0_s + tour.back().duration_s;
  }
  const bool loop = r.shape == RouteShape::kLoop;
  const double length = route_length_m(r);
  double leg_s = 0.0;
  leg_distance(0.0, loop ? r.laps * length : length, r.speed_mps, r.acceleration_mps2, leg_s);
  return loop ? leg_s + 2.0 * r.pause_s : r.laps * 2.0 * (r.pause_s + leg_s) + r.pause_s;
}

}  // namespace harmoloc::sim_host
