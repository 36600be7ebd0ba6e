// Training on the neighbour graph (algorithms/harmonic_selection.hpp): the solve against a dense
// reference built from the definitions, the harmonic property, cross-validation on a problem
// whose best kernel width is known, board selection dropping a feature that is pure noise, and
// the Bray-Curtis known-place test of the online query.
// GCC 12 reports null dereferences inside Eigen's reductions and std::vector<bool> once the
// reference loops below are inlined; they are false positives (the vectors are never empty).
#pragma GCC diagnostic ignored "-Wnull-dereference"

#include "harmoloc/algorithms/harmonic_selection.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "harmoloc/algorithms/harmonic_localizer.hpp"
#include "harmoloc/algorithms/random.hpp"

namespace ha = harmoloc::algorithms;

namespace {

// A route: m samples along a smooth curve in a 3-D area space, coordinates (x, y) along it.
struct Route {
  Eigen::MatrixXd features;
  Eigen::MatrixXd xy;
  std::vector<bool> labelled;
};

Route make_route(int m, int every, double noise, std::uint64_t seed = 7) {
  Route r;
  r.features.resize(m, 3);
  r.xy.resize(m, 2);
  r.labelled.assign(static_cast<std::size_t>(m), false);
  ha::Pcg32 rng(seed);
  for (int i = 0; i < m; ++i) {
    const double t = static_cast<double>(i) / (m - 1);
    r.features(i, 0) = 1.0 + 2.0 * t + noise * rng.normal();
    r.features(i, 1) = 3.0 - 1.5 * t * t + noise * rng.normal();
    r.features(i, 2) = 0.5 + std::sin(3.0 * t) + noise * rng.normal();
    r.xy(i, 0) = 2.0 + 0.3 * std::sin(2.0 * t);
    r.xy(i, 1) = 0.4 + 1.2 * t;
    r.labelled[static_cast<std::size_t>(i)] = (i % every) == 0;
  }
  return r;
}

}  // namespace

TEST(NeighbourGraph, MatchesDenseReferenceAndIsHarmonic) {
  const Route r = make_route(40, 5, 0.01);
  const int k = 4;
  const double gamma = 0.05;
  const Eigen::MatrixXd f = ha::solve_on_neighbour_graph(r.features, r.labelled, r.xy, k, gamma);

  // Reference from the definitions: neighbours by brute force, symmetrised, self-tuning weights,
  // a minimum spanning tree added, L = D - W, dense solve of (P + gamma L) f = C.
  const Eigen::Index m = r.features.rows();
  Eigen::MatrixXd d2(m, m);
  for (Eigen::Index i = 0; i < m; ++i)
    for (Eigen::Index j = 0; j < m; ++j)
      d2(i, j) = (r.features.row(i) - r.features.row(j)).squaredNorm();
  std::vector<double> scale(static_cast<std::size_t>(m));
  Eigen::MatrixXi edge = Eigen::MatrixXi::Zero(m, m);
  for (Eigen::Index i = 0; i < m; ++i) {
    std::vector<std::pair<double, Eigen::Index>> order;
    for (Eigen::Index j = 0; j < m; ++j)
      if (j != i) order.emplace_back(d2(i, j), j);
    std::sort(order.begin(), order.end());
    scale[static_cast<std::size_t>(i)] = std::sqrt(order[k - 1].first) + 1e-6;
    for (int n = 0; n < k; ++n)
      edge(i, order[static_cast<std::size_t>(n)].second) =
          edge(order[static_cast<std::size_t>(n)].second, i) = 1;
  }
  {  // Prim
    std::vector<bool> in(static_cast<std::size_t>(m), false);
    in[0] = true;
    for (Eigen::Index added = 1; added < m; ++added) {
      double best = 1e300;
      Eigen::Index bi = 0, bj = 0;
      for (Eigen::Index i = 0; i < m; ++i)
        for (Eigen::Index j = 0; j < m; ++j)
          if (in[static_cast<std::size_t>(i)] && !in[static_cast<std::size_t>(j)] &&
              d2(i, j) < best) {
            best = d2(i, j);
            bi = i;
            bj = j;
          }
      in[static_cast<std::size_t>(bj)] = true;
      edge(bi, bj) = edge(bj, bi) = 1;
    }
  }
  Eigen::MatrixXd w = Eigen::MatrixXd::Zero(m, m);
  for (Eigen::Index i = 0; i < m; ++i)
    for (Eigen::Index j = 0; j < m; ++j)
      if (edge(i, j) != 0)
        w(i, j) = std::max(1e-6, std::exp(-d2(i, j) / (scale[static_cast<std::size_t>(i)] *
                                                       scale[static_cast<std::size_t>(j)])));
  Eigen::MatrixXd a = gamma * (Eigen::MatrixXd(w.rowwise().sum().asDiagonal()) - w);
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(m, 2);
  for (Eigen::Index i = 0; i < m; ++i) {
    if (r.labelled[static_cast<std::size_t>(i)]) {
      a(i, i) += 1.0;
      c.row(i) = r.xy.row(i);
    }
  }
  const Eigen::MatrixXd ref = a.fullPivLu().solve(c);
  EXPECT_LT((f - ref).cwiseAbs().maxCoeff(), 1e-9);

  // Harmonic: every unlabelled value is the weighted mean of its neighbours'.
  for (Eigen::Index i = 0; i < m; ++i) {
    if (r.labelled[static_cast<std::size_t>(i)]) continue;
    const Eigen::RowVectorXd mean = (w.row(i) * f) / w.row(i).sum();
    EXPECT_LT((mean - f.row(i)).cwiseAbs().maxCoeff(), 1e-9) << i;
  }
}

