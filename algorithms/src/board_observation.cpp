#include "harmoloc/algorithms/board_observation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace harmoloc::algorithms {

BoardFeatures board_features(float area_scale, const AreaVector& areas) {
  BoardFeatures f;
  f.count = std::min(areas.count, kMaxBoards);
  for (std::size_t b = 0; b < f.count; ++b) {
    f.value[b] = static_cast<float>(areas.pixels[b]) * area_scale;
    if (areas.cut_by_side(b)) f.cut_mask |= 1U << b;
  }
  return f;
}

BoardFeatures board_features(const ForwardMap& map, float area_scale, const AreaVector& areas) {
  BoardFeatures f = board_features(area_scale, areas);
  if (!map.has_bearings) return f;
  for (std::size_t b = 0; b < f.count; ++b) {
    if (board_image_angle(map, areas, b, f.angle_rad[b])) f.angle_mask |= 1U << b;
  }
  return f;
}

std::array<float, kMaxBoards> board_maxima(const ForwardMap& map) {
  std::array<float, kMaxBoards> m{};
  const std::size_t boards = std::min<std::size_t>(map.board_count, kMaxBoards);
  const bool terms = ForwardMap::kHeadingTermStorage && map.has_heading_terms;
  for (std::size_t c = 0; c < map.stored_cells(); ++c) {
    const float* e = map.expected.data() + c * kMaxBoards;
    // With heading terms, the most the cell expects at any heading.
    const float* t = terms ? map.heading_terms.data() + c * kMaxBoards * 2 : nullptr;
    for (std::size_t b = 0; b < boards; ++b)
      m[b] = std::max(m[b], e[b] + (t != nullptr ? std::hypot(t[2 * b], t[2 * b + 1]) : 0.0F));
  }
  return m;
}

bool frame_implausible(const ForwardMap& map, const std::array<float, kMaxBoards>& maxima,
                       const BoardFeatures& observed, double ratio) {
  if (!(ratio > 0.0)) return false;
  const std::size_t boards = std::min<std::size_t>({map.board_count, observed.count, kMaxBoards});
  std::size_t modelled = 0, beyond = 0;
  for (std::size_t b = 0; b < boards; ++b) {
    if (!(map.sigma[b] > 0.0F)) continue;
    ++modelled;
    if (static_cast<double>(observed.value[b]) > ratio * static_cast<double>(maxima[b])) ++beyond;
  }
  return modelled > 0 && 2 * beyond > modelled;
}

