#pragma once
/// @file Placing every frame of a training run by its wheel odometry between the labels.
///
/// Labels are sparse (a pose every 20 cm or more along a long route); the encoders between them
/// are dense and good over short distances. This smoother finds the trajectory that follows the
/// odometry and passes through every label: a least-squares problem over a chain of poses (one
/// at every frame and label time), odometry increments as relative-pose measurements, labels as
/// position (and, where they carry one, heading) measurements, solved by Gauss-Newton with a
/// sparse factorisation. The result is a pose, with heading, for every frame, even when the
/// labels carry none. Each label is also predicted from the odometry between its two neighbours
/// alone (leave one out), which tells a mistyped or misdated label from the rest.
///
/// Host code (training): allocates freely, never runs in the cycle.

#include <cstdint>
#include <vector>

#include "harmoloc/algorithms/geometry.hpp"
#include "harmoloc/algorithms/odometry.hpp"

namespace harmoloc::algorithms {

/// The wheel counters at one time, unwrapped (cumulative ticks, any start).
struct OdometrySample {
  double t_s = 0.0;
  std::int64_t left_ticks = 0;
  std::int64_t right_ticks = 0;
};

/// Cumulative ticks of @p odometry (time-ordered, not empty) at @p t_s: linear between samples,
/// held beyond the ends.
void ticks_at(const std::vector<OdometrySample>& odometry, double t_s, double& left, double& right);

/// A labelled pose from an external reference.
struct PlacementLabel {
  double t_s = 0.0;
  double x_m = 0.0;
  double y_m = 0.0;
  double yaw_rad = 0.0;
  bool has_yaw = false;
};

struct PlacementOptions {
  /// Standard deviation of a label's position (the reference's accuracy).
  double label_sigma_m = 0.005;
  /// Standard deviation of a label's heading, where labels carry one.
  double label_yaw_sigma_rad = 0.05;
  /// Relative noise of the odometry's travel and turn per step (slip, uneven floor), and the
  /// floors per step. Only their ratio to the label noise matters much.
  double travel_noise = 0.02;
  double turn_noise = 0.02;
  double step_floor_m = 0.0002;
  double turn_floor_rad = 0.0005;
  int iterations = 20;
};

struct PlacementResult {
  /// Pose at each query time (map frame), heading included.
  std::vector<Pose2> poses;
  /// Distance travelled (sum of |travel|, metres) from the start of the odometry, at each query
  /// time: a run's own clock in space (a standing robot does not advance it).
  std::vector<double> travel_m;
  /// Travel to the nearest label (metres): how far the odometry had to carry the placement.
  std::vector<double> support_m;
  /// Per label: the distance between the label and its prediction from the odometry between its
  /// two neighbours (leave one out; -1 for the first and last label, which have one neighbour).
  std::vector<double> label_residual_m;
  /// Per label: the distance between the label and the smoothed trajectory.
  std::vector<double> label_fit_m;
  int gauss_newton_iterations = 0;
};

/// Unwraps counters that wrap at 2^counter_bits into cumulative ticks.
std::vector<OdometrySample> unwrap_counters(const std::vector<double>& t_s,
                                            const std::vector<std::uint32_t>& left,
                                            const std::vector<std::uint32_t>& right,
                                            std::uint8_t counter_bits);

/// Places the query times (ascending) by @p odometry (ascending times) between @p labels
/// (ascending times). Queries and labels outside the odometry's time span are clamped to its
/// ends. Throws std::invalid_argument with a one-line reason for fewer than 2 labels, labels
/// that do not increase in time, or no odometry.
PlacementResult place_by_odometry(const std::vector<double>& query_t_s,
                                  const std::vector<OdometrySample>& odometry,
                                  const DiffDriveGeometry& geometry,
                                  const std::vector<PlacementLabel>& labels,
                                  const PlacementOptions& options = {});

}  // namespace harmoloc::algorithms
