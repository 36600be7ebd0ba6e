#pragma once
/// @file Offline half of the harmonic localizer (Wu & Qin 2010, eq. 7-8): semi-supervised least
/// squares on the complete graph of training area vectors, and the choice of its parameters.
/// Host/start-up code: allocates freely, never runs in the cycle.

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Dense>

namespace harmoloc::algorithms {

/// Normalised graph Laplacian L = I - D^-1/2 W D^-1/2 with W_ij = exp(-sigma ||O_i - O_j||^2)
/// over the complete graph (W_ii = 1, as the kernel matrix of the paper).
Eigen::MatrixXd normalized_laplacian(const Eigen::MatrixXd& features, double sigma);

/// Solves (P + gamma L) f = C (eq. 8; the paper's "P - gamma L" is a sign typo). P is 1 on
/// labelled samples and 0 elsewhere; C holds the labels (0 where unlabelled).
Eigen::VectorXd solve_semi_supervised(const Eigen::MatrixXd& features,
                                      const std::vector<bool>& labelled,
                                      const Eigen::VectorXd& labels, double sigma, double gamma);

/// Eq. 9 evaluated for each row of @p queries against (features, targets): the offline twin of
/// harmonic_query(), used for cross-validation.
Eigen::VectorXd harmonic_predict(const Eigen::MatrixXd& features, const Eigen::VectorXd& targets,
                                 double sigma, const Eigen::MatrixXd& queries);

struct AxisChoice {
  double sigma = 0.0;
  double gamma = 0.0;
  double cv_mse = 0.0;  ///< cross-validated mean squared error, m^2
};

struct CrossValidationOptions {
  int folds = 5;
  std::vector<double> sigma_grid;  ///< empty: a geometric grid around 1 / median ||O_i - O_j||^2
  std::vector<double> gamma_grid;  ///< empty: {0.001, 0.003, 0.01, 0.03, 0.1}
};

/// Chooses sigma and gamma for one axis by k-fold cross-validation over the labelled samples:
/// each fold's labelled samples are taken out of the training set altogether, the rest is solved
/// with eq. 8 and the held-out ones are predicted with eq. 9, as the firmware would see them.
AxisChoice choose_axis_parameters(const Eigen::MatrixXd& features,
                                  const std::vector<bool>& labelled, const Eigen::VectorXd& labels,
                                  const CrossValidationOptions& options);

/// ||a_i - b_j||^2 for every row i of @p a and j of @p b (clamped at 0 against rounding).
Eigen::MatrixXd squared_distances(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b);

/// Median of the entries above the diagonal of a symmetric distance matrix (1 when there are
/// none or the median is not positive): median_squared_distance() for a matrix already computed.
double median_off_diagonal(const Eigen::MatrixXd& d2);

/// Median of the pairwise squared distances between rows (the usual kernel-width scale).
double median_squared_distance(const Eigen::MatrixXd& features);

}  // namespace harmoloc::algorithms