namespace {

/// Each board's bearing log-likelihood at one place, free of the robot's heading (bit b of mask:
/// board b has one there).
struct BearingFit {
  std::array<double, kMaxBoards> log_like{};
  std::uint32_t mask = 0;
  double heading_rad = 0.0;  ///< the heading the bearings agree on
};

/// The boards' bearings at a place, weighed without knowing the heading: each board seen whole
/// implies one (its image angle plus the map's world bearing of it there), and at the right place
/// they agree. The heading is the one that fits most boards (each board's own tried, each other
/// board costing its chi2 up to that of the outlier floor; then moved to the mean of those within
/// three widths), so a single moved board costs only itself. With fewer than two such boards
/// there is nothing to compare: none. With @p heading_hint_rad (the heading found at a place
/// nearby: the robot has one heading) the bearings are read at the camera's place at once. Near
/// the robot's own place, where it matters, the hint is within degrees of the heading found there,
/// which moves the camera's place by millimetres.
BearingFit bearing_fit(const ForwardMap& map, const BoardFeatures& observed, double x_m, double y_m,
                       const BoardModelParams& params, std::uint32_t leave_out,
                       const double* heading_hint_rad = nullptr) {
  BearingFit fit;
  if (!params.bearings || !map.has_bearings) return fit;
  const std::size_t boards = std::min<std::size_t>({map.board_count, observed.count, kMaxBoards});
  const double c = params.outlier_floor;
  // Beyond this chi2 a board's likelihood is mostly the floor's: -2 ln c.
  const double chi2_cap = c > 0.0 ? -2.0 * std::log(c) : std::numeric_limits<double>::infinity();
  std::array<double, kMaxBoards> implied{}, inv_var{};
  std::uint32_t mask = 0;
  double heading = heading_hint_rad != nullptr ? *heading_hint_rad : 0.0;
  // Where the bearings are read depends on the heading when the camera sits ahead of the axle:
  // without a hint, a first pass at the axle's place gives the heading, a second at the camera's.
  const bool ahead = map.bearing_camera_forward_m != 0.0F;
  const int passes = ahead && heading_hint_rad == nullptr ? 2 : 1;
  for (int pass = 0; pass < passes; ++pass) {
    const bool at_camera = ahead && (pass == 1 || heading_hint_rad != nullptr);
    const GridPoint at = at_camera
                             ? bearing_point(map, x_m, y_m, std::cos(heading), std::sin(heading))
                             : locate(map, x_m, y_m);
    mask = 0;
    for (std::size_t b = 0; b < boards; ++b) {
      const double sigma = static_cast<double>(map.bearing_sigma_rad[b]);
      float bearing = 0.0F;
      if (((observed.angle_mask >> b) & 1U) == 0U || ((leave_out >> b) & 1U) != 0U ||
          !(map.sigma[b] > 0.0F) || !(sigma > 0.0) || !expected_bearing(map, at, b, bearing))
        continue;
      implied[b] =
          wrap_once_rad(static_cast<double>(observed.angle_rad[b]) + static_cast<double>(bearing));
      inv_var[b] = 1.0 / (sigma * sigma);
      mask |= 1U << b;
    }
    if (__builtin_popcount(mask) < 2) return fit;
    double best_cost = std::numeric_limits<double>::infinity();
    for (std::uint32_t m = mask; m != 0U; m &= m - 1U) {
      const double h = implied[static_cast<std::size_t>(__builtin_ctz(m))];
      double cost = 0.0;
      for (std::uint32_t n = mask; n != 0U; n &= n - 1U) {
        const auto b = static_cast<std::size_t>(__builtin_ctz(n));
        const double r = wrap_once_rad(implied[b] - h);
        cost += std::min(r * r * inv_var[b], chi2_cap);
      }
      if (cost < best_cost) {
        best_cost = cost;
        heading = h;
      }
    }
    double shift = 0.0, weight = 0.0;
    for (std::uint32_t n = mask; n != 0U; n &= n - 1U) {
      const auto b = static_cast<std::size_t>(__builtin_ctz(n));
      const double r = wrap_once_rad(implied[b] - heading);
      if (r * r * inv_var[b] > 9.0) continue;
      shift += r * inv_var[b];
      weight += inv_var[b];
    }
    if (weight > 0.0) heading = wrap_once_rad(heading + shift / weight);
  }
  for (std::uint32_t n = mask; n != 0U; n &= n - 1U) {
    const auto b = static_cast<std::size_t>(__builtin_ctz(n));
    const double r = wrap_once_rad(implied[b] - heading);
    fit.log_like[b] = std::log(std::exp(-0.5 * r * r * inv_var[b]) + c);
  }
  fit.mask = mask;
  fit.heading_rad = heading;
  return fit;
}

// board_preference from what the map expects at place a (@p ea) and at place b (@p eb), and the
// boards' bearings' fits there (@p bearing_a, @p bearing_b).
double preference(const ForwardMap& map, const BoardFeatures& observed, const float* ea,
                  const float* eb, const BearingFit& bearing_a, const BearingFit& bearing_b,
                  const BoardModelParams& params, std::uint32_t leave_out) {
  const std::size_t boards = std::min<std::size_t>({map.board_count, observed.count, kMaxBoards});
  const double c = params.outlier_floor;
  const double hidden = std::max(params.hidden_floor, c);
  double sum = 0.0;
  for (std::size_t b = 0; b < boards; ++b) {
    if (!(map.sigma[b] > 0.0F) || ((leave_out >> b) & 1U) != 0U) continue;
    const double cut = cut_width(observed, params, b);
    if (!(cut > 0.0)) continue;
    // The trained noise itself, not widened by sigma_scale: that widening is for weighing a
    // cloud frame after frame; here two places are compared, and the evidence must hold for
    // several frames before it counts.
    const double width = cut * static_cast<double>(map.sigma[b]);
    const double ra = (static_cast<double>(observed.value[b]) - static_cast<double>(ea[b])) / width;
    const double rb = (static_cast<double>(observed.value[b]) - static_cast<double>(eb[b])) / width;
    const double la = std::exp(-0.5 * ra * ra) + c;
    double lb = std::exp(-0.5 * rb * rb) + c;
    // A board that shows less than place b expects may be hidden there (a person, a box): that
    // is likelier than an arbitrary outlier, so b loses less by it.
    if (rb < 0.0) lb = std::max(lb, hidden);
    sum += std::log(la) - std::log(lb);
    // A board seen whole shows where it is, hidden or not elsewhere: its bearing counts where
    // both places have one.
    if (((bearing_a.mask & bearing_b.mask) >> b) & 1U)
      sum += bearing_a.log_like[b] - bearing_b.log_like[b];
  }
  return sum;
}

}  // namespace

