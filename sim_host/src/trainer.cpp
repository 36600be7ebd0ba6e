#include "harmoloc/sim_host/trainer.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>
#include <stdexcept>

#include "harmoloc/algorithms/harmonic_training.hpp"
#include "harmoloc/sim_host/file_camera.hpp"
#include "harmoloc/sim_host/metadata.hpp"
#include "harmoloc/sim_host/tum.hpp"

namespace harmoloc::sim_host {

namespace {

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

TrainReport train_map(const TrainOptions& opt, algorithms::MapFile& map) {
  TrainReport report;
  const DatasetMetadata meta = read_metadata(opt.dataset_dir);
  FileCamera camera(opt.dataset_dir, meta);
  const std::vector<StampedPose> labels = read_tum(opt.labels_path);
  if (labels.empty()) throw std::runtime_error(opt.labels_path + ": no labels");
  const std::size_t boards = opt.thresholds.count;

  // Segment every frame.
  std::vector<std::uint8_t> table_storage(algorithms::ColourTable::kEntries);
  algorithms::ColourTable classifier;
  classifier.build(algorithms::BoardClassifier(opt.thresholds), table_storage.data());
  const auto t_seg = std::chrono::steady_clock::now();
  std::vector<algorithms::AreaVector> areas;
  std::vector<std::uint64_t> stamps;
  areas.reserve(camera.frame_count());
  for (;;) {
    hal::FrameView frame;
    const hal::CameraStatus status = camera.acquire(frame, 0);
    if (status == hal::CameraStatus::kEnded) break;
    if (status != hal::CameraStatus::kFrame) continue;
    algorithms::AreaVector a;
    if (frame.format == hal::PixelFormat::kRgb24) {
      algorithms::segment_rgb24(frame.data, frame.width_px, frame.height_px, frame.stride_bytes,
                                classifier, a);
    } else {
      algorithms::segment_yuyv(frame.data, frame.width_px, frame.height_px, frame.stride_bytes,
                               classifier, a);
    }
    areas.push_back(a);
    stamps.push_back(frame.timestamp_ns);
    camera.release();
  }
  report.frames = areas.size();
  report.segment_ms = ms_since(t_seg);

  // Which frames are labelled: a label whose timestamp is within 0.5 ms of a frame's.
  std::vector<int> label_of(areas.size(), -1);
  for (std::size_t l = 0; l < labels.size(); ++l) {
    const auto t_ns = static_cast<std::uint64_t>(std::llround(labels[l].t_s * 1e6)) * 1000ULL;
    const auto it =
        std::lower_bound(stamps.begin(), stamps.end(), t_ns > 500000 ? t_ns - 500000 : 0);
    if (it != stamps.end() && (*it > t_ns ? *it - t_ns : t_ns - *it) <= 500000) {
      label_of[static_cast<std::size_t>(it - stamps.begin())] = static_cast<int>(l);
    } else {
      ++report.labels_unmatched;
    }
  }
  std::vector<std::size_t> labelled_frames, pool;
  for (std::size_t i = 0; i < areas.size(); ++i) {
    bool seen = false;
    for (std::size_t k = 0; k < boards; ++k) seen = seen || areas[i].pixels[k] > 0;
    if (!seen) {
      ++report.empty_frames;
      continue;
    }
    (label_of[i] >= 0 ? labelled_frames : pool).push_back(i);
  }
  if (labelled_frames.size() < 4) {
    std::ostringstream s;
    s << "only " << labelled_frames.size() << " of " << labels.size()
      << " labels match a frame with a board in view (labels must carry the frames' timestamps; at "
         "least 4 needed)";
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

  // Feature boards.
  std::vector<int> feature_boards = opt.boards;
  if (feature_boards.empty()) {
    for (std::size_t k = 0; k < boards; ++k) feature_boards.push_back(static_cast<int>(k));
  }
  for (int b : feature_boards) {
    if (b < 0 || static_cast<std::size_t>(b) >= boards) {
      throw std::runtime_error("board " + std::to_string(b + 1) + " is not among the " +
                               std::to_string(boards) + " configured boards");
    }
  }
  const float area_scale = 100.0F / static_cast<float>(meta.image_width_px * meta.image_height_px);

  // Samples in route order: labelled and unlabelled interleaved by time.
  std::vector<std::size_t> order = labelled_frames;
  order.insert(order.end(), unlabelled_frames.begin(), unlabelled_frames.end());
  std::sort(order.begin(), order.end());
  const auto d = static_cast<Eigen::Index>(feature_boards.size());
  Eigen::MatrixXd features(static_cast<Eigen::Index>(m), d);
  Eigen::VectorXd label_x = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(m));
  Eigen::VectorXd label_y = label_x;
  std::vector<bool> is_labelled(m, false);
  for (std::size_t i = 0; i < m; ++i) {
    const std::size_t f = order[i];
    for (Eigen::Index k = 0; k < d; ++k) {
      features(static_cast<Eigen::Index>(i), k) =
          static_cast<double>(static_cast<float>(areas[f].pixels[static_cast<std::size_t>(
                                  feature_boards[static_cast<std::size_t>(k)])]) *
                              area_scale);
    }
    if (label_of[f] >= 0) {
      is_labelled[i] = true;
      label_x(static_cast<Eigen::Index>(i)) =
          labels[static_cast<std::size_t>(label_of[f])].pose.x_m;
      label_y(static_cast<Eigen::Index>(i)) =
          labels[static_cast<std::size_t>(label_of[f])].pose.y_m;
    }
  }

  const auto t_train = std::chrono::steady_clock::now();
  algorithms::CrossValidationOptions cv;
  cv.folds = opt.folds;
  const algorithms::AxisChoice cx =
      algorithms::choose_axis_parameters(features, is_labelled, label_x, cv);
  const algorithms::AxisChoice cy =
      algorithms::choose_axis_parameters(features, is_labelled, label_y, cv);
  const Eigen::VectorXd fx =
      algorithms::solve_semi_supervised(features, is_labelled, label_x, cx.sigma, cx.gamma);
  const Eigen::VectorXd fy =
      algorithms::solve_semi_supervised(features, is_labelled, label_y, cy.sigma, cy.gamma);
  report.x = AxisReport{cx.sigma, cx.gamma, std::sqrt(cx.cv_mse)};
  report.y = AxisReport{cy.sigma, cy.gamma, std::sqrt(cy.cv_mse)};

  // Known-place bound: generous multiple of how far training samples lie from their neighbours.
  std::vector<double> nearest(m, 1e300);
  for (std::size_t i = 0; i < m; ++i) {
    for (std::size_t j = 0; j < m; ++j) {
      if (i != j) {
        nearest[i] = std::min(nearest[i], (features.row(static_cast<Eigen::Index>(i)) -
                                           features.row(static_cast<Eigen::Index>(j)))
                                              .norm());
      }
    }
  }
  std::sort(nearest.begin(), nearest.end());
  const double p99 =
      nearest[std::min(m - 1, static_cast<std::size_t>(0.99 * static_cast<double>(m)))];
  report.known_place_bound = std::max(4.0 * p99, 1e-3);
  report.train_ms = ms_since(t_train);

  map = algorithms::MapFile{};
  map.image_width_px = meta.image_width_px;
  map.image_height_px = meta.image_height_px;
  map.thresholds = opt.thresholds;
  auto& model = map.model;
  model.sample_count = static_cast<std::uint32_t>(m);
  model.feature_count = static_cast<std::uint32_t>(d);
  for (Eigen::Index k = 0; k < d; ++k)
    model.board_index[static_cast<std::size_t>(k)] =
        static_cast<std::uint8_t>(feature_boards[static_cast<std::size_t>(k)]);
  model.area_scale = area_scale;
  model.sigma_x = static_cast<float>(cx.sigma);
  model.sigma_y = static_cast<float>(cy.sigma);
  model.gamma_x = static_cast<float>(cx.gamma);
  model.gamma_y = static_cast<float>(cy.gamma);
  model.max_nearest_distance = static_cast<float>(report.known_place_bound);
  for (std::size_t i = 0; i < m; ++i) {
    for (Eigen::Index k = 0; k < d; ++k)
      model.sample(i)[k] = static_cast<float>(features(static_cast<Eigen::Index>(i), k));
    model.target_x_m[i] = static_cast<float>(fx(static_cast<Eigen::Index>(i)));
    model.target_y_m[i] = static_cast<float>(fy(static_cast<Eigen::Index>(i)));
  }
  return report;
}

}  // namespace harmoloc::sim_host
