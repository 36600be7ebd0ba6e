#include "harmoloc/sim_host/route.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <sstream>
#include <stdexcept>

namespace harmoloc::sim_host {

using algorithms::kPi;
using algorithms::Pose2;
using algorithms::wrap_angle_rad;

namespace {

struct Polyline {
  std::vector<double> x, y, s;  // s: cumulative arc length
  bool closed = false;          // a loop: arc lengths wrap round
  double length() const { return s.back(); }
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
Polyline make_path(const std::vector<std::array<double, 2>>& w, bool closed, int steps = 400) {
  if (w.size() < 2) throw std::runtime_error("a route needs at least 2 waypoints");
  if (closed && w.size() < 3) throw std::runtime_error("a loop needs at least 3 waypoints");
  Polyline p;
  p.closed = closed;
  const std::size_t n = w.size();
  const auto count = static_cast<std::ptrdiff_t>(n);
  auto pt = [&](std::ptrdiff_t i) {
    if (closed) return w[static_cast<std::size_t>(((i % count) + count) % count)];
    return w[static_cast<std::size_t>(std::clamp<std::ptrdiff_t>(i, 0, count - 1))];
  };
  const int kSteps = steps;
  const std::size_t segments = closed ? n : n - 1;
  for (std::size_t i = 0; i < segments; ++i) {
    const auto p0 = pt(static_cast<std::ptrdiff_t>(i) - 1), p1 = pt(static_cast<std::ptrdiff_t>(i)),
               p2 = pt(static_cast<std::ptrdiff_t>(i) + 1),
               p3 = pt(static_cast<std::ptrdiff_t>(i) + 2);
    for (int k = (i == 0 ? 0 : 1); k <= kSteps; ++k) {
      const double t = static_cast<double>(k) / kSteps, t2 = t * t, t3 = t2 * t;
      double c[2];
      for (int d = 0; d < 2; ++d) {
        c[d] = 0.5 * (2 * p1[d] + (-p0[d] + p2[d]) * t +
                      (2 * p0[d] - 5 * p1[d] + 4 * p2[d] - p3[d]) * t2 +
                      (-p0[d] + 3 * p1[d] - 3 * p2[d] + p3[d]) * t3);
      }
      p.x.push_back(c[0]);
      p.y.push_back(c[1]);
    }
  }
  p.s.assign(p.x.size(), 0.0);
  for (std::size_t k = 1; k < p.x.size(); ++k)
    p.s[k] = p.s[k - 1] + std::hypot(p.x[k] - p.x[k - 1], p.y[k] - p.y[k - 1]);
  return p;
}

// Distance covered after time t on a leg of length L with a trapezoidal speed profile.
double leg_distance(double t, double length, double v, double a, double& duration) {
  double t_acc = v / a;
  double d_acc = 0.5 * a * t_acc * t_acc;
  if (2.0 * d_acc > length) {  // triangle: never reaches cruise speed
    t_acc = std::sqrt(length / a);
    d_acc = 0.5 * length;
    v = a * t_acc;
  }
  const double t_cruise = (length - 2.0 * d_acc) / v;
  duration = 2.0 * t_acc + t_cruise;
  if (t <= 0.0) return 0.0;
  if (t < t_acc) return 0.5 * a * t * t;
  if (t < t_acc + t_cruise) return d_acc + v * (t - t_acc);
  if (t < duration) {
    const double r = duration - t;
    return length - 0.5 * a * r * r;
  }
  return length;
}

constexpr double kLegMargin_s = 0.1;  // "driving": this far inside a leg

// Chooses where a kidnapped robot is put down. Places are route clock phases within a lap, on a
// grid of at most kMaxPhases points (10 ms apart on short laps). A shuttle's lap is forth and
// back with its pauses; a loop's is once round at cruising speed (the phases of its cruise).
class KidnapPlanner {
 public:
  /// The position at phase @p phase_s (route clock within a lap).
  using PlaceFn = std::function<void(double phase_s, double& x_m, double& y_m)>;
  /// The route clock to put the robot down at for phase @p phase_s at run time @p t_s (negative:
  /// none in this run).
  using TauFn = std::function<double(double phase_s, double t_s)>;
  /// The phase a route clock falls on (0 after the route's end).
  using PhaseFn = std::function<double(double route_t_s)>;
  using DrivingFn = std::function<bool(double phase_s)>;

