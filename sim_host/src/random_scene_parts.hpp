#pragma once
/// @file What the pieces of the random scene family (random_scene*.cpp) share: the constants,
/// the rounding and the draws, and the steps of drawing a scene. Private to sim_host/src.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "harmoloc/algorithms/geometry.hpp"
#include "harmoloc/algorithms/random.hpp"
#include "harmoloc/sim_host/lens.hpp"
#include "harmoloc/sim_host/scenario.hpp"

namespace harmoloc::sim_host::random_scene_detail {

using algorithms::kPi;
using algorithms::Pcg32;
using algorithms::Pose2;

constexpr double kDeg = kPi / 180.0;
constexpr double kStandClearance_m = 0.6;  // a stand keeps this far from the route
// The lighting the family allows over a run (and thresholds_for is set for): +-30%.
constexpr double kMinGain = 0.7;
constexpr double kMaxGain = 1.3;
// Stream numbers of the random draws (Pcg32's second argument).
constexpr std::uint64_t kAttemptStream = 1000;
constexpr std::uint64_t kKindStream = 999;
constexpr std::uint64_t kLightingStream = 77;
constexpr std::uint64_t kVariantStream = 91;

// Rounded to 1 / @p per_unit (a decimal that reads back as the same double).
inline double q(double x, double per_unit) {
  return std::round(x * per_unit) / per_unit;
}

class Draw {
 public:
  explicit Draw(Pcg32& rng) : rng_(rng) {}
  double u(double lo, double hi) { return rng_.uniform(lo, hi); }
  /// Whole number in [lo, hi].
  int i(int lo, int hi) {
    return lo +
           static_cast<int>(std::min<double>(hi - lo, std::floor(rng_.uniform() * (hi - lo + 1))));
  }
  bool chance(double p) { return rng_.uniform() < p; }
  std::uint32_t bits() { return rng_.next_u32(); }

 private:
  Pcg32& rng_;
};

// random_scene.cpp: the route and the camera the placement and the feasibility check look with.
std::vector<Pose2> route_places(const RouteSpec& route);
Scenario proxy_of(const Scenario& s);

// random_scene_draw.cpp: the camera, the lighting, the route, the room and the robot.
double widest_ray_rad(const CameraSpec& c);
void draw_camera(Draw& d, double min_fov_deg, CameraSpec& c);
void draw_lighting(Draw& d, double duration_s, Scenario& s);
std::optional<RouteSpec> draw_route(Draw& d, RouteShape shape);
void draw_room(Draw& d, Scenario& s);
void draw_robot(Draw& d, Scenario& s);

// random_scene_board_placement.cpp: the boards, where the camera sees them along the route.

// The view of the route the placement works with: the proxy camera at the route's places.
struct Views {
  Scenario proxy;
  LensModel lens;
  std::vector<Pose2> places;
  std::vector<CameraFrame> frames;
  double frame_px = 0.0;
  double usable_px = 0.0;
  double focal_px = 0.0;
  double half_vfov_rad = 0.0;
  double half_hfov_rad = 0.0;  // of the true view (with the lens) across the width
};

Views views_of(const Scenario& s);
std::optional<std::vector<BoardSpec>> place_boards(Draw& d, const Scenario& s, const Views& v,
                                                   int count);

// random_scene_colours.cpp: the colours of the room's things and of the boards.
Rgb grey(double hue_deg, double s8, double v8);
void colour_boards(Draw& d, std::vector<BoardSpec>& boards);

}  // namespace harmoloc::sim_host::random_scene_detail