TEST(NeighbourGraph, PropagatesLabelsAlongTheRoute) {
  // One label in eight: the unlabelled samples' coordinates follow the route closely, which the
  // complete graph with the normalised Laplacian does not (the reason for this graph).
  const Route r = make_route(120, 8, 0.005);
  const Eigen::MatrixXd f = ha::solve_on_neighbour_graph(r.features, r.labelled, r.xy, 6, 0.01);
  double worst = 0.0;
  // Between the first and the last label: a harmonic function does not extrapolate.
  for (Eigen::Index i = 0; i <= 112; ++i) worst = std::max(worst, (f.row(i) - r.xy.row(i)).norm());
  EXPECT_LT(worst, 0.02) << "worst unlabelled coordinate error " << worst << " m";
}

TEST(NeighbourGraph, SurvivesIdenticalSamplesAndRejectsBadInput) {
  Route r = make_route(30, 3, 0.0);
  for (int i = 1; i < 6; ++i) r.features.row(i) = r.features.row(0);  // the robot stood still
  const Eigen::MatrixXd f = ha::solve_on_neighbour_graph(r.features, r.labelled, r.xy, 4, 0.01);
  EXPECT_TRUE(f.allFinite());
  std::vector<bool> none(r.labelled.size(), false);
  EXPECT_THROW(ha::solve_on_neighbour_graph(r.features, none, r.xy, 4, 0.01),
               std::invalid_argument);
  EXPECT_THROW(ha::solve_on_neighbour_graph(r.features, r.labelled, r.xy, 0, 0.01),
               std::invalid_argument);
  std::vector<bool> short_mask(5, true);
  EXPECT_THROW(ha::solve_on_neighbour_graph(r.features, short_mask, r.xy, 4, 0.01),
               std::invalid_argument);
}

