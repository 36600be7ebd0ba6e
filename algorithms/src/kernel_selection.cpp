#include "harmoloc/algorithms/kernel_selection.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "column_selection.hpp"
#include "harmoloc/algorithms/harmonic_localizer.hpp"
#include "harmoloc/algorithms/harmonic_training.hpp"

namespace harmoloc::algorithms {

namespace {

Eigen::MatrixXd columns_of(const Eigen::MatrixXd& m, const std::vector<int>& columns) {
  Eigen::MatrixXd out(m.rows(), static_cast<Eigen::Index>(columns.size()));
  for (std::size_t c = 0; c < columns.size(); ++c)
    out.col(static_cast<Eigen::Index>(c)) = m.col(columns[c]);
  return out;
}

// Squared distances from each query to each sample, +inf where the sample is of the query's own
// pass (within same_pass_m of travel).
// With @p column_weight above 0 (and columns in both), the centroid columns add theirs.
Eigen::MatrixXd held_out_distances(const PlacedSamples& samples, const PlacedSamples& queries,
                                   const std::vector<int>& columns, double same_pass_m,
                                   double column_weight) {
  Eigen::MatrixXd d2 = squared_distances(columns_of(queries.features, columns),
                                         columns_of(samples.features, columns));
  if (column_weight > 0.0 && samples.columns.size() > 0 && queries.columns.size() > 0) {
    d2 += (column_weight * column_weight) * squared_distances(columns_of(queries.columns, columns),
                                                              columns_of(samples.columns, columns));
  }
  for (Eigen::Index q = 0; q < d2.rows(); ++q) {
    const double tq = queries.travel_m[static_cast<std::size_t>(q)];
    // Samples come in travel order: the excluded ones are one contiguous stretch.
    const auto lo =
        std::lower_bound(samples.travel_m.begin(), samples.travel_m.end(), tq - same_pass_m);
    const auto hi =
        std::upper_bound(samples.travel_m.begin(), samples.travel_m.end(), tq + same_pass_m);
    for (auto it = lo; it < hi; ++it)
      d2(q, static_cast<Eigen::Index>(it - samples.travel_m.begin())) =
          std::numeric_limits<double>::infinity();
  }
  return d2;
}

// Which queries have another pass close by in position: the nearest other-pass sample within
// twice the median such distance over all queries. Elsewhere (the turn at the end of a route
// driven once each way) leaving the own pass out leaves nothing to compare with, and the error
// would measure extrapolation, not a new run over the same place.
std::vector<char> queries_with_other_pass(const PlacedSamples& samples,
                                          const PlacedSamples& queries, double same_pass_m) {
  const auto m = samples.xy.rows();
  std::vector<double> nearest(static_cast<std::size_t>(queries.xy.rows()),
                              std::numeric_limits<double>::infinity());
  for (Eigen::Index q = 0; q < queries.xy.rows(); ++q) {
    const double tq = queries.travel_m[static_cast<std::size_t>(q)];
    double best = std::numeric_limits<double>::infinity();
    for (Eigen::Index j = 0; j < m; ++j) {
      if (std::fabs(samples.travel_m[static_cast<std::size_t>(j)] - tq) < same_pass_m) continue;
      const double dx = samples.xy(j, 0) - queries.xy(q, 0),
                   dy = samples.xy(j, 1) - queries.xy(q, 1);
      best = std::min(best, dx * dx + dy * dy);
    }
    nearest[static_cast<std::size_t>(q)] = std::sqrt(best);
  }
  std::vector<double> finite;
  for (double d : nearest) {
    if (std::isfinite(d)) finite.push_back(d);
  }
  std::vector<char> out(nearest.size(), 0);
  if (finite.empty()) return out;
  auto mid = finite.begin() + static_cast<std::ptrdiff_t>(finite.size() / 2);
  std::nth_element(finite.begin(), mid, finite.end());
  const double bound = std::max(2.0 * *mid, 0.01);
  for (std::size_t q = 0; q < nearest.size(); ++q) out[q] = nearest[q] <= bound ? 1 : 0;
  return out;
}

double median_finite(const Eigen::MatrixXd& m) {
  std::vector<double> v;
  v.reserve(static_cast<std::size_t>(m.size()));
  for (Eigen::Index i = 0; i < m.size(); ++i) {
    const double x = m.data()[i];
    if (std::isfinite(x) && x > 0.0) v.push_back(x);
  }
  if (v.empty()) return 1.0;
  auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid > 0.0 ? *mid : 1.0;
}

// Eq. 9's local linear correction for one query along one axis, for every ridge at once: the
// normal equations of sum_j w_j (t_j - a - b . z_j)^2 + ridge |b|^2 with z_j = O_j - O, their
// intercept a, as the firmware computes it (harmonic_localizer.cpp: the same neglected weights,
// targets relative to the kernel average, the ridge in units of the weight sum / (2 sigma)).
void local_linear_predictions(const Eigen::MatrixXd& fs, const Eigen::RowVectorXd& fq,
                              const Eigen::RowVectorXd& excess, double sigma,
                              const Eigen::VectorXd& target, const std::vector<double>& ridges,
                              double kernel_average, double weight_sum, std::vector<double>& out) {
  const Eigen::Index m = fs.cols(), p = m + 1;
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(p, p);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(p);
  Eigen::VectorXd z(p);
  z(0) = 1.0;
  for (Eigen::Index j = 0; j < fs.rows(); ++j) {
    const double e = sigma * excess(j);
    // The firmware's cut (harmonic_localizer.hpp); also skips +inf (the query's own pass).
    if (!(e <= static_cast<double>(kLocalLinearCutoff))) continue;
    const double w = std::exp(-e);
    z.tail(m) = (fs.row(j) - fq).transpose();
    a.selfadjointView<Eigen::Lower>().rankUpdate(z, w);
    b += (w * (target(j) - kernel_average)) * z;
  }
  a.triangularView<Eigen::StrictlyUpper>() = a.transpose().triangularView<Eigen::StrictlyUpper>();
  out.assign(ridges.size(), kernel_average);
  for (std::size_t r = 0; r < ridges.size(); ++r) {
    Eigen::MatrixXd ar = a;
    ar.diagonal().tail(m).array() += ridges[r] * weight_sum / (2.0 * sigma);
    const Eigen::LLT<Eigen::MatrixXd> llt(ar);
    if (llt.info() != Eigen::Success) continue;
    const double v = kernel_average + llt.solve(b)(0);
    if (std::isfinite(v)) out[r] = v;
  }
}

// exp(-t), skipping the call (and its slow underflow path) where it is 0 in double anyway:
// exp(-t) rounds to 0 from t = 745.2 on (below half the smallest subnormal).
double weight(double t) {
  return t > 746.0 ? 0.0 : std::exp(-t);
}

}  // namespace

std::pair<KernelAxis, KernelAxis> cross_validate_kernel(const PlacedSamples& samples,
                                                        const PlacedSamples& queries,
                                                        const std::vector<int>& columns,
                                                        const KernelSelectionOptions& options) {
  if (columns.empty()) throw std::invalid_argument("cross_validate_kernel: no columns");
  Eigen::MatrixXd d2 =
      held_out_distances(samples, queries, columns, options.same_pass_m, options.column_weight);
  const double median = median_finite(d2);
  // Relative to each query's nearest allowed sample (as the firmware computes eq. 9).
  std::vector<char> usable = queries_with_other_pass(samples, queries, options.same_pass_m);
  for (Eigen::Index q = 0; q < d2.rows(); ++q) {
    const double lo = d2.row(q).minCoeff();
    if (!std::isfinite(lo)) usable[static_cast<std::size_t>(q)] = 0;
    if (!usable[static_cast<std::size_t>(q)]) continue;
    d2.row(q).array() -= lo;
  }
  const double s0 = std::ldexp(1.0, options.sigma_exponent_min) / median;
  std::pair<KernelAxis, KernelAxis> best;
  best.first.cv_mse = best.second.cv_mse = std::numeric_limits<double>::infinity();
  std::size_t count = 0;
  for (char u : usable) count += u ? 1U : 0U;
  if (count == 0)
    throw std::runtime_error("cross-validation: no frame has another pass to compare with");
  // The weights (queries x samples) outgrow the caches: one pass over the matrix a sigma sums
  // the weighted positions and the weights and squares them for the next sigma, a column at a
  // time while it is in the cache, where a matrix product, a row sum and a square would read the
  // whole matrix three times.
  Eigen::MatrixXd w = (-s0 * d2.array()).exp().matrix();  // inf -> weight 0
  Eigen::VectorXd px(w.rows()), py(w.rows()), sum(w.rows());
  for (int e = options.sigma_exponent_min; e <= options.sigma_exponent_max; ++e) {
    px.setZero();
    py.setZero();
    sum.setZero();
    const bool square = e < options.sigma_exponent_max;
    for (Eigen::Index s = 0; s < w.cols(); ++s) {
      auto ws = w.col(s);
      px.noalias() += samples.xy(s, 0) * ws;
      py.noalias() += samples.xy(s, 1) * ws;
      sum += ws;
      if (square) ws = ws.cwiseProduct(ws);  // sigma doubles: each weight squares
    }
    double se[2] = {0.0, 0.0};
    for (Eigen::Index q = 0; q < w.rows(); ++q) {
      if (!usable[static_cast<std::size_t>(q)]) continue;
      const double ex = px(q) / sum(q) - queries.xy(q, 0), ey = py(q) / sum(q) - queries.xy(q, 1);
      se[0] += ex * ex;
      se[1] += ey * ey;
    }
    const double sigma = std::ldexp(1.0, e) / median;
    for (int a = 0; a < 2; ++a) {
      const double mse = se[a] / static_cast<double>(count);
      KernelAxis& b = a == 0 ? best.first : best.second;
      if (std::isfinite(mse) && mse < b.cv_mse) b = KernelAxis{sigma, mse};
    }
  }
  return best;
}

void other_pass_nearest(const PlacedSamples& samples, const PlacedSamples& queries,
                        const std::vector<int>& columns, double same_pass_m,
                        std::vector<double>& distance, std::vector<double>& dissimilarity) {
  distance.clear();
  dissimilarity.clear();
  const Eigen::MatrixXd d2 = held_out_distances(samples, queries, columns, same_pass_m, 0.0);
  const Eigen::MatrixXd fq = columns_of(queries.features, columns);
  const Eigen::MatrixXd fs = columns_of(samples.features, columns);
  const std::vector<char> usable = queries_with_other_pass(samples, queries, same_pass_m);
  for (Eigen::Index q = 0; q < d2.rows(); ++q) {
    Eigen::Index j = 0;
    const double lo = d2.row(q).minCoeff(&j);
    if (!std::isfinite(lo) || !usable[static_cast<std::size_t>(q)]) continue;
    distance.push_back(std::sqrt(lo));
    const double num = (fq.row(q) - fs.row(j)).cwiseAbs().sum();
    const double den = (fq.row(q) + fs.row(j)).sum();
    dissimilarity.push_back(den > 0.0 ? num / den : 1.0);
  }
}

KernelSelection select_kernel_model(const PlacedSamples& samples, const PlacedSamples& queries,
                                    const KernelSelectionOptions& options) {
  KernelSelection out;
  std::vector<int> columns = detail::changing_columns(samples.features);
  auto current = cross_validate_kernel(samples, queries, columns, options);
  out.steps.push_back(
      KernelSelectionStep{columns, current.first.cv_mse, current.second.cv_mse, -1});
  if (options.select_features) {
    auto evaluate = [&](const std::vector<int>& cols) {
      return cross_validate_kernel(samples, queries, cols, options);
    };
    current = detail::eliminate_columns(
        columns, current, options.min_improvement, options.min_boards, evaluate,
        [&](const std::vector<int>& left, const auto& choice, int dropped) {
          out.steps.push_back(
              KernelSelectionStep{left, choice.first.cv_mse, choice.second.cv_mse, dropped});
        });
  }
  out.columns = columns;
  out.x = current.first;
  out.y = current.second;

  // Diagnostics of the chosen model: nearest other-pass sample and the held-out error.
  Eigen::MatrixXd d2 =
      held_out_distances(samples, queries, columns, options.same_pass_m, options.column_weight);
  const Eigen::MatrixXd fq = columns_of(queries.features, columns);
  const Eigen::MatrixXd fs = columns_of(samples.features, columns);
  const std::vector<char> usable = queries_with_other_pass(samples, queries, options.same_pass_m);
  std::vector<std::vector<double>> linear_x, linear_y;  // per query, per ridge
  std::vector<std::pair<double, double>> truth;
  for (Eigen::Index q = 0; q < d2.rows(); ++q) {
    Eigen::Index j = 0;
    const double lo = d2.row(q).minCoeff(&j);
    if (!std::isfinite(lo) || !usable[static_cast<std::size_t>(q)]) continue;
    out.nearest_distance.push_back(std::sqrt(lo));
    out.query_row.push_back(static_cast<std::size_t>(q));
    const double num = (fq.row(q) - fs.row(j)).cwiseAbs().sum();
    const double den = (fq.row(q) + fs.row(j)).sum();
    out.nearest_dissimilarity.push_back(den > 0.0 ? num / den : 1.0);
    double px = 0, py = 0, sx = 0, sy = 0;
    for (Eigen::Index s = 0; s < d2.cols(); ++s) {
      const double ex = d2(q, s) - lo;
      if (!std::isfinite(ex)) continue;
      const double wx = weight(out.x.sigma * ex);
      const double wy = out.y.sigma == out.x.sigma ? wx : weight(out.y.sigma * ex);
      px += wx * samples.xy(s, 0);
      py += wy * samples.xy(s, 1);
      sx += wx;
      sy += wy;
    }
    out.error_x_m.push_back(px / sx - queries.xy(q, 0));
    out.error_y_m.push_back(py / sy - queries.xy(q, 1));
    if (options.local_linear_ridges.empty()) continue;
    const Eigen::RowVectorXd excess = d2.row(q).array() - lo;
    std::vector<double> p;
    local_linear_predictions(fs, fq.row(q), excess, out.x.sigma, samples.xy.col(0),
                             options.local_linear_ridges, px / sx, sx, p);
    linear_x.push_back(p);
    local_linear_predictions(fs, fq.row(q), excess, out.y.sigma, samples.xy.col(1),
                             options.local_linear_ridges, py / sy, sy, p);
    linear_y.push_back(p);
    truth.emplace_back(queries.xy(q, 0), queries.xy(q, 1));
  }
  const auto mse = [](const std::vector<double>& e) {
    double s = 0.0;
    for (double v : e) s += v * v;
    return e.empty() ? 0.0 : s / static_cast<double>(e.size());
  };
  out.kernel_average_cv_mse_x = mse(out.error_x_m);
  out.kernel_average_cv_mse_y = mse(out.error_y_m);
  out.x.cv_mse = out.kernel_average_cv_mse_x;
  out.y.cv_mse = out.kernel_average_cv_mse_y;
  // The local linear correction, where it beats the kernel average clearly.
  double best_score = (out.x.cv_mse + out.y.cv_mse) * (1.0 - options.min_improvement);
  for (std::size_t r = 0; r < options.local_linear_ridges.size() && !truth.empty(); ++r) {
    std::vector<double> ex, ey;
    for (std::size_t i = 0; i < truth.size(); ++i) {
      ex.push_back(linear_x[i][r] - truth[i].first);
      ey.push_back(linear_y[i][r] - truth[i].second);
    }
    const double score = mse(ex) + mse(ey);
    if (score < best_score) {
      best_score = score;
      out.local_linear_ridge = options.local_linear_ridges[r];
      out.x.cv_mse = mse(ex);
      out.y.cv_mse = mse(ey);
      out.error_x_m = ex;
      out.error_y_m = ey;
    }
  }
  return out;
}

}  // namespace harmoloc::algorithms
