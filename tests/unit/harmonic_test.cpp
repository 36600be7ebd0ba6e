// The harmonic localizer (Wu & Qin 2010): the offline semi-supervised solve against a dense solve
// built here from the definitions, eq. 9 against a direct evaluation, the fixed-capacity float
// online query against the double offline twin, the known-place test, and the parameter search.
#include "harmoloc/algorithms/harmonic_localizer.hpp"
#include "harmoloc/algorithms/harmonic_model.hpp"
#include "harmoloc/algorithms/harmonic_training.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "harmoloc/algorithms/random.hpp"

namespace ha = harmoloc::algorithms;

namespace {

// 30 samples along a smooth 2-D curve (an area vector that changes smoothly along a route) with a
// little deterministic jitter; the label is the curve parameter (a coordinate along the route).
struct Problem {
  Eigen::MatrixXd features;
  Eigen::VectorXd labels;  // true coordinate of every sample
  std::vector<bool> labelled;
};

Problem make_problem(int m = 30, int every = 4) {
  Problem p;
  p.features.resize(m, 2);
  p.labels.resize(m);
  p.labelled.assign(static_cast<std::size_t>(m), false);
  ha::Pcg32 rng(99);
  for (int i = 0; i < m; ++i) {
    const double t = static_cast<double>(i) / (m - 1);  // 0..1
    p.features(i, 0) = 1.0 + 2.0 * t + 0.01 * rng.normal();
    p.features(i, 1) = 3.0 - 1.5 * t * t + 0.01 * rng.normal();
    p.labels(i) = 4.2 * t;  // metres along the route
    p.labelled[static_cast<std::size_t>(i)] = (i % every) == 0;
  }
  return p;
}

// The dense system of eq. 8 built from its definitions with plain loops.
Eigen::MatrixXd reference_laplacian(const Eigen::MatrixXd& o, double sigma) {
  const Eigen::Index m = o.rows();
  Eigen::MatrixXd w(m, m);
  for (Eigen::Index i = 0; i < m; ++i) {
    for (Eigen::Index j = 0; j < m; ++j) {
      double d2 = 0.0;
      for (Eigen::Index k = 0; k < o.cols(); ++k) d2 += (o(i, k) - o(j, k)) * (o(i, k) - o(j, k));
      w(i, j) = std::exp(-sigma * d2);
    }
  }
  Eigen::VectorXd deg(m);
  for (Eigen::Index i = 0; i < m; ++i) {
    double s = 0.0;
    for (Eigen::Index j = 0; j < m; ++j) s += w(i, j);
    deg(i) = s;
  }
  Eigen::MatrixXd l(m, m);
  for (Eigen::Index i = 0; i < m; ++i) {
    for (Eigen::Index j = 0; j < m; ++j) {
      l(i, j) = (i == j ? 1.0 : 0.0) - w(i, j) / std::sqrt(deg(i) * deg(j));
    }
  }
  return l;
}

Eigen::VectorXd reference_solve(const Eigen::MatrixXd& o, const std::vector<bool>& labelled,
                                const Eigen::VectorXd& labels, double sigma, double gamma) {
  const Eigen::Index m = o.rows();
  const Eigen::MatrixXd l = reference_laplacian(o, sigma);
  Eigen::MatrixXd a(m, m);
  Eigen::VectorXd c = Eigen::VectorXd::Zero(m);
  for (Eigen::Index i = 0; i < m; ++i) {
    for (Eigen::Index j = 0; j < m; ++j) a(i, j) = gamma * l(i, j);
    if (labelled[static_cast<std::size_t>(i)]) {
      a(i, i) += 1.0;
      c(i) = labels(i);
    }
  }
  return Eigen::FullPivLU<Eigen::MatrixXd>(a).solve(c);
}

// Eq. 9 straight from its definition (no shift by the nearest sample), in long double.
double reference_eq9(const Eigen::MatrixXd& o, const Eigen::VectorXd& f, double sigma,
                     const Eigen::RowVectorXd& q) {
  long double num = 0.0L, den = 0.0L;
  for (Eigen::Index j = 0; j < o.rows(); ++j) {
    long double d2 = 0.0L;
    for (Eigen::Index k = 0; k < o.cols(); ++k) {
      const long double t = static_cast<long double>(q(k)) - static_cast<long double>(o(j, k));
      d2 += t * t;
    }
    const long double w = std::exp(-static_cast<long double>(sigma) * d2);
    num += w * static_cast<long double>(f(j));
    den += w;
  }
  return static_cast<double>(num / den);
}

}  // namespace

