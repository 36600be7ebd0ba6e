#pragma once
/// @file Fixed-capacity particle filter over (x, y, yaw) (Guo & Li 2013): differential-drive motion
/// model with AMCL-style noise; the measurement is either every board's area against the
/// forward map (robust per-board likelihood, board_observation.hpp) or, for maps without a
/// forward model, the harmonic localizer's position fix; low-variance resampling. Static
/// memory; deterministic for a given seed.

#include <array>
#include <cstddef>
#include <cstdint>

#include "harmoloc/algorithms/board_observation.hpp"
#include "harmoloc/algorithms/geometry.hpp"
#include "harmoloc/algorithms/odometry.hpp"
#include "harmoloc/algorithms/random.hpp"

namespace harmoloc::algorithms {

struct MotionNoise {
  /// Variances grow with motion as in AMCL's odometry model: yaw noise variance
  /// alpha1 yaw^2 + alpha2 dist^2, distance noise variance alpha3 dist^2 + alpha4 yaw^2.
  double alpha1 = 0.02;
  double alpha2 = 0.02;
  double alpha3 = 0.02;
  double alpha4 = 0.002;
  /// Floor on the per-step standard deviations, so a stopped robot still diffuses a little.
  double min_distance_sigma_m = 0.0005;
  double min_yaw_sigma_rad = 0.0005;
};

/// Adaptive particle count (KLD-sampling, Fox 2003, as AMCL users know it): at each resampling
/// the cloud gets as many particles as bound the Kullback-Leibler divergence between the
/// particles and the posterior they sample by @p epsilon with probability 1 - delta (@p z_upper
/// is the standard normal's upper 1 - delta quantile), counting the poses' bins of
/// @p bin_xy_m x @p bin_xy_m x @p bin_yaw_rad the resampled cloud occupies; never fewer than
/// @p min_particles, never more than the configured count (the capacity, reserved at
/// configure()). Many particles when lost, few when converged.
struct KldSampling {
  bool enabled = false;
  std::size_t min_particles = 256;
  double bin_xy_m = 0.05;
  double bin_yaw_rad = 0.17453292519943295;  // 10 degrees
  double epsilon = 0.05;
  double z_upper = 2.326;  // delta = 0.01

  /// The particle count KLD-sampling asks for with @p bins occupied bins (before the bounds).
  double required(std::size_t bins) const;
};

struct PoseEstimate {
  Pose2 mean;
  PoseCovariance covariance;
  double effective_particles = 0.0;
};

class ParticleFilter {
 public:
  static constexpr std::size_t kMaxParticles = 4096;

  /// @p particle_count must be 1..kMaxParticles (clamped): the capacity; every (re)seed starts
  /// with that many, and without KLD-sampling the count never changes.
  void configure(std::size_t particle_count, std::uint64_t seed, const MotionNoise& noise);
  /// Turns the adaptive particle count on or off (off after configure()).
  void set_kld_sampling(const KldSampling& kld) { kld_ = kld; }

  /// Spreads the particles around @p centre: Gaussian in x and y, and in yaw unless
  /// @p uniform_yaw, in which case yaw is uniform over the circle.
  void initialize(const Pose2& centre, double position_sigma_m, double yaw_sigma_rad,
                  bool uniform_yaw);
  bool initialized() const { return initialized_; }

  /// As initialize(), with the particles shared between two centres, half around each (the
  /// same yaw for both): for two candidate places that the next frames will tell apart.
  void initialize_between(const Pose2& a, const Pose2& b, double position_sigma_m,
                          double yaw_sigma_rad, bool uniform_yaw);
  /// As above, each centre with its own position spread: for two candidates whose errors differ
  /// (a searched pose and a harmonic fix).
  void initialize_between(const Pose2& a, double a_sigma_m, const Pose2& b, double b_sigma_m,
                          double yaw_sigma_rad, bool uniform_yaw);

  /// Spreads the particles over @p count candidate positions (each particle near one of them,
  /// picked at random: Gaussian in x and y), yaw uniform. For relocalizing when all that is
  /// known is that the robot is somewhere the map was trained (its training positions). Does
  /// nothing when @p count is 0.
  void initialize_around_points(const float* x_m, const float* y_m, std::size_t count,
                                double position_sigma_m);

  /// Applies one odometry step to every particle with sampled noise.
  void predict(const OdometryDelta& delta);

  /// Spreads the particles uniformly over the rectangle [x0, x1] x [y0, y1], yaw uniform (the
  /// AMCL-style global re-seed, kept as the baseline relocalization).
  void initialize_uniform(double x0_m, double y0_m, double x1_m, double y1_m);

  /// Random walk of every particle (motion unknown, e.g. while odometry is missing).
  void diffuse(double position_sigma_m, double yaw_sigma_rad);