  // Works out, for each phase a kidnap may start from and each number of kidnaps still to come,
  // whether a target exists from which all of them can keep the minimum distance. Positions here
  // are the route's own (@p nominal, without the wander), so the distance must hold with a margin
  // of twice the wander's bound on both ends.
  void plan(double lap_s, const DrivingFn& driving, const KidnapSpec& spec, double wander_bound_m,
            const PlaceFn& nominal) {
    spec_ = spec;
    lap_s_ = lap_s;
    phases_ = std::min<std::size_t>(kMaxPhases,
                                    static_cast<std::size_t>(std::ceil(lap_s / kPhaseStep_s)));
    dphi_ = lap_s / static_cast<double>(phases_);
    driving_.assign(phases_, 0);
    std::vector<double> x(phases_), y(phases_);
    std::vector<std::size_t> next(phases_);
    for (std::size_t j = 0; j < phases_; ++j) {
      const double phi = static_cast<double>(j) * dphi_;
      driving_[j] = driving(phi) ? 1 : 0;
      nominal(phi, x[j], y[j]);
      next[j] = index_of(std::fmod(phi + spec.interval_s, lap_s));
    }
    const double far_m = spec.min_distance_m + 2.0 * wander_bound_m + kGridMargin_m;
    const auto step = [&](const std::vector<char>* later) {
      std::vector<std::size_t> targets;
      for (std::size_t j = 0; j < phases_; ++j) {
        if (driving_[j] && (later == nullptr || (*later)[next[j]])) targets.push_back(j);
      }
      std::vector<char> ok(phases_, 0);
      for (std::size_t j = 0; j < phases_; ++j) {
        for (const std::size_t t : targets) {
          if (std::hypot(x[t] - x[j], y[t] - y[j]) >= far_m) {
            ok[j] = 1;
            break;
          }
        }
      }
      return ok;
    };
    ok_.clear();
    ok_.push_back(step(nullptr));
    // The sets shrink with every level; they settle within a few levels on real routes. Beyond
    // kMaxLookahead levels the last is used (a later kidnap may then find no place: an error).
    for (int r = 1; r < spec.count && r < kMaxLookahead; ++r) {
      std::vector<char> ok = step(&ok_.back());
      if (ok == ok_.back()) break;  // a fixed point: the same for any more kidnaps
      ok_.push_back(std::move(ok));
    }
  }

  // The route time to put the robot down at, for kidnap @p k (0-based) at run time @p t_s; the
  // next kidnap comes @p next_gap_s later (negative: none). @p place gives the exact position
  // (with the wander) a route time would put the robot at now.
  double choose(std::size_t k, double t_s, double next_gap_s, const Pose2& from,
                algorithms::Pcg32& rng, const PlaceFn& place, const TauFn& tau_for,
                const PhaseFn& phase_of) const {
    const std::size_t later = static_cast<std::size_t>(spec_.count) - 1 - k;
    std::vector<double> good, far;
    for (std::size_t j = 0; j < phases_; ++j) {
      if (!driving_[j]) continue;
      const double phi = static_cast<double>(j) * dphi_;
      double x = 0.0, y = 0.0;
      place(phi, x, y);
      if (std::hypot(x - from.x_m, y - from.y_m) < spec_.min_distance_m) continue;
      const double tau = tau_for(phi, t_s);
      if (tau < 0.0) continue;
      far.push_back(tau);
      if (later > 0) {
        const std::size_t next = index_of(phase_of(tau + next_gap_s));
        if (!ok_[std::min(later - 1, ok_.size() - 1)][next]) continue;
      }
      good.push_back(tau);
    }
    // Without a place that keeps every later kidnap possible, any far enough place will do (a
    // later kidnap may then fail with the error below).
    const std::vector<double>& pick = good.empty() ? far : good;
    if (pick.empty()) {
      std::ostringstream msg;
      msg << "kidnap " << k + 1 << " at " << t_s << " s: no place where the robot drives on the "
          << "route is " << spec_.min_distance_m << " m or more from (" << from.x_m << ", "
          << from.y_m << "); move kidnaps.first_s or kidnaps.interval_s, or lower "
          << "kidnaps.min_distance_m";
      throw std::runtime_error(msg.str());
    }
    const auto i =
        std::min(pick.size() - 1,
                 static_cast<std::size_t>(rng.uniform() * static_cast<double>(pick.size())));
    return pick[i];
  }

 private:
  static constexpr std::size_t kMaxPhases = 4000;
  static constexpr int kMaxLookahead = 64;
  static constexpr double kPhaseStep_s = 0.01;
  static constexpr double kGridMargin_m = 0.005;

  std::size_t index_of(double phase_s) const {
    return static_cast<std::size_t>(std::llround(phase_s / dphi_)) % phases_;
  }