TEST(HarmonicTraining, LaplacianMatchesDefinition) {
  const Problem p = make_problem();
  for (double sigma : {0.1, 2.0, 30.0}) {
    const Eigen::MatrixXd l = ha::normalized_laplacian(p.features, sigma);
    const Eigen::MatrixXd ref = reference_laplacian(p.features, sigma);
    ASSERT_EQ(l.rows(), 30);
    ASSERT_EQ(l.cols(), 30);
    EXPECT_LT((l - ref).cwiseAbs().maxCoeff(), 1e-12) << "sigma " << sigma;
    // Symmetric, and D^1/2 1 is in its null space.
    EXPECT_LT((l - l.transpose()).cwiseAbs().maxCoeff(), 1e-14);
  }
}

TEST(HarmonicTraining, SolveMatchesDenseFullPivLu) {
  const Problem p = make_problem();
  for (double sigma : {0.5, 2.0, 8.0}) {
    for (double gamma : {0.001, 0.015, 0.3}) {
      const Eigen::VectorXd f =
          ha::solve_semi_supervised(p.features, p.labelled, p.labels, sigma, gamma);
      const Eigen::VectorXd ref = reference_solve(p.features, p.labelled, p.labels, sigma, gamma);
      ASSERT_EQ(f.size(), 30);
      EXPECT_LT((f - ref).cwiseAbs().maxCoeff(), 1e-7 * (1.0 + ref.cwiseAbs().maxCoeff()))
          << "sigma " << sigma << " gamma " << gamma;
    }
  }
}

TEST(HarmonicTraining, SmallGammaReproducesTheLabels) {
  const Problem p = make_problem();
  const Eigen::VectorXd f = ha::solve_semi_supervised(p.features, p.labelled, p.labels, 2.0, 1e-6);
  for (Eigen::Index i = 0; i < p.features.rows(); ++i) {
    if (p.labelled[static_cast<std::size_t>(i)]) {
      EXPECT_NEAR(f(i), p.labels(i), 1e-4) << i;
    }
  }
  // The unlabelled ones are interpolated from the graph: inside the labels' range, not 0.
  for (Eigen::Index i = 1; i < p.features.rows(); i += 4) {
    EXPECT_GT(f(i), -0.5) << i;
    EXPECT_LT(f(i), 4.2 + 0.5) << i;
  }
}

TEST(HarmonicTraining, SolveRejectsMismatchedSizes) {
  const Problem p = make_problem();
  std::vector<bool> short_mask(p.labelled.begin(), p.labelled.end() - 1);
  EXPECT_THROW(ha::solve_semi_supervised(p.features, short_mask, p.labels, 2.0, 0.01),
               std::invalid_argument);
}

TEST(HarmonicTraining, PredictIsEquationNine) {
  const Problem p = make_problem();
  const Eigen::VectorXd f = ha::solve_semi_supervised(p.features, p.labelled, p.labels, 2.0, 0.015);
  Eigen::MatrixXd queries(4, 2);
  queries << 1.5, 2.9, 2.2, 2.5, 0.0, 0.0, 3.0, 1.5;
  for (double sigma : {0.3, 2.0, 10.0}) {
    const Eigen::VectorXd got = ha::harmonic_predict(p.features, f, sigma, queries);
    ASSERT_EQ(got.size(), 4);
    for (Eigen::Index q = 0; q < queries.rows(); ++q) {
      EXPECT_NEAR(got(q), reference_eq9(p.features, f, sigma, queries.row(q)), 1e-10)
          << "sigma " << sigma << " q " << q;
    }
  }
  // Hand-sized case: two samples at 0 and 1 with targets 0 and 10, query at 0.5 with sigma
  // ln(2)/0.25: equal weights -> 5; query at 0: weights 1 and 1/2^4 -> 10/17.
  Eigen::MatrixXd two(2, 1);
  two << 0.0, 1.0;
  Eigen::VectorXd t(2);
  t << 0.0, 10.0;
  Eigen::MatrixXd q(2, 1);
  q << 0.5, 0.0;
  const Eigen::VectorXd hand = ha::harmonic_predict(two, t, std::log(2.0) / 0.25, q);
  EXPECT_NEAR(hand(0), 5.0, 1e-12);
  EXPECT_NEAR(hand(1), 10.0 / 17.0, 1e-12);
}

TEST(HarmonicTraining, PredictFarFromAllSamplesIsFiniteAndNearestTarget) {
  const Problem p = make_problem();
  Eigen::MatrixXd far(1, 2);
  far << 500.0, -300.0;  // exp(-sigma d^2) underflows for every sample
  const Eigen::VectorXd got = ha::harmonic_predict(p.features, p.labels, 5.0, far);
  ASSERT_TRUE(std::isfinite(got(0)));
  // The nearest sample dominates completely.
  Eigen::Index nearest = 0;
  (p.features.rowwise() - far.row(0)).rowwise().squaredNorm().minCoeff(&nearest);
  EXPECT_NEAR(got(0), p.labels(nearest), 1e-9);
}

