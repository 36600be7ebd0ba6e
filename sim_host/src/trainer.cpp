#include "harmoloc/sim_host/trainer.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "harmoloc/algorithms/harmonic_training.hpp"
#include "harmoloc/algorithms/kernel_selection.hpp"
#include "harmoloc/algorithms/route_placement.hpp"
#include "harmoloc/dataset/area_log.hpp"
#include "harmoloc/dataset/metadata.hpp"
#include "harmoloc/host/file_camera.hpp"

namespace harmoloc::sim_host {

namespace {

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

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

double quantile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())))];
}

}  // namespace

AreaSeries segment_dataset(const std::string& dataset_dir,
                           const algorithms::ThresholdSet& thresholds) {
  const dataset::DatasetMetadata meta = dataset::read_metadata(dataset_dir);
  host::FileCamera camera(dataset_dir, meta);
  std::vector<std::uint8_t> table_storage(algorithms::ColourTable::kEntries);
  algorithms::ColourTable table;
  table.build(algorithms::BoardClassifier(thresholds), table_storage.data());
  const auto t0 = std::chrono::steady_clock::now();
  AreaSeries run;
  run.image_width_px = meta.image_width_px;
  run.image_height_px = meta.image_height_px;
  run.areas.reserve(camera.frame_count());
  for (;;) {
    hal::FrameView frame;
    const hal::CameraStatus status = camera.acquire(frame, 0);
    if (status == hal::CameraStatus::kEnded) break;
    if (status != hal::CameraStatus::kFrame) continue;
    algorithms::AreaVector a;
    if (frame.format == hal::PixelFormat::kRgb24) {
      algorithms::segment_rgb24(frame.data, frame.width_px, frame.height_px, frame.stride_bytes,
                                table, a);
    } else {
      algorithms::segment_yuyv(frame.data, frame.width_px, frame.height_px, frame.stride_bytes,
                               table, a);
    }
    run.areas.push_back(a);
    run.timestamp_ns.push_back(frame.timestamp_ns);
    camera.release();
  }
  run.segment_ms = ms_since(t0);
  run.odometry = read_dataset_odometry(dataset_dir, meta);
  return run;
}

AreaSeries read_area_series(const std::string& areas_path,
                            const algorithms::ThresholdSet& thresholds) {
  const dataset::AreaLog log = dataset::read_area_log(areas_path);
  if (log.board_names.size() != thresholds.count) {
    throw std::runtime_error(areas_path + ": has " + std::to_string(log.board_names.size()) +
                             " boards but the config has " + std::to_string(thresholds.count));
  }
  if (log.thresholds_crc32 != dataset::thresholds_fingerprint(thresholds)) {
    throw std::runtime_error(areas_path +
                             ": was recorded with other colour thresholds than the config "
                             "(thresholds_crc32 differs); train with the config the robot used");
  }
  AreaSeries run;
  run.image_width_px = log.image_width_px;
  run.image_height_px = log.image_height_px;
  run.timestamp_ns = log.timestamp_ns;
  run.areas = log.areas;
  return run;
}

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
  std::vector<int> candidates = opt.boards;
  if (candidates.empty()) {
    for (std::size_t k = 0; k < boards; ++k) candidates.push_back(static_cast<int>(k));
  }
  for (int b : candidates) {
    if (b < 0 || static_cast<std::size_t>(b) >= boards) {
      throw std::runtime_error("board " + std::to_string(b + 1) + " is not among the " +
                               std::to_string(boards) + " configured boards");
    }
  }
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
    for (const auto& step : sel.steps) {
      BoardStep b;
      for (int c : step.columns) b.boards.push_back(candidates[static_cast<std::size_t>(c)]);
      b.dropped = step.dropped >= 0 ? candidates[static_cast<std::size_t>(step.dropped)] : -1;
      b.cv_rmse_x_m = std::sqrt(step.cv_mse_x);
      b.cv_rmse_y_m = std::sqrt(step.cv_mse_y);
      report.board_steps.push_back(b);
    }
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

  map = algorithms::MapFile{};
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