double board_preference(const ForwardMap& map, const BoardFeatures& observed, double ax_m,
                        double ay_m, double bx_m, double by_m, const BoardModelParams& params,
                        std::uint32_t leave_out, double yaw_rad) {
  std::array<float, kMaxBoards> ea{}, eb{};
  const SeenHeading heading = seen_heading(yaw_rad);
  expected_at_pose(map, locate(map, ax_m, ay_m), ax_m, ay_m, heading, ea.data());
  expected_at_pose(map, locate(map, bx_m, by_m), bx_m, by_m, heading, eb.data());
  return preference(map, observed, ea.data(), eb.data(),
                    bearing_fit(map, observed, ax_m, ay_m, params, leave_out),
                    bearing_fit(map, observed, bx_m, by_m, params, leave_out), params, leave_out);
}

PlacePreference board_preference_near(const ForwardMap& map, const BoardFeatures& observed,
                                      double ax_m, double ay_m, double radius_m, double bx_m,
                                      double by_m, double min_distance_m,
                                      const BoardModelParams& params, std::uint32_t leave_out,
                                      double yaw_rad) {
  // Place b and the heading are the same for every candidate.
  const SeenHeading heading = seen_heading(yaw_rad);
  std::array<float, kMaxBoards> ea{}, eb{};
  expected_at_pose(map, locate(map, bx_m, by_m), bx_m, by_m, heading, eb.data());
  const BearingFit bearing_b = bearing_fit(map, observed, bx_m, by_m, params, leave_out);
  expected_at_pose(map, locate(map, ax_m, ay_m), ax_m, ay_m, heading, ea.data());
  const BearingFit bearing_a = bearing_fit(map, observed, ax_m, ay_m, params, leave_out);
  PlacePreference best{
      preference(map, observed, ea.data(), eb.data(), bearing_a, bearing_b, params, leave_out),
      ax_m, ay_m};
  if (!(radius_m > 0.0) || !map.present()) return best;
  const double* hint = bearing_a.mask != 0U ? &bearing_a.heading_rad : nullptr;
  // A grid of at most 25 x 25 places over the disc, none finer than the map's cells.
  const double step = std::max(static_cast<double>(map.cell_m), radius_m / 12.0);
  const int reach = static_cast<int>(std::floor(radius_m / step));
  const double on_route_m = params.route_free_m + 2.0 * params.route_sigma_m;
  for (int j = -reach; j <= reach; ++j) {
    for (int i = -reach; i <= reach; ++i) {
      const double dx = i * step, dy = j * step;
      if (dx * dx + dy * dy > radius_m * radius_m || (i == 0 && j == 0)) continue;
      const double x = ax_m + dx, y = ay_m + dy;
      if (std::hypot(x - bx_m, y - by_m) < min_distance_m) continue;
      const GridPoint at = locate(map, x, y);
      if (static_cast<double>(route_distance(map, at)) > on_route_m) continue;
      expected_at_pose(map, at, x, y, heading, ea.data());
      const double nats = preference(map, observed, ea.data(), eb.data(),
                                     bearing_fit(map, observed, x, y, params, leave_out, hint),
                                     bearing_b, params, leave_out);
      if (nats > best.nats) best = PlacePreference{nats, x, y};
    }
  }
  return best;
}

