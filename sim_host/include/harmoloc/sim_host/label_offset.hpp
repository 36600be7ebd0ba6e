#pragma once
/// @file The constant offset between an external reference's clock and the robot's, estimated
/// from the training run's wheel odometry (harmoloc-train --label-offset auto).
///
/// Over a short stretch the odometry is good: the distance it says the robot covered between two
/// labels' times must be the distance between the labels. With the labels' times shifted by the
/// wrong offset, the odometry measures the distance over the wrong stretch, which differs wherever
/// the robot speeds up, slows down or turns. The estimate is the shift that makes them agree best
/// (least squares over pairs of labels up to four apart, searched on a 5 ms grid). A run at
/// constant speed cannot tell: when the estimate's standard error is above 50 ms none is given.

#include <string>
#include <vector>

#include "harmoloc/dataset/tum.hpp"
#include "harmoloc/sim_host/training_odometry.hpp"

namespace harmoloc::sim_host {

struct LabelOffsetEstimate {
  bool found = false;
  /// Add this to every label's time to put it on the robot's clock.
  double offset_s = 0.0;
  /// RMS misfit (m) of the label distances at the best offset and at no offset.
  double rms_at_best_m = 0.0, rms_at_zero_m = 0.0;
  /// The smallest misfit at least 0.2 s away from the best, over the best (RMS ratio).
  double contrast = 0.0;
  /// The estimate's standard error (least squares); an estimate needs 50 ms or better.
  double standard_error_s = 0.0;
  std::string why_not;  ///< when !found
};

/// Searches offsets within +-@p max_offset_s.
LabelOffsetEstimate estimate_label_offset(const OdometryTrack& odometry,
                                          const std::vector<dataset::StampedPose>& labels,
                                          double max_offset_s = 2.0);

}  // namespace harmoloc::sim_host
