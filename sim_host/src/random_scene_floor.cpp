// The floor runs of a random scene (issue 20): a coverage run that drives lanes over a floor
// around the trained route at several headings (the training run of a floor map), and test runs
// that visit random poses on that floor, never driven in training (turns on the spot, straight
// legs).
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "harmoloc/sim_host/random_scene.hpp"
#include "harmoloc/sim_host/route.hpp"
#include "harmoloc/sim_host/scene_renderer.hpp"
#include "random_scene_parts.hpp"

namespace harmoloc::sim_host {

using namespace random_scene_detail;
using algorithms::wrap_angle_rad;

namespace {

constexpr double kGridStep_m = 0.2;        // the floor's covered places are checked this often
constexpr double kWallMargin_m = 0.5;      // the floor keeps this far from the walls
constexpr double kDeskMargin_m = 0.3;      // and from the desk
constexpr double kCoverageBudget_s = 360;  // a coverage run lasts about this long at most
constexpr double kMinCoverageSpeed_mps = 0.15;
constexpr double kLaneSpacing_m = 0.35;  // lanes this far apart, widened to fit the budget
constexpr double kFeasibleShare = 0.8;   // a heading is covered where this share sees 2 boards
constexpr std::uint64_t kFloorStream = 131;
constexpr double kKidnapFirst_s = 10.0;     // a roam's kidnaps: the first,
constexpr double kKidnapInterval_s = 10.0;  // and one every this long

struct Frame2 {
  double ux, uy;  // the floor's long axis
  double vx() const { return -uy; }
  double vy() const { return ux; }
};

double usable_px(const Scenario& proxy) {
  const double frame_px =
      static_cast<double>(proxy.camera.width_px) * static_cast<double>(proxy.camera.height_px);
  return std::max(60.0, kUsableBoardShare * frame_px);
}

std::size_t boards_in_view(const SceneRenderer& r, const Pose2& p, double usable) {
  std::size_t n = 0;
  for (const std::uint32_t c : r.visible_board_pixels(p)) n += c >= usable ? 1 : 0;
  return n;
}

bool on_floor(const FloorPlan& f, double x, double y, double inset_m) {
  const double dx = x - f.centre_x_m, dy = y - f.centre_y_m;
  const double u = dx * std::cos(f.axis_rad) + dy * std::sin(f.axis_rad);
  const double v = -dx * std::sin(f.axis_rad) + dy * std::cos(f.axis_rad);
  return std::fabs(u) <= f.half_length_m - inset_m && std::fabs(v) <= f.half_width_m - inset_m;
}

// Whether the floor's corners keep clear of the walls and the desk.
bool clear_of_room(const Scenario& s, const FloorPlan& f) {
  const double c = std::cos(f.axis_rad), sn = std::sin(f.axis_rad);
  for (const double a : {-1.0, 1.0}) {
    for (const double b : {-1.0, 1.0}) {
      const double x = f.centre_x_m + a * f.half_length_m * c - b * f.half_width_m * sn;
      const double y = f.centre_y_m + a * f.half_length_m * sn + b * f.half_width_m * c;
      if (x < s.room.x_m[0] + kWallMargin_m || x > s.room.x_m[1] - kWallMargin_m ||
          y < s.room.y_m[0] + kWallMargin_m || y > s.room.y_m[1] - kWallMargin_m)
        return false;
      if (s.desk.present && x > s.desk.x_m[0] - kDeskMargin_m &&
          x < s.desk.x_m[1] + kDeskMargin_m && y > s.desk.front_y_m - kDeskMargin_m)
        return false;
    }
  }
  return true;
}

// The places of the floor the checks look at: a grid kGridStep_m apart, inset half a step.
std::vector<std::array<double, 2>> grid_of(const FloorPlan& f) {
  std::vector<std::array<double, 2>> out;
  const double c = std::cos(f.axis_rad), sn = std::sin(f.axis_rad);
  const int nu = std::max(1, static_cast<int>(std::floor(2.0 * f.half_length_m / kGridStep_m)));
  const int nv = std::max(1, static_cast<int>(std::floor(2.0 * f.half_width_m / kGridStep_m)));
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) {
      const double u = -f.half_length_m + (i + 0.5) * 2.0 * f.half_length_m / nu;
      const double v = -f.half_width_m + (j + 0.5) * 2.0 * f.half_width_m / nv;
      out.push_back({f.centre_x_m + u * c - v * sn, f.centre_y_m + u * sn + v * c});
    }
  }
  return out;
}

