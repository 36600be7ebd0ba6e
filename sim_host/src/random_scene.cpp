#include "harmoloc/sim_host/random_scene.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "harmoloc/algorithms/random.hpp"
#include "harmoloc/sim_host/route.hpp"
#include "harmoloc/sim_host/scene_renderer.hpp"
#include "random_scene_parts.hpp"

namespace harmoloc::sim_host::random_scene_detail {

namespace {

constexpr double kCheckStep_m = 0.25;
constexpr double kCheckTurn_deg = 15.0;  // a tour's turns on the spot, checked this often
constexpr std::uint32_t kProxyWidth_px = 320;

}  // namespace

// Where the camera would be along the route: the route's own places every kCheckStep_m with the
// heading of the curve (driven forward; a shuttle's way back is the same places reversing); a
// tour's places as driven, its turns on the spot every kCheckTurn_deg.
std::vector<Pose2> route_places(const RouteSpec& route) {
  if (route.shape == RouteShape::kTour) return tour_places(route, kCheckStep_m, kCheckTurn_deg);
  const auto pts = route_curve(route, kCheckStep_m);
  std::vector<Pose2> out;
  const bool loop = route.shape == RouteShape::kLoop;
  const std::size_t n = loop ? pts.size() - 1 : pts.size();  // a loop's last point is its first
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t a = i == 0 ? (loop ? pts.size() - 2 : 0) : i - 1;
    const std::size_t b = i + 1 < pts.size() ? i + 1 : i;
    const double yaw = std::atan2(pts[b][1] - pts[a][1], pts[b][0] - pts[a][0]);
    out.push_back(Pose2{pts[i][0], pts[i][1], yaw});
  }
  return out;
}

// The scene with its camera scaled to kProxyWidth_px (same field, lens and aspect): the
// feasibility check and the board placement look through it.
Scenario proxy_of(const Scenario& s) {
  Scenario p = s;
  CameraSpec& c = p.camera;
  const double scale = static_cast<double>(kProxyWidth_px) / c.width_px;
  c.height_px =
      std::max<std::uint32_t>(16, static_cast<std::uint32_t>(std::lround(c.height_px * scale)));
  c.width_px = kProxyWidth_px;
  c.principal_offset_x_px *= scale;
  c.principal_offset_y_px *= scale;
  p.occluders.clear();
  p.board_moves.clear();
  p.kidnaps = KidnapSpec{};
  return p;
}

}  // namespace harmoloc::sim_host::random_scene_detail

namespace harmoloc::sim_host {

using namespace random_scene_detail;

namespace {

constexpr int kMaxAttempts = 500;

// One attempt at a scene. The route's shape and the labels' kind are the seed's (drawn once
// from their own stream), so that redrawn attempts keep the family's mix.
std::optional<Scenario> draw_scene(std::uint64_t seed, Draw& d) {
  Scenario s;
  s.name = "random-" + std::to_string(seed);
  Pcg32 kind_rng(seed, kKindStream);
  const RouteShape shape = kind_rng.uniform() < 0.5 ? RouteShape::kLoop : RouteShape::kShuttle;
  s.labels_with_heading = kind_rng.uniform() < 0.5;
  const std::optional<RouteSpec> route = draw_route(d, shape);
  if (!route) return std::nullopt;
  s.route = *route;
  const bool loop = s.route.shape == RouteShape::kLoop;
  // A loop turns the camera all round: it takes a wider view and more boards to keep two in
  // view everywhere.
  draw_camera(d, loop ? 80.0 : 60.0, s.camera);
  draw_room(d, s);
  if (route_crosses_itself(s.route)) return std::nullopt;
  draw_robot(d, s);
  s.labelled_frames = 64;
  const Views v = views_of(s);
  const int count = loop ? d.i(6, 8) : d.i(3, 8);
  std::optional<std::vector<BoardSpec>> boards = place_boards(d, s, v, count);
  if (!boards) return std::nullopt;
  colour_boards(d, *boards);
  s.boards = std::move(*boards);
  draw_lighting(d, run_duration_s(s), s);
  return s;
}

std::string describe(const Scenario& s, int attempt, const FeasibilityReport& f) {
  std::ostringstream o;
  o.precision(3);
  const CameraSpec& c = s.camera;
  std::size_t ellipses = 0, stands = 0;
  for (const BoardSpec& b : s.boards) {
    ellipses += b.shape == BoardShape::kEllipse ? 1 : 0;
    stands += b.stand ? 1 : 0;
  }
  o << "random scene: " << (s.route.shape == RouteShape::kLoop ? "loop" : "shuttle") << " route "
    << route_length_m(s.route) << " m at " << s.route.speed_mps << " m/s in a "
    << s.room.x_m[1] - s.room.x_m[0] << " x " << s.room.y_m[1] - s.room.y_m[0] << " m room"
    << (s.desk.present ? " with a desk" : "") << "; " << s.boards.size() << " boards (" << ellipses
    << " ellipses, " << stands << " on stands); " << c.width_px << "x" << c.height_px << ", k1 "
    << c.k1 << ", noise " << c.pixel_noise << "; labels "
    << (s.labels_with_heading ? "with heading" : "yaw 0") << "; feasible at attempt " << attempt + 1
    << " (>= " << f.min_boards_in_view << " boards in view at " << f.points << " places, 3+ at "
    << std::lround(100.0 * f.share_with_three) << "%)";
  return o.str();
}

}  // namespace

FeasibilityReport check_feasibility(const Scenario& s) {
  FeasibilityReport r;
  const Scenario proxy = proxy_of(s);
  const SceneRenderer renderer(proxy);
  const double frame_px =
      static_cast<double>(proxy.camera.width_px) * static_cast<double>(proxy.camera.height_px);
  const double usable = std::max(60.0, kUsableBoardShare * frame_px);
  const std::vector<Pose2> places = route_places(s.route);
  r.points = places.size();
  r.min_boards_in_view = s.boards.size();
  std::size_t three = 0;
  for (const Pose2& p : places) {
    const std::vector<std::uint32_t> counts = renderer.visible_board_pixels(p);
    std::size_t in_view = 0;
    for (const std::uint32_t c : counts) {
      in_view += c >= usable ? 1 : 0;
      r.max_board_share = std::max(r.max_board_share, c / frame_px);
    }
    r.min_boards_in_view = std::min(r.min_boards_in_view, in_view);
    three += in_view >= 3 ? 1 : 0;
  }
  r.share_with_three =
      places.empty() ? 0.0 : static_cast<double>(three) / static_cast<double>(places.size());
  std::ostringstream why;
  if (r.min_boards_in_view < 2) {
    why << "a place on the route sees only " << r.min_boards_in_view << " usable boards";
  } else if (r.max_board_share > kMaxBoardShare) {
    why << "a board fills " << std::lround(100.0 * r.max_board_share) << "% of the frame";
  }
  r.reason = why.str();
  r.feasible = r.reason.empty();
  return r;
}

Scenario random_scenario(std::uint64_t seed) {
  for (int attempt = 0; attempt < kMaxAttempts; ++attempt) {
    Pcg32 rng(seed, kAttemptStream + static_cast<std::uint64_t>(attempt));
    Draw d(rng);
    std::optional<Scenario> s = draw_scene(seed, d);
    if (!s) continue;
    const FeasibilityReport f = check_feasibility(*s);
    if (!f.feasible) continue;
    s->description = describe(*s, attempt, f);
    return *s;
  }
  throw std::runtime_error("random scene " + std::to_string(seed) + ": no feasible draw in " +
                           std::to_string(kMaxAttempts) + " attempts");
}

}  // namespace harmoloc::sim_host
