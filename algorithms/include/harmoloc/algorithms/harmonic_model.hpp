#pragma once
/// @file The precomputed harmonic map (Wu & Qin 2010): training area vectors and the coordinates
/// the offline solve gave each of them. Fixed capacity, so the firmware can hold it in static
/// memory.

#include <array>
#include <cstddef>
#include <cstdint>

#include "harmoloc/algorithms/column_gain.hpp"
#include "harmoloc/algorithms/segmentation.hpp"

/// Whether the model has room for the boards' centroid columns (map format 12). A co-processor
/// build leaves it out (128 KiB at full capacity) and refuses a map that holds them.
#ifndef HARMOLOC_HARMONIC_COLUMNS
#define HARMOLOC_HARMONIC_COLUMNS 1
#endif

namespace harmoloc::algorithms {

struct HarmonicModel {
  static constexpr std::size_t kMaxSamples = 4096;
  static constexpr std::size_t kMaxFeatures = kMaxBoards;
  static constexpr bool kHoldsColumns = HARMOLOC_HARMONIC_COLUMNS != 0;

  std::uint32_t sample_count = 0;
  std::uint32_t feature_count = 0;
  /// Which boards (indices into the threshold set) are features, in feature order.
  std::array<std::uint8_t, kMaxFeatures> board_index{};
  /// Each feature's weight in eq. 9's distance (1: used, 0: left out of the kernel by the
  /// trainer's board selection). The known-place test compares every feature regardless, so a
  /// board the kernel does without still tells a strange view from a trained one. Maps before
  /// version 4 have 1 everywhere.
  std::array<float, kMaxFeatures> feature_weight{1, 1, 1, 1, 1, 1, 1, 1};
  /// feature = area_px * area_scale / column_gain.at(t), t the board's centroid column as an
  /// offset from the frame's centre (column_gain.hpp). The trainer sets 100 / (width * height):
  /// percent of frame.
  float area_scale = 0.0F;
  /// The area's gain by column (version 13; absent, plain areas, before it). The samples hold
  /// features with it removed, and so does every query (areas_to_features()).
  ColumnGain column_gain;
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

  /// The boards' centroid columns in eq. 9's distance (version 12; 0: areas only, as before).
  /// Two places on a route can show the same amounts of each board with the boards at other
  /// columns (at a turn, or where the route passes a board twice); the areas alone cannot tell
  /// them apart. Each sample then also holds, per feature, column_feature() of its frame, and the
  /// query's squared distance adds column_weight^2 * sqrt(feature_weight) * (c - c_j)^2 over the
  /// features the kernel uses. The known-place test compares areas only.
  float column_weight = 0.0F;
  /// Row-major sample_count x feature_count, like features (only when column_weight > 0).
  std::array<float, kHoldsColumns ? kMaxSamples * kMaxFeatures : 1> columns{};

  const float* sample(std::size_t i) const { return features.data() + i * kMaxFeatures; }
  float* sample(std::size_t i) { return features.data() + i * kMaxFeatures; }
  const float* sample_columns(std::size_t i) const { return columns.data() + i * kMaxFeatures; }
  float* sample_columns(std::size_t i) { return columns.data() + i * kMaxFeatures; }
  bool uses_columns() const { return kHoldsColumns && column_weight > 0.0F; }
};

/// The fix error stored with the sample nearest to (@p x_m, @p y_m) (the place a fix names),
/// 0 if the model has none. A pass over every sample: the cycle reads FixErrorGrid instead.
float fix_error_near(const HarmonicModel& model, double x_m, double y_m);

/// Whether @p model holds per-sample fix errors (map format 11; they are all or none, never all
/// 0).
bool has_fix_errors(const HarmonicModel& model);

/// Converts a frame's board areas into the model's feature vector (area_scale, then the column
/// gain removed where the frame measured columns).
void areas_to_features(const HarmonicModel& model, const AreaVector& areas,
                       std::array<float, HarmonicModel::kMaxFeatures>& features);

/// One board's centroid-column feature: (u - 0.5) * sqrt(@p feature), u its centroid column as a
/// fraction of the frame's width (0 left .. 1 right), @p feature its area feature; 0 when the
/// board is not in view. Signed, and it grows with the board, so that a board a few pixels wide
/// whose centroid jumps weighs little.
float column_feature(double centroid_column_px, std::uint32_t width_px, float feature);

/// The frame's column features in the model's feature order, each from the board's plain area
/// (area_scale x pixels, the column gain not removed: the column carries the side's stretch as
/// the trainer measured it). False (and all 0) when the frame's columns were not measured.
bool areas_to_columns(const HarmonicModel& model, const AreaVector& areas,
                      std::array<float, HarmonicModel::kMaxFeatures>& columns);

}  // namespace harmoloc::algorithms
