#pragma once
/// @file The precomputed harmonic map (Wu & Qin 2010): training area vectors and the coordinates
/// the offline solve gave each of them. Fixed capacity, so the firmware can hold it in static
/// memory.

#include <array>
#include <cstddef>
#include <cstdint>

#include "harmoloc/algorithms/segmentation.hpp"

namespace harmoloc::algorithms {

struct HarmonicModel {
  static constexpr std::size_t kMaxSamples = 4096;
  static constexpr std::size_t kMaxFeatures = kMaxBoards;

  std::uint32_t sample_count = 0;
  std::uint32_t feature_count = 0;
  /// Which boards (indices into the threshold set) are features, in feature order.
  std::array<std::uint8_t, kMaxFeatures> board_index{};
  /// Each feature's weight in eq. 9's distance (1: used, 0: left out of the kernel by the
  /// trainer's board selection). The known-place test compares every feature regardless, so a
  /// board the kernel does without still tells a strange view from a trained one. Maps before
  /// version 4 have 1 everywhere.
  std::array<float, kMaxFeatures> feature_weight{1, 1, 1, 1, 1, 1, 1, 1};
  /// feature = area_px * area_scale. The trainer sets 100 / (width * height): percent of frame.
  float area_scale = 0.0F;
  /// Kernel widths of W = exp(-sigma * ||O_i - O_j||^2), per output axis, in 1/feature^2.
  float sigma_x = 0.0F;
  float sigma_y = 0.0F;
  /// Regularisation weights the offline solve used (kept for the record).
  float gamma_x = 0.0F;
  float gamma_y = 0.0F;
  /// Known-place test: a fix whose nearest training sample is farther than this (in feature
  /// units, Euclidean) is flagged as off the trained route.
  float max_nearest_distance = 0.0F;
  /// Known-place test: a fix whose Bray-Curtis dissimilarity sum|O - O_j| / sum(O + O_j) to its
  /// nearest training sample j exceeds this is flagged too. Relative, so it tells a wrong place
  /// from a far one equally well where areas are large or small. 1 disables the test.
  float max_dissimilarity = 1.0F;

  /// Local linear correction of eq. 9 (0: off, plain eq. 9): the fix is the intercept of a
  /// weighted least-squares plane through the kernel's neighbours, which removes the pull towards
  /// the interior that a kernel average has at the ends of a route. The slopes are shrunk by a
  /// ridge of this many times the kernel's own spread (1 / (2 sigma)) times the weight sum.
  float local_linear_ridge = 0.0F;
  /// Row-major sample_count x feature_count.
  std::array<float, kMaxSamples * kMaxFeatures> features{};
  std::array<float, kMaxSamples> target_x_m{};
  std::array<float, kMaxSamples> target_y_m{};
  /// Per sample (version 11; 0 everywhere in older maps): the RMS error per axis of the training
  /// run's cross-validated fixes that landed near the sample's place (metres,
  /// local_fix_error.hpp). Where a place's areas look like another place's, a fix naming it is
  /// often wrong; the filter's fix term is that much wider there.
  std::array<float, kMaxSamples> fix_error_m{};

  const float* sample(std::size_t i) const { return features.data() + i * kMaxFeatures; }
  float* sample(std::size_t i) { return features.data() + i * kMaxFeatures; }
};

/// The fix error stored with the sample nearest to (@p x_m, @p y_m) (the place a fix names),
/// 0 if the model has none. A pass over every sample: the cycle reads FixErrorGrid instead.
float fix_error_near(const HarmonicModel& model, double x_m, double y_m);

/// Whether @p model holds per-sample fix errors (map format 11; they are all or none, never all
/// 0).
bool has_fix_errors(const HarmonicModel& model);

/// Converts a frame's board areas into the model's feature vector.
void areas_to_features(const HarmonicModel& model, const AreaVector& areas,
                       std::array<float, HarmonicModel::kMaxFeatures>& features);

}  // namespace harmoloc::algorithms