// Cross-validation against a reference written here from its definition: interleaved folds over
// the labels, each fold's labels out of the training set, solve, predict with eq. 9.
TEST(NeighbourSelection, CrossValidationMatchesReferenceAndFindsAnInteriorSigma) {
  const Route r = make_route(90, 3, 0.01);
  ha::SelectionOptions o;
  o.folds = 5;
  o.neighbours = {4, 6};
  o.gammas = {0.01, 0.1};
  o.sigma_exponent_min = 0;
  o.sigma_exponent_max = 14;
  const auto got = ha::cross_validate_neighbour_model(r.features, r.labelled, r.xy, {0, 1, 2}, o);

  const Eigen::Index m = r.features.rows();
  std::vector<int> labels;
  for (Eigen::Index i = 0; i < m; ++i)
    if (r.labelled[static_cast<std::size_t>(i)]) labels.push_back(static_cast<int>(i));
  std::vector<double> pairs;
  for (Eigen::Index i = 0; i < m; ++i)
    for (Eigen::Index j = i + 1; j < m; ++j)
      pairs.push_back((r.features.row(i) - r.features.row(j)).squaredNorm());
  std::nth_element(pairs.begin(), pairs.begin() + static_cast<std::ptrdiff_t>(pairs.size() / 2),
                   pairs.end());
  const double median = pairs[pairs.size() / 2];
  double best[2] = {1e300, 1e300}, best_sigma[2] = {0, 0};
  for (int k : o.neighbours) {
    for (double g : o.gammas) {
      for (int e = 0; e <= 14; ++e) {
        const double sigma = std::ldexp(1.0, e) / median;
        double se[2] = {0, 0};
        for (int fold = 0; fold < o.folds; ++fold) {
          std::vector<int> keep, held;
          for (Eigen::Index i = 0; i < m; ++i) {
            const auto at = std::find(labels.begin(), labels.end(), static_cast<int>(i));
            const bool out = at != labels.end() && (at - labels.begin()) % o.folds == fold;
            (out ? held : keep).push_back(static_cast<int>(i));
          }
          Eigen::MatrixXd f(static_cast<Eigen::Index>(keep.size()), 3);
          Eigen::MatrixXd c(static_cast<Eigen::Index>(keep.size()), 2);
          std::vector<bool> l;
          for (std::size_t a = 0; a < keep.size(); ++a) {
            f.row(static_cast<Eigen::Index>(a)) = r.features.row(keep[a]);
            c.row(static_cast<Eigen::Index>(a)) = r.xy.row(keep[a]);
            l.push_back(r.labelled[static_cast<std::size_t>(keep[a])]);
          }
          const Eigen::MatrixXd sol = ha::solve_on_neighbour_graph(f, l, c, k, g);
          for (int h : held) {
            Eigen::VectorXd d2(f.rows());
            for (Eigen::Index a = 0; a < f.rows(); ++a)
              d2(a) = (f.row(a) - r.features.row(h)).squaredNorm();
            const Eigen::ArrayXd w = (-sigma * (d2.array() - d2.minCoeff())).exp();
            for (int axis = 0; axis < 2; ++axis) {
              const double p = (w * sol.col(axis).array()).sum() / w.sum();
              se[axis] += (p - r.xy(h, axis)) * (p - r.xy(h, axis));
            }
          }
        }
        for (int axis = 0; axis < 2; ++axis) {
          const double mse = se[axis] / static_cast<double>(labels.size());
          if (mse < best[axis]) {
            best[axis] = mse;
            best_sigma[axis] = sigma;
          }
        }
      }
    }
  }
  EXPECT_NEAR(got.first.cv_mse, best[0], 1e-12 + 1e-9 * best[0]);
  EXPECT_NEAR(got.second.cv_mse, best[1], 1e-12 + 1e-9 * best[1]);
  // The median is computed another way here: equal to the last few bits.
  EXPECT_NEAR(got.first.sigma, best_sigma[0], 1e-9 * best_sigma[0]);
  EXPECT_NEAR(got.second.sigma, best_sigma[1], 1e-9 * best_sigma[1]);
  // A smooth route sampled densely: the best kernel is neither the widest nor the narrowest.
  for (double s : {got.first.sigma, got.second.sigma}) {
    const double e = std::log2(s * median);
    EXPECT_GT(e, 0.5);
    EXPECT_LT(e, 13.5);
  }
}

