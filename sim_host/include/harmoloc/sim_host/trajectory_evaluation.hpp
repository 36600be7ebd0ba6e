#pragma once
/// @file Scoring of an estimated trajectory against ground truth: each estimate pose against the
/// truth interpolated at its time. No spatial alignment: both are in the map frame, and an
/// offset between them is an error the report must show. Host only.

#include <cstddef>
#include <vector>

#include "harmoloc/dataset/tum.hpp"

namespace harmoloc::sim_host {

/// The error of one estimated pose against the ground truth interpolated at its time.
/// dx, dy = estimate - truth; heading = wrap(estimate yaw - truth yaw), in [-pi, pi).
struct ErrorSample {
  double t_s = 0.0;
  double dx_m = 0.0;
  double dy_m = 0.0;
  double position_m = 0.0;
  double heading_rad = 0.0;
};

struct EvaluateOptions {
  /// Leaves out the estimate poses earlier than truth.front().t_s + skip_initial_s (the filter's
  /// convergence). The window is anchored on the ground truth's start so that the fused estimate
  /// and the raw fixes are scored on the same stretch of time.
  double skip_initial_s = 0.0;
};

struct TrajectoryErrors {
  std::size_t count = 0;          ///< Poses scored.
  std::size_t outside_truth = 0;  ///< Estimate poses outside the truth's time span (not scored).
  std::size_t skipped = 0;        ///< Poses inside the span but within skip_initial_s.
  double skip_initial_s = 0.0;
  double rmse_x_m = 0.0;
  double rmse_y_m = 0.0;
  double rmse_position_m = 0.0;  ///< sqrt(mean(dx^2 + dy^2)).
  double mse_x_cm2 = 0.0;        ///< mean(dx^2), in cm^2 (as the harmonic-localizer paper reports).
  double mse_y_cm2 = 0.0;
  double mean_position_m = 0.0;
  double max_position_m = 0.0;
  double p95_position_m = 0.0;  ///< percentile(position errors, 95), see percentile().
  double rmse_heading_deg = 0.0;
  double max_heading_deg = 0.0;      ///< Largest |heading error|.
  std::vector<ErrorSample> samples;  ///< The scored poses, in time order.
};

/// Scores @p estimate against @p truth (both in time order, as read_tum returns them). Every
/// estimate pose whose time lies in the truth's span is compared with the truth interpolated at
/// that time. With no pose to score, returns count == 0 and zeros (the caller decides whether
/// that is an error).
TrajectoryErrors evaluate(const std::vector<dataset::StampedPose>& truth,
                          const std::vector<dataset::StampedPose>& estimate,
                          const EvaluateOptions& options = {});

/// The p-th percentile (0..100) of @p values with linear interpolation between closest ranks
/// (numpy's default): rank = p/100 * (n - 1). Returns 0 for an empty vector.
double percentile(std::vector<double> values, double p);

}  // namespace harmoloc::sim_host
