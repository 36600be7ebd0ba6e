// algorithms::select_kernel_model: the cross-validated choice of eq. 9's kernel and of its local
// linear correction, on a route driven forth and back twice whose boards change linearly along it.
#include "harmoloc/algorithms/kernel_selection.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "harmoloc/algorithms/random.hpp"

namespace harmoloc::algorithms {
namespace {

// A 2 m straight route driven 0 -> 2 -> 0 -> 2 -> 0, per_leg frames a leg; three boards
// whose areas change smoothly with x (one of them decreasing), with noise.
PlacedSamples straight_route(std::uint64_t seed, double noise, int per_leg) {
  Pcg32 rng(seed);
  PlacedSamples s;
  s.features.resize(4 * per_leg, 3);
  s.xy.resize(4 * per_leg, 2);
  for (int i = 0; i < 4 * per_leg; ++i) {
    const int leg = i / per_leg, k = i % per_leg;
    const double along = 2.0 * (k + 0.37 * leg) / per_leg;  // each pass between the others
    const double x = leg % 2 == 0 ? along : 2.0 - along;
    s.xy(i, 0) = x;
    s.xy(i, 1) = 0.3 + 0.002 * rng.normal();
    s.features(i, 0) = 1.0 + 2.0 * x + noise * rng.normal();
    s.features(i, 1) = 5.0 - 1.5 * x + noise * rng.normal();
    s.features(i, 2) = 0.5 + 0.5 * x * x + noise * rng.normal();
    s.travel_m.push_back(2.0 * i / per_leg);
  }
  return s;
}

// Frames 10 cm apart with little noise: a kernel average can only lean towards the nearest
// frames of other passes, a local plane interpolates between them.
TEST(KernelSelection, LocalLinearIsChosenWhereItCrossValidatesBetter) {
  const PlacedSamples samples = straight_route(1, 0.005, 20);
  KernelSelectionOptions options;
  const KernelSelection with = select_kernel_model(samples, samples, options);
  EXPECT_GT(with.local_linear_ridge, 0.0);
  EXPECT_LT(with.x.cv_mse, with.kernel_average_cv_mse_x);
  // The per-query errors are the chosen fix's: their mean square is the reported CV error.
  double se = 0.0;
  for (double e : with.error_x_m) se += e * e;
  ASSERT_FALSE(with.error_x_m.empty());
  EXPECT_NEAR(se / static_cast<double>(with.error_x_m.size()), with.x.cv_mse, 1e-12);

  options.local_linear_ridges.clear();
  const KernelSelection without = select_kernel_model(samples, samples, options);
  EXPECT_EQ(without.local_linear_ridge, 0.0);
  EXPECT_DOUBLE_EQ(without.x.cv_mse, without.kernel_average_cv_mse_x);
  EXPECT_DOUBLE_EQ(without.kernel_average_cv_mse_x, with.kernel_average_cv_mse_x);
}

TEST(KernelSelection, LocalLinearIsLeftOutWhereItDoesNotHelp) {
  // Features that do not follow the position at all: no plane through them predicts better
  // than the average, and the plain kernel average is kept.
  PlacedSamples samples = straight_route(2, 0.01, 100);
  Pcg32 rng(9);
  for (Eigen::Index i = 0; i < samples.features.rows(); ++i)
    for (Eigen::Index k = 0; k < samples.features.cols(); ++k)
      samples.features(i, k) = rng.uniform(0.0, 1.0);
  const KernelSelection sel = select_kernel_model(samples, samples, KernelSelectionOptions{});
  EXPECT_EQ(sel.local_linear_ridge, 0.0);
}

// Boards whose areas depend only on the distance from the route's middle: x and 2 - x look the
// same by their areas, the boards stand left of the camera on one half and right on the other.
// With the centroid columns in the kernel (KernelSelectionOptions::column_weight), CV tells the
// halves apart; the known-place calibration (other_pass_nearest) compares areas only.
TEST(KernelSelection, CentroidColumnsTellApartMirroredHalves) {
  PlacedSamples samples = straight_route(3, 0.005, 40);
  samples.columns.resize(samples.features.rows(), samples.features.cols());
  for (Eigen::Index i = 0; i < samples.features.rows(); ++i) {
    const double x = samples.xy(i, 0), d = std::fabs(x - 1.0);
    samples.features(i, 0) = 1.0 + 2.0 * d;
    samples.features(i, 1) = 5.0 - 1.5 * d;
    samples.features(i, 2) = 0.5 + 0.5 * d * d;
    for (Eigen::Index k = 0; k < 3; ++k)
      samples.columns(i, k) = (x < 1.0 ? -0.3 : 0.3) * std::sqrt(samples.features(i, k));
  }
  KernelSelectionOptions options;
  options.select_features = false;
  const KernelSelection areas = select_kernel_model(samples, samples, options);
  options.column_weight = 1.0;
  const KernelSelection columns = select_kernel_model(samples, samples, options);
  EXPECT_GT(std::sqrt(areas.x.cv_mse), 0.2) << "mirrored halves: half the fixes on the wrong one";
  EXPECT_LT(std::sqrt(columns.x.cv_mse), 0.05);
  std::vector<double> d_areas, s_areas, d_columns, s_columns;
  other_pass_nearest(samples, samples, areas.columns, options.same_pass_m, d_areas, s_areas);
  samples.columns *= 100.0;  // columns far apart change nothing there
  other_pass_nearest(samples, samples, areas.columns, options.same_pass_m, d_columns, s_columns);
  EXPECT_EQ(d_areas, d_columns);
}

// cross_validate_kernel sums every sigma's weights from the first one's by squaring; the chosen
// model's diagnostics weigh each sample with exp() directly. Both must give the same held-out
// error at the chosen widths, with and without the centroid columns.
TEST(KernelSelection, CrossValidationMatchesTheDirectKernelAverage) {
  PlacedSamples samples = straight_route(4, 0.02, 60);
  samples.columns.resize(samples.features.rows(), samples.features.cols());
  Pcg32 rng(5);
  for (Eigen::Index i = 0; i < samples.columns.rows(); ++i)
    for (Eigen::Index k = 0; k < samples.columns.cols(); ++k)
      samples.columns(i, k) = rng.uniform(-0.5, 0.5);
  KernelSelectionOptions options;
  options.select_features = false;
  options.local_linear_ridges.clear();
  for (const double column_weight : {0.0, 1.0}) {
    options.column_weight = column_weight;
    const auto cv = cross_validate_kernel(samples, samples, {0, 1, 2}, options);
    const KernelSelection sel = select_kernel_model(samples, samples, options);
    ASSERT_GT(cv.first.cv_mse, 0.0);
    EXPECT_EQ(sel.x.sigma, cv.first.sigma);
    EXPECT_EQ(sel.y.sigma, cv.second.sigma);
    EXPECT_NEAR(sel.kernel_average_cv_mse_x, cv.first.cv_mse, 1e-6 * cv.first.cv_mse);
    EXPECT_NEAR(sel.kernel_average_cv_mse_y, cv.second.cv_mse, 1e-6 * cv.second.cv_mse);
  }
}

// Two boards that follow the position and three that are only noise: cross-validation would keep
// the two, but a fix from two boards cannot be checked for a moved one, so the selection stops
// at KernelSelectionOptions::min_boards (three). A run with only two boards that change keeps
// both, whatever they are worth.
TEST(KernelSelection, KeepsAtLeastMinBoards) {
  const PlacedSamples route = straight_route(6, 0.005, 40);
  PlacedSamples samples = route;
  samples.features.resize(route.features.rows(), 5);
  Pcg32 rng(11);
  for (Eigen::Index i = 0; i < samples.features.rows(); ++i) {
    samples.features(i, 0) = route.features(i, 0);
    samples.features(i, 1) = route.features(i, 1);
    for (Eigen::Index k = 2; k < 5; ++k) samples.features(i, k) = rng.uniform(0.0, 10.0);
  }
  KernelSelectionOptions options;
  options.local_linear_ridges.clear();
  options.min_boards = 1;
  const KernelSelection free = select_kernel_model(samples, samples, options);
  ASSERT_LE(free.columns.size(), 2U) << "the noise boards must hurt, or the test shows nothing";
  options.min_boards = 3;
  const KernelSelection three = select_kernel_model(samples, samples, options);
  ASSERT_EQ(three.columns.size(), 3U);
  EXPECT_EQ(three.columns[0], 0);
  EXPECT_EQ(three.columns[1], 1);
  EXPECT_EQ(KernelSelectionOptions{}.min_boards, 3U);

  PlacedSamples two = samples;
  two.features.conservativeResize(Eigen::NoChange, 2);
  two.features.col(1).setConstant(1.0);  // one board that changes and one that does not
  two.features.conservativeResize(Eigen::NoChange, 3);
  two.features.col(2) = samples.features.col(2);
  EXPECT_EQ(select_kernel_model(two, two, options).columns, (std::vector<int>{0, 2}));
}

}  // namespace
}  // namespace harmoloc::algorithms