TEST(HarmonicTraining, MedianSquaredDistance) {
  Eigen::MatrixXd three(3, 1);
  three << 0.0, 1.0, 3.0;  // pairwise d^2: 1, 9, 4 -> median 4
  EXPECT_DOUBLE_EQ(ha::median_squared_distance(three), 4.0);
  Eigen::MatrixXd pts(3, 2);
  pts << 0, 0, 3, 4, 6, 8;  // d^2: 25, 100, 25 -> median 25
  EXPECT_DOUBLE_EQ(ha::median_squared_distance(pts), 25.0);
}

namespace {

void fill_model(ha::HarmonicModel& model, const Problem& p, const Eigen::VectorXd& fx,
                const Eigen::VectorXd& fy) {
  model.sample_count = static_cast<std::uint32_t>(p.features.rows());
  model.feature_count = static_cast<std::uint32_t>(p.features.cols());
  model.area_scale = 1.0F;
  model.sigma_x = 2.0F;
  model.sigma_y = 7.5F;
  model.gamma_x = 0.015F;
  model.gamma_y = 0.01F;
  model.max_nearest_distance = 0.2F;
  for (Eigen::Index i = 0; i < p.features.rows(); ++i) {
    for (Eigen::Index k = 0; k < p.features.cols(); ++k) {
      model.sample(static_cast<std::size_t>(i))[k] = static_cast<float>(p.features(i, k));
    }
    model.target_x_m[static_cast<std::size_t>(i)] = static_cast<float>(fx(i));
    model.target_y_m[static_cast<std::size_t>(i)] = static_cast<float>(fy(i));
  }
}

// The model's float contents as the double matrices harmonic_predict takes.
void model_as_double(const ha::HarmonicModel& m, Eigen::MatrixXd& o, Eigen::VectorXd& fx,
                     Eigen::VectorXd& fy) {
  o.resize(m.sample_count, m.feature_count);
  fx.resize(m.sample_count);
  fy.resize(m.sample_count);
  for (std::size_t i = 0; i < m.sample_count; ++i) {
    for (std::size_t k = 0; k < m.feature_count; ++k) {
      o(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(k)) =
          static_cast<double>(m.sample(i)[k]);
    }
    fx(static_cast<Eigen::Index>(i)) = static_cast<double>(m.target_x_m[i]);
    fy(static_cast<Eigen::Index>(i)) = static_cast<double>(m.target_y_m[i]);
  }
}

}  // namespace

TEST(HarmonicQuery, FloatOnlineMatchesDoubleOffline) {
  const Problem p = make_problem();
  const Eigen::VectorXd fx =
      ha::solve_semi_supervised(p.features, p.labelled, p.labels, 2.0, 0.015);
  Eigen::VectorXd y_labels = 0.5 * p.labels.array().square().matrix();
  const Eigen::VectorXd fy = ha::solve_semi_supervised(p.features, p.labelled, y_labels, 7.5, 0.01);
  auto model = std::make_unique<ha::HarmonicModel>();
  fill_model(*model, p, fx, fy);
  Eigen::MatrixXd o;
  Eigen::VectorXd tx, ty;
  model_as_double(*model, o, tx, ty);

  ha::Pcg32 rng(5);
  for (int n = 0; n < 200; ++n) {
    std::array<float, ha::HarmonicModel::kMaxFeatures> q{};
    q[0] = static_cast<float>(rng.uniform(0.5, 3.5));
    q[1] = static_cast<float>(rng.uniform(1.0, 3.5));
    q[2] = 123.0F;  // beyond feature_count: must be ignored
    Eigen::MatrixXd qd(1, 2);
    qd << static_cast<double>(q[0]), static_cast<double>(q[1]);
    const ha::HarmonicFix fix = ha::harmonic_query(*model, q);
    const double ex = ha::harmonic_predict(o, tx, 2.0, qd)(0);
    const double ey = ha::harmonic_predict(o, ty, 7.5, qd)(0);
    ASSERT_NEAR(fix.x_m, ex, 2e-4 * (1.0 + std::fabs(ex))) << n;
    ASSERT_NEAR(fix.y_m, ey, 2e-4 * (1.0 + std::fabs(ey))) << n;
    const double nearest = std::sqrt((o.rowwise() - qd.row(0)).rowwise().squaredNorm().minCoeff());
    ASSERT_NEAR(fix.nearest_distance, nearest, 1e-4) << n;
  }
}

