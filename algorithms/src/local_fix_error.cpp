#include "harmoloc/algorithms/local_fix_error.hpp"

#include <cmath>
#include <stdexcept>

namespace harmoloc::algorithms {

std::vector<double> local_fix_errors(const Eigen::MatrixXd& sample_xy,
                                     const Eigen::MatrixXd& fix_xy,
                                     const std::vector<double>& error_x_m,
                                     const std::vector<double>& error_y_m,
                                     const LocalFixErrorOptions& options) {
  const auto fixes = static_cast<std::size_t>(fix_xy.rows());
  if (error_x_m.size() != fixes || error_y_m.size() != fixes || fix_xy.cols() != 2)
    throw std::invalid_argument("local_fix_errors: one error per fix");
  if (!(options.radius_m > 0.0)) throw std::invalid_argument("local_fix_errors: radius <= 0");
  const double r2 = options.radius_m * options.radius_m;
  std::vector<double> out(static_cast<std::size_t>(sample_xy.rows()), options.fallback_m);
  for (Eigen::Index i = 0; i < sample_xy.rows(); ++i) {
    double sum_sq = 0.0;
    std::size_t n = 0;
    for (std::size_t q = 0; q < fixes; ++q) {
      const auto row = static_cast<Eigen::Index>(q);
      const double dx = fix_xy(row, 0) - sample_xy(i, 0), dy = fix_xy(row, 1) - sample_xy(i, 1);
      if (dx * dx + dy * dy > r2) continue;
      sum_sq += 0.5 * (error_x_m[q] * error_x_m[q] + error_y_m[q] * error_y_m[q]);
      ++n;
    }
    if (n > 0 && n >= options.min_fixes)
      out[static_cast<std::size_t>(i)] = std::sqrt(sum_sq / static_cast<double>(n));
  }
  return out;
}

Eigen::MatrixXd cross_validated_fixes(const KernelSelection& selection,
                                      const PlacedSamples& queries) {
  const std::size_t n = selection.query_row.size();
  if (selection.error_x_m.size() != n || selection.error_y_m.size() != n)
    throw std::invalid_argument("cross_validated_fixes: one query row per error");
  Eigen::MatrixXd fix(static_cast<Eigen::Index>(n), 2);
  for (std::size_t i = 0; i < n; ++i) {
    const auto q = static_cast<Eigen::Index>(selection.query_row[i]);
    if (q >= queries.xy.rows()) throw std::invalid_argument("cross_validated_fixes: no such query");
    fix(static_cast<Eigen::Index>(i), 0) = queries.xy(q, 0) + selection.error_x_m[i];
    fix(static_cast<Eigen::Index>(i), 1) = queries.xy(q, 1) + selection.error_y_m[i];
  }
  return fix;
}

}  // namespace harmoloc::algorithms
