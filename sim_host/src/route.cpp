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
  double length() const { return s.back(); }
  void at(double si, double& px, double& py, double& tx, double& ty) const {
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

// Catmull-Rom through the waypoints (end points repeated), densely sampled.
Polyline make_path(const std::vector<std::array<double, 2>>& w) {
  if (w.size() < 2) throw std::runtime_error("a route needs at least 2 waypoints");
  Polyline p;
  const std::size_t n = w.size();
  auto pt = [&](std::ptrdiff_t i) {
    return w[static_cast<std::size_t>(
        std::clamp<std::ptrdiff_t>(i, 0, static_cast<std::ptrdiff_t>(n) - 1))];
  };
  constexpr int kSteps = 400;
  for (std::size_t i = 0; i + 1 < n; ++i) {
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

// Chooses where a kidnapped robot is put down. Places are route clock phases within a lap, on a
// grid of at most kMaxPhases points (10 ms apart on short laps).
class KidnapPlanner {
 public:
  using PlaceFn = std::function<void(double route_t_s, double& x_m, double& y_m)>;

  // Works out, for each phase a kidnap may start from and each number of kidnaps still to come,
  // whether a target exists from which all of them can keep the minimum distance. Positions here
  // are the route's own (@p nominal, without the wander), so the distance must hold with a margin
  // of twice the wander's bound on both ends.
  void plan(double lap_s, double pause_s, double leg_s, const KidnapSpec& spec,
            double wander_bound_m, const PlaceFn& nominal) {
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
      const bool forward = phi > pause_s + kLegMargin_s && phi < pause_s + leg_s - kLegMargin_s;
      const bool back = phi > 2.0 * pause_s + leg_s + kLegMargin_s && phi < lap_s - kLegMargin_s;
      driving_[j] = forward || back ? 1 : 0;
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
  double choose(std::size_t k, double t_s, double next_gap_s, int laps, const Pose2& from,
                algorithms::Pcg32& rng, const PlaceFn& place) const {
    const std::size_t later = static_cast<std::size_t>(spec_.count) - 1 - k;
    std::vector<double> good, far;
    for (std::size_t j = 0; j < phases_; ++j) {
      if (!driving_[j]) continue;
      const double phi = static_cast<double>(j) * dphi_;
      double x = 0.0, y = 0.0;
      place(phi, x, y);
      if (std::hypot(x - from.x_m, y - from.y_m) < spec_.min_distance_m) continue;
      // The latest lap that puts the route clock at or before the run time, so that the rest of
      // the run fits in the route; in the first lap that is not always possible, and the robot
      // then finishes its route early and waits at its start.
      const double lap =
          std::clamp(std::floor((t_s - phi) / lap_s_), 0.0, static_cast<double>(laps - 1));
      const double tau = lap * lap_s_ + phi;
      far.push_back(tau);
      if (later > 0) {
        const double next_tau = tau + next_gap_s;
        const std::size_t next =
            next_tau >= laps * lap_s_ ? 0 : index_of(std::fmod(next_tau, lap_s_));
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
  static constexpr double kLegMargin_s = 0.1;  // "driving": this far inside a leg
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
  const Polyline path = make_path(r.waypoints_m);
  const double length = path.length();
  double leg_s = 0.0;
  leg_distance(0.0, length, r.speed_mps, r.acceleration_mps2, leg_s);
  const double lap_s = 2.0 * (r.pause_s + leg_s);
  const double total_s = r.laps * lap_s + r.pause_s;

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

  // Where the route clock @p tau puts the robot: arc length along the route and the direction of
  // travel (0 while it stands: the pauses at both ends and after the last lap).
  auto route_at = [&](double tau, double& s, int& dir) {
    double leg = 0.0;
    const double in_lap = std::fmod(tau, lap_s);
    const bool done = tau >= r.laps * lap_s;
    s = 0.0;
    dir = 0;
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
    planner.plan(lap_s, r.pause_s, leg_s, ks, wander_bound, [&](double tau, double& x, double& y) {
      double s = 0.0, tx, ty;
      int dir = 0;
      route_at(tau, s, dir);
      path.at(s, x, y, tx, ty);
    });
  }

  std::vector<MotionSample> out(count);
  std::vector<KidnapEvent> events;
  double travelled = 0.0, last_s = 0.0;
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
      const double tau = planner.choose(k, t, next_gap_s, r.laps, from, *kidnap_rng,
                                        [&](double route_t, double& x, double& y) {
                                          double s = 0.0;
                                          int dir = 0;
                                          route_at(route_t, s, dir);
                                          position(s, travelled, x, y);
                                        });
      shift_s = tau - t;
    }
    const double tau = t + shift_s;
    double s = 0.0;
    int dir = 0;
    route_at(tau, s, dir);
    if (!jump) travelled += std::fabs(s - last_s);  // the wander carries on across a jump
    last_s = s;
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

}  // namespace harmoloc::sim_host