// A straight route from x = 0 to 1 m whose two boards grow and shrink linearly with x: the
// kernel average at the route's end leans towards the interior (it averages only samples on one
// side); the local linear correction does not, and inside the route both agree.
TEST(HarmonicQuery, LocalLinearRemovesTheKernelAverageBiasAtARouteEnd) {
  auto model = std::make_unique<ha::HarmonicModel>();
  model->sample_count = 101;
  model->feature_count = 2;
  model->sigma_x = model->sigma_y = 2.0F;  // wide: about 0.5 feature units, 5 cm of route
  model->max_nearest_distance = 1.0F;
  model->max_dissimilarity = 1.0F;
  const auto features_at = [](double x) {
    std::array<float, ha::HarmonicModel::kMaxFeatures> f{};
    f[0] = static_cast<float>(1.0 + 10.0 * x);
    f[1] = static_cast<float>(12.0 - 8.0 * x);
    return f;
  };
  for (std::size_t i = 0; i < 101; ++i) {
    const double x = 0.01 * static_cast<double>(i);
    const auto f = features_at(x);
    model->sample(i)[0] = f[0];
    model->sample(i)[1] = f[1];
    model->target_x_m[i] = static_cast<float>(x);
    model->target_y_m[i] = 0.5F;
  }
  const ha::HarmonicFix plain_end = ha::harmonic_query(*model, features_at(0.0));
  const ha::HarmonicFix plain_mid = ha::harmonic_query(*model, features_at(0.503));
  EXPECT_GT(plain_end.x_m, 0.02) << "the kernel average's pull towards the interior";
  model->local_linear_ridge = 0.01F;
  const ha::HarmonicFix linear_end = ha::harmonic_query(*model, features_at(0.0));
  const ha::HarmonicFix linear_mid = ha::harmonic_query(*model, features_at(0.503));
  EXPECT_NEAR(linear_end.x_m, 0.0, 0.003);
  EXPECT_NEAR(linear_end.y_m, 0.5, 1e-5);
  EXPECT_NEAR(linear_mid.x_m, 0.503, 0.003);
  EXPECT_NEAR(plain_mid.x_m, linear_mid.x_m, 0.003);
  // A strong ridge shrinks the correction back towards the kernel average.
  model->local_linear_ridge = 100.0F;
  const ha::HarmonicFix shrunk_end = ha::harmonic_query(*model, features_at(0.0));
  EXPECT_GT(shrunk_end.x_m, 0.5 * plain_end.x_m);
  // With a board masked (the robust fix), the correction uses the other one and stays finite.
  model->local_linear_ridge = 0.01F;
  ha::FeatureMask use{};
  use[0] = true;
  const ha::HarmonicFix masked_end = ha::harmonic_query(*model, features_at(0.0), use);
  EXPECT_NEAR(masked_end.x_m, 0.0, 0.003);
  // A degenerate neighbourhood (every sample the same features): the kernel average, finite.
  for (std::size_t i = 0; i < 101; ++i) model->sample(i)[0] = model->sample(i)[1] = 3.0F;
  const ha::HarmonicFix flat = ha::harmonic_query(*model, features_at(0.2));
  EXPECT_TRUE(std::isfinite(flat.x_m));
  EXPECT_NEAR(flat.x_m, 0.5, 1e-3);
}

