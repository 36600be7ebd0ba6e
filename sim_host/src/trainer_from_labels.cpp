#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

#include "harmoloc/algorithms/harmonic_training.hpp"
#include "trainer_parts.hpp"

namespace harmoloc::sim_host::trainer_detail {

namespace {

// Leave-one-out: how far (distance, Bray-Curtis dissimilarity) each training sample lies from
// its nearest other sample.
void leave_one_out(const Eigen::MatrixXd& f, std::vector<double>& distance,
                   std::vector<double>& dissimilarity) {
  const Eigen::Index m = f.rows();
  distance.assign(static_cast<std::size_t>(m), 0.0);
  dissimilarity.assign(static_cast<std::size_t>(m), 0.0);
  for (Eigen::Index i = 0; i < m; ++i) {
    double best = 1e300;
    Eigen::Index nearest = -1;
    for (Eigen::Index j = 0; j < m; ++j) {
      if (i == j) continue;
      const double d2 = (f.row(i) - f.row(j)).squaredNorm();
      if (d2 < best) {
        best = d2;
        nearest = j;
      }
    }
    distance[static_cast<std::size_t>(i)] = std::sqrt(best);
    if (nearest >= 0) {
      const double num = (f.row(i) - f.row(nearest)).cwiseAbs().sum();
      const double den = (f.row(i) + f.row(nearest)).sum();
      dissimilarity[static_cast<std::size_t>(i)] = den > 0.0 ? num / den : 1.0;
    }
  }
}

}  // namespace

// Wu & Qin's setting: the labelled frames (timestamps equal to a label's) and an evenly spread
// subset of the others, unlabelled; the neighbour graph (or the paper's complete graph).
void train_from_labels(const AreaSeries& run, const std::vector<dataset::StampedPose>& labels,
                       const TrainOptions& opt, algorithms::MapFile& map, TrainReport& report) {
  report.segment_ms = run.segment_ms;
  report.frames = run.areas.size();
  const std::size_t boards = opt.thresholds.count;
  if (labels.empty()) throw std::runtime_error("no labels");

  // Which frames are labelled: the frame nearest a label's time, within the tolerance.
  const auto& stamps = run.timestamp_ns;
  const std::uint64_t tol = opt.label_tolerance_ns;
  std::vector<int> label_of(run.areas.size(), -1);
  for (std::size_t l = 0; l < labels.size(); ++l) {
    const auto t_ns = static_cast<std::uint64_t>(std::llround(labels[l].t_s * 1e6)) * 1000ULL;
    auto it = std::lower_bound(stamps.begin(), stamps.end(), t_ns > tol ? t_ns - tol : 0);
    const auto gap = [t_ns](std::uint64_t s) { return s > t_ns ? s - t_ns : t_ns - s; };
    while (it != stamps.end() && it + 1 != stamps.end() && gap(*(it + 1)) < gap(*it)) ++it;
    if (it != stamps.end() && gap(*it) <= tol) {
      label_of[static_cast<std::size_t>(it - stamps.begin())] = static_cast<int>(l);
    } else {
      ++report.labels_unmatched;
    }
  }
  std::vector<std::size_t> labelled_frames, pool;
  for (std::size_t i = 0; i < run.areas.size(); ++i) {
    bool seen = false;
    for (std::size_t k = 0; k < boards; ++k) seen = seen || run.areas[i].pixels[k] > 0;
    if (!seen) {
      ++report.empty_frames;
      continue;
    }
    (label_of[i] >= 0 ? labelled_frames : pool).push_back(i);
  }
  if (opt.max_labelled > 0 && labelled_frames.size() > static_cast<std::size_t>(opt.max_labelled)) {
    // Evenly spread over the run; the others join the unlabelled pool.
    std::vector<std::size_t> kept;
    const std::size_t n = labelled_frames.size(), want = static_cast<std::size_t>(opt.max_labelled);
    std::vector<bool> take(n, false);
    for (std::size_t k = 0; k < want; ++k) take[(k * n + n / 2) / want] = true;
    for (std::size_t k = 0; k < n; ++k) {
      if (take[k]) {
        kept.push_back(labelled_frames[k]);
      } else {
        pool.push_back(labelled_frames[k]);
        label_of[labelled_frames[k]] = -1;
      }
    }
    std::sort(pool.begin(), pool.end());
    labelled_frames = kept;
  }
  if (labelled_frames.size() < 4) {
    std::ostringstream s;
    s << "only " << labelled_frames.size() << " of " << labels.size()
      << " labels match a frame with a board in view (without wheel odometry a label must be "
         "within --label-tolerance-ms of a frame's timestamp; at least 4 needed)";
    throw std::runtime_error(s.str());
  }
  std::size_t want = opt.unlabelled >= 0
                         ? static_cast<std::size_t>(opt.unlabelled)
                         : static_cast<std::size_t>(opt.unlabelled_ratio *
                                                    static_cast<double>(labelled_frames.size()));
  want = std::min(want, pool.size());
  std::vector<std::size_t> unlabelled_frames;
  for (std::size_t k = 0; k < want; ++k)
    unlabelled_frames.push_back(pool[(k * pool.size() + pool.size() / 2) / want]);
  const std::size_t m = labelled_frames.size() + unlabelled_frames.size();
  if (m > algorithms::HarmonicModel::kMaxSamples) {
    throw std::runtime_error("too many training samples (" + std::to_string(m) + ", at most 4096)");
  }
  report.labelled = labelled_frames.size();
  report.unlabelled = unlabelled_frames.size();

  // Candidate feature boards.
  const std::vector<int> candidates = candidate_boards(opt.boards, boards);
  // Area normalisation: percent of the frame, so sigma and the bounds do not depend on the
  // resolution the robot records at.
  const float area_scale = 100.0F / static_cast<float>(run.image_width_px * run.image_height_px);

  // Samples in route order: labelled and unlabelled interleaved by time.
  std::vector<std::size_t> order = labelled_frames;
  order.insert(order.end(), unlabelled_frames.begin(), unlabelled_frames.end());
  std::sort(order.begin(), order.end());
  const auto dc = static_cast<Eigen::Index>(candidates.size());
  Eigen::MatrixXd all_features(static_cast<Eigen::Index>(m), dc);
  Eigen::MatrixXd labels_xy = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(m), 2);
  std::vector<bool> is_labelled(m, false);
  for (std::size_t i = 0; i < m; ++i) {
    const std::size_t f = order[i];
    const auto row = static_cast<Eigen::Index>(i);
    for (Eigen::Index k = 0; k < dc; ++k) {
      // Rounded through float as the firmware computes it, so training sees what it will see.
      all_features(row, k) =
          static_cast<double>(static_cast<float>(run.areas[f].pixels[static_cast<std::size_t>(
                                  candidates[static_cast<std::size_t>(k)])]) *
                              area_scale);
    }
    if (label_of[f] >= 0) {
      is_labelled[i] = true;
      labels_xy(row, 0) = labels[static_cast<std::size_t>(label_of[f])].pose.x_m;
      labels_xy(row, 1) = labels[static_cast<std::size_t>(label_of[f])].pose.y_m;
    }
  }

