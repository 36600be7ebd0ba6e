#include "harmoloc/algorithms/particle_filter.hpp"

#include <algorithm>
#include <cmath>

namespace harmoloc::algorithms {

void ParticleFilter::configure(std::size_t particle_count, std::uint64_t seed,
                               const MotionNoise& noise) {
  capacity_ = std::clamp<std::size_t>(particle_count, 1, kMaxParticles);
  count_ = capacity_;
  kld_ = KldSampling{};
  noise_ = noise;
  rng_.reseed(seed);
  initialized_ = false;
}

void ParticleFilter::initialize(const Pose2& centre, double position_sigma_m, double yaw_sigma_rad,
                                bool uniform_yaw) {
  initialize_between(centre, centre, position_sigma_m, yaw_sigma_rad, uniform_yaw);
}

void ParticleFilter::initialize_between(const Pose2& a, const Pose2& b, double position_sigma_m,
                                        double yaw_sigma_rad, bool uniform_yaw) {
  initialize_between(a, position_sigma_m, b, position_sigma_m, yaw_sigma_rad, uniform_yaw);
}

void ParticleFilter::initialize_between(const Pose2& a, double a_sigma_m, const Pose2& b,
                                        double b_sigma_m, double yaw_sigma_rad, bool uniform_yaw) {
  start_seed();
  const double w = 1.0 / static_cast<double>(count_);
  for (std::size_t i = 0; i < count_; ++i) {
    const bool at_a = i % 2 == 0;
    const Pose2& centre = at_a ? a : b;
    const double position_sigma_m = at_a ? a_sigma_m : b_sigma_m;
    Particle& p = particles_[i];
    p.x_m = rng_.normal(centre.x_m, position_sigma_m);
    p.y_m = rng_.normal(centre.y_m, position_sigma_m);
    p.yaw_rad = uniform_yaw ? rng_.uniform(-kPi, kPi)
                            : wrap_angle_rad(rng_.normal(centre.yaw_rad, yaw_sigma_rad));
    weights_[i] = w;
  }
  initialized_ = true;
}

void ParticleFilter::initialize_around_points(const float* x_m, const float* y_m, std::size_t count,
                                              double position_sigma_m) {
  if (count == 0) return;
  start_seed();
  const double w = 1.0 / static_cast<double>(count_);
  for (std::size_t i = 0; i < count_; ++i) {
    const auto k =
        std::min(count - 1, static_cast<std::size_t>(rng_.uniform() * static_cast<double>(count)));
    Particle& p = particles_[i];
    p.x_m = rng_.normal(static_cast<double>(x_m[k]), position_sigma_m);
    p.y_m = rng_.normal(static_cast<double>(y_m[k]), position_sigma_m);
    p.yaw_rad = rng_.uniform(-kPi, kPi);
    weights_[i] = w;
  }
  initialized_ = true;
}

void ParticleFilter::initialize_uniform(double x0_m, double y0_m, double x1_m, double y1_m) {
  start_seed();
  const double w = 1.0 / static_cast<double>(count_);
  for (std::size_t i = 0; i < count_; ++i) {
    Particle& p = particles_[i];
    p.x_m = rng_.uniform(x0_m, x1_m);
    p.y_m = rng_.uniform(y0_m, y1_m);
    p.yaw_rad = rng_.uniform(-kPi, kPi);
    weights_[i] = w;
  }
  initialized_ = true;
}

void ParticleFilter::predict(const OdometryDelta& delta) {
  const double d2 = delta.distance_m * delta.distance_m;
  const double y2 = delta.yaw_rad * delta.yaw_rad;
  const double sigma_yaw =
      std::max(noise_.min_yaw_sigma_rad, std::sqrt(noise_.alpha1 * y2 + noise_.alpha2 * d2));
  const double sigma_dist =
      std::max(noise_.min_distance_sigma_m, std::sqrt(noise_.alpha3 * d2 + noise_.alpha4 * y2));
  for (std::size_t i = 0; i < count_; ++i) {
    Particle& p = particles_[i];
    const OdometryDelta noisy{delta.distance_m + sigma_dist * rng_.normal(),
                              delta.yaw_rad + sigma_yaw * rng_.normal()};
    const Pose2 moved = apply_arc(Pose2{p.x_m, p.y_m, p.yaw_rad}, noisy);
    p = Particle{moved.x_m, moved.y_m, moved.yaw_rad};
  }
}

void ParticleFilter::replace_some(const Pose2& centre, double position_sigma_m,
                                  double yaw_sigma_rad, std::size_t count, double total_weight) {
  if (!initialized_ || count_ < 2 || count == 0 || !(total_weight > 0.0 && total_weight < 1.0))
    return;
  count = std::min(count, count_ - 1);
  // The slots first (marked with a negative weight), then the others' weight, then the draws.
  const double step = static_cast<double>(count_) / static_cast<double>(count);
  double at = rng_.uniform() * step;
  for (std::size_t k = 0; k < count; ++k, at += step)
    weights_[std::min(count_ - 1, static_cast<std::size_t>(at))] = -1.0;
  double rest = 0.0;
  std::size_t slots = 0;
  for (std::size_t i = 0; i < count_; ++i) {
    if (weights_[i] < 0.0)
      ++slots;
    else
      rest += weights_[i];
  }
  const double each = total_weight / static_cast<double>(slots);
  // Others without weight (or not finite) share the rest evenly.
  const bool even = !(rest > 0.0 && std::isfinite(rest));
  const double scale = even ? 0.0 : (1.0 - total_weight) / rest;
  const double even_weight = (1.0 - total_weight) / static_cast<double>(count_ - slots);
  for (std::size_t i = 0; i < count_; ++i) {
    if (!(weights_[i] < 0.0)) {
      weights_[i] = even ? even_weight : weights_[i] * scale;
      continue;
    }
    Particle& p = particles_[i];
    p.x_m = rng_.normal(centre.x_m, position_sigma_m);
    p.y_m = rng_.normal(centre.y_m, position_sigma_m);
    p.yaw_rad = wrap_angle_rad(rng_.normal(centre.yaw_rad, yaw_sigma_rad));
    weights_[i] = each;
  }
}

void ParticleFilter::diffuse(double position_sigma_m, double yaw_sigma_rad) {
  for (std::size_t i = 0; i < count_; ++i) {
    Particle& p = particles_[i];
    p.x_m += position_sigma_m * rng_.normal();
    p.y_m += position_sigma_m * rng_.normal();
    p.yaw_rad = wrap_angle_rad(p.yaw_rad + yaw_sigma_rad * rng_.normal());
  }
}

void ParticleFilter::shift(double dx_m, double dy_m, double dyaw_rad) {
  for (std::size_t i = 0; i < count_; ++i) {
    Particle& p = particles_[i];
    p.x_m += dx_m;
    p.y_m += dy_m;
    p.yaw_rad = wrap_angle_rad(p.yaw_rad + dyaw_rad);
  }
}

void ParticleFilter::update_position(double x_m, double y_m, double sigma_m,
                                     double outlier_probability) {
  const double inv_two_var = 0.5 / (sigma_m * sigma_m);
  const double inlier = 1.0 - outlier_probability;
  double sum = 0.0;
  for (std::size_t i = 0; i < count_; ++i) {
    const double dx = particles_[i].x_m - x_m;
    const double dy = particles_[i].y_m - y_m;
    weights_[i] *= inlier * std::exp(-(dx * dx + dy * dy) * inv_two_var) + outlier_probability;
    sum += weights_[i];
  }
  normalize(sum);
}

namespace {

// Whether the map's bearings are read at the camera's place (bearings or visibility, and a
// camera ahead of the axle).
bool camera_bearings_of(const BoardUpdate& u) {
  const ForwardMap& map = *u.map;
  return (u.bearing_mask != 0U || map.has_visibility) && map.bearing_camera_forward_m != 0.0F;
}

// The boards measured this frame that take their bearing from the map's projection (bit b).
std::uint32_t projected_bearing_boards(const BoardUpdate& u) {
  std::uint32_t boards = 0;
  for (std::uint32_t mask = u.bearing_mask; mask != 0U; mask &= mask - 1U) {
    const auto b = static_cast<std::size_t>(__builtin_ctz(mask));
    if (b < kMaxBoards && u.map->projection.points[b] != 0U) boards |= 1U << b;
  }
  return boards;
}

// The boards that read the cells' view where the map has visibility (bit b): those taking part
// whose area is not projected, and those whose bearing is read from the cells. A projected area
// the outline cannot follow at a particle falls back to the cells' view there (project_at_pose).
std::uint32_t table_boards_of(const BoardUpdate& u, std::uint32_t outlines) {
  std::uint32_t used = 0;
  for (std::size_t b = 0; b < u.boards && b < kMaxBoards; ++b)
    if (u.use[b]) used |= 1U << b;
  return (used & ~u.area_projection_mask) | (u.bearing_mask & ~outlines);
}

// Whether the boards' likelihood needs the pose's heading as a unit vector: the heading terms,
// or the camera's place.
bool needs_unit_heading(const BoardUpdate& u) {
  return u.map->has_heading_terms || camera_bearings_of(u) || projected_bearing_boards(u) != 0U ||
         u.area_projection_mask != 0U;
}

// What the map's projection says at one particle: its offset from the estimate, the boards
// whose bearing the quadratics there give (BoardUpdate::near_at), and the image angles of those
// whose outline was projected from the particle itself.
struct ProjectedAtPose {
  float dx = 0.0F, dy = 0.0F, dyaw = 0.0F;
  std::uint32_t near_bearings = 0;
  std::uint32_t has_angle = 0;              ///< boards of angle_rad (bit b)
  std::array<float, kMaxBoards> angle_rad;  // read only where has_angle says
};

// The projected boards at @p pose: within a quadratic's reach of the estimate its value, else
// the outline projected from the pose, once for both its centroid column (under the same law as
// the measured one: their difference is the residual) and, where the map projects its areas,
// its area in the frame, written to @p expected. Returns the boards whose projected area the
// outline cannot follow from this pose (bit b): they keep the cells' area. Only for a map that
// projects something: the default map pays nothing.
inline std::uint32_t project_at_pose(const BoardUpdate& u, const Pose2& pose, float cos_yaw,
                                     float sin_yaw, std::uint32_t outlines, float* expected,
                                     ProjectedAtPose& view) {
  const ForwardMap& map = *u.map;
  if ((u.near_bearing_mask | u.near_area_mask) != 0U) {
    view.dx = static_cast<float>(pose.x_m - u.near_at.x_m);
    view.dy = static_cast<float>(pose.y_m - u.near_at.y_m);
    view.dyaw = static_cast<float>(wrap_once_rad(pose.yaw_rad - u.near_at.yaw_rad));
  }
  const float off_m = std::max(std::fabs(view.dx), std::fabs(view.dy));
  const float off_rad = std::fabs(view.dyaw);
  for (std::uint32_t mask = u.near_bearing_mask; mask != 0U; mask &= mask - 1U) {
    const auto b = static_cast<std::size_t>(__builtin_ctz(mask));
    if (u.near_bearing[b].covers(off_m, off_rad)) view.near_bearings |= 1U << b;
  }
  std::uint32_t near_areas = 0;
  for (std::uint32_t mask = u.near_area_mask; mask != 0U; mask &= mask - 1U) {
    const auto b = static_cast<std::size_t>(__builtin_ctz(mask));
    if (!u.near_area[b].covers(off_m, off_rad)) continue;
    expected[b] = u.near_area[b].at(view.dx, view.dy, view.dyaw);
    near_areas |= 1U << b;
  }
  const std::uint32_t areas = u.area_projection_mask & ~near_areas;
  const std::uint32_t projected = areas | (outlines & ~view.near_bearings);
  std::uint32_t unfollowed = 0;
  if (projected == 0U) return unfollowed;
  // The camera is placed once per particle.
  const CameraAtPose camera = camera_at_pose(map.projection, static_cast<float>(pose.x_m),
                                             static_cast<float>(pose.y_m), cos_yaw, sin_yaw);
  for (std::uint32_t mask = projected; mask != 0U; mask &= mask - 1U) {
    const auto b = static_cast<std::size_t>(__builtin_ctz(mask));
    const bool area = ((areas >> b) & 1U) != 0U;
    const ProjectedOutline o = project_outline(map.projection, camera, b, area);
    if (area && o.has_area) expected[b] = o.area_px * map.projection.area_per_px[b];
    if (area && !o.has_area) unfollowed |= 1U << b;
    if (o.has_column) {
      view.angle_rad[b] = image_angle_of_column(map, o.column_px);
      view.has_angle |= 1U << b;
    }
  }
  return unfollowed;
}

// The boards' untempered likelihood at one pose, its cell @p at located and its heading's
// cosine and sine given (in float, as both uses are: sinf and cosf cost fewer instructions than
// sin and cos; 1 and 0 where needs_unit_heading is false); @p camera_bearings as
// camera_bearings_of says, @p outlines as projected_bearing_boards and @p table_boards as
// table_boards_of, taken once per update.
inline double likelihood_at(const BoardUpdate& u, const GridPoint& at, const Pose2& pose,
                            float cos_yaw, float sin_yaw, bool camera_bearings,
                            std::uint32_t outlines, std::uint32_t table_boards) {
  const ForwardMap& map = *u.map;
  std::array<float, kMaxBoards> expected{};
  if (map.has_heading_terms) {
    // Each particle at its own heading, the harmonic read beyond the covered headings too: a
    // particle facing a heading the run never drove there must still look unlike the view,
    // and read at the covered edge it looked like it (on 19 random floors the position's
    // median went 22.3 -> 25.3 cm with the edge, docs/sweep.md).
    // Not keeping to the coverage, the heading needs no sector: its cos and sin only.
    SeenHeading heading;
    heading.cos_yaw = cos_yaw;
    heading.sin_yaw = sin_yaw;
    heading.keep_to_coverage = false;
    expected_features(map, at, heading, expected.data());
  } else {
    expected_features(map, at, expected.data());
  }
  // Where the map's bearings are read: the particle's camera place when they are seen from it.
  const GridPoint seen_from =
      camera_bearings ? bearing_point(map, pose.x_m, pose.y_m, cos_yaw, sin_yaw) : at;
  // With visibility the bearings are read there already: the bearing term below takes them.
  std::array<float, kMaxBoards> seen_bearing{};
  const auto yaw = static_cast<float>(pose.yaw_rad);
  if (map.has_visibility && table_boards != 0U)
    apply_visibility(map, seen_from, yaw, expected.data(), seen_bearing.data(), table_boards);
  ProjectedAtPose view;
  if ((outlines | u.area_projection_mask) != 0U) {
    const std::uint32_t unfollowed =
        project_at_pose(u, pose, cos_yaw, sin_yaw, outlines, expected.data(), view);
    if (map.has_visibility && unfollowed != 0U)
      apply_visibility(map, seen_from, yaw, expected.data(), nullptr, unfollowed);
  }
  double likelihood = 1.0;
  for (std::size_t b = 0; b < u.boards; ++b) {
    if (!u.use[b]) continue;
    const float e = u.observed[b] - expected[b];
    likelihood *= static_cast<double>(u.gain[b] * std::exp(-e * e * u.inv_two_var[b]) + u.floor[b]);
  }
  // Bearings: the particle sees board b at world bearing yaw - angle; the map says where the
  // training run saw it from here (from the particle's camera place, where the map's bearings
  // are seen from it).
  // A board's bearing factor at residual r: its Gaussian in the board's mixture.
  const auto bearing_factor = [&u](std::size_t b, float r) {
    return static_cast<double>(u.gain[b] * std::exp(-r * r * u.bearing_inv_two_var[b]) +
                               u.floor[b]);
  };
  for (std::uint32_t mask = u.bearing_mask; mask != 0U; mask &= mask - 1U) {
    const auto b = static_cast<std::size_t>(__builtin_ctz(mask));
    float bearing = 0.0F;
    if (((view.near_bearings >> b) & 1U) != 0U) {
      likelihood *=
          bearing_factor(b, u.near_bearing[b].at(view.dx, view.dy, view.dyaw) - u.angle_rad[b]);
      continue;
    }
    if (((outlines >> b) & 1U) != 0U) {
      // A particle from which the board lies behind the camera (or beyond the lens's image)
      // expects no board where the frame shows one whole: an outlier, as a far miss is.
      if (((view.has_angle >> b) & 1U) == 0U) {
        likelihood *= static_cast<double>(u.floor[b]);
        continue;
      }
      // Both within the lens's half field of view (under pi / 2): no wrap needed.
      likelihood *= bearing_factor(b, view.angle_rad[b] - u.angle_rad[b]);
      continue;
    }
    if (map.has_visibility) {
      bearing = seen_bearing[b];
      if (bearing == ForwardMap::kNoBearing) continue;
    } else if (!expected_bearing(map, seen_from, b, bearing)) {
      continue;
    }
    double d = pose.yaw_rad - static_cast<double>(u.angle_rad[b]) - static_cast<double>(bearing);
    // yaw and bearing lie in [-pi, pi] and the law's angle within a half turn, so two turns
    // at most bring d back (and a value that is not finite stays bounded in work).
    d = wrap_once_rad(wrap_once_rad(d));
    const auto r = static_cast<float>(d);
    likelihood *= bearing_factor(b, r);
  }
  return likelihood;
}

}  // namespace

double ParticleFilter::board_likelihood(const BoardUpdate& u, const Pose2& pose) {
  if (u.map == nullptr) return 1.0;
  Pose2 p = pose;
  p.yaw_rad = wrap_angle_rad(pose.yaw_rad);
  float cos_yaw = 1.0F, sin_yaw = 0.0F;
  if (needs_unit_heading(u)) {
    const auto yaw = static_cast<float>(p.yaw_rad);
    cos_yaw = std::cos(yaw);
    sin_yaw = std::sin(yaw);
  }
  const std::uint32_t outlines = projected_bearing_boards(u);
  return likelihood_at(u, locate(*u.map, p.x_m, p.y_m), p, cos_yaw, sin_yaw, camera_bearings_of(u),
                       outlines, table_boards_of(u, outlines));
}

double ParticleFilter::update_boards(const BoardUpdate& u) {
  const ForwardMap& map = *u.map;
  double sum = 0.0, match = 0.0;
  const bool unit_heading = needs_unit_heading(u);
  const bool camera_bearings = camera_bearings_of(u);
  const std::uint32_t outlines = projected_bearing_boards(u);
  const std::uint32_t table_boards = table_boards_of(u, outlines);
  for (std::size_t i = 0; i < count_; ++i) {
    const GridPoint at = locate(map, particles_[i].x_m, particles_[i].y_m);
    float cos_yaw = 1.0F, sin_yaw = 0.0F;
    if (unit_heading) {
      const auto yaw = static_cast<float>(particles_[i].yaw_rad);
      cos_yaw = std::cos(yaw);
      sin_yaw = std::sin(yaw);
    }
    const Pose2 pose{particles_[i].x_m, particles_[i].y_m, particles_[i].yaw_rad};
    double likelihood =
        likelihood_at(u, at, pose, cos_yaw, sin_yaw, camera_bearings, outlines, table_boards);
    // The match is the observation model's own (untempered): tempering compresses exactly the
    // change the kidnap test looks for.
    match += weights_[i] * likelihood;
    // likelihood^(1/tempering), in float: weights need no more precision than that.
    if (u.inv_tempering != 1.0 && likelihood > 0.0) {
      likelihood = static_cast<double>(
          std::exp(std::log(static_cast<float>(likelihood)) * static_cast<float>(u.inv_tempering)));
    }
    const float off_route = route_distance(map, at) - u.route_free_m;
    if (off_route > 0.0F)
      likelihood *= static_cast<double>(std::exp(-off_route * off_route * u.route_inv_two_var));
    float heading_rad = 0.0F;
    if (u.heading_inv_two_var > 0.0F && route_heading(map, at, heading_rad)) {
      // Both angles lie in [-pi, pi] (particles are kept wrapped), so one turn puts it back.
      double d = particles_[i].yaw_rad - static_cast<double>(heading_rad);
      d = wrap_once_rad(d);
      const float off_heading = static_cast<float>(std::fabs(d)) - u.heading_free_rad;
      if (off_heading > 0.0F)
        likelihood *=
            static_cast<double>(std::exp(-off_heading * off_heading * u.heading_inv_two_var));
    }
    weights_[i] *= likelihood;
    sum += weights_[i];
  }
  normalize(sum);
  return match;
}

void ParticleFilter::normalize(double sum) {
  if (!(sum > 0.0) || !std::isfinite(sum)) {
    const double w = 1.0 / static_cast<double>(count_);
    for (std::size_t i = 0; i < count_; ++i) weights_[i] = w;
    return;
  }
  const double inv = 1.0 / sum;
  for (std::size_t i = 0; i < count_; ++i) weights_[i] *= inv;
}

void ParticleFilter::start_seed() {
  count_ = capacity_;
}

double KldSampling::required(std::size_t bins) const {
  if (bins <= 1) return 1.0;
  // Fox 2003, eq. 12 (the Wilson-Hilferty approximation of the chi-square quantile).
  const double k = static_cast<double>(bins - 1);
  const double a = 2.0 / (9.0 * k);
  const double c = 1.0 - a + std::sqrt(a) * z_upper;
  return k / (2.0 * epsilon) * c * c * c;
}

std::size_t ParticleFilter::occupied_bins(double start) {
  const double inv_xy = 1.0 / kld_.bin_xy_m, inv_yaw = 1.0 / kld_.bin_yaw_rad;
  // 21 bits per axis, offset so that no key is 0 (the empty slot). Bounded before the
  // conversion, so that a particle far out (or not a number) only shares an edge bin.
  const auto axis = [](double v) {
    const double bounded = v > -1.0e6 ? (v < 1.0e6 ? v : 1.0e6) : -1.0e6;
    return static_cast<std::uint64_t>(static_cast<std::int64_t>(std::floor(bounded)) + (1 << 20)) &
           0x1FFFFFU;
  };
  std::size_t occupied = 0;
  std::uint64_t last = 0;
  systematic_draw(count_, start, [&](std::size_t, std::size_t i) {
    const Particle& p = particles_[i];
    const std::uint64_t key = (axis(p.x_m * inv_xy) << 42U) | (axis(p.y_m * inv_xy) << 21U) |
                              axis((p.yaw_rad + kPi) * inv_yaw) | (1ULL << 63U);
    if (key == last) return;  // systematic draws repeat a particle back to back
    last = key;
    auto slot = static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ULL) >> 51U);  // 13 bits
    // At most count_ keys in 2 x kMaxParticles slots: an empty slot is always found.
    while (bins_[slot] != 0U && bins_[slot] != key) slot = (slot + 1) % kBinSlots;
    if (bins_[slot] == 0U) {
      bins_[slot] = key;
      used_slots_[occupied++] = static_cast<std::uint16_t>(slot);
    }
  });
  for (std::size_t k = 0; k < occupied; ++k) bins_[used_slots_[k]] = 0U;  // empty for next time
  return occupied;
}