// Two stretches of a route that show the same amounts of two boards, with the boards at other
// columns (a turn, or a board passed twice): areas alone cannot tell them apart, the centroid
// columns (map format 12) can. The known-place test still compares areas only, and a board
// left out takes its column with it.
TEST(HarmonicQuery, CentroidColumnsTellApartPlacesWithTheSameAreas) {
  auto model = std::make_unique<ha::HarmonicModel>();
  model->sample_count = 40;
  model->feature_count = 2;
  model->sigma_x = model->sigma_y = 50.0F;
  model->max_nearest_distance = 0.5F;
  model->max_dissimilarity = 1.0F;
  const auto areas_at = [](std::size_t i) {
    std::array<float, ha::HarmonicModel::kMaxFeatures> f{};
    const double s = static_cast<double>(i % 20) / 19.0;
    f[0] = static_cast<float>(2.0 + 3.0 * s);
    f[1] = static_cast<float>(4.0 - 2.0 * s);
    return f;
  };
  // Stretch A (samples 0..19, x = 0..1.9 m) sees both boards left of centre, stretch B (20..39,
  // x = 5..6.9 m) right of it.
  const auto columns_at = [&](std::size_t i) {
    const auto f = areas_at(i);
    ha::ColumnFeatures c{};
    const double u = i < 20 ? 0.2 : 0.8;
    for (std::size_t k = 0; k < 2; ++k) c[k] = ha::column_feature(u * 319.0, 320, f[k]);
    return c;
  };
  for (std::size_t i = 0; i < 40; ++i) {
    const auto f = areas_at(i);
    const auto c = columns_at(i);
    for (std::size_t k = 0; k < 2; ++k) {
      model->sample(i)[k] = f[k];
      model->sample_columns(i)[k] = c[k];
    }
    model->target_x_m[i] = static_cast<float>(i < 20 ? 0.1 * static_cast<double>(i)
                                                     : 5.0 + 0.1 * static_cast<double>(i - 20));
  }
  const auto q = areas_at(27);
  const auto qc = columns_at(27);
  // Without columns in the map (weight 0), or without the frame's: half way between the two.
  const ha::HarmonicFix areas_only = ha::harmonic_query(*model, q, &qc);
  EXPECT_NEAR(areas_only.x_m, 0.5 * (0.7 + 5.7), 0.01);
  model->column_weight = 1.0F;
  const ha::HarmonicFix blind = ha::harmonic_query(*model, q);
  EXPECT_NEAR(blind.x_m, areas_only.x_m, 1e-9);
  const ha::HarmonicFix fix = ha::harmonic_query(*model, q, &qc);
  EXPECT_NEAR(fix.x_m, 5.7, 0.01);
  EXPECT_TRUE(fix.known_place);
  // The known-place distance is over the areas: 0 here although the other stretch's columns
  // differ, and unchanged by the columns.
  EXPECT_NEAR(fix.nearest_distance, 0.0, 1e-6);
  EXPECT_EQ(fix.nearest_distance, areas_only.nearest_distance);
  // One board left out: its column goes with it, the other still tells B from A.
  ha::FeatureMask use{};
  use[0] = true;
  EXPECT_NEAR(ha::harmonic_query(*model, q, use, &qc).x_m, 5.7, 0.01);
  // A frame whose board 0 sits where stretch A saw it, board 1 where B did: with board 1 left
  // out, stretch A.
  ha::ColumnFeatures mixed = qc;
  mixed[0] = columns_at(7)[0];
  EXPECT_NEAR(ha::harmonic_query(*model, q, use, &mixed).x_m, 0.7, 0.01);
}

TEST(HarmonicModel, ColumnFeatures) {
  // (u - 0.5) sqrt(feature), u = centroid / (width - 1); 0 for a board not in view.
  EXPECT_FLOAT_EQ(ha::column_feature(0.0, 320, 4.0F), -1.0F);
  EXPECT_FLOAT_EQ(ha::column_feature(319.0, 320, 4.0F), 1.0F);
  EXPECT_FLOAT_EQ(ha::column_feature(159.5, 320, 9.0F), 0.0F);
  EXPECT_EQ(ha::column_feature(10.0, 320, 0.0F), 0.0F);
  EXPECT_EQ(ha::column_feature(10.0, 1, 4.0F), 0.0F);  // no width to place it in
  auto model = std::make_unique<ha::HarmonicModel>();
  model->feature_count = 2;
  model->board_index = {2, 0};
  model->area_scale = 100.0F / (320.0F * 240.0F);
  ha::AreaVector areas;
  areas.count = 3;
  areas.pixels = {768, 0, 3072, 0, 0, 0, 0, 0};
  areas.column_sum = {768ULL * 319ULL, 0, 0, 0, 0, 0, 0, 0};  // board 0 at the right edge
  std::array<float, ha::HarmonicModel::kMaxFeatures> f{};
  ha::areas_to_features(*model, areas, f);
  ha::ColumnFeatures c{};
  c.fill(7.0F);
  EXPECT_FALSE(ha::areas_to_columns(*model, areas, c)) << "columns not measured";
  for (float v : c) EXPECT_EQ(v, 0.0F);
  areas.width_px = 320;
  EXPECT_TRUE(ha::areas_to_columns(*model, areas, c));
  EXPECT_FLOAT_EQ(c[0], -1.0F);  // board 2: 4 %, at the left edge
  EXPECT_FLOAT_EQ(c[1], 0.5F);   // board 0: 1 %, at the right edge
}