  const auto t_train = std::chrono::steady_clock::now();
  std::vector<int> columns;
  Eigen::VectorXd fx, fy;
  if (opt.method == TrainMethod::kPaper) {
    for (Eigen::Index k = 0; k < dc; ++k) columns.push_back(static_cast<int>(k));
    algorithms::CrossValidationOptions cv;
    cv.folds = opt.folds;
    const Eigen::VectorXd lx = labels_xy.col(0), ly = labels_xy.col(1);
    const algorithms::AxisChoice cx =
        algorithms::choose_axis_parameters(all_features, is_labelled, lx, cv);
    const algorithms::AxisChoice cy =
        algorithms::choose_axis_parameters(all_features, is_labelled, ly, cv);
    fx = algorithms::solve_semi_supervised(all_features, is_labelled, lx, cx.sigma, cx.gamma);
    fy = algorithms::solve_semi_supervised(all_features, is_labelled, ly, cy.sigma, cy.gamma);
    report.x = AxisReport{cx.sigma, cx.gamma, std::sqrt(cx.cv_mse), 0};
    report.y = AxisReport{cy.sigma, cy.gamma, std::sqrt(cy.cv_mse), 0};
  } else {
    algorithms::SelectionOptions so;
    so.folds = opt.folds;
    so.gap = opt.cv_gap;
    so.min_improvement = opt.min_improvement;
    so.select_features = opt.select_boards && opt.boards.empty();
    const algorithms::ModelSelection sel =
        algorithms::select_neighbour_model(all_features, is_labelled, labels_xy, so);
    columns = sel.columns;
    for (Eigen::Index k = 0; k < dc; ++k) {
      if (all_features.col(k).maxCoeff() <= all_features.col(k).minCoeff())
        report.constant_boards.push_back(candidates[static_cast<std::size_t>(k)]);
    }
    report_board_steps(sel.steps, candidates, report.board_steps);
    Eigen::MatrixXd chosen(static_cast<Eigen::Index>(m), static_cast<Eigen::Index>(columns.size()));
    for (std::size_t c = 0; c < columns.size(); ++c)
      chosen.col(static_cast<Eigen::Index>(c)) = all_features.col(columns[c]);
    // One graph per axis (each axis chose its own neighbour count and gamma).
    fx = algorithms::solve_on_neighbour_graph(chosen, is_labelled, labels_xy.col(0),
                                              sel.x.neighbours, sel.x.gamma)
             .col(0);
    fy = algorithms::solve_on_neighbour_graph(chosen, is_labelled, labels_xy.col(1),
                                              sel.y.neighbours, sel.y.gamma)
             .col(0);
    report.x = AxisReport{sel.x.sigma, sel.x.gamma, std::sqrt(sel.x.cv_mse), sel.x.neighbours};
    report.y = AxisReport{sel.y.sigma, sel.y.gamma, std::sqrt(sel.y.cv_mse), sel.y.neighbours};
  }
  for (int c : columns) report.boards.push_back(candidates[static_cast<std::size_t>(c)]);
  const auto d = static_cast<Eigen::Index>(columns.size());
  Eigen::MatrixXd features(static_cast<Eigen::Index>(m), d);
  for (Eigen::Index c = 0; c < d; ++c)
    features.col(c) = all_features.col(columns[static_cast<std::size_t>(c)]);