namespace {

// Every frame placed by the odometry between the labels. Throws, naming the label, when a label
// lies far from where the odometry between its neighbours puts it.
algorithms::PlacementResult place_frames(const AreaSeries& run,
                                         const std::vector<dataset::StampedPose>& labels,
                                         const TrainOptions& opt, PlacementReport& report) {
  const std::uint64_t t0 = run.timestamp_ns.front();
  const auto rel = [t0](std::uint64_t t) {
    return t >= t0 ? static_cast<double>(t - t0) * 1e-9 : -static_cast<double>(t0 - t) * 1e-9;
  };
  const std::vector<algorithms::OdometrySample> odometry = run.odometry.relative_to(t0);
  const double odo_begin = odometry.front().t_s, odo_end = odometry.back().t_s;
  bool labels_have_yaw = false;
  for (const dataset::StampedPose& l : labels)
    labels_have_yaw = labels_have_yaw || l.pose.yaw_rad != 0.0;
  std::vector<algorithms::PlacementLabel> placement_labels;
  const double t0_s =
      static_cast<double>(t0 / 1000000000ULL) + static_cast<double>(t0 % 1000000000ULL) * 1e-9;
  for (std::size_t l = 0; l < labels.size(); ++l) {
    const dataset::StampedPose& s = labels[l];
    const double t = s.t_s - t0_s;
    char where[96];
    std::snprintf(where, sizeof where, "label %zu of %zu (t = %.3f s)", l + 1, labels.size(),
                  s.t_s);
    if (!std::isfinite(s.pose.x_m) || !std::isfinite(s.pose.y_m) || std::fabs(s.pose.x_m) > 1e4 ||
        std::fabs(s.pose.y_m) > 1e4) {
      throw std::runtime_error(std::string(where) + ": position is not a place on a floor");
    }
    if (t < odo_begin - 0.05 || t > odo_end + 0.05) {
      throw std::runtime_error(std::string(where) +
                               ": outside the run's wheel odometry (labels must be on the "
                               "robot's clock)");
    }
    if (!placement_labels.empty() && !(t > placement_labels.back().t_s)) {
      throw std::runtime_error(std::string(where) + ": labels must be in time order");
    }
    placement_labels.push_back(
        algorithms::PlacementLabel{t, s.pose.x_m, s.pose.y_m, s.pose.yaw_rad, labels_have_yaw});
  }
  std::vector<double> query;
  query.reserve(run.timestamp_ns.size());
  for (std::uint64_t t : run.timestamp_ns) query.push_back(rel(t));
  // The odometry measured against the labels first: the placement, and the firmware with the
  // map, use the wheels as they are, not as configured.
  report.odometry =
      algorithms::calibrate_odometry(odometry, run.odometry.geometry, placement_labels);
  const algorithms::OdometryScale& scale = report.odometry.scale;
  constexpr double kMaxScaleError = 0.2;
  for (const double v : {scale.left, scale.right, scale.track}) {
    if (std::fabs(v - 1.0) > kMaxScaleError) {
      char msg[320];
      std::snprintf(msg, sizeof msg,
                    "the labels and the wheel odometry disagree: they need the left wheel x %.3f, "
                    "the right x %.3f and the track x %.3f of the configured geometry (more than "
                    "%.0f%% off): check wheel_radius_m, track_m, ticks_per_rev and the wheel "
                    "directions, and that the labels are in metres on the robot's clock",
                    scale.left, scale.right, scale.track, 100.0 * kMaxScaleError);
      throw std::runtime_error(msg);
    }
  }
  algorithms::PlacementResult placed = algorithms::place_by_odometry(
      query, odometry, algorithms::calibrated(run.odometry.geometry, scale), placement_labels);

  // Labels that the odometry between their neighbours does not support.
  std::vector<double> residuals;
  for (double r : placed.label_residual_m) {
    if (r >= 0.0) residuals.push_back(r);
  }
  if (!residuals.empty()) {
    report.median_label_residual_m = quantile(residuals, 0.5);
    for (std::size_t l = 0; l < placed.label_residual_m.size(); ++l) {
      if (placed.label_residual_m[l] > report.worst_label_residual_m) {
        report.worst_label_residual_m = placed.label_residual_m[l];
        report.worst_label = static_cast<int>(l);
      }
    }
    if (report.worst_label_residual_m > opt.label_outlier_m &&
        report.worst_label_residual_m > opt.label_outlier_ratio * report.median_label_residual_m) {
      const dataset::StampedPose& bad = labels[static_cast<std::size_t>(report.worst_label)];
      char msg[320];
      std::snprintf(msg, sizeof msg,
                    "label %d of %zu (t = %.3f s, x %.3f, y %.3f) is %.1f cm from where the "
                    "wheel odometry between its neighbours puts the robot (median of the labels "
                    "%.1f cm): check its position, units and time",
                    report.worst_label + 1, labels.size(), bad.t_s, bad.pose.x_m, bad.pose.y_m,
                    100.0 * report.worst_label_residual_m, 100.0 * report.median_label_residual_m);
      throw std::runtime_error(msg);
    }
  }
  std::vector<double> spacing;
  for (std::size_t l = 1; l < placement_labels.size(); ++l) {
    const auto a = static_cast<std::size_t>(
        std::lower_bound(query.begin(), query.end(), placement_labels[l - 1].t_s) - query.begin());
    const auto b = static_cast<std::size_t>(
        std::lower_bound(query.begin(), query.end(), placement_labels[l].t_s) - query.begin());
    if (a < query.size() && b < query.size())
      spacing.push_back(placed.travel_m[b] - placed.travel_m[a]);
  }
  if (!spacing.empty()) report.label_spacing_m = quantile(spacing, 0.5);
  report.travel_m = placed.travel_m.empty() ? 0.0 : placed.travel_m.back();
  report.used = true;
  return placed;
}

double rms(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x * x;
  return v.empty() ? 0.0 : std::sqrt(s / static_cast<double>(v.size()));
}

}  // namespace