TEST(HarmonicQuery, KnownPlaceFlag) {
  const Problem p = make_problem();
  auto model = std::make_unique<ha::HarmonicModel>();
  fill_model(*model, p, p.labels, p.labels);
  std::array<float, ha::HarmonicModel::kMaxFeatures> q{};
  // A training vector: distance 0, known, and the fix is close to its own target.
  q[0] = model->sample(7)[0];
  q[1] = model->sample(7)[1];
  ha::HarmonicFix fix = ha::harmonic_query(*model, q);
  EXPECT_TRUE(fix.known_place);
  EXPECT_NEAR(fix.nearest_distance, 0.0, 1e-6);
  // Far away (exp(-sigma d^2) underflows for every sample): flagged, and still a finite
  // estimate inside the range of the targets (weights relative to the nearest sample), not 0/0.
  for (const auto& far :
       {std::array<float, 2>{400.0F, 250.0F}, std::array<float, 2>{-300.0F, 90.0F}}) {
    q[0] = far[0];
    q[1] = far[1];
    fix = ha::harmonic_query(*model, q);
    EXPECT_FALSE(fix.known_place);
    ASSERT_TRUE(std::isfinite(fix.x_m));
    ASSERT_TRUE(std::isfinite(fix.y_m));
    EXPECT_GT(fix.nearest_distance, 100.0);
    EXPECT_GE(fix.x_m, p.labels.minCoeff() - 1e-6);
    EXPECT_LE(fix.x_m, p.labels.maxCoeff() + 1e-6);
  }
  // Just inside / just outside the bound (0.2) from sample 0 along a direction away from the rest.
  q[0] = model->sample(0)[0] - 0.15F;
  q[1] = model->sample(0)[1];
  EXPECT_TRUE(ha::harmonic_query(*model, q).known_place);
  q[0] = model->sample(0)[0] - 0.25F;
  EXPECT_FALSE(ha::harmonic_query(*model, q).known_place);
}

namespace {

// Two samples of two boards: one at the origin (no board visible, target 0), one showing the
// first board (target x 2 m).
std::unique_ptr<ha::HarmonicModel> two_sample_model() {
  auto model = std::make_unique<ha::HarmonicModel>();
  model->sample_count = 2;
  model->feature_count = 2;
  model->sigma_x = model->sigma_y = 1.0F;
  model->max_nearest_distance = 1.0F;
  model->area_scale = 1.0F;
  model->sample(1)[0] = 1.0F;
  model->target_x_m[1] = 2.0F;
  return model;
}

}  // namespace

TEST(HarmonicQuery, NoBoardSeenIsNotAKnownPlace) {
  // A black frame matches the sample at the origin exactly but must not count as a known place.
  const auto model = two_sample_model();
  std::array<float, ha::HarmonicModel::kMaxFeatures> q{};
  const ha::HarmonicFix fix = ha::harmonic_query(*model, q);
  EXPECT_FALSE(fix.known_place);
  EXPECT_FALSE(fix.board_seen);
  EXPECT_NEAR(fix.nearest_distance, 0.0, 1e-9);
  // Eq. 9 by hand: weights 1 and e^-1.
  EXPECT_NEAR(fix.x_m, 2.0 * std::exp(-1.0) / (1.0 + std::exp(-1.0)), 1e-6);
  q[0] = 1.0F;
  const ha::HarmonicFix seen = ha::harmonic_query(*model, q);
  EXPECT_TRUE(seen.board_seen);
  EXPECT_TRUE(seen.known_place);
}

TEST(HarmonicQuery, BoardSeenCountsTheBoardsTheQueryCompares) {
  // A frame showing only a board the query leaves out (masked) shows it none of its boards.
  const auto model = two_sample_model();
  model->sample(1)[1] = 1.0F;
  std::array<float, ha::HarmonicModel::kMaxFeatures> q{};
  q[1] = 1.0F;
  EXPECT_TRUE(ha::harmonic_query(*model, q).board_seen);
  ha::FeatureMask use{};
  use[0] = true;
  EXPECT_FALSE(ha::harmonic_query(*model, q, use).board_seen);
  q[0] = 0.5F;
  EXPECT_TRUE(ha::harmonic_query(*model, q, use).board_seen);
}

namespace {

// Three boards along a 2 m stretch (samples at x 0, 1, 2 m): boards 0 and 1 tell the places
// apart, board 2 grows fast along it (it enters the frame from the side).
std::unique_ptr<ha::HarmonicModel> cut_board_model() {
  auto model = std::make_unique<ha::HarmonicModel>();
  model->sample_count = 3;
  model->feature_count = 3;
  model->board_index = {0, 1, 2};
  model->sigma_x = model->sigma_y = 1.0F;
  model->max_nearest_distance = 100.0F;
  model->area_scale = 1.0F;
  const float board0[] = {1.0F, 2.0F, 3.0F}, board1[] = {3.0F, 2.0F, 1.0F};
  const float board2[] = {0.0F, 5.0F, 10.0F};
  for (std::size_t i = 0; i < 3; ++i) {
    model->sample(i)[0] = board0[i];
    model->sample(i)[1] = board1[i];
    model->sample(i)[2] = board2[i];
    model->target_x_m[i] = static_cast<float>(i);
  }
  return model;
}

// The three boards' features, and a frame's areas with them as pixel counts (nothing cut).
std::array<float, ha::HarmonicModel::kMaxFeatures> three_boards(float b0, float b1, float b2) {
  std::array<float, ha::HarmonicModel::kMaxFeatures> q{};
  q[0] = b0;
  q[1] = b1;
  q[2] = b2;
  return q;
}

ha::AreaVector areas_of(const std::array<float, ha::HarmonicModel::kMaxFeatures>& features) {
  ha::AreaVector a;
  a.count = 3;
  for (std::size_t b = 0; b < 3; ++b) a.pixels[b] = static_cast<std::uint32_t>(features[b]);
  return a;
}

}  // namespace