  KidnapSpec spec_;
  double lap_s_ = 0.0;
  double dphi_ = 0.0;
  std::size_t phases_ = 0;
  std::vector<char> driving_;
  std::vector<std::vector<char>> ok_;  // ok_[r][phase]: a kidnap from there, r more after it
};

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
  // Wheel travel from the pose increments (standard differential drive); none across a jump.
  const double half_track = 0.5 * scenario.robot.track_m;
  double mean_sin = 0.0, mean_cos = 0.0;
  std::size_t next_jump = 0;
  for (std::size_t i = 0; i < count; ++i) {
    mean_sin += std::sin(out[i].pose.yaw_rad);
    mean_cos += std::cos(out[i].pose.yaw_rad);
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
  if (stats != nullptr) {
    stats->length_m = length;
    stats->duration_s = total_s;
    const double mean = std::atan2(mean_sin, mean_cos);
    double worst = 0.0;
    for (const MotionSample& m : out)
      worst = std::max(worst, std::fabs(wrap_angle_rad(m.pose.yaw_rad - mean)));
    stats->max_heading_offset_deg = worst * 180.0 / kPi;
  }
  if (kidnaps != nullptr) *kidnaps = std::move(events);
  return out;
}

std::vector<std::array<double, 2>> route_curve(const RouteSpec& route, double step_m) {
  const Polyline path = make_path(route.waypoints_m, route.shape == RouteShape::kLoop);
  const double length = path.length();
  const auto n = std::max<std::size_t>(2, static_cast<std::size_t>(std::ceil(length / step_m)) + 1);
  std::vector<std::array<double, 2>> out;
  out.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    double x, y, tx, ty;
    path.at(length * static_cast<double>(i) / static_cast<double>(n - 1), x, y, tx, ty);
    out.push_back({x, y});
  }
  return out;
}

double run_duration_s(const Scenario& scenario) {
  const RouteSpec& r = scenario.route;
  const bool loop = r.shape == RouteShape::kLoop;
  const double length = route_length_m(r);
  double leg_s = 0.0;
  leg_distance(0.0, loop ? r.laps * length : length, r.speed_mps, r.acceleration_mps2, leg_s);
  return loop ? leg_s + 2.0 * r.pause_s : r.laps * 2.0 * (r.pause_s + leg_s) + r.pause_s;
}

double route_length_m(const RouteSpec& route) {
  return make_path(route.waypoints_m, route.shape == RouteShape::kLoop).length();
}

bool route_crosses_itself(const RouteSpec& route, std::string* why) {
  constexpr double kClearance_m = 0.05;
  const bool loop = route.shape == RouteShape::kLoop;
  const Polyline path = make_path(route.waypoints_m, loop, 40);
  const std::size_t n = path.x.size();
  const double length = path.length();
  // Two points closer than the clearance whose distance along the curve is more than a few times
  // it (so not neighbours), or segments that intersect.
  const auto along = [&](std::size_t i, std::size_t j) {
    const double d = std::fabs(path.s[i] - path.s[j]);
    return loop ? std::min(d, length - d) : d;
  };
  const auto cross = [](double ax, double ay, double bx, double by, double cx, double cy, double dx,
                        double dy) {
    const auto orient = [](double px, double py, double qx, double qy, double rx, double ry) {
      return (qx - px) * (ry - py) - (qy - py) * (rx - px);
    };
    const double o1 = orient(ax, ay, bx, by, cx, cy), o2 = orient(ax, ay, bx, by, dx, dy);
    const double o3 = orient(cx, cy, dx, dy, ax, ay), o4 = orient(cx, cy, dx, dy, bx, by);
    return ((o1 > 0) != (o2 > 0)) && ((o3 > 0) != (o4 > 0));
  };
  for (std::size_t i = 0; i + 1 < n; ++i) {
    for (std::size_t j = i + 2; j + 1 < n; ++j) {
      if (along(i, j) < 4.0 * kClearance_m || along(i + 1, j) < 4.0 * kClearance_m ||
          along(i, j + 1) < 4.0 * kClearance_m)
        continue;
      const bool close = std::hypot(path.x[i] - path.x[j], path.y[i] - path.y[j]) < kClearance_m;
      if (close || cross(path.x[i], path.y[i], path.x[i + 1], path.y[i + 1], path.x[j], path.y[j],
                         path.x[j + 1], path.y[j + 1])) {
        if (why != nullptr) {
          std::ostringstream m;
          m << "the " << (loop ? "loop" : "route") << " crosses or touches itself near ("
            << path.x[i] << ", " << path.y[i] << ")";
          *why = m.str();
        }
        return true;
      }
    }
  }
  return false;
}

}  // namespace harmoloc::sim_host