static void check_labels(const std::vector<dataset::StampedPose>& labels) {
  char msg[320];
  for (std::size_t l = 0; l < labels.size(); ++l) {
    const dataset::StampedPose& s = labels[l];
    if (!std::isfinite(s.t_s) || !std::isfinite(s.pose.x_m) || !std::isfinite(s.pose.y_m) ||
        std::fabs(s.pose.x_m) > 1e4 || std::fabs(s.pose.y_m) > 1e4) {
      std::snprintf(msg, sizeof msg,
                    "label %zu of %zu (t = %.3f s): (%g, %g) is not a place on a floor", l + 1,
                    labels.size(), s.t_s, s.pose.x_m, s.pose.y_m);
      throw std::runtime_error(msg);
    }
    if (l > 0 && !(s.t_s > labels[l - 1].t_s)) {
      std::snprintf(msg, sizeof msg, "label %zu of %zu (t = %.3f s): labels must be in time order",
                    l + 1, labels.size(), s.t_s);
      throw std::runtime_error(msg);
    }
  }
  // A ground robot does not cover metres in a moment: a label far from both its neighbours, more
  // than 5 m/s could explain, is mistyped (units, a swapped coordinate) or misdated.
  const auto jump = [&](std::size_t a, std::size_t b) {
    const double d = std::hypot(labels[a].pose.x_m - labels[b].pose.x_m,
                                labels[a].pose.y_m - labels[b].pose.y_m);
    return d > 0.5 + 5.0 * std::fabs(labels[a].t_s - labels[b].t_s) ? d : 0.0;
  };
  for (std::size_t l = 0; l < labels.size(); ++l) {
    const double before = l > 0 ? jump(l, l - 1) : -1.0;
    const double after = l + 1 < labels.size() ? jump(l, l + 1) : -1.0;
    if (before != 0.0 && after != 0.0 && (before > 0.0 || after > 0.0)) {
      std::snprintf(msg, sizeof msg,
                    "label %zu of %zu (t = %.3f s, x %g, y %g) is %.3g m from its neighbours: "
                    "check its position, units and time",
                    l + 1, labels.size(), labels[l].t_s, labels[l].pose.x_m, labels[l].pose.y_m,
                    std::max(before, after));
      throw std::runtime_error(msg);
    }
  }
}

