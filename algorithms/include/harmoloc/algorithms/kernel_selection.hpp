#pragma once
/// @file Choosing the harmonic map's kernel widths and feature boards when every training sample
/// has a position (frames placed by odometry between the labels, route_placement.hpp). With
/// every sample placed, eq. 8 leaves each sample's coordinates where the placement put them, and
/// what remains to choose is eq. 9's kernel width per axis and the boards it compares.
///
/// Cross-validation holds out frames and predicts each from the samples of *other passes*: the
/// samples whose travel along the run lies within `same_pass_m` of the held-out frame's are left
/// out, so a held-out frame cannot copy its own neighbours of a thirtieth of a second before, and
/// the error it measures is that of a new run over the same place (another wander, other noise).
/// The same leave-pass-out distances calibrate the known-place test.
///
/// Host code (training): allocates freely, never runs in the cycle.

#include <cstddef>
#include <vector>

#include <Eigen/Dense>

#include "harmoloc/algorithms/fix_board_check.hpp"

namespace harmoloc::algorithms {

struct PlacedSamples {
  Eigen::MatrixXd features;  ///< m x d, the map's feature units
  Eigen::MatrixXd xy;        ///< m x 2, metres
  std::vector<double> travel_m;
  /// m x d, each feature's centroid-column feature (HarmonicModel::columns), scaled as the
  /// kernel weighs it; empty: none.
  Eigen::MatrixXd columns;
};

struct KernelSelectionOptions {
  double same_pass_m = 0.10;    ///< held-out frames do not see samples this close in travel
  int sigma_exponent_min = -2;  ///< kernel widths 2^e / median ||O_i - O_j||^2
  int sigma_exponent_max = 16;
  bool select_features = true;
  /// Drop a board while that lowers the summed x + y CV error by more than this fraction.
  double min_improvement = 0.05;
  /// Boards the selection never goes below (where the run has that many that change). Two
  /// boards fit a static training run well, but a fix from two cannot be checked: leaving one
  /// out leaves a single board, so nothing tells which of the two moved, and a moved board drags
  /// the fix and the filter with it (algorithms/fix_board_check.hpp keeps at least two and so
  /// needs three). Cross-validation on the training run cannot see this, as no board moves in
  /// it (docs/training.md).
  std::size_t min_boards = kFixCheckMinBoards;
  /// Ridges tried for eq. 9's local linear correction (HarmonicModel::local_linear_ridge); the
  /// one with the lowest x + y CV error is kept where it beats the plain kernel average by more
  /// than min_improvement. Empty: the plain average.
  std::vector<double> local_linear_ridges{0.003, 0.01, 0.03, 0.1, 0.3};
  /// The centroid columns' weight in eq. 9's distance (HarmonicModel::column_weight): the
  /// kernel's squared distance adds column_weight^2 |C_q - C_j|^2 over the chosen columns (when
  /// samples and queries hold columns). The known-place calibration compares areas only.
  double column_weight = 0.0;
};

struct KernelAxis {
  double sigma = 0.0;
  double cv_mse = 0.0;  ///< m^2
};

struct KernelSelectionStep {
  std::vector<int> columns;
  double cv_mse_x = 0.0, cv_mse_y = 0.0;
  int dropped = -1;
};

struct KernelSelection {
  std::vector<int> columns;  ///< chosen feature columns, ascending
  KernelAxis x, y;
  std::vector<KernelSelectionStep> steps;
  /// The local linear correction's ridge cross-validation chose (0: the plain kernel average).
  /// x and y's cv_mse and the per-query errors below are those of the fix with it.
  double local_linear_ridge = 0.0;
  double kernel_average_cv_mse_x = 0.0, kernel_average_cv_mse_y = 0.0;
  /// Per query (with the chosen columns): distance (the kernel's, centroid columns included)
  /// and Bray-Curtis dissimilarity to the nearest sample of another pass, and the prediction's
  /// error (metres; x, y).
  std::vector<double> nearest_distance, nearest_dissimilarity;
  std::vector<double> error_x_m, error_y_m;
  /// The row in the queries of each entry above (queries without another pass have none).
  std::vector<std::size_t> query_row;
};

/// Cross-validated eq. 9 error of predicting @p queries (held out: their own pass's samples are
/// left out) from @p samples with the feature @p columns; best sigma per axis.
std::pair<KernelAxis, KernelAxis> cross_validate_kernel(const PlacedSamples& samples,
                                                        const PlacedSamples& queries,
                                                        const std::vector<int>& columns,
                                                        const KernelSelectionOptions& options);

/// For each held-out query that has another pass close by: the distance and the Bray-Curtis
/// dissimilarity (over @p columns, unweighted) to the nearest sample of another pass. What a
/// frame of a new run over a trained place looks like: the known-place test's calibration.
void other_pass_nearest(const PlacedSamples& samples, const PlacedSamples& queries,
                        const std::vector<int>& columns, double same_pass_m,
                        std::vector<double>& distance, std::vector<double>& dissimilarity);

/// Chooses the columns (backward elimination while CV improves by more than
/// options.min_improvement; columns that never vary are left out first) and each axis's width,
/// and fills the chosen model's per-query diagnostics.
KernelSelection select_kernel_model(const PlacedSamples& samples, const PlacedSamples& queries,
                                    const KernelSelectionOptions& options);

}  // namespace harmoloc::algorithms
