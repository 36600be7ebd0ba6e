#pragma once
/// @file Calibrating the wheel odometry from a labelled training run.
///
/// Two wheels are never exactly alike and the track that matters is where the tyres touch the
/// floor, not what the drawing says: a 0.5% difference between the wheels on a 15 cm track turns
/// the dead reckoning 2 degrees per metre. The filter corrects heading only through the
/// positions it causes, so such a bias becomes a standing offset of the fused pose (a random
/// scene of the sweep: 4 degrees and 4.7 cm RMSE against 0.9 degrees and 1.0 cm with exact
/// wheels). The training run holds what is needed to measure it: labels and the encoders
/// between them.
///
/// Method: every stretch of about `window_m` of travel between labels is dead-reckoned with the
/// scaled geometry and laid over its labels by the rotation and shift that fit best (heading is
/// free: labels need not carry one); the three scales (left wheel, right wheel, track) minimise
/// the labels' squared misfit over all stretches, with a weak prior at 1 so that a route without
/// turns leaves the track as configured. Gauss-Newton with numerical derivatives: three
/// parameters, a few dozen dead reckonings of the run.
///
/// Host code (training): allocates freely, never runs in the cycle.

#include <vector>

#include "harmoloc/algorithms/odometry.hpp"
#include "harmoloc/algorithms/route_placement.hpp"

namespace harmoloc::algorithms {

struct CalibrationOptions {
  /// Travel a stretch of labels spans (metres): long enough that a scale error shows, short
  /// enough that slip does not add up.
  double window_m = 2.0;
  /// Fewest labels in a stretch.
  int min_labels = 4;
  /// The prior's standard deviation on each scale around 1 (what a measured geometry is
  /// trusted to).
  double prior_sigma = 0.05;
  /// A label's position error (metres): the misfits' unit.
  double label_sigma_m = 0.005;
  int iterations = 12;
};

struct OdometryCalibration {
  /// False when the run has too few stretches to say anything: then the scale is 1.
  bool used = false;
  OdometryScale scale;
  int stretches = 0;
  /// RMS misfit of the labels in their stretches, with the geometry as configured and as
  /// calibrated (metres).
  double misfit_before_m = 0.0;
  double misfit_after_m = 0.0;
};

/// Measures @p geometry's scales from @p odometry (ascending times) and @p labels (ascending
/// times, at least 2). Never throws for data it can read: a run it cannot calibrate from returns
/// `used == false`.
OdometryCalibration calibrate_odometry(const std::vector<OdometrySample>& odometry,
                                       const DiffDriveGeometry& geometry,
                                       const std::vector<PlacementLabel>& labels,
                                       const CalibrationOptions& options = {});

}  // namespace harmoloc::algorithms