TrainReport train_on_areas(const AreaSeries& run, const std::vector<dataset::StampedPose>& labels,
                           const TrainOptions& opt, algorithms::MapFile& map) {
  check_labels(labels);
  TrainReport report;
  report.segment_ms = run.segment_ms;
  report.frames = run.areas.size();
  if (labels.empty()) throw std::runtime_error("no labels");
  if (run.areas.empty()) throw std::runtime_error("the run has no frames");
  const std::size_t boards = opt.thresholds.count;
  const float area_scale = 100.0F / static_cast<float>(run.image_width_px * run.image_height_px);
  std::vector<std::vector<float>> all(run.areas.size(), std::vector<float>(boards, 0.0F));
  for (std::size_t i = 0; i < run.areas.size(); ++i) {
    for (std::size_t b = 0; b < boards; ++b)
      all[i][b] = static_cast<float>(run.areas[i].pixels[b]) * area_scale;
  }
  const bool with_odometry =
      opt.use_odometry && !run.odometry.empty() && opt.method == TrainMethod::kNeighbourGraph;
  if (!with_odometry) {
    train_from_labels(run, labels, opt, map, report);
    if (opt.forward_map) {
      const auto t_forward = std::chrono::steady_clock::now();
      report.forward = train_forward_map(all, run.timestamp_ns, labels, map.model, boards,
                                         opt.forward, map.forward);
      report.has_forward_map = true;
      report.forward_ms = ms_since(t_forward);
    }
    return report;
  }

  const auto t_train = std::chrono::steady_clock::now();
  PlacementReport& pr = report.placement;
  const algorithms::PlacementResult placed = place_frames(run, labels, opt, pr);
  // The stretch the labels cover, and how far beyond it the odometry may carry a frame.
  std::vector<PlacedFrame> frames;
  pr.poses = placed.poses;
  for (std::uint64_t t : run.timestamp_ns)
    pr.times_s.push_back(static_cast<double>(t / 1000000000ULL) +
                         static_cast<double>(t % 1000000000ULL) * 1e-9);
  pr.placed.assign(run.areas.size(), false);
  for (std::size_t i = 0; i < run.areas.size(); ++i) {
    bool seen = false;
    for (std::size_t b = 0; b < boards; ++b) seen = seen || run.areas[i].pixels[b] > 0;
    if (!seen) {
      ++report.empty_frames;
      continue;
    }
    if (placed.support_m[i] > opt.max_extrapolation_m) {
      ++pr.beyond_labels;
      continue;
    }
    pr.placed[i] = true;
    frames.push_back(
        PlacedFrame{i, static_cast<double>(run.timestamp_ns[i] - run.timestamp_ns[0]) * 1e-9,
                    placed.travel_m[i], placed.poses[i]});
  }
  pr.frames = frames.size();
  if (frames.size() < 16)
    throw std::runtime_error("only " + std::to_string(frames.size()) +
                             " frames with a board in view lie within the labelled stretch");

  // The harmonic map over every placed frame: samples and held-out queries evenly spread.
  std::vector<int> candidates = opt.boards;
  if (candidates.empty()) {
    for (std::size_t k = 0; k < boards; ++k) candidates.push_back(static_cast<int>(k));
  }
  for (int b : candidates) {
    if (b < 0 || static_cast<std::size_t>(b) >= boards) {
      throw std::runtime_error("board " + std::to_string(b + 1) + " is not among the " +
                               std::to_string(boards) + " configured boards");
    }
  }
  const auto pick = [](std::size_t total, std::size_t want) {
    std::vector<std::size_t> out;
    want = std::min(want, total);
    for (std::size_t k = 0; k < want; ++k) out.push_back((k * total + total / 2) / want);
    return out;
  };
  const auto fill = [&](const std::vector<std::size_t>& which) {
    algorithms::PlacedSamples s;
    s.features.resize(static_cast<Eigen::Index>(which.size()),
                      static_cast<Eigen::Index>(candidates.size()));
    s.xy.resize(static_cast<Eigen::Index>(which.size()), 2);
    for (std::size_t r = 0; r < which.size(); ++r) {
      const PlacedFrame& f = frames[which[r]];
      for (std::size_t c = 0; c < candidates.size(); ++c) {
        s.features(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) =
            static_cast<double>(all[f.index][static_cast<std::size_t>(candidates[c])]);
      }
      s.xy(static_cast<Eigen::Index>(r), 0) = f.pose.x_m;
      s.xy(static_cast<Eigen::Index>(r), 1) = f.pose.y_m;
      s.travel_m.push_back(f.travel_m);
    }
    return s;
  };
  const std::vector<std::size_t> sample_rows = pick(
      frames.size(),
      static_cast<std::size_t>(std::clamp(
          opt.max_placed_samples, 16, static_cast<int>(algorithms::HarmonicModel::kMaxSamples))));
  const algorithms::PlacedSamples samples = fill(sample_rows);
  const algorithms::PlacedSamples queries =
      fill(pick(frames.size(), static_cast<std::size_t>(std::max(opt.max_cv_queries, 16))));
  algorithms::KernelSelectionOptions ko;
  ko.same_pass_m = opt.same_pass_m;
  ko.select_features = opt.select_boards && opt.boards.empty();
  if (!opt.local_linear) ko.local_linear_ridges.clear();
  algorithms::KernelSelection sel = algorithms::select_kernel_model(samples, queries, ko);

  // The same with each board's feature in units of its noise (the forward map measures it
  // against other passes): a large board's few percent of noise then no longer drowns a small
  // board's informative change. Kept where cross-validation prefers it.
  std::vector<double> scale(candidates.size(), 1.0);
  const auto forward = std::make_unique<algorithms::ForwardMap>();
  bool have_forward = false;
  ForwardMapReport forward_report;
  double forward_ms = 0.0;
  if (opt.forward_map) {
    const auto t_forward = std::chrono::steady_clock::now();
    forward_report = train_forward_map_placed(all, frames, boards, opt.forward, *forward);
    forward_ms = ms_since(t_forward);
    have_forward = true;
  }
  if (have_forward && opt.noise_weighted_kernel) {
    const ForwardMapReport& noise = forward_report;
    double largest = 0.0;
    for (std::size_t c = 0; c < candidates.size(); ++c) {
      const double sigma = noise.sigma[static_cast<std::size_t>(candidates[c])];
      scale[c] = sigma > 0.0 ? 1.0 / sigma : 0.0;
      largest = std::max(largest, scale[c]);
    }
    if (largest > 0.0) {
      for (double& v : scale) v = v > 0.0 ? v / largest : 1.0;  // kernel weights scale^2 <= 1
      const auto scaled = [&](algorithms::PlacedSamples s) {
        for (std::size_t c = 0; c < candidates.size(); ++c)
          s.features.col(static_cast<Eigen::Index>(c)) *= scale[c];
        return s;
      };
      algorithms::KernelSelection weighted =
          algorithms::select_kernel_model(scaled(samples), scaled(queries), ko);
      if (weighted.x.cv_mse + weighted.y.cv_mse < sel.x.cv_mse + sel.y.cv_mse) {
        sel = std::move(weighted);
        report.noise_weighted = true;
      }
    }
  }
  if (!report.noise_weighted) std::fill(scale.begin(), scale.end(), 1.0);

  // Every board whose area changes is a feature; the ones the selection dropped stay in the
  // map with weight 0 in the kernel, so that the known-place test still compares them.
  std::vector<int> features_in_map;
  for (Eigen::Index k = 0; k < samples.features.cols(); ++k) {
    if (samples.features.col(k).maxCoeff() <= samples.features.col(k).minCoeff())
      report.constant_boards.push_back(candidates[static_cast<std::size_t>(k)]);
    else
      features_in_map.push_back(static_cast<int>(k));
  }
  for (const auto& step : sel.steps) {
    BoardStep b;
    for (int c : step.columns) b.boards.push_back(candidates[static_cast<std::size_t>(c)]);
    b.dropped = step.dropped >= 0 ? candidates[static_cast<std::size_t>(step.dropped)] : -1;
    b.cv_rmse_x_m = std::sqrt(step.cv_mse_x);
    b.cv_rmse_y_m = std::sqrt(step.cv_mse_y);
    report.board_steps.push_back(b);
  }
  for (int c : sel.columns) report.boards.push_back(candidates[static_cast<std::size_t>(c)]);
  report.x = AxisReport{sel.x.sigma, 0.0, std::sqrt(sel.x.cv_mse), 0};
  report.y = AxisReport{sel.y.sigma, 0.0, std::sqrt(sel.y.cv_mse), 0};
  report.local_linear_ridge = sel.local_linear_ridge;
  report.kernel_average_cv_rmse_x_m = std::sqrt(sel.kernel_average_cv_mse_x);
  report.kernel_average_cv_rmse_y_m = std::sqrt(sel.kernel_average_cv_mse_y);
  pr.cv_rmse_placed_x_m = rms(sel.error_x_m);
  pr.cv_rmse_placed_y_m = rms(sel.error_y_m);
  pr.harmonic_from_placed = true;
  report.labelled = labels.size();
  report.unlabelled = sample_rows.size();

  // Known-place bounds from how far each held-out frame lies from the nearest sample of
  // another pass, over every feature: what a frame of a new run over the same place looks like.
  std::vector<double> nearest_distance, nearest_dissimilarity;
  algorithms::other_pass_nearest(samples, queries, features_in_map, opt.same_pass_m,
                                 nearest_distance, nearest_dissimilarity);
  if (nearest_distance.empty())
    throw std::runtime_error(
        "no frame of the run has another pass over the same place to compare "
        "with: drive the route at least forth and back (or twice round)");
  report.known_place_bound = std::max(4.0 * quantile(nearest_distance, 0.99), 1e-3);
  report.dissimilarity_bound =
      std::min(1.0, std::max(opt.known_place_margin * quantile(nearest_dissimilarity, 0.99), 0.01));
  report.train_ms = ms_since(t_train);

  map = algorithms::MapFile{};
  map.image_width_px = run.image_width_px;
  map.image_height_px = run.image_height_px;
  map.thresholds = opt.thresholds;
  auto& model = map.model;
  model.sample_count = static_cast<std::uint32_t>(sample_rows.size());
  model.feature_count = static_cast<std::uint32_t>(features_in_map.size());
  for (std::size_t k = 0; k < features_in_map.size(); ++k) {
    const int c = features_in_map[k];
    model.board_index[k] = static_cast<std::uint8_t>(candidates[static_cast<std::size_t>(c)]);
    const bool chosen = std::find(sel.columns.begin(), sel.columns.end(), c) != sel.columns.end();
    model.feature_weight[k] = chosen ? static_cast<float>(scale[static_cast<std::size_t>(c)] *
                                                          scale[static_cast<std::size_t>(c)])
                                     : 0.0F;
  }
  model.area_scale = area_scale;
  model.sigma_x = static_cast<float>(report.x.sigma);
  model.sigma_y = static_cast<float>(report.y.sigma);
  model.gamma_x = 0.0F;
  model.gamma_y = 0.0F;
  model.local_linear_ridge = static_cast<float>(sel.local_linear_ridge);
  model.max_nearest_distance = static_cast<float>(report.known_place_bound);
  model.max_dissimilarity = static_cast<float>(report.dissimilarity_bound);
  for (std::size_t i = 0; i < sample_rows.size(); ++i) {
    for (std::size_t k = 0; k < features_in_map.size(); ++k) {
      model.sample(i)[k] =
          static_cast<float>(samples.features(static_cast<Eigen::Index>(i), features_in_map[k]));
    }
    model.target_x_m[i] = static_cast<float>(samples.xy(static_cast<Eigen::Index>(i), 0));
    model.target_y_m[i] = static_cast<float>(samples.xy(static_cast<Eigen::Index>(i), 1));
  }

  map.calibration.present = true;
  map.calibration.fix_rmse_x_m = static_cast<float>(pr.cv_rmse_placed_x_m);
  map.calibration.fix_rmse_y_m = static_cast<float>(pr.cv_rmse_placed_y_m);
  if (report.placement.odometry.used) {
    const algorithms::OdometryScale& s = report.placement.odometry.scale;
    map.calibration.odometry_present = true;
    map.calibration.left_wheel_scale = static_cast<float>(s.left);
    map.calibration.right_wheel_scale = static_cast<float>(s.right);
    map.calibration.track_scale = static_cast<float>(s.track);
  }

  if (have_forward) {
    map.forward = *forward;
    report.forward = forward_report;
    map.calibration.pass_spread_m = static_cast<float>(report.forward.pass_spread_m);
    report.has_forward_map = true;
    report.forward_ms = forward_ms;
  }
  return report;
}