namespace {

/// For each board of @p boards (bit b) whose bearing the map holds for a robot at (@p x_m,
/// @p y_m) facing @p yaw_rad (@p cos_yaw, @p sin_yaw): the smaller of @p residual[b] and
/// |yaw - angle_b - phi_b| (infinite: none yet), phi_b read at the bearings' place, or the
/// difference of the angles where the map projects the board's bearing.
void fit_bearings(const ForwardMap& map, double x_m, double y_m, double yaw_rad, double cos_yaw,
                  double sin_yaw, const BoardFeatures& observed, std::uint32_t boards,
                  std::array<double, kMaxBoards>& residual) {
  if (boards == 0U) return;
  const GridPoint at = bearing_point(map, x_m, y_m, cos_yaw, sin_yaw);
  CameraOnce camera(map.projection, x_m, y_m, cos_yaw, sin_yaw);
  for (std::uint32_t mask = boards; mask != 0U; mask &= mask - 1U) {
    const auto b = static_cast<std::size_t>(__builtin_ctz(mask));
    if (b >= observed.count) continue;
    if (map.projection.points[b] != 0U) {
      float angle = 0.0F;
      if (!projected_image_angle(map, camera.get(), b, angle)) continue;
      residual[b] = std::min(residual[b], std::fabs(static_cast<double>(angle) -
                                                    static_cast<double>(observed.angle_rad[b])));
      continue;
    }
    float bearing = 0.0F;
    if (!expected_bearing(map, at, b, bearing)) continue;
    double d = yaw_rad - static_cast<double>(observed.angle_rad[b]) - static_cast<double>(bearing);
    // yaw and bearing lie in [-pi, pi] and the law's angle within a half turn (as in the
    // particle filter's update): two turns at most.
    d = wrap_once_rad(wrap_once_rad(d));
    residual[b] = std::min(residual[b], std::fabs(d));
  }
}

/// How many poses near the estimate fit_near_quadratics projects from (near_poses).
constexpr std::size_t kNearPoses = 18;

/// NearQuadratic's value at offset @p d (dx, dy, dyaw), in double for the fit.
double quadratic_at(const std::array<double, 10>& q, const double (&d)[3]) {
  return NearQuadratic::value(q, d[0], d[1], d[2]);
}

/// The pairs of axes whose corners give the quadratic's cross terms: (x, y), (x, yaw), (y, yaw).
constexpr std::size_t kPairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};

/// One board's quadratic about the estimate (NearQuadratic::q) from its values at
/// near_poses's offsets: the gradient and the curvatures along the axes from the centre and
/// the six moves along them, the cross terms from the three corners (+, +); whether it misses
/// the values at the other eight corners by at most @p tolerance.
bool fit_quadratic(const std::array<float, kNearPoses>& at,
                   const std::array<std::array<double, 3>, kNearPoses>& offsets, double tolerance,
                   std::array<float, 10>& quadratic) {
  std::array<double, 10> q{};
  q[0] = static_cast<double>(at[0]);
  for (std::size_t k = 0; k < 3; ++k) {
    const double h = offsets[2 + 2 * k][k];
    const auto lo = static_cast<double>(at[1 + 2 * k]), hi = static_cast<double>(at[2 + 2 * k]);
    q[1 + k] = (hi - lo) / (2.0 * h);
    q[4 + k] = (hi + lo - 2.0 * q[0]) / (2.0 * h * h);
  }
  // The cross terms: what the corner adds beyond the axes' terms.
  for (std::size_t p = 0; p < 3; ++p) {
    const std::size_t i = kPairs[p][0], j = kPairs[p][1];
    const std::array<double, 3>& d = offsets[7 + p];
    const double without = quadratic_at(q, {d[0], d[1], d[2]});
    q[7 + p] = (static_cast<double>(at[7 + p]) - without) / (d[i] * d[j]);
  }
  bool fits = true;
  for (std::size_t k = 10; k < kNearPoses; ++k) {
    const std::array<double, 3>& d = offsets[k];
    fits = fits &&
           std::fabs(quadratic_at(q, {d[0], d[1], d[2]}) - static_cast<double>(at[k])) <= tolerance;
  }
  for (std::size_t k = 0; k < 10; ++k) quadratic[k] = static_cast<float>(q[k]);
  return fits;
}

