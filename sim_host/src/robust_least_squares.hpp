#pragma once
// Robust Levenberg-Marquardt for the host's geometry fits (private to sim_host/src): Huber
// weights recomputed at every step. Tens of parameters at most (a board's six; a camera's seven
// and its boards' six each) over hundreds to thousands of residuals, so the normal equations are
// dense and small.
#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <vector>

namespace harmoloc::sim_host::detail {

inline double huber_cost(const Eigen::VectorXd& r, double k) {
  double c = 0.0;
  for (Eigen::Index i = 0; i < r.size(); ++i) {
    const double a = std::fabs(r[i]);
    c += a <= k ? 0.5 * a * a : k * (a - 0.5 * k);
  }
  return c;
}

struct RobustSolution {
  Eigen::VectorXd p;
  double cost = std::numeric_limits<double>::infinity();
  bool converged = false;  ///< the cost stopped falling before the iterations ran out
};

/// The Jacobian of @p residuals at @p p by central differences, @p step per parameter.
template <typename Residuals>
void central_differences(Residuals& residuals, const Eigen::VectorXd& p,
                         const std::vector<double>& step, Eigen::Index rows, Eigen::MatrixXd& jac) {
  Eigen::VectorXd rp, rm;
  jac.resize(rows, p.size());
  for (Eigen::Index j = 0; j < p.size(); ++j) {
    Eigen::VectorXd a = p, b = p;
    const double h = step[static_cast<std::size_t>(j)];
    a[j] += h;
    b[j] -= h;
    residuals(a, rp);
    residuals(b, rm);
    jac.col(j) = (rp - rm) / (2.0 * h);
  }
}

/// Minimises the Huber cost (threshold @p huber) of @p residuals(p, r) from @p p;
/// @p jacobian(p, rows, J) fills J.
template <typename Residuals, typename Jacobian>
RobustSolution robust_least_squares(Residuals residuals, Jacobian jacobian, Eigen::VectorXd p,
                                    double huber, int max_iterations) {
  const Eigen::Index n = p.size();
  Eigen::VectorXd r, rq;
  residuals(p, r);
  double cost = huber_cost(r, huber);
  if (!std::isfinite(cost)) return {p, cost, false};
  double lambda = 1e-3;
  Eigen::MatrixXd jac;
  for (int it = 0; it < max_iterations; ++it) {
    jacobian(p, r.size(), jac);
    Eigen::VectorXd w(r.size());
    for (Eigen::Index i = 0; i < r.size(); ++i) {
      const double a = std::fabs(r[i]);
      w[i] = a <= huber ? 1.0 : huber / a;
    }
    const Eigen::MatrixXd jtj = jac.transpose() * w.asDiagonal() * jac;
    const Eigen::VectorXd jtr = jac.transpose() * w.asDiagonal() * r;
    bool stepped = false;
    for (int tries = 0; tries < 10 && !stepped; ++tries) {
      Eigen::MatrixXd a = jtj;
      for (Eigen::Index d = 0; d < n; ++d) a(d, d) += lambda * (jtj(d, d) + 1e-9);
      // J is the residuals' Jacobian: the damped Gauss-Newton step is -(J^T W J + D)^-1 J^T W r.
      const Eigen::VectorXd s = -a.ldlt().solve(jtr);
      if (!s.allFinite()) break;
      const Eigen::VectorXd q = p + s;
      residuals(q, rq);
      const double c = huber_cost(rq, huber);
      if (c < cost) {
        const double gain = cost - c;
        p = q;
        r = rq;
        cost = c;
        lambda = std::max(lambda * 0.3, 1e-9);
        stepped = true;
        if (gain < 1e-7 * (1.0 + cost)) return {p, cost, true};
      } else {
        lambda *= 10.0;
      }
    }
    if (!stepped) return {p, cost, true};  // no step lowers the cost: a minimum
  }
  return {p, cost, false};
}

}  // namespace harmoloc::sim_host::detail