TEST(NeighbourSelection, DropsANoiseBoardAndKeepsTheGoodOnes) {
  Route r = make_route(200, 3, 0.002);
  Eigen::MatrixXd with_noise(r.features.rows(), 5);
  ha::Pcg32 rng(3);
  with_noise.leftCols(3) = r.features;
  for (Eigen::Index i = 0; i < with_noise.rows(); ++i) {
    with_noise(i, 3) = 2.0 * rng.uniform(0.0, 1.0);  // a board that flickers at random
    with_noise(i, 4) = 1.25;                         // a board whose area never changes
  }
  const ha::ModelSelection s =
      ha::select_neighbour_model(with_noise, r.labelled, r.xy, ha::SelectionOptions{});
  EXPECT_EQ(s.columns, (std::vector<int>{0, 1, 2}));
  ASSERT_GE(s.steps.size(), 2U);
  EXPECT_EQ(s.steps.front().columns, (std::vector<int>{0, 1, 2, 3}));  // constant one left out
  EXPECT_EQ(s.steps[1].dropped, 3);
  EXPECT_LT(s.steps[1].cv_mse_x + s.steps[1].cv_mse_y, s.steps[0].cv_mse_x + s.steps[0].cv_mse_y);

  ha::SelectionOptions keep_all;
  keep_all.select_features = false;
  EXPECT_EQ(ha::select_neighbour_model(with_noise, r.labelled, r.xy, keep_all).columns,
            (std::vector<int>{0, 1, 2, 3}));
  // Never below min_boards (a fix from fewer cannot be checked for a moved board).
  ha::SelectionOptions four;
  four.min_boards = 4;
  EXPECT_EQ(ha::select_neighbour_model(with_noise, r.labelled, r.xy, four).columns,
            (std::vector<int>{0, 1, 2, 3}));
}

TEST(NeighbourSelection, Deterministic) {
  const Route r = make_route(150, 4, 0.01);
  const auto a = ha::select_neighbour_model(r.features, r.labelled, r.xy, ha::SelectionOptions{});
  const auto b = ha::select_neighbour_model(r.features, r.labelled, r.xy, ha::SelectionOptions{});
  EXPECT_EQ(a.columns, b.columns);
  EXPECT_EQ(a.x.sigma, b.x.sigma);
  EXPECT_EQ(a.y.cv_mse, b.y.cv_mse);
}

TEST(KnownPlace, BrayCurtisDissimilarityToTheNearestSample) {
  auto model = std::make_unique<ha::HarmonicModel>();
  model->sample_count = 2;
  model->feature_count = 2;
  model->sigma_x = model->sigma_y = 1.0F;
  model->max_nearest_distance = 100.0F;
  model->max_dissimilarity = 0.1F;
  model->sample(0)[0] = 2.0F;
  model->sample(0)[1] = 2.0F;
  model->sample(1)[0] = 10.0F;
  model->sample(1)[1] = 0.0F;
  std::array<float, ha::HarmonicModel::kMaxFeatures> q{};
  q[0] = 2.2F;
  q[1] = 1.9F;  // nearest is sample 0: (|0.2| + |0.1|) / (2.2 + 1.9 + 2 + 2)
  ha::HarmonicFix fix = ha::harmonic_query(*model, q);
  EXPECT_NEAR(fix.dissimilarity, 0.3 / 8.1, 1e-6);
  EXPECT_TRUE(fix.known_place);
  q[0] = 3.0F;
  q[1] = 1.0F;  // 2 / 8 = 0.25 > 0.1: close in distance (1.41 < 100) but unlike the sample
  fix = ha::harmonic_query(*model, q);
  EXPECT_NEAR(fix.dissimilarity, 0.25, 1e-6);
  EXPECT_FALSE(fix.known_place);
  model->max_dissimilarity = 1.0F;  // a version 1 map: no dissimilarity test
  EXPECT_TRUE(ha::harmonic_query(*model, q).known_place);
}