// The candidate headings: a shuttle's camera faces one way (its mean heading and 20 degrees
// either side); a loop's turns all round (four, a quarter turn apart, from the floor's axis).
std::vector<double> candidate_headings(const Scenario& s, double axis_rad) {
  std::vector<double> out;
  if (s.route.shape == RouteShape::kLoop) {
    for (int k = 0; k < 4; ++k) out.push_back(wrap_angle_rad(axis_rad + k * 0.5 * kPi));
    return out;
  }
  double sx = 0.0, sy = 0.0;
  for (const Pose2& p : route_places(s.route)) {
    sx += std::cos(p.yaw_rad);
    sy += std::sin(p.yaw_rad);
  }
  const double mean = std::atan2(sy, sx);
  for (const double d : {-20.0, 0.0, 20.0}) out.push_back(wrap_angle_rad(mean + d * kDeg));
  return out;
}

// Lanes along heading @p h over the floor, @p spacing_m apart: the tour's waypoints (a zigzag:
// forward along a lane, back diagonally to the next one's start, reversing), starting from the
// end nearest (@p from_x, @p from_y).
void add_lanes(const FloorPlan& f, double h, double spacing_m, double from_x, double from_y,
               std::vector<std::array<double, 3>>& out) {
  const double ex = std::cos(h), ey = std::sin(h), nx = -ey, ny = ex;
  const double c = std::cos(f.axis_rad), sn = std::sin(f.axis_rad);
  const double hu = f.half_length_m - 0.05, hv = f.half_width_m - 0.05;
  // The floor's extent across the lanes.
  double bmax = 0.0;
  for (const double a : {-1.0, 1.0})
    for (const double b : {-1.0, 1.0})
      bmax = std::max(bmax,
                      std::fabs((a * hu * c - b * hv * sn) * nx + (a * hu * sn + b * hv * c) * ny));
  std::vector<std::array<double, 4>> lanes;  // x0, y0, x1, y1
  const int n = std::max(1, static_cast<int>(std::floor((2.0 * bmax - 0.2) / spacing_m)) + 1);
  for (int k = 0; k < n; ++k) {
    const double b = n == 1 ? 0.0 : -bmax + 0.1 + k * (2.0 * bmax - 0.2) / (n - 1);
    // The line centre + b n + a e inside |u| <= hu, |v| <= hv: an interval of a.
    const double px = b * nx, py = b * ny;
    double lo = -1e9, hi = 1e9;
    const double pu = px * c + py * sn, pv = -px * sn + py * c;
    const double eu = ex * c + ey * sn, ev = -ex * sn + ey * c;
    const auto clip = [&](double p, double e, double half) {
      if (std::fabs(e) < 1e-12) {
        if (std::fabs(p) > half) hi = lo - 1.0;
        return;
      }
      const double a0 = (-half - p) / e, a1 = (half - p) / e;
      lo = std::max(lo, std::min(a0, a1));
      hi = std::min(hi, std::max(a0, a1));
    };
    clip(pu, eu, hu);
    clip(pv, ev, hv);
    if (hi - lo < 0.3) continue;  // a corner's sliver
    lanes.push_back({f.centre_x_m + px + lo * ex, f.centre_y_m + py + lo * ey,
                     f.centre_x_m + px + hi * ex, f.centre_y_m + py + hi * ey});
  }
  if (lanes.empty()) return;
  const auto dist = [&](const std::array<double, 4>& l) {
    return std::hypot(l[0] - from_x, l[1] - from_y);
  };
  if (dist(lanes.back()) < dist(lanes.front())) std::reverse(lanes.begin(), lanes.end());
  const double deg = h / kDeg;
  for (const auto& l : lanes) {
    out.push_back({q(l[0], 1000.0), q(l[1], 1000.0), q(deg, 100.0)});
    out.push_back({q(l[2], 1000.0), q(l[3], 1000.0), q(deg, 100.0)});
  }
}