bool ParticleFilter::resample_if_needed(double threshold_fraction) {
  double sum_sq = 0.0;
  for (std::size_t i = 0; i < count_; ++i) sum_sq += weights_[i] * weights_[i];
  const double n_eff = 1.0 / sum_sq;
  if (n_eff >= threshold_fraction * static_cast<double>(count_)) return false;

  const double start = rng_.uniform();
  std::size_t next_count = count_;
  if (kld_.enabled) {
    const double wanted = kld_.required(occupied_bins(start));
    const double low = static_cast<double>(std::min(kld_.min_particles, capacity_));
    next_count = static_cast<std::size_t>(
        std::clamp(std::ceil(wanted), low, static_cast<double>(capacity_)));
  }
  systematic_draw(next_count, start,
                  [&](std::size_t m, std::size_t i) { scratch_[m] = particles_[i]; });
  count_ = next_count;
  const double weight = 1.0 / static_cast<double>(count_);
  for (std::size_t m = 0; m < count_; ++m) {
    particles_[m] = scratch_[m];
    weights_[m] = weight;
  }
  return true;
}

Pose2 ParticleFilter::mean_pose(double* yaw_variance_rad2, double* position_variance_m2) const {
  if (count_ == 0) return Pose2{};
  const double reference = particles_[0].yaw_rad;
  double sx = 0.0, sy = 0.0, syaw = 0.0, syaw2 = 0.0;
  for (std::size_t i = 0; i < count_; ++i) {
    sx += weights_[i] * particles_[i].x_m;
    sy += weights_[i] * particles_[i].y_m;
    // Both headings lie in [-pi, pi] (particles are kept wrapped): one turn puts it back.
    double d = particles_[i].yaw_rad - reference;
    d = wrap_once_rad(d);
    syaw += weights_[i] * d;
    syaw2 += weights_[i] * d * d;
  }
  if (yaw_variance_rad2 != nullptr) *yaw_variance_rad2 = std::max(0.0, syaw2 - syaw * syaw);
  if (position_variance_m2 != nullptr) {
    // A second pass, about the mean: only the callers that ask pay for it.
    double s2 = 0.0;
    for (std::size_t i = 0; i < count_; ++i) {
      const double dx = particles_[i].x_m - sx, dy = particles_[i].y_m - sy;
      s2 += weights_[i] * (dx * dx + dy * dy);
    }
    *position_variance_m2 = 0.5 * s2;
  }
  return Pose2{sx, sy, wrap_angle_rad(reference + syaw)};
}

PoseEstimate ParticleFilter::estimate() const {
  PoseEstimate e;
  double sx = 0.0, sy = 0.0, ss = 0.0, sc = 0.0, sum_sq = 0.0;
  for (std::size_t i = 0; i < count_; ++i) {
    const double w = weights_[i];
    sx += w * particles_[i].x_m;
    sy += w * particles_[i].y_m;
    ss += w * std::sin(particles_[i].yaw_rad);
    sc += w * std::cos(particles_[i].yaw_rad);
    sum_sq += w * w;
  }
  e.mean = Pose2{sx, sy, std::atan2(ss, sc)};
  for (std::size_t i = 0; i < count_; ++i) {
    const double w = weights_[i];
    const double d[3] = {particles_[i].x_m - sx, particles_[i].y_m - sy,
                         wrap_angle_rad(particles_[i].yaw_rad - e.mean.yaw_rad)};
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) e.covariance(r, c) += w * d[r] * d[c];
    }
  }
  e.effective_particles = sum_sq > 0.0 ? 1.0 / sum_sq : 0.0;
  return e;
}

}  // namespace harmoloc::algorithms
