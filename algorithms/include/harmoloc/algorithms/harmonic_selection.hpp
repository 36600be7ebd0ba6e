#pragma once
/// @file Training the harmonic map on a neighbourhood graph, and choosing its parameters and its
/// feature boards by cross-validation (docs/training.md).
///
/// Why not Wu & Qin's complete graph with the normalised Laplacian: its null space is D^1/2 1,
/// not the constants, so the unlabelled samples' coordinates are pulled towards a degree-weighted
/// scale (measured: 12 cm RMSE on unlabelled samples of the desk-shuttle run). A route is a thin
/// manifold in area space; a k-nearest-neighbour graph follows it, and the combinatorial
/// Laplacian D - W makes each unlabelled coordinate the weighted mean of its neighbours' (the
/// harmonic property). Same eq. 8, same eq. 9 online; only the graph differs.
/// Host/start-up code: allocates freely, never runs in the cycle.

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "harmoloc/algorithms/fix_board_check.hpp"

namespace harmoloc::algorithms {

/// Solves (P + gamma L) F = C for every column of @p labels at once (one sparse factorisation),
/// with L = D - W on the symmetrised k-nearest-neighbour graph of the rows of @p features and
/// self-tuning weights W_ij = exp(-d_ij^2 / (s_i s_j)), s_i the distance from i to its k-th
/// neighbour (no kernel width to choose). Throws std::invalid_argument on bad sizes or when no
/// sample is labelled.
Eigen::MatrixXd solve_on_neighbour_graph(const Eigen::MatrixXd& features,
                                         const std::vector<bool>& labelled,
                                         const Eigen::MatrixXd& labels, int neighbours,
                                         double gamma);

struct NeighbourAxisChoice {
  int neighbours = 0;
  double gamma = 0.0;
  double sigma = 0.0;   ///< eq. 9 kernel width for the online query, 1/feature^2
  double cv_mse = 0.0;  ///< cross-validated mean squared error, m^2
};

struct SelectionStep {
  std::vector<int> columns;  ///< feature columns in use
  double cv_mse_x = 0.0, cv_mse_y = 0.0;
  int dropped = -1;  ///< the column this step took out (-1: the starting set)
};

struct ModelSelection {
  std::vector<int> columns;  ///< chosen feature columns, ascending
  NeighbourAxisChoice x, y;
  std::vector<SelectionStep> steps;  ///< how the columns were chosen, in order
};

struct SelectionOptions {
  int folds = 5;
  /// Each held-out sample also takes this many samples on either side (in row order, i.e. along
  /// the route) out of its fold's training set, so that it has no near twin left to copy. On the
  /// four desk routes a gap did not choose better boards than none (docs/training.md), so the
  /// default is 0; it is kept for scenes where training frames come much denser.
  int gap = 0;
  std::vector<int> neighbours{4, 6, 8};
  std::vector<double> gammas{0.01, 0.1};
  /// Query kernel widths: 2^e / median ||O_i - O_j||^2 for e in [min, max].
  int sigma_exponent_min = 0;
  int sigma_exponent_max = 14;
  /// Drop features greedily while cross-validation improves by more than this fraction. The
  /// bar is high on purpose: 64 labels cannot show the rare frames where a missing board makes
  /// two places look alike, so a board goes only when it clearly hurts (measured on the four
  /// desk routes: a 2% bar dropped boards that a test run needed, docs/training.md).
  bool select_features = true;
  double min_improvement = 0.25;
  /// Boards the selection never goes below, where the run has that many that change (why:
  /// KernelSelectionOptions::min_boards).
  std::size_t min_boards = kFixCheckMinBoards;
};

/// Cross-validates the neighbour-graph model on the labelled rows of @p features for the given
/// feature columns: each fold's labelled samples leave the training set altogether, the rest is
/// solved and the held-out ones are predicted with eq. 9, as the firmware would see them.
/// Returns the best (neighbours, gamma, sigma) per axis.
std::pair<NeighbourAxisChoice, NeighbourAxisChoice> cross_validate_neighbour_model(
    const Eigen::MatrixXd& features, const std::vector<bool>& labelled,
    const Eigen::MatrixXd& labels_xy, const std::vector<int>& columns,
    const SelectionOptions& options);

/// Chooses the feature columns (backward elimination: drop the column whose removal lowers the
/// summed x + y CV error most, while it improves by more than options.min_improvement; columns
/// that never vary are dropped first) and each axis's parameters.
ModelSelection select_neighbour_model(const Eigen::MatrixXd& features,
                                      const std::vector<bool>& labelled,
                                      const Eigen::MatrixXd& labels_xy,
                                      const SelectionOptions& options);

}  // namespace harmoloc::algorithms
