// The runs derived from a random scene: other lighting, long runs, kidnaps, a person and a moved
// board.
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "harmoloc/sim_host/lens.hpp"
#include "harmoloc/sim_host/random_scene.hpp"
#include "harmoloc/sim_host/route.hpp"
#include "harmoloc/sim_host/scenario_run.hpp"
#include "harmoloc/sim_host/scene_renderer.hpp"
#include "random_scene_parts.hpp"

namespace harmoloc::sim_host {

using namespace random_scene_detail;

namespace {

std::uint64_t name_hash(const std::string& text) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (const char c : text) {
    h ^= static_cast<unsigned char>(c);
    h *= 0x100000001b3ULL;
  }
  return h;
}

// Keeps the lighting steps at the same share of a run that now lasts @p to_s instead of @p from_s.
void stretch_lighting(Scenario& s, double from_s, double to_s) {
  for (auto& st : s.lighting.steps) st[0] = q(st[0] * to_s / from_s, 10.0);
}

}  // namespace

Scenario with_other_lighting(const Scenario& s, std::uint64_t seed) {
  Scenario out = s;
  Pcg32 rng(seed, kLightingStream);
  Draw d(rng);
  draw_lighting(d, run_duration_s(out), out);
  out.name = s.name + "-light" + std::to_string(seed);
  return out;
}

Scenario long_variant(const Scenario& s, double minutes) {
  Scenario out = s;
  const double before = run_duration_s(s);
  out.route.laps = 1;
  while (run_duration_s(out) < minutes * 60.0 && out.route.laps < 100000) ++out.route.laps;
  stretch_lighting(out, before, run_duration_s(out));
  out.name = s.name + "-long";
  out.description = s.description + "; driven " + std::to_string(out.route.laps) + " laps";
  return out;
}

Scenario kidnap_variant(const Scenario& s, int kidnaps) {
  if (kidnaps < 1) throw std::runtime_error("kidnap_variant: at least 1 kidnap");
  Scenario out = s;
  out.name = s.name + "-kidnap";
  out.occluders.clear();
  out.board_moves.clear();
  // The route's span: kidnaps keep 1 m, or half the span on routes too small for that.
  const auto curve = route_curve(s.route, 0.05);
  double span = 0.0;
  for (std::size_t i = 0; i < curve.size(); i += 2) {
    for (std::size_t j = i + 1; j < curve.size(); j += 2)
      span = std::max(span, std::hypot(curve[i][0] - curve[j][0], curve[i][1] - curve[j][1]));
  }
  out.kidnaps.count = kidnaps;
  out.kidnaps.min_distance_m = q(std::min(1.0, 0.5 * span), 100.0);
  const double before = run_duration_s(s);
  // Try schedules about 15 s apart (the robot needs time to recover between kidnaps) until one
  // works for a few runs of the scene (the kidnap planner throws when none does).
  static const double intervals[] = {15, 14, 16, 13, 17, 12, 18, 20, 22, 25, 30, 11, 10};
  static const double firsts[] = {15, 12, 18, 10, 20, 25, 30};
  std::string last_error;
  for (const double interval : intervals) {
    for (const double first : firsts) {
      out.kidnaps.first_s = first;
      out.kidnaps.interval_s = interval;
      out.route.laps = 1;
      const double need = first + (kidnaps - 1) * interval + 30.0;
      while (run_duration_s(out) < need && out.route.laps < 100000) ++out.route.laps;
      bool ok = true;
      for (std::uint64_t seed = 1; seed <= 3 && ok; ++seed) {
        try {
          Pcg32 motion_rng(seed, 1), kidnap_rng(seed, 5);
          simulate_motion(out, ScenarioRun::kMotionStep_s, motion_rng, nullptr, &kidnap_rng);
        } catch (const std::runtime_error& e) {
          ok = false;
          last_error = e.what();
        }
      }
      if (!ok) continue;
      stretch_lighting(out, before, run_duration_s(out));
      std::ostringstream desc;
      desc << s.description << "; " << kidnaps << " kidnaps (>= " << out.kidnaps.min_distance_m
           << " m) every " << interval << " s from " << first << " s, " << out.route.laps
           << " laps";
      out.description = desc.str();
      return out;
    }
  }
  throw std::runtime_error(s.name + ": no kidnap schedule fits this route (" + last_error + ")");
}