  /// Moves @p count particles (at most all but one; evenly spread over the cloud from a random
  /// start) to draws around @p centre, sharing @p total_weight (0..1) of the cloud's weight, the
  /// others the rest: a second hypothesis beside the cloud, as likely as @p total_weight says,
  /// that the following frames weigh like any other particle (sensor resetting, Lenser and
  /// Veloso 2000). Does nothing before initialisation.
  void replace_some(const Pose2& centre, double position_sigma_m, double yaw_sigma_rad,
                    std::size_t count, double total_weight);
  /// Moves every particle by (@p dx_m, @p dy_m) and turns it by @p dyaw_rad: the cloud keeps its
  /// shape and weights, its centre moves.
  void shift(double dx_m, double dy_m, double dyaw_rad);

  /// Weights particles by a Gaussian position fix; the small @p outlier_probability mixes in a
  /// uniform floor so that one wrong fix cannot wipe out every particle.
  void update_position(double x_m, double y_m, double sigma_m, double outlier_probability);

  /// Weights every particle by the per-board likelihood of @p update (tempered, and its route
  /// term). Returns the sum over the particles of prior weight x the boards' untempered
  /// likelihood: the match between the frame and the cloud that the kidnap test watches (seed
  /// 004's d_t).
  double update_boards(const BoardUpdate& update);

  /// The boards' untempered likelihood of @p update at one pose, exactly as update_boards
  /// weighs a particle there (without the route terms): for comparing two poses in the filter's
  /// own model.
  static double board_likelihood(const BoardUpdate& update, const Pose2& pose);

  /// Low-variance (systematic) resampling when the effective sample size falls below
  /// @p threshold_fraction of the particle count. Returns true if it resampled. With
  /// KLD-sampling on, the new count is chosen from the bins the resampled cloud occupies.
  bool resample_if_needed(double threshold_fraction);

  PoseEstimate estimate() const;
  /// The weighted mean pose without covariance and without trigonometry: the heading is the
  /// mean of every particle's heading relative to the first particle's, which is the circular
  /// mean for any cloud narrower than a half turn (a wider one has no meaningful heading).
  /// @p yaw_variance_rad2, when given, receives the weighted variance of the headings about it;
  /// @p position_variance_m2 the mean of the positions' variances along x and y.
  Pose2 mean_pose(double* yaw_variance_rad2 = nullptr,
                  double* position_variance_m2 = nullptr) const;
  std::size_t size() const { return count_; }
  std::size_t capacity() const { return capacity_; }

  struct Particle {
    double x_m;
    double y_m;
    double yaw_rad;
  };
  const Particle& particle(std::size_t i) const { return particles_[i]; }
  double weight(std::size_t i) const { return weights_[i]; }

 private:
  /// Divides the weights by @p sum; a sum that is 0 or not finite (every particle ruled out)
  /// makes them uniform instead, so that no single frame can wipe out the cloud.
  void normalize(double sum);
  /// Every particle back, equally weighted (the start of every seed).
  void start_seed();
  /// Low-variance (systematic) draw of @p draws particles from the present weights, offset
  /// @p start (0..1): calls @p take(m, i) for draw m of particle i.
  template <typename Take>
  void systematic_draw(std::size_t draws, double start, Take take) const {
    // start * step + m * step, not (start + m) * step: the rounding the filter always had.
    const double step = 1.0 / static_cast<double>(draws);
    const double first = start * step;
    double cumulative = weights_[0];
    std::size_t i = 0;
    for (std::size_t m = 0; m < draws; ++m) {
      const double u = first + static_cast<double>(m) * step;
      while (u > cumulative && i + 1 < count_) cumulative += weights_[++i];
      take(m, i);
    }
  }
  /// The number of distinct KLD bins among the particles that systematic resampling at the
  /// present count would draw (@p start: the draw's offset, 0..1).
  std::size_t occupied_bins(double start);

  /// Open-addressed set of bin keys (0: empty), twice the capacity so that it never fills.
  static constexpr std::size_t kBinSlots = 2 * kMaxParticles;
  static_assert(kBinSlots == 8192, "occupied_bins() hashes to 13 bits");

  std::array<Particle, kMaxParticles> particles_{};
  std::array<Particle, kMaxParticles> scratch_{};
  std::array<double, kMaxParticles> weights_{};
  std::array<std::uint64_t, kBinSlots> bins_{};
  std::array<std::uint16_t, kMaxParticles> used_slots_{};  ///< the bins_ slots to empty again
  std::size_t count_ = 0;
  std::size_t capacity_ = 0;
  KldSampling kld_{};
  MotionNoise noise_{};
  Pcg32 rng_{};
  bool initialized_ = false;
};

}  // namespace harmoloc::algorithms
