#pragma once
/// @file Relative Pose Error (RPE), translation part, as evo's `evo_rpe` computes it, so that
/// users can compare the report's numbers with the tool they know. Where the absolute error
/// (trajectory_evaluation.hpp) says how far the estimate is from the truth, the relative error
/// says how much it drifts over a stretch: a constant offset costs nothing here.
///
/// For each pair (i, j) of estimate poses: E = (Q_i^-1 Q_j)^-1 (P_i^-1 P_j), with Q the ground
/// truth and P the estimate at the same times; the error is |translation(E)|. The pairs are evo's
/// "consecutive pairs" (its default, no --all_pairs):
/// - over a distance (evo: --delta 1 --delta_unit m): the path length walked along the
///   *estimate* (evo's default; it has --pairs_from_reference for the truth) is summed from pose
///   to pose; each time it reaches delta, that pose is an anchor and the sum restarts. As in evo,
///   the first anchor is the pose where the path first reaches delta (not pose 0).
/// - over a time (evo has no time unit; at a steady rate it is --delta N --delta_unit f with N =
///   rate x seconds): pose 0 is the first anchor, then each pose at least delta after the last
///   anchor.
/// Consecutive anchors form the pairs. Host only; allocates freely.

#include <cstddef>
#include <vector>

#include "harmoloc/algorithms/geometry.hpp"
#include "harmoloc/dataset/tum.hpp"

namespace harmoloc::sim_host {

/// The truth and the estimate at one estimate pose's time.
struct PosePair {
  double t_s = 0.0;
  algorithms::Pose2 truth;
  algorithms::Pose2 estimate;
};

/// Each estimate pose at or after @p from_s that lies in the truth's time span, with the truth
/// interpolated at its time (the same poses evaluate() scores).
std::vector<PosePair> pair_with_truth(const std::vector<dataset::StampedPose>& truth,
                                      const std::vector<dataset::StampedPose>& estimate,
                                      double from_s);

enum class DeltaUnit { kMetres, kSeconds };

struct RelativeErrorSample {
  double t_start_s = 0.0;
  double t_end_s = 0.0;
  double error_m = 0.0;
};

struct RelativeErrors {
  double delta = 0.0;
  DeltaUnit unit = DeltaUnit::kMetres;
  std::size_t pairs = 0;  ///< 0: the run is too short (or too still) for one pair.
  double rmse_m = 0.0;
  double mean_m = 0.0;
  double median_m = 0.0;  ///< numpy's median (the mean of the middle two for an even count)
  double max_m = 0.0;
  std::vector<RelativeErrorSample> samples;
};

/// The RPE translation part over @p delta metres or seconds (> 0). Pure.
RelativeErrors relative_errors(const std::vector<PosePair>& poses, double delta, DeltaUnit unit);

}  // namespace harmoloc::sim_host