/// The offsets from the estimate the projections are taken at, for a reach of @p reach_m along
/// x and y and @p reach_rad along the heading: the estimate; minus and plus the reach along x,
/// y and the heading; the corners (+, +) of the pairs (x, y), (x, yaw), (y, yaw); their
/// corners (-, -) and (+, -); and the two corners (+, +, +) and (-, -, -).
std::array<std::array<double, 3>, kNearPoses> near_poses(double reach_m, double reach_rad) {
  const double h[3] = {reach_m, reach_m, reach_rad};
  std::array<std::array<double, 3>, kNearPoses> o{};
  for (std::size_t k = 0; k < 3; ++k) {
    o[1 + 2 * k][k] = -h[k];
    o[2 + 2 * k][k] = h[k];
  }
  for (std::size_t p = 0; p < 3; ++p) {
    const std::size_t i = kPairs[p][0], j = kPairs[p][1];
    o[7 + p][i] = h[i];
    o[7 + p][j] = h[j];
    o[10 + p][i] = -h[i];
    o[10 + p][j] = -h[j];
    o[13 + p][i] = h[i];
    o[13 + p][j] = -h[j];
  }
  o[16] = {h[0], h[1], h[2]};
  o[17] = {-h[0], -h[1], -h[2]};
  return o;
}

/// The projections near the estimate @p at for one reach: the poses' offsets and cameras.
struct NearViews {
  std::array<std::array<double, 3>, kNearPoses> offsets{};
  std::array<CameraAtPose, kNearPoses> cameras{};

  NearViews(const ForwardMap& map, const Pose2& at, double reach_m, double reach_rad)
      : offsets(near_poses(reach_m, reach_rad)) {
    for (std::size_t k = 0; k < kNearPoses; ++k) {
      const double x = at.x_m + offsets[k][0], y = at.y_m + offsets[k][1];
      const double yaw = at.yaw_rad + offsets[k][2];
      cameras[k] =
          camera_at_pose(map.projection, static_cast<float>(x), static_cast<float>(y),
                         static_cast<float>(std::cos(yaw)), static_cast<float>(std::sin(yaw)));
    }
  }
};

// The share of the cloud's spread its particles are weighed over: the bandwidth Silverman's
// rule of thumb gives a kernel density over @p particles points in three dimensions (x, y and
// the heading), (4 / (5 n))^(1/7): 0.36 of the spread at 1024 particles, 0.44 at 256.
double kernel_bandwidth_share(std::size_t particles) {
  return std::pow(4.0 / (5.0 * static_cast<double>(particles)), 1.0 / 7.0);
}

