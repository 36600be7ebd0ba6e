#pragma once
/// @file Learning the forward map (algorithms/forward_map.hpp) from a training run: each frame
/// gets a position, from its labels where they are close in time (the robot moves smoothly
/// between two labels half a second apart) and from the trained harmonic map elsewhere; each
/// grid cell then takes the kernel-weighted mean of the frames' board areas around it. The
/// kernel width is chosen, and each board's noise measured, against frames of other passes
/// (docs/filter.md).

#include <cstdint>
#include <limits>
#include <vector>

#include "harmoloc/algorithms/bearing_calibration.hpp"
#include "harmoloc/algorithms/forward_map.hpp"
#include "harmoloc/algorithms/geometry.hpp"
#include "harmoloc/algorithms/harmonic_model.hpp"
#include "harmoloc/dataset/tum.hpp"

namespace harmoloc::sim_host {

/// The heading terms' ridges harmoloc-train --heading-terms tries (ForwardMapOptions).
inline const std::vector<double> kHeadingRidges{0.1, 0.03, 0.01, 0.003, 0.001};

struct ForwardMapOptions {
  double max_label_gap_s = 1.0;  ///< interpolate between labels at most this far apart in time
  /// The grid stores the tiles within this distance of a training position.
  double margin_m = 0.25;
  double min_cell_m = 0.02;  ///< finest cell; coarser when the stored tiles exceed max_tiles
  /// Most tiles the map may store (0: the firmware's capacity, ForwardMap::kMaxTiles); less for
  /// a board whose build holds fewer (the bare-metal kernels: 64).
  std::size_t max_tiles = 0;
  std::vector<double> bandwidths_m{0.01, 0.015, 0.02, 0.03, 0.05};  ///< candidates
  /// Ridges tried for the heading terms (ForwardMap::has_heading_terms), times the kernel weight
  /// on the harmonic's two coefficients, cross-validated with the bandwidths against other
  /// passes; empty (the default): no heading terms. kHeadingRidges is the trainer's list
  /// (`harmoloc-train --heading-terms`). Not the default: on the floor runs of 19 random scenes
  /// they brought the heading and the kidnaps closer, the position only in the median
  /// (docs/sweep.md).
  std::vector<double> heading_ridges;
  /// Wide kernels tried for the heading terms too (with heading_ridges): a local-linear fit that
  /// reaches the lanes driven at the place's other headings (forward_map_training_fit.cpp).
  std::vector<double> heading_bandwidths_m{0.1, 0.2, 0.35};
  /// The heading terms are kept only when they lower the validation's mean square error by at
  /// least this share (a route's passes run one way: the terms fit its few degrees of wobble
  /// and gain nothing).
  double heading_terms_min_gain = 0.05;
  double exclude_same_pass_s = 1.0;  ///< validation leaves out frames this close in time
  /// With frames placed by odometry: validation leaves out frames this close in travel instead
  /// (a robot that stands still does not start another pass).
  double exclude_same_pass_m = 0.10;
  /// The camera's offset ahead of the axle (metres; the dataset's camera.forward_offset_m or
  /// `harmoloc-train --camera-forward-m`); NaN: not given. Given, the boards' bearings are kept
  /// over the camera's place and taken from frames of every heading (ForwardMap's
  /// bearing_camera_forward_m).
  double camera_forward_m = std::numeric_limits<double>::quiet_NaN();
  /// Visibility instead of heading terms (ForwardMap::has_visibility): where the bearings are
  /// seen from the camera's place, each cell also keeps every board's feature seen whole from
  /// there and its angular half-width. @c visibility asks for it on any map;
  /// @c visibility_on_floors (the default) on a floor map only (the passes' heading spread at
  /// least algorithms::kFloorMapPassHeadingSpread_rad), where on random floors it bettered the
  /// position, the largest error and the kidnaps (docs/sweep.md); both false: never.
  bool visibility = false;
  bool visibility_on_floors = true;
};

struct ForwardMapReport {
  std::size_t frames = 0;         ///< frames with a board in view
  std::size_t interpolated = 0;   ///< positioned from labels
  std::size_t from_harmonic = 0;  ///< positioned by the harmonic map (known place)
  std::size_t by_odometry = 0;    ///< placed by odometry between the labels
  double bandwidth_m = 0.0;
  std::size_t cells = 0;      ///< stored cells (the stored tiles' cells)
  std::vector<double> sigma;  ///< per board (feature units), 0 = not modelled
  /// The same without heading terms (equal to sigma when the map has none): the noise a model
  /// that sees no heading (the harmonic map) meets.
  std::vector<double> heading_blind_sigma;
  double validation_rmse = 0.0;  ///< over all modelled boards, feature units
  /// The heading terms' ridge when the map holds them (0: none), the validation RMS without them
  /// (then) and the best with them (whether kept or not; 0: not tried).
  double heading_ridge = 0.0;
  double mean_validation_rmse = 0.0;
  double heading_terms_validation_rmse = 0.0;
  /// The heading terms' wide kernel (0: the narrow one, bandwidth_m), and whether the cells'
  /// level comes from the narrow kernel (the wide fit's harmonic on the narrow mean).
  double heading_bandwidth_m = 0.0;
  bool heading_narrow_level = false;
  /// Median distance from a frame to the nearest frame of another pass (metres).
  double pass_spread_m = 0.0;
  /// Upper quartile of the heading difference between a frame and the nearest frame of another
  /// pass (radians; 0 without headings): a few degrees on a route (its passes run one way, or
  /// reverse along it), the lanes' heading difference on a floor driven at several headings.
  double pass_heading_spread_rad = 0.0;
  bool has_heading = false;
  /// With headings: the mean share of the circle of headings the map covers (ForwardMap's
  /// heading coverage) over the cells within a kernel width of the training run: about 0.3 on a
  /// route driven one way (a 90-degree reach around one heading), 0.6 forth and back, up to 1
  /// on a floor driven at every heading.
  double covered_heading_fraction = 0.0;
  /// Bearings (train_forward_map_placed with a law): per board, the spread of its world bearing
  /// between passes (radians, 0: not modelled), and the stored cells holding any bearing.
  bool has_bearings = false;
  /// Whether the map holds visibility (ForwardMapOptions::visibility), and its angle gain.
  bool visibility = false;
  /// Whether the options asked for it on this run (always, or on a floor), held or not.
  bool visibility_wanted = false;
  double visibility_angle_gain = 0.0;
  std::vector<double> bearing_sigma_rad;
  std::size_t bearing_cells = 0;
  std::size_t bearing_residuals = 0;  ///< frames x boards the spreads were measured on
  /// Where the bearings are seen from: the camera's offset ahead of the axle (0: the axle).
  double bearing_camera_forward_m = 0.0;
};

/// Fits @p out for @p board_count boards. @p areas_features holds every frame's board features
/// (area_scale x pixels, all boards), @p timestamps_ns their times; @p model is the trained
/// harmonic map (for frames no label pair covers). Throws std::runtime_error when fewer than
/// 8 frames can be positioned.
ForwardMapReport train_forward_map(const std::vector<std::vector<float>>& features,
                                   const std::vector<std::uint64_t>& timestamps_ns,
                                   const std::vector<dataset::StampedPose>& labels,
                                   const algorithms::HarmonicModel& model, std::size_t board_count,
                                   const ForwardMapOptions& options, algorithms::ForwardMap& out);

/// A frame with the pose the odometry placed it at (trainer_on_areas.cpp).
struct PlacedFrame {
  std::size_t index = 0;  ///< into the run's frames
  double t_s = 0.0;
  double travel_m = 0.0;  ///< distance driven since the start of the run
  algorithms::Pose2 pose;
};

/// Board bearings for the forward map: the lens's law and what each frame saw.
struct BearingObservations {
  double a1_rad = 0.0, a3_rad = 0.0;  ///< the law (algorithms/bearing_calibration.hpp)
  /// The optical axis's image angle under the law, where the visibility's angle gain is centred
  /// (ForwardMap::visibility_axis_rad); 0: the centre column (a law triangulated from frames).
  double axis_rad = 0.0;
  /// Per frame of the run (PlacedFrame::index) and board: the world bearing the frame saw the
  /// board at (yaw - angle of its centroid column), NaN where the board gave none.
  std::vector<std::vector<float>> world_rad;
  /// The same frames' boards' angular half-widths (radians): half the angle the square root of
  /// the board's pixels spans at the optical axis (the visibility's soft edge).
  std::vector<std::vector<float>> half_width_rad;
  /// Where each board stands (algorithms/bearing_calibration.hpp; empty: not known). The
  /// visibility carries a frame's view of a placed board to a nearby place by its distance and
  /// direction from there.
  std::vector<algorithms::BoardPlacement> placements;
};

/// Fits @p out to frames placed by odometry (every frame has a pose with heading); the kernel
/// width and each board's noise are validated against other passes by travel. With
/// @p bearings, each cell also gets every board's world bearing (the same kernel over the frames
/// of the nearest frame's direction that saw the board whole) and each board the spread of its
/// bearing between passes.
ForwardMapReport train_forward_map_placed(const std::vector<std::vector<float>>& features,
                                          const std::vector<PlacedFrame>& placed,
                                          std::size_t board_count, const ForwardMapOptions& options,
                                          algorithms::ForwardMap& out,
                                          const BearingObservations* bearings = nullptr);

}  // namespace harmoloc::sim_host
