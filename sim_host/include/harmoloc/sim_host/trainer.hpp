#pragma once
/// @file The map trainer (seed 000, offline half): measures the board areas of a recorded run
/// (or reads them from an area log), takes the frames whose timestamps carry a label as labelled
/// and an evenly spread subset of the rest as unlabelled, chooses the feature boards, the graph
/// and the kernel widths by cross-validation, solves eq. 8 and writes the map
/// (docs/training.md).

#include <cstdint>
#include <string>
#include <vector>

#include "harmoloc/algorithms/harmonic_selection.hpp"
#include "harmoloc/algorithms/map_codec.hpp"
#include "harmoloc/algorithms/segmentation.hpp"
#include "harmoloc/sim_host/forward_map_training.hpp"
#include "harmoloc/sim_host/tum.hpp"

namespace harmoloc::sim_host {

/// How eq. 8 is posed.
enum class TrainMethod {
  kNeighbourGraph,  ///< k-nearest-neighbour graph, combinatorial Laplacian (the default)
  kPaper,           ///< seed 000 as written: complete graph, normalised Laplacian
};

struct TrainOptions {
  std::string dataset_dir;  ///< a dataset folder to segment, or
  std::string areas_path;   ///< an area log recorded by the firmware (harmoloc --record-areas)
  std::string labels_path;
  algorithms::ThresholdSet thresholds;
  int unlabelled = -1;            ///< how many unlabelled frames; -1: ratio x labelled
  double unlabelled_ratio = 2.2;  ///< seed 000's best: 64 labelled + 140 unlabelled
  int max_labelled = -1;          ///< use at most this many labels (evenly spread); -1: all
  std::vector<int> boards;        ///< 0-based board indices used as features; empty: choose
  bool select_boards = true;      ///< with boards empty: drop boards that do not help (CV)
  int folds = 5;
  int cv_gap = 0;                 ///< see algorithms::SelectionOptions::gap
  double min_improvement = 0.25;  ///< see algorithms::SelectionOptions::min_improvement
  /// Known-place dissimilarity bound = this x the 99th percentile of the training samples'
  /// leave-one-out dissimilarity (docs/training.md).
  double known_place_margin = 1.5;
  TrainMethod method = TrainMethod::kNeighbourGraph;
  bool forward_map = true;  ///< also learn the forward map the particle filter weighs boards with
  ForwardMapOptions forward;
};

struct AxisReport {
  double sigma = 0, gamma = 0, cv_rmse_m = 0;
  int neighbours = 0;
};

struct BoardStep {
  std::vector<int> boards;  ///< 0-based board indices in use after this step
  int dropped = -1;         ///< the board this step dropped (-1: the starting set)
  double cv_rmse_x_m = 0, cv_rmse_y_m = 0;
};

struct TrainReport {
  std::size_t frames = 0, labelled = 0, unlabelled = 0, labels_unmatched = 0, empty_frames = 0;
  AxisReport x, y;
  std::vector<int> boards;           ///< chosen feature boards, 0-based
  std::vector<int> constant_boards;  ///< boards left out because their area never changed
  std::vector<BoardStep> board_steps;
  double known_place_bound = 0;    ///< nearest-sample distance bound, feature units
  double dissimilarity_bound = 0;  ///< Bray-Curtis bound to the nearest sample
  double segment_ms = 0, train_ms = 0;
  bool has_forward_map = false;
  ForwardMapReport forward;
  double forward_ms = 0;
};

/// The board areas of every frame of a run, in time order.
struct AreaSeries {
  std::uint32_t image_width_px = 0, image_height_px = 0;
  std::vector<std::uint64_t> timestamp_ns;
  std::vector<algorithms::AreaVector> areas;
  double segment_ms = 0;
};

/// Segments a dataset folder with @p thresholds (the firmware's own segmentation).
AreaSeries segment_dataset(const std::string& dataset_dir,
                           const algorithms::ThresholdSet& thresholds);
/// Reads an area log, checking that it was measured with @p thresholds.
AreaSeries read_area_series(const std::string& areas_path,
                            const algorithms::ThresholdSet& thresholds);

/// Trains on measured areas; fills @p map. Throws std::runtime_error with one line on bad input.
TrainReport train_on_areas(const AreaSeries& run, const std::vector<StampedPose>& labels,
                           const TrainOptions& options, algorithms::MapFile& map);

/// Reads the run (dataset_dir or areas_path) and the labels, then trains.
TrainReport train_map(const TrainOptions& options, algorithms::MapFile& map);

}  // namespace harmoloc::sim_host
