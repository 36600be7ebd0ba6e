#include "harmoloc/algorithms/harmonic_selection.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

#include <Eigen/Sparse>

#include "column_selection.hpp"
#include "harmoloc/algorithms/harmonic_training.hpp"

namespace harmoloc::algorithms {

namespace {

// Each row's nearest other rows, closest first (at most @p count).
std::vector<std::vector<int>> nearest_rows(const Eigen::MatrixXd& d2, int count) {
  const auto m = static_cast<int>(d2.rows());
  const int k = std::min(count, m - 1);
  std::vector<std::vector<int>> out(static_cast<std::size_t>(m));
  std::vector<int> order(static_cast<std::size_t>(m));
  for (int i = 0; i < m; ++i) {
    std::iota(order.begin(), order.end(), 0);
    std::swap(order[static_cast<std::size_t>(i)], order.back());  // not its own neighbour
    const double* row = d2.data() + i * m;  // symmetric: column i is row i, contiguous
    const auto by_distance = [row](int a, int b) {
      return row[a] < row[b] || (row[a] == row[b] && a < b);
    };
    // Select, then sort only the k chosen: linear in m rather than m log k.
    if (k > 0 && k < m - 1)
      std::nth_element(order.begin(), order.begin() + k, order.end() - 1, by_distance);
    std::sort(order.begin(), order.begin() + k, by_distance);
    out[static_cast<std::size_t>(i)].assign(order.begin(), order.begin() + k);
  }
  return out;
}

// Edges of a minimum spanning tree of the complete graph (Prim, O(m^2)): added to the
// neighbour graph so it is always connected, so that every unlabelled sample is reached by some
// label even where the route leaves a gap in area space.
std::vector<std::pair<int, int>> spanning_tree(const Eigen::MatrixXd& d2) {
  const auto m = static_cast<int>(d2.rows());
  std::vector<std::pair<int, int>> edges;
  if (m < 2) return edges;
  // The rows not yet in the tree, packed at the front of `rest`, with their best distance to it.
  std::vector<int> rest(static_cast<std::size_t>(m - 1)), from(static_cast<std::size_t>(m), 0);
  std::vector<double> best(static_cast<std::size_t>(m), std::numeric_limits<double>::infinity());
  std::iota(rest.begin(), rest.end(), 1);
  int current = 0;
  for (std::size_t left = rest.size(); left > 0; --left) {
    const double* column = d2.data() + static_cast<std::ptrdiff_t>(current) * m;  // symmetric
    std::size_t pick = 0;
    for (std::size_t r = 0; r < left; ++r) {
      const auto j = static_cast<std::size_t>(rest[r]);
      if (column[j] < best[j]) {
        best[j] = column[j];
        from[j] = current;
      }
      if (best[j] < best[static_cast<std::size_t>(rest[pick])]) pick = r;
    }
    const int next = rest[pick];
    rest[pick] = rest[left - 1];
    edges.emplace_back(std::min(next, from[static_cast<std::size_t>(next)]),
                       std::max(next, from[static_cast<std::size_t>(next)]));
    current = next;
  }
  return edges;
}

// (P + gamma L) F = C on the union of the k-nearest-neighbour graph (first k of each list) and
// the spanning tree, for each gamma: one graph, one symbolic analysis, one factorisation each.
std::vector<Eigen::MatrixXd> solve_graph(const Eigen::MatrixXd& d2,
                                         const std::vector<std::vector<int>>& nearest,
                                         const std::vector<std::pair<int, int>>& tree, int k,
                                         const std::vector<bool>& labelled,
                                         const Eigen::MatrixXd& labels,
                                         const std::vector<double>& gammas) {
  const auto m = static_cast<Eigen::Index>(d2.rows());
  std::vector<double> scale(static_cast<std::size_t>(m));
  std::vector<std::pair<int, int>> edges = tree;
  for (Eigen::Index i = 0; i < m; ++i) {
    const auto& nn = nearest[static_cast<std::size_t>(i)];
    const int kk = std::min<int>(k, static_cast<int>(nn.size()));
    scale[static_cast<std::size_t>(i)] =
        kk > 0 ? std::sqrt(d2(i, nn[static_cast<std::size_t>(kk - 1)])) + 1e-6 : 1.0;
    for (int n = 0; n < kk; ++n) {
      const int j = nn[static_cast<std::size_t>(n)];
      edges.emplace_back(std::min<int>(static_cast<int>(i), j),
                         std::max<int>(static_cast<int>(i), j));
    }
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());

  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(2 * edges.size() + static_cast<std::size_t>(m));
  Eigen::VectorXd degree = Eigen::VectorXd::Zero(m);
  for (const auto& [i, j] : edges) {
    // Floored: a robot standing still gives identical samples (scale 0), and the graph must
    // stay connected in floating point too.
    const double w = std::max(1e-6, std::exp(-d2(i, j) / (scale[static_cast<std::size_t>(i)] *
                                                          scale[static_cast<std::size_t>(j)])));
    entries.emplace_back(i, j, -w);
    entries.emplace_back(j, i, -w);
    degree(i) += w;
    degree(j) += w;
  }
  for (Eigen::Index i = 0; i < m; ++i) entries.emplace_back(i, i, degree(i));
  Eigen::SparseMatrix<double> laplacian(m, m);
  laplacian.setFromTriplets(entries.begin(), entries.end());
  Eigen::VectorXd p = Eigen::VectorXd::Zero(m);
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(m, labels.cols());
  for (Eigen::Index i = 0; i < m; ++i) {
    if (labelled[static_cast<std::size_t>(i)]) {
      p(i) = 1.0;
      rhs.row(i) = labels.row(i);
    }
  }
  // Symmetric positive definite: the graph is connected and at least one sample is labelled.
  // Every diagonal entry is stored (the degrees), so P + gamma L keeps L's pattern.
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver;
  Eigen::SparseMatrix<double> a = laplacian;
  solver.analyzePattern(a);
  std::vector<Eigen::MatrixXd> out;
  for (double gamma : gammas) {
    a = laplacian * gamma;
    a.diagonal() += p;
    solver.factorize(a);
    Eigen::MatrixXd f = solver.solve(rhs);
    if (solver.info() != Eigen::Success || !f.allFinite())
      throw std::runtime_error("the training graph could not be solved (duplicate samples?)");
    out.push_back(std::move(f));
  }
  return out;
}

Eigen::MatrixXd select_columns(const Eigen::MatrixXd& m, const std::vector<int>& columns) {
  Eigen::MatrixXd out(m.rows(), static_cast<Eigen::Index>(columns.size()));
  for (std::size_t c = 0; c < columns.size(); ++c)
    out.col(static_cast<Eigen::Index>(c)) = m.col(columns[c]);
  return out;
}

}  // namespace

Eigen::MatrixXd solve_on_neighbour_graph(const Eigen::MatrixXd& features,
                                         const std::vector<bool>& labelled,
                                         const Eigen::MatrixXd& labels, int neighbours,
                                         double gamma) {
  const Eigen::Index m = features.rows();
  if (static_cast<Eigen::Index>(labelled.size()) != m || labels.rows() != m || m < 2) {
    throw std::invalid_argument("solve_on_neighbour_graph: sizes differ or fewer than 2 samples");
  }
  if (std::none_of(labelled.begin(), labelled.end(), [](bool b) { return b; }))
    throw std::invalid_argument("solve_on_neighbour_graph: no labelled sample");
  if (neighbours < 1 || !(gamma > 0.0))
    throw std::invalid_argument("solve_on_neighbour_graph: neighbours >= 1 and gamma > 0 needed");
  const Eigen::MatrixXd d2 = squared_distances(features, features);
  return solve_graph(d2, nearest_rows(d2, neighbours), spanning_tree(d2), neighbours, labelled,
                     labels, {gamma})
      .front();
}

std::pair<NeighbourAxisChoice, NeighbourAxisChoice> cross_validate_neighbour_model(
    const Eigen::MatrixXd& all_features, const std::vector<bool>& labelled,
    const Eigen::MatrixXd& labels_xy, const std::vector<int>& columns,
    const SelectionOptions& options) {
  const Eigen::MatrixXd features = select_columns(all_features, columns);
  const Eigen::Index m = features.rows();
  std::vector<int> labelled_rows;
  for (std::size_t i = 0; i < labelled.size(); ++i) {
    if (labelled[i]) labelled_rows.push_back(static_cast<int>(i));
  }
  if (labelled_rows.size() < 4) throw std::invalid_argument("cross-validation needs 4 labels");
  const int folds = std::max(2, std::min(options.folds, static_cast<int>(labelled_rows.size())));
  const Eigen::MatrixXd d2_all = squared_distances(features, features);
  const double median = median_off_diagonal(d2_all);
  std::vector<double> sigmas;
  for (int e = options.sigma_exponent_min;
       e <= std::max(options.sigma_exponent_min, options.sigma_exponent_max); ++e) {
    sigmas.push_back(std::ldexp(1.0, e) / median);
  }
  const int max_k = *std::max_element(options.neighbours.begin(), options.neighbours.end());

  // errors[k][gamma][sigma][axis]
  const std::size_t nk = options.neighbours.size(), ng = options.gammas.size(), ns = sigmas.size();
  std::vector<double> sq_error(nk * ng * ns * 2, 0.0);

  // Every row's nearest rows over the whole set, once: a fold's lists are these with its
  // removed rows skipped. Enough are kept for the largest fold's removals.
  std::size_t most_removed = 0;
  for (int fold = 0; fold < folds; ++fold) {
    const std::size_t held = (labelled_rows.size() + static_cast<std::size_t>(folds - 1 - fold)) /
                             static_cast<std::size_t>(folds);
    most_removed = std::max(most_removed, held * static_cast<std::size_t>(2 * options.gap + 1));
  }
  const auto global_nearest =
      nearest_rows(d2_all, max_k + static_cast<int>(std::min<std::size_t>(most_removed, m)));
  std::size_t count = 0;
  for (int fold = 0; fold < folds; ++fold) {
    // Interleaved folds: labels come in route order, so every fold spans the route.
    std::vector<bool> held_mask(static_cast<std::size_t>(m), false);
    std::vector<bool> out_mask(static_cast<std::size_t>(m), false);
    for (std::size_t k = 0; k < labelled_rows.size(); ++k) {
      if (static_cast<int>(k) % folds == fold) {
        held_mask[static_cast<std::size_t>(labelled_rows[k])] = true;
        out_mask[static_cast<std::size_t>(labelled_rows[k])] = true;
      }
    }
    for (Eigen::Index i = 0; i < m; ++i) {
      if (!held_mask[static_cast<std::size_t>(i)]) continue;
      for (Eigen::Index j = std::max<Eigen::Index>(0, i - options.gap);
           j <= std::min<Eigen::Index>(m - 1, i + options.gap); ++j) {
        out_mask[static_cast<std::size_t>(j)] = true;
      }
    }
    std::vector<int> keep, held;
    for (Eigen::Index i = 0; i < m; ++i) {
      if (held_mask[static_cast<std::size_t>(i)]) {
        held.push_back(static_cast<int>(i));
      } else if (!out_mask[static_cast<std::size_t>(i)]) {
        keep.push_back(static_cast<int>(i));
      }
    }
    const auto mk = static_cast<Eigen::Index>(keep.size());
    Eigen::MatrixXd d2(mk, mk);
    Eigen::MatrixXd keep_labels(mk, 2);
    std::vector<bool> keep_labelled(keep.size());
    for (Eigen::Index a = 0; a < mk; ++a) {
      for (Eigen::Index b = 0; b < mk; ++b) d2(a, b) = d2_all(keep[a], keep[b]);
      keep_labels.row(a) = labels_xy.row(keep[a]);
      keep_labelled[static_cast<std::size_t>(a)] = labelled[static_cast<std::size_t>(keep[a])];
    }
    // Held-out queries' distances to the kept samples, relative to each query's nearest (the
    // firmware's exp(-sigma (d^2 - d_min^2))).
    Eigen::MatrixXd excess(static_cast<Eigen::Index>(held.size()), mk);
    for (std::size_t h = 0; h < held.size(); ++h) {
      for (Eigen::Index b = 0; b < mk; ++b)
        excess(static_cast<Eigen::Index>(h), b) = d2_all(held[h], keep[b]);
      excess.row(static_cast<Eigen::Index>(h)).array() -=
          excess.row(static_cast<Eigen::Index>(h)).minCoeff();
    }
    // sigma doubles from one grid step to the next, so each step's weights are the previous
    // step's squared: one exp per distance for the whole grid.
    std::vector<Eigen::MatrixXd> weights;
    weights.push_back((-sigmas.front() * excess).array().exp().matrix());
    for (std::size_t si = 1; si < sigmas.size(); ++si)
      weights.push_back(weights.back().cwiseProduct(weights.back()));
    std::vector<int> position(static_cast<std::size_t>(m), -1);  // row -> index in keep
    for (std::size_t a = 0; a < keep.size(); ++a)
      position[static_cast<std::size_t>(keep[a])] = static_cast<int>(a);
    std::vector<std::vector<int>> nearest(keep.size());
    for (std::size_t a = 0; a < keep.size(); ++a) {
      for (int j : global_nearest[static_cast<std::size_t>(keep[a])]) {
        if (static_cast<int>(nearest[a].size()) == max_k) break;
        if (position[static_cast<std::size_t>(j)] >= 0)
          nearest[a].push_back(position[static_cast<std::size_t>(j)]);
      }
    }
    const auto tree = spanning_tree(d2);
    // Every (k, gamma) solution side by side: one product per sigma predicts them all.
    Eigen::MatrixXd solutions(mk, static_cast<Eigen::Index>(nk * ng * 2));
    for (std::size_t ki = 0; ki < nk; ++ki) {
      const std::vector<Eigen::MatrixXd> solved = solve_graph(
          d2, nearest, tree, options.neighbours[ki], keep_labelled, keep_labels, options.gammas);
      for (std::size_t gi = 0; gi < ng; ++gi)
        solutions.middleCols(static_cast<Eigen::Index>((ki * ng + gi) * 2), 2) = solved[gi];
    }
    for (std::size_t si = 0; si < ns; ++si) {
      const Eigen::MatrixXd p =
          (weights[si] * solutions).array().colwise() / weights[si].rowwise().sum().array();
      for (std::size_t c = 0; c < nk * ng; ++c) {
        for (std::size_t h = 0; h < held.size(); ++h) {
          for (int axis = 0; axis < 2; ++axis) {
            const double e =
                p(static_cast<Eigen::Index>(h), static_cast<Eigen::Index>(c * 2) + axis) -
                labels_xy(held[h], axis);
            sq_error[(c * ns + si) * 2 + static_cast<std::size_t>(axis)] += e * e;
          }
        }
      }
    }
    count += held.size();
  }
  std::pair<NeighbourAxisChoice, NeighbourAxisChoice> best;
  best.first.cv_mse = best.second.cv_mse = std::numeric_limits<double>::infinity();
  for (std::size_t ki = 0; ki < nk; ++ki) {
    for (std::size_t gi = 0; gi < ng; ++gi) {
      for (std::size_t si = 0; si < ns; ++si) {
        for (int axis = 0; axis < 2; ++axis) {
          const double mse =
              sq_error[((ki * ng + gi) * ns + si) * 2 + static_cast<std::size_t>(axis)] /
              static_cast<double>(count);
          NeighbourAxisChoice& b = axis == 0 ? best.first : best.second;
          if (std::isfinite(mse) && mse < b.cv_mse)
            b = NeighbourAxisChoice{options.neighbours[ki], options.gammas[gi], sigmas[si], mse};
        }
      }
    }
  }
  if (!std::isfinite(best.first.cv_mse) || !std::isfinite(best.second.cv_mse))
    throw std::runtime_error("cross-validation found no usable parameters");
  return best;
}

ModelSelection select_neighbour_model(const Eigen::MatrixXd& features,
                                      const std::vector<bool>& labelled,
                                      const Eigen::MatrixXd& labels_xy,
                                      const SelectionOptions& options) {
  ModelSelection out;
  std::vector<int> columns = detail::changing_columns(features);
  // Boards are screened with one graph (the middle neighbour count, the first gamma) and every
  // sigma; the full grid runs once, on the chosen boards. The graph parameters matter little
  // next to the boards (measured), and this keeps training within its time budget.
  SelectionOptions screen = options;
  screen.neighbours = {options.neighbours[options.neighbours.size() / 2]};
  screen.gammas = {options.gammas.front()};
  auto evaluate = [&](const std::vector<int>& cols) {
    return cross_validate_neighbour_model(features, labelled, labels_xy, cols, screen);
  };
  auto current = evaluate(columns);
  out.steps.push_back(SelectionStep{columns, current.first.cv_mse, current.second.cv_mse, -1});
  if (options.select_features) {
    current = detail::eliminate_columns(
        columns, current, options.min_improvement, options.min_boards, evaluate,
        [&](const std::vector<int>& left, const auto& choice, int dropped) {
          out.steps.push_back(
              SelectionStep{left, choice.first.cv_mse, choice.second.cv_mse, dropped});
        });
  }
  out.columns = columns;
  current = cross_validate_neighbour_model(features, labelled, labels_xy, columns, options);
  out.x = current.first;
  out.y = current.second;
  return out;
}

}  // namespace harmoloc::algorithms