Scenario dynamic_variant(const Scenario& s) {
  Scenario out = s;
  out.name = s.name + "-dynamic";
  out.occluders.clear();
  out.board_moves.clear();
  out.kidnaps = KidnapSpec{};
  const double before = run_duration_s(s);
  out.route.laps = std::max(2, s.route.laps);
  const double duration = run_duration_s(out);
  stretch_lighting(out, before, duration);
  Pcg32 rng(name_hash(s.name), kVariantStream);
  Draw d(rng);
  const ScenarioRun run(out, 1);
  const Scenario proxy = proxy_of(out);
  const auto curve = route_curve(out.route, 0.05);
  const auto clear_of_route = [&](double x, double y, double margin) {
    for (const auto& p : curve) {
      if (std::hypot(p[0] - x, p[1] - y) < margin) return false;
    }
    return true;
  };
  const RoomSpec& room = out.room;
  const auto inside = [&](double x, double y, double margin) {
    return x > room.x_m[0] + margin && x < room.x_m[1] - margin && y > room.y_m[0] + margin &&
           y < room.y_m[1] - margin;
  };
  // The person: stands 3.5 s on the line of sight to a board well in view, near the board (so
  // that the board stays hidden while the robot moves on), clear of the route; walks in and out
  // at 1 m/s from 2.5 m to the side.
  constexpr double kStand_s = 3.5, kWalk_mps = 1.0, kAside_m = 2.5;
  bool placed = false;
  std::size_t hidden_board = out.boards.size();
  std::ostringstream what;
  const double fractions[] = {0.35, 0.45, 0.3, 0.5, 0.4, 0.25, 0.55, 0.6, 0.2, 0.65};
  for (int tries = 0; tries < 3 && !placed; ++tries) {
    for (const double fraction : fractions) {
      if (placed) break;
      const double t_mid = q(fraction * duration + d.u(-2.0, 2.0), 10.0);
      if (t_mid < 5.0 || t_mid > duration - 5.0) continue;
      const auto frame = static_cast<std::size_t>(std::lround(t_mid * out.camera.rate_hz));
      if (frame >= run.frame_count()) continue;
      SceneRenderer clean(proxy);
      clean.set_time(t_mid);
      const Pose2 pose = run.truth(frame);
      const std::vector<std::uint32_t> seen = clean.visible_board_pixels(pose);
      std::vector<std::size_t> order(seen.size());
      for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
      std::stable_sort(order.begin(), order.end(),
                       [&](std::size_t a, std::size_t b) { return seen[a] > seen[b]; });
      const CameraFrame cam = camera_frame_of(out.camera, pose);
      for (std::size_t rank = 0; rank < std::min<std::size_t>(3, order.size()) && !placed; ++rank) {
        const BoardSpec& board = out.boards[order[rank]];
        if (seen[order[rank]] < 150) break;
        const double bx = board.centre_x_m, by = board.centre_y_m;
        const double dist = std::hypot(cam.origin[0] - bx, cam.origin[1] - by);
        for (const double near : {0.6, 0.9, 0.45, 1.2}) {
          if (near > dist - 0.6) continue;
          const double ux = (cam.origin[0] - bx) / dist, uy = (cam.origin[1] - by) / dist;
          const double px = q(bx + near * ux, 1000.0), py = q(by + near * uy, 1000.0);
          if (!inside(px, py, 0.3) || !clear_of_route(px, py, 0.6)) continue;
          // Walk in from the side that stays in the room.
          double ex = px - uy * kAside_m, ey = py + ux * kAside_m;
          if (!inside(ex, ey, 0.3)) {
            ex = px + uy * kAside_m;
            ey = py - ux * kAside_m;
          }
          ex = q(std::clamp(ex, room.x_m[0] + 0.3, room.x_m[1] - 0.3), 1000.0);
          ey = q(std::clamp(ey, room.y_m[0] + 0.3, room.y_m[1] - 0.3), 1000.0);
          const double walk = q(std::hypot(ex - px, ey - py) / kWalk_mps, 10.0);
          const double t0 = q(t_mid - 0.4 * kStand_s, 10.0);
          OccluderSpec person;
          person.name = "person";
          person.colour = grey(d.u(200.0, 250.0), d.u(10.0, 30.0), d.u(70.0, 110.0));
          person.radius_m = q(d.u(0.2, 0.25), 1000.0);
          person.height_m = q(d.u(1.65, 1.85), 1000.0);
          person.path = {{q(t0 - walk, 10.0), ex, ey},
                         {t0, px, py},
                         {q(t0 + kStand_s, 10.0), px, py},
                         {q(t0 + kStand_s + walk, 10.0), ex, ey}};
          if (person.path.front()[0] < 0.0) continue;
          // Hidden (under 30% of its pixels) in every frame of 2.5 s while the person stands?
          Scenario trial = proxy;
          trial.occluders = {person};
          SceneRenderer with(trial), without(proxy);
          bool hidden = true;
          for (double t = t0 + 0.5; t <= t0 + 3.0 && hidden; t += 0.25) {
            const auto k = static_cast<std::size_t>(std::lround(t * out.camera.rate_hz));
            if (k >= run.frame_count()) {
              hidden = false;
              break;
            }
            with.set_time(t);
            without.set_time(t);
            const double a = with.visible_board_pixels(run.truth(k))[order[rank]];
            const double b = without.visible_board_pixels(run.truth(k))[order[rank]];
            hidden = b >= 50.0 && a <= 0.3 * b;
          }
          if (!hidden) continue;
          out.occluders.push_back(person);
          hidden_board = order[rank];
          what << "a person hides " << board.name << " from " << t0 << " s for " << kStand_s
               << " s";
          placed = true;
          break;
        }
      }
    }
  }
  if (!placed) throw std::runtime_error(s.name + ": no place for a person to hide a board");
  // A board moved 30 cm along its wall (a stand's: along its width) halfway through the run: the
  // one most often in view.
  std::vector<double> total(out.boards.size(), 0.0);
  {
    SceneRenderer clean(proxy);
    for (std::size_t k = 0; k < run.frame_count();
         k += std::max<std::size_t>(1, run.frame_count() / 40)) {
      const auto counts = clean.visible_board_pixels(run.truth(k));
      for (std::size_t b = 0; b < counts.size(); ++b) total[b] += counts[b];
    }
  }
  std::vector<std::size_t> order(total.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return total[a] > total[b]; });
  // Another board than the one the person hides, when there is one that can move.
  std::stable_partition(order.begin(), order.end(),
                        [&](std::size_t b) { return b != hidden_board; });
  bool moved = false;
  for (const std::size_t b : order) {
    const BoardSpec& board = out.boards[b];
    double ax = -std::sin(board.facing_yaw_rad), ay = std::cos(board.facing_yaw_rad);
    if (!board.stand) {
      // Along the nearest wall.
      const double to_x = std::min(board.centre_x_m - room.x_m[0], room.x_m[1] - board.centre_x_m);
      const double to_y = std::min(board.centre_y_m - room.y_m[0], room.y_m[1] - board.centre_y_m);
      ax = to_y < to_x ? 1.0 : 0.0;
      ay = to_y < to_x ? 0.0 : 1.0;
    }
    const double half = 0.5 * board.width_m + 0.1;
    const double first = d.chance(0.5) ? 1.0 : -1.0;
    for (const double sg : {first, -first}) {
      const double dx = q(0.3 * sg * ax, 1000.0), dy = q(0.3 * sg * ay, 1000.0);
      const double nx = board.centre_x_m + dx, ny = board.centre_y_m + dy;
      const bool fits =
          board.stand ? inside(nx, ny, half) && clear_of_route(nx, ny, kStandClearance_m + half)
                      : (ax != 0.0 ? nx > room.x_m[0] + half && nx < room.x_m[1] - half
                                   : ny > room.y_m[0] + half && ny < room.y_m[1] - half);
      if (!fits) continue;
      BoardMoveSpec m;
      m.board = board.name;
      m.at_s = q(0.55 * duration, 10.0);
      m.offset_m = {dx, dy, 0.0};
      out.board_moves.push_back(m);
      what << "; " << board.name << " moved 30 cm at " << m.at_s << " s";
      moved = true;
      break;
    }
    if (moved) break;
  }
  if (!moved) throw std::runtime_error(s.name + ": no board can move 30 cm along its wall");
  out.description = s.description + "; " + std::to_string(out.route.laps) + " laps; " + what.str();
  return out;
}

}  // namespace harmoloc::sim_host
