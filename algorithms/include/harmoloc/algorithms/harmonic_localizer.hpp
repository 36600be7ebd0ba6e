#pragma once
/// @file Online harmonic localizer (Wu & Qin 2010, eq. 9): f_new = sum_j W'_j f_j / sum_j W'_j with
/// W'_j = exp(-sigma ||O_new - O_j||^2) over all training samples. O(n d), no allocation.

#include <array>
#include <cstdint>

#include "harmoloc/algorithms/harmonic_model.hpp"

namespace harmoloc::algorithms {

struct HarmonicFix {
  double x_m = 0.0;
  double y_m = 0.0;
  /// Euclidean distance (feature units) to the nearest training sample.
  double nearest_distance = 0.0;
  /// Bray-Curtis dissimilarity (0 = identical .. 1 = nothing in common) to that sample: the
  /// fix's confidence measure.
  double dissimilarity = 1.0;
  /// True when the frame looks like a place the map was trained on (nearest_distance within the
  /// model's bound, dissimilarity within the model's bound) and some board was seen at all.
  bool known_place = false;
  /// False when none of the boards the query compares showed a pixel: eq. 9 still returns a
  /// place (the samples' with the least area), but the frame says nothing about where the robot
  /// is, so that place is no fix (a turn facing a bare wall;
  /// docs/sweep.md, 2026-12-01 (afternoon)).
  bool board_seen = false;
  /// True when the fix left out a board the frame's side cuts (harmonic_fix()).
  bool cut_board_left_out = false;
};

/// Neighbours whose weight is below exp(-kLocalLinearCutoff) (1e-7) of the nearest sample's are
/// left out of the local linear correction's plane: they cannot tilt it measurably, and leaving
/// them out keeps its normal equations to the samples the kernel reaches. The trainer's
/// cross-validation (kernel_selection.cpp) uses the same cut, so that it scores the fix the
/// firmware computes.
constexpr float kLocalLinearCutoff = 16.0F;

/// A frame's centroid-column features (areas_to_columns()), in the model's feature order.
using ColumnFeatures = std::array<float, HarmonicModel::kMaxFeatures>;

/// Evaluates eq. 9 for one feature vector. The weights are computed relative to the nearest
/// sample (exp(-sigma (d^2 - d_min^2))), which leaves eq. 9 unchanged but cannot underflow.
/// @p columns: the frame's column features, used when the model has them
/// (HarmonicModel::column_weight); null for a frame whose columns were not measured (the kernel
/// then compares areas only, which a map trained with columns does less well).
HarmonicFix harmonic_query(const HarmonicModel& model,
                           const std::array<float, HarmonicModel::kMaxFeatures>& features,
                           const ColumnFeatures* columns = nullptr);

/// Which of the model's features a query may use (true) or must leave out (false).
using FeatureMask = std::array<bool, HarmonicModel::kMaxFeatures>;

/// Eq. 9 over the features @p use allows only: distances, the known-place test and the kernel
/// leave the others out (the kernel widths scaled by d / d_used, so that the weights keep their
/// spread). For a fix that an occluded or moved board must not drag. With every feature allowed
/// it equals the plain query; with none, it is not a known place. A board left out takes its
/// column with it.
HarmonicFix harmonic_query(const HarmonicModel& model,
                           const std::array<float, HarmonicModel::kMaxFeatures>& features,
                           const FeatureMask& use, const ColumnFeatures* columns = nullptr);

/// The features a frame's fix compares: every one, less those of the boards the frame's side cuts
/// (AreaVector::side_pixels), as long as two boards the kernel weighs stay in view uncut. A cut
/// board's area (and column) follows the heading more than the place: its cut edge moves across
/// the frame by a focal length per radian of heading, and a route map holds one heading per
/// place, so a pass a few degrees off the training pass's heading reads as another place. One
/// board alone names every place at its distance; then the cut board stays (as the fix's board
/// check keeps two). Frames without side counts (area logs written before them) cut nothing.
/// @p features from areas_to_features(). Returns true when it left a board out.
bool uncut_features(const HarmonicModel& model, const AreaVector& areas,
                    const std::array<float, HarmonicModel::kMaxFeatures>& features,
                    FeatureMask& use);

/// Eq. 9 for a frame as the firmware computes it: over uncut_features(), @p use set to them.
HarmonicFix harmonic_fix(const HarmonicModel& model, const AreaVector& areas,
                         const std::array<float, HarmonicModel::kMaxFeatures>& features,
                         const ColumnFeatures* columns, FeatureMask& use);

}  // namespace harmoloc::algorithms
