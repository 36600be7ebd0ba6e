#pragma once
/// @file What the pieces of the map trainer share (private to sim_host/src/): training from the
/// labelled frames alone (trainer_from_labels.cpp), the frames placed by odometry between the
/// labels (trainer_placement.cpp), the labels' checks (trainer_checks.cpp), and small helpers
/// (trainer_on_areas.cpp). The public side is harmoloc/sim_host/trainer.hpp.

#include <chrono>
#include <cmath>
#include <cstddef>
#include <vector>

#include "harmoloc/algorithms/map_codec.hpp"
#include "harmoloc/algorithms/route_placement.hpp"
#include "harmoloc/dataset/tum.hpp"
#include "harmoloc/sim_host/forward_map_training.hpp"
#include "harmoloc/sim_host/trainer.hpp"

namespace harmoloc::sim_host::trainer_detail {

// trainer_on_areas.cpp
double ms_since(std::chrono::steady_clock::time_point t0);
double quantile(std::vector<double> v, double q);

// trainer_from_labels.cpp
void train_from_labels(const AreaSeries& run, const std::vector<dataset::StampedPose>& labels,
                       const TrainOptions& opt, algorithms::MapFile& map, TrainReport& report);

// trainer_placement.cpp
algorithms::PlacementResult place_frames(const AreaSeries& run,
                                         const std::vector<dataset::StampedPose>& labels,
                                         const TrainOptions& opt, PlacementReport& report);

// trainer_column_gain.cpp: the gain fitted on pairs of @p frames over one place at one heading
// (boards [0, @p boards)); plain areas (both coefficients 0) when it cannot be.
algorithms::ColumnGain fit_column_gain(const AreaSeries& run,
                                       const std::vector<PlacedFrame>& frames, std::size_t boards,
                                       ColumnGainReport& report);

// trainer_checks.cpp
void check_labels(const std::vector<dataset::StampedPose>& labels);

/// The camera and the boards fitted to the placed @p frames (TrainOptions::fit_geometry), the
/// camera @p camera_height_m above the floor (0: unknown, not fitted).
GeometryReport fit_training_geometry(const AreaSeries& run, const std::vector<PlacedFrame>& frames,
                                     const algorithms::BearingCalibration& bearings,
                                     const TrainOptions& opt, double camera_height_m);

/// The camera's height the fit takes: TrainOptions::camera_height_m, else the run's; 0 when
/// neither knows it.
double training_camera_height_m(const AreaSeries& run, const TrainOptions& opt);
// The boards a map may use: those the user chose (0-based), or all @p boards; throws on a board
// that is not configured.
std::vector<int> candidate_boards(const std::vector<int>& chosen, std::size_t boards);

// The report's account of a board selection, step by step, in board numbers: either selection
// (the harmonic map's from the labels, the kernel map's on placed frames) has the same steps.
template <typename Step>
void report_board_steps(const std::vector<Step>& steps, const std::vector<int>& candidates,
                        std::vector<BoardStep>& out) {
  for (const Step& step : steps) {
    BoardStep b;
    for (int c : step.columns) b.boards.push_back(candidates[static_cast<std::size_t>(c)]);
    b.dropped = step.dropped >= 0 ? candidates[static_cast<std::size_t>(step.dropped)] : -1;
    b.cv_rmse_x_m = std::sqrt(step.cv_mse_x);
    b.cv_rmse_y_m = std::sqrt(step.cv_mse_y);
    out.push_back(b);
  }
}

}  // namespace harmoloc::sim_host::trainer_detail