// The scene with its route replaced by an empty tour (one lap, no wander) and without events.
Scenario floor_tour_of(const Scenario& s) {
  Scenario out = s;
  out.occluders.clear();
  out.board_moves.clear();
  out.kidnaps = KidnapSpec{};
  RouteSpec& r = out.route;
  r.shape = RouteShape::kTour;
  r.laps = 1;
  r.wander_m = 0.0;
  r.waypoints_m.clear();
  r.heading_deg.clear();
  return out;
}

// Keeps @p out's lighting steps at the share of its run they had in @p scene's.
void keep_lighting_shares(const Scenario& scene, Scenario& out) {
  const double before = run_duration_s(scene), after = run_duration_s(out);
  for (auto& st : out.lighting.steps) st[0] = q(st[0] * after / before, 10.0);
}

}  // namespace

FloorPlan floor_plan(const Scenario& s) {
  const auto curve = route_curve(s.route, 0.05);
  double mx = 0.0, my = 0.0;
  for (const auto& p : curve) {
    mx += p[0];
    my += p[1];
  }
  mx /= static_cast<double>(curve.size());
  my /= static_cast<double>(curve.size());
  double sxx = 0.0, syy = 0.0, sxy = 0.0;
  for (const auto& p : curve) {
    sxx += (p[0] - mx) * (p[0] - mx);
    syy += (p[1] - my) * (p[1] - my);
    sxy += (p[0] - mx) * (p[1] - my);
  }
  FloorPlan f;
  f.axis_rad = 0.5 * std::atan2(2.0 * sxy, sxx - syy);
  const double c = std::cos(f.axis_rad), sn = std::sin(f.axis_rad);
  double u0 = 1e9, u1 = -1e9, v0 = 1e9, v1 = -1e9;
  for (const auto& p : curve) {
    const double u = (p[0] - mx) * c + (p[1] - my) * sn, v = -(p[0] - mx) * sn + (p[1] - my) * c;
    u0 = std::min(u0, u), u1 = std::max(u1, u), v0 = std::min(v0, v), v1 = std::max(v1, v);
  }
  // The floor: the route's extent with a margin, within what a few minutes of lanes cover.
  const double speed = std::max(s.route.speed_mps, kMinCoverageSpeed_mps);
  const double budget_m2 = speed * kCoverageBudget_s * kLaneSpacing_m / (2.0 * 3.0);
  f.half_length_m = std::clamp(0.5 * (u1 - u0) + 0.3, 0.5, 1.5);
  f.half_width_m = std::clamp(0.5 * (v1 - v0) + 0.3, 0.5, 1.0);
  const double area = 4.0 * f.half_length_m * f.half_width_m;
  if (area > budget_m2) {
    const double k = std::sqrt(budget_m2 / area);
    f.half_length_m = std::max(0.4, f.half_length_m * k);
    f.half_width_m = std::max(0.4, f.half_width_m * k);
  }
  f.centre_x_m = mx + 0.5 * (u0 + u1) * c - 0.5 * (v0 + v1) * sn;
  f.centre_y_m = my + 0.5 * (u0 + u1) * sn + 0.5 * (v0 + v1) * c;
  // Where the floor misses the walls, the desk or the boards' view: smaller, and nearer the
  // route's middle.
  const auto mid = curve[curve.size() / 2];
  const Scenario proxy = proxy_of(s);
  const SceneRenderer renderer(proxy);
  const double usable = usable_px(proxy);
  std::string why = "no try";
  for (int attempt = 0; attempt < 12; ++attempt) {
    if (attempt > 0) {
      f.half_length_m = std::max(0.3, 0.85 * f.half_length_m);
      f.half_width_m = std::max(0.3, 0.85 * f.half_width_m);
      f.centre_x_m += 0.3 * (mid[0] - f.centre_x_m);
      f.centre_y_m += 0.3 * (mid[1] - f.centre_y_m);
    }
    if (!clear_of_room(s, f)) {
      why = "the floor runs into a wall or the desk";
      continue;
    }
    const auto grid = grid_of(f);
    f.headings_rad.clear();
    for (const double h : candidate_headings(s, f.axis_rad)) {
      std::size_t fine = 0;
      for (const auto& p : grid)
        fine += boards_in_view(renderer, Pose2{p[0], p[1], h}, usable) >= 2;
      if (static_cast<double>(fine) >= kFeasibleShare * static_cast<double>(grid.size()))
        f.headings_rad.push_back(h);
    }
    if (f.headings_rad.size() >= 2) {
      f.places = grid.size();
      return f;
    }
    why = "fewer than 2 headings see 2 boards over the floor";
  }
  throw std::runtime_error(s.name + ": no floor to cover (" + why + ")");
}

