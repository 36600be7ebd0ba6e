// The per-sample fix errors the trainer stores in the map (local_fix_error.hpp): each sample
// takes the error of the held-out fixes that landed near its place, not of those taken there.
#include "harmoloc/algorithms/local_fix_error.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <stdexcept>

namespace ha = harmoloc::algorithms;

namespace {

Eigen::MatrixXd points(std::initializer_list<std::pair<double, double>> xy) {
  Eigen::MatrixXd m(static_cast<Eigen::Index>(xy.size()), 2);
  Eigen::Index i = 0;
  for (const auto& [x, y] : xy) {
    m(i, 0) = x;
    m(i, 1) = y;
    ++i;
  }
  return m;
}

}  // namespace

TEST(LocalFixError, EachSampleTakesTheFixesThatNamedItsPlace) {
  // Samples at 0, 1 and 3 m along x. Three fixes landed at 1 m although they were taken at
  // 1.2 m (20 cm off along x), three at 0 m right; none near 3 m.
  const Eigen::MatrixXd samples = points({{0.0, 0.0}, {1.0, 0.0}, {3.0, 0.0}});
  const Eigen::MatrixXd fixes =
      points({{0.0, 0.01}, {0.01, 0.0}, {-0.01, 0.0}, {1.0, 0.0}, {1.01, 0.0}, {0.99, 0.01}});
  const std::vector<double> ex{0.0, 0.0, 0.0, -0.2, -0.2, -0.2};
  const std::vector<double> ey{0.01, 0.01, 0.01, 0.0, 0.0, 0.0};
  ha::LocalFixErrorOptions o;
  o.radius_m = 0.05;
  o.fallback_m = 0.04;
  const std::vector<double> e = ha::local_fix_errors(samples, fixes, ex, ey, o);
  ASSERT_EQ(e.size(), 3U);
  EXPECT_NEAR(e[0], 0.01 / std::sqrt(2.0), 1e-12);  // RMS per axis
  EXPECT_NEAR(e[1], 0.2 / std::sqrt(2.0), 1e-12);
  EXPECT_EQ(e[2], 0.04);  // no fix landed near: the global error
  // Fewer fixes than min_fixes near a sample: the global error too.
  o.min_fixes = 4;
  EXPECT_EQ(ha::local_fix_errors(samples, fixes, ex, ey, o)[1], 0.04);
  // Errors that do not match the fixes, or no radius: refused.
  EXPECT_THROW(ha::local_fix_errors(samples, fixes, {0.0}, ey, o), std::invalid_argument);
  o.radius_m = 0.0;
  EXPECT_THROW(ha::local_fix_errors(samples, fixes, ex, ey, o), std::invalid_argument);
}

TEST(LocalFixError, CrossValidatedFixesPairEachErrorWithItsQuery) {
  // The selection skips queries without another pass: its errors name their query rows.
  ha::PlacedSamples queries;
  queries.xy = points({{0.0, 0.0}, {1.0, 0.0}, {2.0, 0.0}});
  ha::KernelSelection sel;
  sel.error_x_m = {0.1, -0.1};
  sel.error_y_m = {0.0, 0.2};
  sel.query_row = {0, 2};
  const Eigen::MatrixXd f = ha::cross_validated_fixes(sel, queries);
  ASSERT_EQ(f.rows(), 2);
  EXPECT_DOUBLE_EQ(f(0, 0), 0.1);
  EXPECT_DOUBLE_EQ(f(1, 0), 1.9);
  EXPECT_DOUBLE_EQ(f(1, 1), 0.2);
  sel.query_row = {0, 3};
  EXPECT_THROW(ha::cross_validated_fixes(sel, queries), std::invalid_argument);
  sel.query_row = {0};
  EXPECT_THROW(ha::cross_validated_fixes(sel, queries), std::invalid_argument);
}