void check_trained_map(const TrainReport& report, const std::vector<dataset::StampedPose>& labels,
                       const algorithms::MapFile& map, const TrainOptions& opt) {
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  for (const dataset::StampedPose& l : labels) {
    x0 = std::min(x0, l.pose.x_m);
    y0 = std::min(y0, l.pose.y_m);
    x1 = std::max(x1, l.pose.x_m);
    y1 = std::max(y1, l.pose.y_m);
  }
  const double extent = std::hypot(x1 - x0, y1 - y0);
  char msg[320];
  // The map's coordinates must lie where the labels are (a little beyond, for the stretch the
  // odometry carries past the first and last label).
  const double margin = std::max(opt.max_extrapolation_m, 0.1 * extent);
  const algorithms::HarmonicModel& m = map.model;
  for (std::size_t i = 0; i < m.sample_count; ++i) {
    const double x = m.target_x_m[i], y = m.target_y_m[i];
    if (!(x >= x0 - margin && x <= x1 + margin && y >= y0 - margin && y <= y1 + margin)) {
      std::snprintf(msg, sizeof msg,
                    "the trained map puts a sample at (%.3g, %.3g) m, outside the labelled region "
                    "(%.3g..%.3g, %.3g..%.3g) m: the labels do not fit the run (check their units "
                    "and times)",
                    x, y, x0, x1, y0, y1);
      throw std::runtime_error(msg);
    }
  }
  // A cross-validated error of a quarter of the labelled region is no map of it.
  const double cv = std::hypot(report.x.cv_rmse_m, report.y.cv_rmse_m);
  if (!std::isfinite(cv) || cv > std::max(0.25 * extent, 0.05)) {
    std::snprintf(msg, sizeof msg,
                  "cross-validated error %.3g m is absurd for labels spanning %.3g m: the boards "
                  "do not tell places apart (check the colour windows, the labels' units and "
                  "times)",
                  cv, extent);
    throw std::runtime_error(msg);
  }
}