TEST(HarmonicQuery, UncutFeaturesLeaveOutCutBoardsWhileTwoOthersAreInView) {
  const auto model = cut_board_model();
  std::array<float, ha::HarmonicModel::kMaxFeatures> q = three_boards(1.0F, 3.0F, 4.0F);
  ha::AreaVector a = areas_of(q);
  ha::FeatureMask use{};
  EXPECT_FALSE(ha::uncut_features(*model, a, q, use)) << "no side pixels: nothing cut";
  EXPECT_TRUE(use[0] && use[1] && use[2]);

  a.side_pixels[2] = 7;
  EXPECT_TRUE(ha::uncut_features(*model, a, q, use));
  EXPECT_TRUE(use[0] && use[1]);
  EXPECT_FALSE(use[2]);

  // Two cut: one uncut board alone names every place at its distance; nothing is left out.
  a.side_pixels[1] = 3;
  EXPECT_FALSE(ha::uncut_features(*model, a, q, use));
  EXPECT_TRUE(use[0] && use[1] && use[2]);

  // A board the kernel does without (weight 0) is no second board in view.
  a.side_pixels[1] = 0;
  model->feature_weight[1] = 0.0F;
  EXPECT_FALSE(ha::uncut_features(*model, a, q, use));
  EXPECT_TRUE(use[2]);
  model->feature_weight[1] = 1.0F;

  // A board out of view is not cut, whatever its side count says.
  q[2] = 0.0F;
  EXPECT_FALSE(ha::uncut_features(*model, a, q, use));
  EXPECT_TRUE(use[2]);
}

TEST(HarmonicQuery, CutBoardDoesNotDragTheFix) {
  // At x = 0, board 2 half in view: a few degrees of heading more show as much of it as the
  // training run saw at x = 2 m. With it the fix goes there; without it, it stays at x = 0.
  const auto model = cut_board_model();
  std::array<float, ha::HarmonicModel::kMaxFeatures> q = three_boards(1.0F, 3.0F, 10.0F);
  ha::AreaVector a = areas_of(q);
  ha::FeatureMask use{};
  const ha::HarmonicFix uncut_frame = ha::harmonic_fix(*model, a, q, nullptr, use);
  EXPECT_GT(uncut_frame.x_m, 1.5) << "the board is not cut: the fix compares it";
  EXPECT_FALSE(uncut_frame.cut_board_left_out);
  a.side_pixels[2] = 10;
  const ha::HarmonicFix fix = ha::harmonic_fix(*model, a, q, nullptr, use);
  EXPECT_FALSE(use[2]);
  EXPECT_TRUE(fix.cut_board_left_out);
  EXPECT_LT(std::fabs(fix.x_m), 0.2);
  EXPECT_TRUE(fix.board_seen);
}

TEST(HarmonicQuery, EmptyModelGivesNoFix) {
  auto model = std::make_unique<ha::HarmonicModel>();
  std::array<float, ha::HarmonicModel::kMaxFeatures> q{};
  q[0] = 1.0F;
  const ha::HarmonicFix fix = ha::harmonic_query(*model, q);
  EXPECT_FALSE(fix.known_place);
  EXPECT_EQ(fix.x_m, 0.0);
}

TEST(HarmonicModel, AreasToFeaturesSelectsAndScales) {
  auto model = std::make_unique<ha::HarmonicModel>();
  model->feature_count = 3;
  model->board_index = {0, 1, 4};
  model->area_scale = 100.0F / (320.0F * 240.0F);
  ha::AreaVector areas;
  areas.count = 6;
  areas.pixels = {768, 1536, 99, 99, 7680, 99, 0, 0};
  std::array<float, ha::HarmonicModel::kMaxFeatures> f{};
  f.fill(5.0F);
  ha::areas_to_features(*model, areas, f);
  EXPECT_FLOAT_EQ(f[0], 1.0F);  // 768 px of 76800 = 1 %
  EXPECT_FLOAT_EQ(f[1], 2.0F);
  EXPECT_FLOAT_EQ(f[2], 10.0F);
  for (std::size_t k = 3; k < f.size(); ++k) EXPECT_EQ(f[k], 0.0F) << k;
  // A board index beyond the frame's board count reads as 0 pixels.
  areas.count = 2;
  ha::areas_to_features(*model, areas, f);
  EXPECT_EQ(f[2], 0.0F);
}