Scenario coverage_variant(const Scenario& s) {
  const FloorPlan f = floor_plan(s);
  Scenario out = floor_tour_of(s);
  RouteSpec& r = out.route;
  r.speed_mps = std::max(s.route.speed_mps, kMinCoverageSpeed_mps);
  double spacing = kLaneSpacing_m;
  for (int attempt = 0; attempt < 10; ++attempt, spacing *= 1.2) {
    std::vector<std::array<double, 3>> poses;
    for (const double h : f.headings_rad) {
      const double x = poses.empty() ? f.centre_x_m : poses.back()[0];
      const double y = poses.empty() ? f.centre_y_m : poses.back()[1];
      add_lanes(f, h, spacing, x, y, poses);
    }
    r.waypoints_m.clear();
    r.heading_deg.clear();
    for (const auto& p : poses) {
      r.waypoints_m.push_back({p[0], p[1]});
      r.heading_deg.push_back(p[2]);
    }
    if (run_duration_s(out) <= kCoverageBudget_s * 1.2) break;
  }
  keep_lighting_shares(s, out);
  out.name = s.name + "-coverage";
  std::ostringstream d;
  d.precision(3);
  d << s.description << "; coverage run over a " << 2.0 * f.half_length_m << " x "
    << 2.0 * f.half_width_m << " m floor at " << f.headings_rad.size() << " headings (";
  for (std::size_t k = 0; k < f.headings_rad.size(); ++k)
    d << (k ? ", " : "") << std::lround(f.headings_rad[k] / kDeg);
  d << " deg), lanes " << spacing << " m apart, " << route_length_m(r) << " m in "
    << run_duration_s(out) << " s";
  out.description = d.str();
  return out;
}