/// BoardUpdate's quadratics near the estimate @p at (BoardUpdate::near_bearing, near_area): the
/// bearings of the projected boards of @p bearing_boards, each to a tolerance of its spread, the
/// areas of @p area_boards (bit b), each to a tolerance of @p area_noise[b] (the projection's
/// noise widened by the cloud's spread, as the particles are weighed with it); the reach from
/// the cloud's spread (@p position_sigma_m, @p yaw_sigma_rad). A few dozen projections a board a
/// frame, where the particles would take one each.
void fit_near_quadratics(const ForwardMap& map, const Pose2& at, std::uint32_t bearing_boards,
                         std::uint32_t area_boards, const std::array<float, kMaxBoards>& area_noise,
                         double position_sigma_m, double yaw_sigma_rad, BoardUpdate& update) {
  update.near_bearing_mask = 0;
  update.near_area_mask = 0;
  update.near_at = at;
  std::uint32_t outlines = 0;
  for (std::uint32_t mask = bearing_boards; mask != 0U; mask &= mask - 1U) {
    const auto b = static_cast<std::size_t>(__builtin_ctz(mask));
    if (b < kMaxBoards && map.projection.points[b] != 0U) outlines |= 1U << b;
  }
  bearing_boards = outlines;
  if ((bearing_boards | area_boards) == 0U) return;
  // The reaches, widest first: two sigma of the cloud's, half of it, the narrowest.
  const double narrow_m = BoardUpdate::kNearReach_m, narrow_rad = BoardUpdate::kNearReach_rad;
  const double wide_m = std::clamp(2.0 * position_sigma_m, narrow_m, 0.15);
  const double wide_rad = std::clamp(2.0 * yaw_sigma_rad, narrow_rad, 10.0 * kPi / 180.0);
  const double reaches[3][2] = {
      {wide_m, wide_rad},
      {std::max(narrow_m, 0.5 * wide_m), std::max(narrow_rad, 0.5 * wide_rad)},
      {narrow_m, narrow_rad}};
  // One reach's projections at a time (1.3 KB on the stack), each board trying the reaches in
  // turn until one fits.
  std::uint32_t bearings_left = bearing_boards, areas_left = area_boards;
  for (std::size_t t = 0; t < 3 && (bearings_left | areas_left) != 0U; ++t) {
    // A reach no wider than the next one's is tried there.
    if (t < 2 && !(reaches[t][0] > reaches[t + 1][0] || reaches[t][1] > reaches[t + 1][1]))
      continue;
    const NearViews views(map, at, reaches[t][0], reaches[t][1]);
    const auto take = [&](const std::array<float, kNearPoses>& values, double tolerance,
                          NearQuadratic& near) {
      if (!fit_quadratic(values, views.offsets, tolerance, near.q)) return false;
      near.reach_m = static_cast<float>(reaches[t][0]);
      near.reach_rad = static_cast<float>(reaches[t][1]);
      return true;
    };
    for (std::uint32_t mask = bearings_left | areas_left; mask != 0U; mask &= mask - 1U) {
      const auto b = static_cast<std::size_t>(__builtin_ctz(mask));
      bool angles = ((bearings_left >> b) & 1U) != 0U, areas = ((areas_left >> b) & 1U) != 0U;
      std::array<float, kNearPoses> angle{}, feature{};
      for (std::size_t k = 0; k < kNearPoses && (angles || areas); ++k) {
        const ProjectedOutline o = project_outline(map.projection, views.cameras[k], b, areas);
        angles = angles && o.has_column;
        areas = areas && o.has_area;
        if (angles) angle[k] = image_angle_of_column(map, o.column_px);
        if (areas) feature[k] = o.area_px * map.projection.area_per_px[b];
      }
      if (angles && take(angle,
                         static_cast<double>(BoardUpdate::kNearTolerance) *
                             static_cast<double>(weighed_bearing_sigma_rad(map, b)),
                         update.near_bearing[b])) {
        update.near_bearing_mask |= 1U << b;
        bearings_left &= ~(1U << b);
      }
      if (areas && take(feature,
                        static_cast<double>(BoardUpdate::kNearTolerance) *
                            static_cast<double>(area_noise[b]),
                        update.near_area[b])) {
        update.near_area_mask |= 1U << b;
        areas_left &= ~(1U << b);
      }
    }
  }
}

}  // namespace

void BoardReliability::reset(const BoardModelParams& params) {
  static_probability_.fill(params.motion_index_max);
  moved_.fill(false);
}

