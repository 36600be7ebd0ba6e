#pragma once
/// @file Where a kidnapped robot is put down (simulate_motion's kidnaps, route.cpp). Private to
/// sim_host/src.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <functional>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "harmoloc/algorithms/geometry.hpp"
#include "harmoloc/algorithms/random.hpp"
#include "harmoloc/sim_host/scenario.hpp"

namespace harmoloc::sim_host::route_detail {

using algorithms::Pose2;

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

}  // namespace harmoloc::sim_host::route_detail
