#pragma once

// Choosing which boards' areas (feature columns) a position model uses; shared by the harmonic
// model's selection (harmonic_selection.cpp) and the kernel model's (kernel_selection.cpp).
// Training only (host, allocates).

#include <cstddef>
#include <limits>
#include <stdexcept>
#include <vector>

#include <Eigen/Core>

namespace harmoloc::algorithms::detail {

// The columns whose value changes along the run: a board that never changes carries no position
// and only dilutes the distances.
inline std::vector<int> changing_columns(const Eigen::MatrixXd& features) {
  std::vector<int> columns;
  for (Eigen::Index c = 0; c < features.cols(); ++c) {
    if (features.col(c).maxCoeff() > features.col(c).minCoeff())
      columns.push_back(static_cast<int>(c));
  }
  if (columns.empty()) throw std::runtime_error("no board's area changes along the run");
  return columns;
}

// Backward elimination from @p current (the choice for all of @p columns): while more than
// @p min_columns (at least one) are left, drops the column whose removal gives the lowest summed x
// and y cross-validated MSE, as long as that sum is lower than the current one by more than @p
// min_improvement (relative). @p evaluate(columns) returns a pair of axis choices (`.first.cv_mse`,
// `.second.cv_mse`); @p on_drop(columns, choice, dropped_column) sees each step. Returns the
// choice for the columns left.
template <typename Choice, typename Evaluate, typename OnDrop>
Choice eliminate_columns(std::vector<int>& columns, Choice current, double min_improvement,
                         std::size_t min_columns, Evaluate&& evaluate, OnDrop&& on_drop) {
  const std::size_t keep = min_columns > 1 ? min_columns : 1;
  while (columns.size() > keep) {
    double best_score = std::numeric_limits<double>::infinity();
    std::size_t best_drop = 0;
    Choice best_choice;
    for (std::size_t d = 0; d < columns.size(); ++d) {
      std::vector<int> trial = columns;
      trial.erase(trial.begin() + static_cast<std::ptrdiff_t>(d));
      const Choice c = evaluate(trial);
      const double score = c.first.cv_mse + c.second.cv_mse;
      if (score < best_score) {
        best_score = score;
        best_drop = d;
        best_choice = c;
      }
    }
    const double now = current.first.cv_mse + current.second.cv_mse;
    if (!(best_score < now * (1.0 - min_improvement))) break;
    const int dropped = columns[best_drop];
    columns.erase(columns.begin() + static_cast<std::ptrdiff_t>(best_drop));
    current = best_choice;
    on_drop(columns, current, dropped);
  }
  return current;
}

}  // namespace harmoloc::algorithms::detail