BoardAssessment BoardReliability::assess(const ForwardMap& map, const BoardFeatures& observed,
                                         const Pose2& estimate, const BoardModelParams& params,
                                         BoardUpdate& update, double yaw_variance_rad2,
                                         double position_sigma_m, std::size_t particles) {
  BoardAssessment a;
  update.map = &map;
  update.boards = std::min<std::size_t>(map.board_count, observed.count);
  const GridPoint at = locate(map, estimate.x_m, estimate.y_m);
  std::array<float, kMaxBoards> expected{};
  const SeenHeading heading = seen_heading(estimate.yaw_rad);
  expected_at_pose(map, at, estimate.x_m, estimate.y_m, heading, expected.data());
  // The range of what the map expects within the spread around the estimate (a cross of four
  // points): a board whose area falls inside it, or nearest its edge, is judged by that.
  std::array<float, kMaxBoards> lo = expected, hi = expected;
  // The same for the bearings: the smallest bearing residual at those points, where the map
  // holds one.
  const std::uint32_t bearing_boards =
      params.bearings && map.has_bearings ? observed.angle_mask : 0U;
  std::array<double, kMaxBoards> bearing_residual{};
  bearing_residual.fill(std::numeric_limits<double>::infinity());
  const double cos_yaw = std::cos(estimate.yaw_rad), sin_yaw = std::sin(estimate.yaw_rad);
  fit_bearings(map, estimate.x_m, estimate.y_m, estimate.yaw_rad, cos_yaw, sin_yaw, observed,
               bearing_boards, bearing_residual);
  // What the map expects at the estimate moved by @p d along +-x and +-y, folded into [lo, hi]
  // per board; @p at_point(x, y) at each of the four places as well.
  const auto over_cross = [&](double d, std::array<float, kMaxBoards>& range_lo,
                              std::array<float, kMaxBoards>& range_hi, const auto& at_point) {
    const double offsets[4][2] = {{d, 0.0}, {-d, 0.0}, {0.0, d}, {0.0, -d}};
    std::array<float, kMaxBoards> e{};
    for (const auto& o : offsets) {
      const double x = estimate.x_m + o[0], y = estimate.y_m + o[1];
      expected_at_pose(map, locate(map, x, y), x, y, heading, e.data());
      for (std::size_t b = 0; b < kMaxBoards; ++b) {
        range_lo[b] = std::min(range_lo[b], e[b]);
        range_hi[b] = std::max(range_hi[b], e[b]);
      }
      at_point(x, y);
    }
  };
  if (params.position_spread_m > 0.0) {
    over_cross(params.position_spread_m, lo, hi, [&](double x, double y) {
      fit_bearings(map, x, y, estimate.yaw_rad, cos_yaw, sin_yaw, observed, bearing_boards,
                   bearing_residual);
    });
  }
  // How far the projected areas change across the cloud's spread (assess's comment), and
  // across the particles' bandwidth.
  std::array<float, kMaxBoards> cloud_lo = expected, cloud_hi = expected;
  std::array<float, kMaxBoards> kernel_lo = expected, kernel_hi = expected;
  const double bandwidth_m =
      particles > 0 ? position_sigma_m * kernel_bandwidth_share(particles) : position_sigma_m;
  if (position_sigma_m > 0.0 && projects_areas(map)) {
    over_cross(std::min(position_sigma_m, 0.5), cloud_lo, cloud_hi, [](double, double) {});
    if (bandwidth_m < position_sigma_m) {
      over_cross(std::min(bandwidth_m, 0.5), kernel_lo, kernel_hi, [](double, double) {});
    } else {
      kernel_lo = cloud_lo;
      kernel_hi = cloud_hi;
    }
  }
  // The board check's (over the cloud's spread) and the particles' (over their bandwidth).
  std::array<double, kMaxBoards> weight_inv_var{};
  std::array<double, kMaxBoards> inv_var{};
  // A projected area's noise widened over the particles' bandwidth (not scaled), as the
  // particles are weighed: the yardstick of its quadratic near the estimate.
  std::array<float, kMaxBoards> area_noise{};
  // A sign of a move in this frame: the board disagrees by showing more area than the map
  // expects around the estimate, or a bearing off. An occlusion only hides.
  std::array<bool, kMaxBoards> sign_of_a_move{};
  update.bearing_mask = 0;
  update.area_projection_mask = 0;
  for (std::size_t b = 0; b < update.boards; ++b) {
    update.observed[b] = observed.value[b];
    const double cut = cut_width(observed, params, b);
    update.use[b] = map.sigma[b] > 0.0F && cut > 0.0;
    if (!update.use[b]) continue;
    if (projects_area(map, b)) update.area_projection_mask |= 1U << b;
    // The projection's own noise where the board's areas are projected.
    const double width = cut * params.sigma_scale * static_cast<double>(weighed_area_sigma(map, b));
    const double across =
        projects_area(map, b) ? 0.5 * static_cast<double>(cloud_hi[b] - cloud_lo[b]) : 0.0;
    const double kernel =
        projects_area(map, b) ? 0.5 * static_cast<double>(kernel_hi[b] - kernel_lo[b]) : 0.0;
    inv_var[b] = 1.0 / (width * width + across * across);
    weight_inv_var[b] = 1.0 / (width * width + kernel * kernel);
    const double noise = static_cast<double>(weighed_area_sigma(map, b));
    area_noise[b] = static_cast<float>(std::sqrt(noise * noise + kernel * kernel));
    const float o = observed.value[b];
    const double r = o < lo[b]   ? static_cast<double>(o) - static_cast<double>(lo[b])
                     : o > hi[b] ? static_cast<double>(o) - static_cast<double>(hi[b])
                                 : 0.0;
    a.chi2[b] = static_cast<float>(r * r * inv_var[b]);
    // The residual is the projection's where the board is projected (fit_bearings).
    const double bearing_sigma = static_cast<double>(weighed_bearing_sigma_rad(map, b));
    if (std::isfinite(bearing_residual[b]) && bearing_sigma > 0.0) {
      const double bearing_width = params.sigma_scale * bearing_sigma;
      const double variance = bearing_width * bearing_width + std::max(0.0, yaw_variance_rad2);
      a.bearing_chi2[b] = static_cast<float>(bearing_residual[b] * bearing_residual[b] / variance);
      a.chi2[b] += a.bearing_chi2[b];
    }
    ++a.modelled;
    if (static_cast<double>(a.chi2[b]) < params.consensus_chi2) {
      ++a.agreeing;
    } else {
      if (r > 0.0) ++a.exceeding;
      sign_of_a_move[b] =
          r > 0.0 || (r == 0.0 && static_cast<double>(a.bearing_chi2[b]) >= params.consensus_chi2);
    }
  }
  a.consensus = a.modelled > 0 && static_cast<double>(a.agreeing) >
                                      params.consensus_fraction * static_cast<double>(a.modelled);
  fit_near_quadratics(map, estimate, bearing_boards, update.area_projection_mask, area_noise,
                      position_sigma_m, std::sqrt(std::max(0.0, yaw_variance_rad2)), update);

  const double c = params.outlier_floor;
  for (std::size_t b = 0; b < update.boards; ++b) {
    if (!update.use[b]) continue;
    const auto chi2 = static_cast<double>(a.chi2[b]);
    double s = 1.0;
    if (params.robust && a.consensus) {
      if (chi2 > params.dcs_phi) s = 2.0 * params.dcs_phi / (params.dcs_phi + chi2);
      // EM with forgetting: the posterior probability that this frame's observation came from
      // the static board, blended into the motion index.
      double& w = static_probability_[b];
      const double fit = w * std::exp(-0.5 * chi2);
      const double responsibility = fit / (fit + (1.0 - w) * c);
      if (sign_of_a_move[b]) moved_[b] = true;
      const double rate = responsibility > w && moved_[b] ? params.motion_index_rise_rate
                                                          : params.motion_index_rate;
      w = std::clamp((1.0 - rate) * w + rate * responsibility, params.motion_index_min,
                     params.motion_index_max);
      if (!distrusted(b)) moved_[b] = false;
    }
    a.scaling[b] = static_cast<float>(s);
    const double w = params.robust ? static_probability_[b] : 1.0;
    update.gain[b] = static_cast<float>(w);
    update.floor[b] = static_cast<float>(params.robust ? (1.0 - w) * c : 0.0);
    update.inv_two_var[b] = static_cast<float>(0.5 * s * s * weight_inv_var[b]);
    const double bearing_sigma = static_cast<double>(weighed_bearing_sigma_rad(map, b));
    if (params.bearings && map.has_bearings && bearing_sigma > 0.0 &&
        ((observed.angle_mask >> b) & 1U) != 0U) {
      const double width = params.sigma_scale * bearing_sigma;
      update.bearing_mask |= 1U << b;
      update.angle_rad[b] = observed.angle_rad[b];
      update.bearing_inv_two_var[b] = static_cast<float>(0.5 * s * s / (width * width));
    }
  }
  update.inv_tempering = 1.0 / params.tempering;
  update.route_free_m = static_cast<float>(params.route_free_m);
  update.route_inv_two_var =
      params.route_sigma_m > 0.0
          ? static_cast<float>(0.5 / (params.route_sigma_m * params.route_sigma_m))
          : 0.0F;
  constexpr double kRadPerDeg = 3.14159265358979323846 / 180.0;
  update.heading_free_rad = static_cast<float>(params.route_heading_free_deg * kRadPerDeg);
  const double heading_sigma_rad = params.route_heading_sigma_deg * kRadPerDeg;
  update.heading_inv_two_var =
      map.has_heading && heading_sigma_rad > 0.0
          ? static_cast<float>(0.5 / (heading_sigma_rad * heading_sigma_rad))
          : 0.0F;
  return a;
}

}  // namespace harmoloc::algorithms
