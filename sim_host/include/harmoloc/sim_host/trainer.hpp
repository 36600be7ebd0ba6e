#pragma once
/// @file The map trainer (seed 000, offline half): segments a recorded run, takes the frames whose
/// timestamps carry a label as labelled and an evenly spread subset of the rest as unlabelled,
/// chooses kernel width and regularisation per axis by cross-validation, solves eq. 8 and writes
/// the map.

#include <cstdint>
#include <string>
#include <vector>

#include "harmoloc/algorithms/map_codec.hpp"
#include "harmoloc/algorithms/segmentation.hpp"

namespace harmoloc::sim_host {

struct TrainOptions {
  std::string dataset_dir;
  std::string labels_path;
  algorithms::ThresholdSet thresholds;
  std::vector<std::string> board_names;
  int unlabelled = -1;            ///< how many unlabelled frames; -1: ratio x labelled
  double unlabelled_ratio = 2.2;  ///< seed 000's best: 64 labelled + 140 unlabelled
  std::vector<int> boards;        ///< 0-based board indices used as features; empty: every board
  int folds = 5;
};

struct AxisReport {
  double sigma = 0, gamma = 0, cv_rmse_m = 0;
};

struct TrainReport {
  std::size_t frames = 0, labelled = 0, unlabelled = 0, labels_unmatched = 0, empty_frames = 0;
  AxisReport x, y;
  double known_place_bound = 0;
  double segment_ms = 0, train_ms = 0;
};

/// Trains; fills @p map. Throws std::runtime_error with one line on bad input.
TrainReport train_map(const TrainOptions& options, algorithms::MapFile& map);

}  // namespace harmoloc::sim_host
