#include "harmoloc/algorithms/harmonic_training.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace harmoloc::algorithms {

namespace {

Eigen::MatrixXd select_rows(const Eigen::MatrixXd& m, const std::vector<int>& rows) {
  Eigen::MatrixXd out(static_cast<Eigen::Index>(rows.size()), m.cols());
  for (std::size_t i = 0; i < rows.size(); ++i)
    out.row(static_cast<Eigen::Index>(i)) = m.row(rows[i]);
  return out;
}

}  // namespace

Eigen::MatrixXd squared_distances(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  const Eigen::VectorXd an = a.rowwise().squaredNorm();
  const Eigen::VectorXd bn = b.rowwise().squaredNorm();
  Eigen::MatrixXd d2 = (-2.0 * a * b.transpose()).colwise() + an;
  d2.rowwise() += bn.transpose();
  return d2.cwiseMax(0.0);
}

Eigen::MatrixXd normalized_laplacian(const Eigen::MatrixXd& features, double sigma) {
  const Eigen::MatrixXd w = (-sigma * squared_distances(features, features)).array().exp().matrix();
  const Eigen::VectorXd d_inv_sqrt = w.rowwise().sum().array().rsqrt().matrix();
  Eigen::MatrixXd l = -(d_inv_sqrt.asDiagonal() * w * d_inv_sqrt.asDiagonal());
  l.diagonal().array() += 1.0;
  return l;
}

Eigen::VectorXd solve_semi_supervised(const Eigen::MatrixXd& features,
                                      const std::vector<bool>& labelled,
                                      const Eigen::VectorXd& labels, double sigma, double gamma) {
  const Eigen::Index m = features.rows();
  if (static_cast<Eigen::Index>(labelled.size()) != m || labels.size() != m) {
    throw std::invalid_argument("solve_semi_supervised: sizes differ");
  }
  Eigen::MatrixXd a = gamma * normalized_laplacian(features, sigma);
  Eigen::VectorXd c = Eigen::VectorXd::Zero(m);
  for (Eigen::Index i = 0; i < m; ++i) {
    if (labelled[static_cast<std::size_t>(i)]) {
      a(i, i) += 1.0;
      c(i) = labels(i);
    }
  }
  // P + gamma L is symmetric positive definite when at least one sample is labelled and the
  // graph is connected (complete graph, positive weights).
  return a.ldlt().solve(c);
}

Eigen::VectorXd harmonic_predict(const Eigen::MatrixXd& features, const Eigen::VectorXd& targets,
                                 double sigma, const Eigen::MatrixXd& queries) {
  const Eigen::MatrixXd d2 = squared_distances(queries, features);
  Eigen::VectorXd out(queries.rows());
  for (Eigen::Index q = 0; q < queries.rows(); ++q) {
    const double d2_min = d2.row(q).minCoeff();
    const Eigen::ArrayXd w = (-sigma * (d2.row(q).array() - d2_min)).exp().transpose();
    out(q) = (w * targets.array()).sum() / w.sum();
  }
  return out;
}

double median_squared_distance(const Eigen::MatrixXd& features) {
  return median_off_diagonal(squared_distances(features, features));
}

double median_off_diagonal(const Eigen::MatrixXd& d2) {
  std::vector<double> values;
  values.reserve(static_cast<std::size_t>(d2.rows() * (d2.rows() - 1) / 2));
  for (Eigen::Index i = 0; i < d2.rows(); ++i) {
    for (Eigen::Index j = i + 1; j < d2.cols(); ++j) values.push_back(d2(i, j));
  }
  if (values.empty()) return 1.0;
  auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  return *mid > 0.0 ? *mid : 1.0;
}

AxisChoice choose_axis_parameters(const Eigen::MatrixXd& features,
                                  const std::vector<bool>& labelled, const Eigen::VectorXd& labels,
                                  const CrossValidationOptions& options) {
  std::vector<int> labelled_rows;
  for (std::size_t i = 0; i < labelled.size(); ++i) {
    if (labelled[i]) labelled_rows.push_back(static_cast<int>(i));
  }
  const int folds = std::max(2, std::min(options.folds, static_cast<int>(labelled_rows.size())));
  if (static_cast<int>(labelled_rows.size()) < 2) {
    throw std::invalid_argument("cross-validation needs at least 2 labelled samples");
  }

  std::vector<double> sigma_grid = options.sigma_grid;
  if (sigma_grid.empty()) {
    const double base = 1.0 / median_squared_distance(features);
    for (int e = -2; e <= 12; ++e) sigma_grid.push_back(base * std::pow(2.0, e));
  }
  std::vector<double> gamma_grid = options.gamma_grid;
  if (gamma_grid.empty()) gamma_grid = {0.001, 0.003, 0.01, 0.03, 0.1};

  AxisChoice best;
  best.cv_mse = std::numeric_limits<double>::infinity();
  const Eigen::Index m = features.rows();
  for (double sigma : sigma_grid) {
    for (double gamma : gamma_grid) {
      double sq_error = 0.0;
      int count = 0;
      for (int fold = 0; fold < folds; ++fold) {
        // Interleaved folds: labelled samples come in route order, so every fold spans the route.
        std::vector<int> keep, held;
        std::vector<bool> held_mask(static_cast<std::size_t>(m), false);
        for (std::size_t k = 0; k < labelled_rows.size(); ++k) {
          if (static_cast<int>(k) % folds == fold)
            held_mask[static_cast<std::size_t>(labelled_rows[k])] = true;
        }
        for (Eigen::Index i = 0; i < m; ++i) {
          (held_mask[static_cast<std::size_t>(i)] ? held : keep).push_back(static_cast<int>(i));
        }
        std::vector<bool> keep_labelled;
        Eigen::VectorXd keep_labels(static_cast<Eigen::Index>(keep.size()));
        bool any = false;
        for (std::size_t k = 0; k < keep.size(); ++k) {
          keep_labelled.push_back(labelled[static_cast<std::size_t>(keep[k])]);
          keep_labels(static_cast<Eigen::Index>(k)) = labels(keep[k]);
          any = any || keep_labelled.back();
        }
        if (!any || held.empty()) continue;
        const Eigen::MatrixXd keep_features = select_rows(features, keep);
        const Eigen::VectorXd f =
            solve_semi_supervised(keep_features, keep_labelled, keep_labels, sigma, gamma);
        const Eigen::VectorXd predicted =
            harmonic_predict(keep_features, f, sigma, select_rows(features, held));
        for (std::size_t k = 0; k < held.size(); ++k) {
          const double e = predicted(static_cast<Eigen::Index>(k)) - labels(held[k]);
          sq_error += e * e;
          ++count;
        }
      }
      const double mse = count > 0 ? sq_error / count : std::numeric_limits<double>::infinity();
      if (std::isfinite(mse) && mse < best.cv_mse) best = AxisChoice{sigma, gamma, mse};
    }
  }
  if (!std::isfinite(best.cv_mse))
    throw std::runtime_error("cross-validation found no usable parameters");
  return best;
}

}  // namespace harmoloc::algorithms