  // Known-place bounds, calibrated on how far each training sample lies from the others (leave
  // one out): the dissimilarity bound is known_place_margin times its 99th percentile, the
  // distance bound a looser backstop at four times (docs/training.md has the measured rates;
  // samples from other passes over the same place were tried as the reference and separated
  // on-route from off-route frames worse).
  std::vector<double> loo_distance, loo_dissimilarity;
  leave_one_out(features, loo_distance, loo_dissimilarity);
  report.known_place_bound = std::max(4.0 * quantile(loo_distance, 0.99), 1e-3);
  const double dissimilarity_bound =
      std::min(1.0, std::max(opt.known_place_margin * quantile(loo_dissimilarity, 0.99), 0.01));
  report.dissimilarity_bound = dissimilarity_bound;
  report.train_ms = ms_since(t_train);

  algorithms::reset_in_place(map);
  map.image_width_px = run.image_width_px;
  map.image_height_px = run.image_height_px;
  map.thresholds = opt.thresholds;
  auto& model = map.model;
  model.sample_count = static_cast<std::uint32_t>(m);
  model.feature_count = static_cast<std::uint32_t>(d);
  for (std::size_t k = 0; k < report.boards.size(); ++k)
    model.board_index[k] = static_cast<std::uint8_t>(report.boards[k]);
  model.area_scale = area_scale;
  model.sigma_x = static_cast<float>(report.x.sigma);
  model.sigma_y = static_cast<float>(report.y.sigma);
  model.gamma_x = static_cast<float>(report.x.gamma);
  model.gamma_y = static_cast<float>(report.y.gamma);
  model.max_nearest_distance = static_cast<float>(report.known_place_bound);
  model.max_dissimilarity = static_cast<float>(dissimilarity_bound);
  for (std::size_t i = 0; i < m; ++i) {
    for (Eigen::Index k = 0; k < d; ++k)
      model.sample(i)[k] = static_cast<float>(features(static_cast<Eigen::Index>(i), k));
    model.target_x_m[i] = static_cast<float>(fx(static_cast<Eigen::Index>(i)));
    model.target_y_m[i] = static_cast<float>(fy(static_cast<Eigen::Index>(i)));
  }
}

}  // namespace harmoloc::sim_host::trainer_detail