Scenario roam_variant(const Scenario& s, std::uint64_t seed, int waypoints, int kidnaps) {
  if (waypoints < 2) throw std::runtime_error("roam_variant: at least 2 waypoints");
  if (kidnaps < 0) throw std::runtime_error("roam_variant: kidnaps must not be negative");
  const FloorPlan f = floor_plan(s);
  const Scenario proxy = proxy_of(s);
  const SceneRenderer renderer(proxy);
  const double usable = usable_px(proxy);
  Pcg32 rng(seed, kFloorStream);
  Draw d(rng);
  Scenario out = floor_tour_of(s);
  RouteSpec& r = out.route;
  const auto draw_pose = [&]() {
    const double u = d.u(-1.0, 1.0) * (f.half_length_m - 0.1);
    const double v = d.u(-1.0, 1.0) * (f.half_width_m - 0.1);
    const double h = f.headings_rad[static_cast<std::size_t>(
                         d.i(0, static_cast<int>(f.headings_rad.size()) - 1))] +
                     d.u(-12.0, 12.0) * kDeg;
    const double c = std::cos(f.axis_rad), sn = std::sin(f.axis_rad);
    return std::array<double, 3>{q(f.centre_x_m + u * c - v * sn, 1000.0),
                                 q(f.centre_y_m + u * sn + v * c, 1000.0),
                                 q(wrap_angle_rad(h) / kDeg, 100.0)};
  };
  // Every place of every leg (and of its turns on the spot) sees 2 boards.
  const auto leg_fine = [&](const std::array<double, 3>& a, const std::array<double, 3>& b) {
    RouteSpec leg = r;
    leg.waypoints_m = {{a[0], a[1]}, {b[0], b[1]}};
    leg.heading_deg = {a[2], b[2]};
    for (const Pose2& p : tour_places(leg, 0.1, 10.0)) {
      if (!on_floor(f, p.x_m, p.y_m, 0.0) || boards_in_view(renderer, p, usable) < 2) return false;
    }
    return true;
  };
  const auto add = [&](const std::array<double, 3>& p) {
    r.waypoints_m.push_back({p[0], p[1]});
    r.heading_deg.push_back(p[2]);
  };
  const auto start = [&]() {
    for (int tries = 0; tries < 200; ++tries) {
      const std::array<double, 3> p = draw_pose();
      if (leg_fine(p, p)) return add(p);
    }
    throw std::runtime_error(s.name + ": no place on the floor to start a roam");
  };
  start();
  // With kidnaps the roam lasts until 10 s after the last one (more poses where needed).
  KidnapSpec& ks = out.kidnaps;
  ks.first_s = kKidnapFirst_s;
  ks.interval_s = kKidnapInterval_s;
  ks.min_distance_m = std::min(1.0, 0.4 * std::hypot(2.0 * f.half_length_m, 2.0 * f.half_width_m));
  const double need_s = kidnaps > 0 ? ks.first_s + (kidnaps - 1) * ks.interval_s + 10.0 : 0.0;
  // A pose from which no leg keeps 2 boards in view is a dead end: the roam steps back to the
  // pose before it (or starts afresh) and draws on from there. Random floor 1's roam with
  // kidnaps met one and the sweep had no kidnaps on that floor.
  int step_backs = 0;
  for (int legs = 1; static_cast<int>(r.waypoints_m.size()) < waypoints ||
                     (kidnaps > 0 && run_duration_s(out) < need_s);
       ++legs) {
    if (legs > 1000) throw std::runtime_error(s.name + ": the roam cannot be made long enough");
    const std::array<double, 3> at{r.waypoints_m.back()[0], r.waypoints_m.back()[1],
                                   r.heading_deg.back()};
    bool found = false;
    for (int tries = 0; tries < 200 && !found; ++tries) {
      const std::array<double, 3> next = draw_pose();
      if (std::hypot(next[0] - at[0], next[1] - at[1]) < 0.3 || !leg_fine(at, next)) continue;
      add(next);
      found = true;
    }
    if (found) continue;
    // Bounded: a floor where most poses are dead ends fails as before, and soon.
    if (++step_backs > 20)
      throw std::runtime_error(s.name + ": no roam leg that keeps 2 boards in view");
    r.waypoints_m.pop_back();
    r.heading_deg.pop_back();
    if (r.waypoints_m.empty()) start();
  }
  // The kidnaps, one by one: where the robot is at the kidnap's time (with the earlier ones),
  // a pose on the floor far enough from it from which the rest of its way keeps 2 boards in view.
  for (int k = 0; k < kidnaps; ++k) {
    const double t_k = ks.first_s + k * ks.interval_s;
    bool found = false;
    for (int tries = 0; tries < 300 && !found; ++tries) {
      const std::array<double, 3> to = draw_pose();
      Scenario trial = out;
      trial.kidnaps.count = k + 1;
      trial.kidnaps.poses.push_back(to);
      Pcg32 motion_rng(seed, kFloorStream + 1);
      std::vector<KidnapEvent> events;
      std::vector<MotionSample> m;
      try {
        m = simulate_motion(trial, 0.05, motion_rng, nullptr, nullptr, &events);
      } catch (const std::runtime_error&) {
        continue;
      }
      if (events.size() != static_cast<std::size_t>(k + 1)) continue;
      const KidnapEvent& e = events.back();
      if (std::hypot(e.to.x_m - e.from.x_m, e.to.y_m - e.from.y_m) < ks.min_distance_m) continue;
      bool fine = true;
      for (std::size_t i = 0; i < m.size() && fine; i += 5) {
        if (m[i].t_s < t_k - 1e-9) continue;
        if (m[i].t_s > t_k + ks.interval_s) break;
        fine = on_floor(f, m[i].pose.x_m, m[i].pose.y_m, 0.0) &&
               boards_in_view(renderer, m[i].pose, usable) >= 2;
      }
      if (!fine) continue;
      out = trial;
      found = true;
    }
    if (!found)
      throw std::runtime_error(s.name + ": no kidnap place on the floor for kidnap " +
                               std::to_string(k + 1));
  }
  keep_lighting_shares(s, out);
  out.name = s.name + "-roam" + std::to_string(seed);
  std::ostringstream o;
  o.precision(3);
  o << s.description << "; roam " << seed << ": " << r.waypoints_m.size() << " poses on the floor, "
    << route_length_m(r) << " m";
  if (kidnaps > 0)
    o << ", " << kidnaps << " kidnaps (at least " << ks.min_distance_m << " m) every "
      << ks.interval_s << " s from " << ks.first_s << " s";
  out.description = o.str();
  return out;
}

}  // namespace harmoloc::sim_host