TrainReport train_map(const TrainOptions& opt, algorithms::MapFile& map) {
  if (opt.dataset_dir.empty() == opt.areas_path.empty())
    throw std::runtime_error("give either a dataset folder or an area log");
  AreaSeries run = opt.areas_path.empty() ? segment_dataset(opt.dataset_dir, opt.thresholds)
                                          : read_area_series(opt.areas_path, opt.thresholds);
  if (!opt.areas_path.empty() && !opt.encoders_path.empty())
    run.odometry = read_odometry_file(opt.encoders_path, opt.can_layout, opt.geometry);
  std::vector<dataset::StampedPose> labels = dataset::read_tum(opt.labels_path);
  if (labels.empty()) throw std::runtime_error(opt.labels_path + ": no labels");
  double offset_s = opt.label_offset_s;
  LabelOffsetEstimate estimate;
  if (opt.label_offset_auto) {
    if (run.odometry.empty() || !opt.use_odometry) {
      throw std::runtime_error(
          "--label-offset auto needs the run's wheel odometry (a dataset folder's encoder log, or "
          "--encoders with an area log)");
    }
    estimate = estimate_label_offset(run.odometry, labels);
    if (!estimate.found) {
      throw std::runtime_error("cannot estimate the labels' clock offset from the odometry: " +
                               estimate.why_not + "; give --label-offset SECONDS");
    }
    offset_s = estimate.offset_s;
  }
  for (dataset::StampedPose& l : labels) l.t_s += offset_s;
  TrainReport report = train_on_areas(run, labels, opt, map);
  report.label_offset_s = offset_s;
  report.label_offset_estimated = opt.label_offset_auto;
  report.label_offset = estimate;
  for (const dataset::StampedPose& l : labels)
    report.labels_have_yaw = report.labels_have_yaw || l.pose.yaw_rad != 0.0;
  check_trained_map(report, labels, map, opt);
  return report;
}

}  // namespace harmoloc::sim_host