namespace {

// 1-D feature along a smooth curve, label a known smooth function of position: the fit needs a
// kernel neither much wider nor much narrower than the sample spacing.
Problem make_curve(int m, int every) {
  Problem p;
  p.features.resize(m, 1);
  p.labels.resize(m);
  p.labelled.assign(static_cast<std::size_t>(m), false);
  for (int i = 0; i < m; ++i) {
    const double s = static_cast<double>(i) / (m - 1);  // position along the route, 0..1
    p.features(i, 0) = 10.0 * s + 2.0 * s * s;          // area grows smoothly with position
    p.labels(i) = 1.5 * std::sin(3.0 * s) + 0.5 * s;    // the coordinate, metres
    p.labelled[static_cast<std::size_t>(i)] = (i % every) == 0;
  }
  return p;
}

// The documented cross-validation with one fold per labelled sample (leave-one-out: the fold
// assignment is then unambiguous), built from reference_solve and reference_eq9.
double reference_loo_mse(const Problem& p, double sigma, double gamma) {
  const Eigen::Index m = p.features.rows();
  double sq = 0.0;
  int n = 0;
  for (Eigen::Index held = 0; held < m; ++held) {
    if (!p.labelled[static_cast<std::size_t>(held)]) continue;
    Eigen::MatrixXd o(m - 1, p.features.cols());
    Eigen::VectorXd c(m - 1);
    std::vector<bool> mask;
    for (Eigen::Index i = 0, r = 0; i < m; ++i) {
      if (i == held) continue;
      o.row(r) = p.features.row(i);
      c(r) = p.labels(i);
      mask.push_back(p.labelled[static_cast<std::size_t>(i)]);
      ++r;
    }
    const Eigen::VectorXd f = reference_solve(o, mask, c, sigma, gamma);
    const double e = reference_eq9(o, f, sigma, p.features.row(held)) - p.labels(held);
    sq += e * e;
    ++n;
  }
  return sq / n;
}

}  // namespace

TEST(ChooseAxisParameters, PicksFromTheGivenGridAndMatchesReferenceCrossValidation) {
  const Problem p = make_curve(40, 5);  // 8 labelled
  ha::CrossValidationOptions options;
  options.folds = 8;  // = labelled count: leave-one-out
  options.sigma_grid = {0.02, 0.3, 3.0};
  options.gamma_grid = {0.003, 0.03};
  const ha::AxisChoice choice =
      ha::choose_axis_parameters(p.features, p.labelled, p.labels, options);

  double best = std::numeric_limits<double>::infinity(), best_sigma = 0.0, best_gamma = 0.0;
  for (double s : options.sigma_grid) {
    for (double g : options.gamma_grid) {
      const double mse = reference_loo_mse(p, s, g);
      if (mse < best) {
        best = mse;
        best_sigma = s;
        best_gamma = g;
      }
    }
  }
  EXPECT_EQ(choice.sigma, best_sigma);
  EXPECT_EQ(choice.gamma, best_gamma);
  EXPECT_NEAR(choice.cv_mse, best, 1e-9 + 1e-6 * best);
}

TEST(ChooseAxisParameters, DefaultGridChoosesAnInteriorSigmaWithSmallError) {
  const Problem p = make_curve(60, 4);  // 15 labelled
  ha::CrossValidationOptions options;
  const ha::AxisChoice choice =
      ha::choose_axis_parameters(p.features, p.labelled, p.labels, options);
  // The default grid is base * 2^e, e = -2..12, base = 1 / median ||O_i - O_j||^2.
  const double base = 1.0 / ha::median_squared_distance(p.features);
  const double e = std::log2(choice.sigma / base);
  EXPECT_NEAR(e, std::round(e), 1e-9);
  EXPECT_GT(e, -2.0 + 0.5) << "sigma at the wide edge of the grid: " << choice.sigma;
  EXPECT_LT(e, 12.0 - 0.5) << "sigma at the narrow edge of the grid: " << choice.sigma;
  const std::vector<double> gammas = {0.001, 0.003, 0.01, 0.03, 0.1};
  EXPECT_NE(std::find(gammas.begin(), gammas.end(), choice.gamma), gammas.end());
  // Label variance is ~0.3 m^2; a good fit of this smooth curve is far below that.
  const double mean = p.labels.mean();
  const double var = (p.labels.array() - mean).square().mean();
  EXPECT_LT(choice.cv_mse, 0.1 * var) << "cv mse " << choice.cv_mse << " label variance " << var;
  EXPECT_GT(choice.cv_mse, 0.0);
}

TEST(ChooseAxisParameters, RejectsTooFewLabels) {
  Problem p = make_curve(20, 100);  // only sample 0 labelled
  EXPECT_THROW(
      ha::choose_axis_parameters(p.features, p.labelled, p.labels, ha::CrossValidationOptions{}),
      std::invalid_argument);
}
