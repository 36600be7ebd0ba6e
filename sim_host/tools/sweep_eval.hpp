#pragma once
/// @file The sweep over random scenes (docs/sweep.md): for one scene of the random family, train
/// a map on its training run exactly as a robot owner would (its own colour windows, 64 labels,
/// the wheel odometry), then replay through the firmware's own cycle a test run of the same
/// route (other noise, other lighting), a run with kidnaps, a run with a person walking through
/// and a board moved, and a long nominal run for false alarms; and score each against the
/// targets. Everything is rendered in memory; nothing in the estimator knows the scene.

#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "harmoloc/algorithms/segmentation.hpp"
#include "harmoloc/firmware/config.hpp"
#include "harmoloc/sim_host/scenario.hpp"

namespace harmoloc::sim_host {

struct SweepOptions {
  bool nominal = true;
  bool kidnap = true;
  bool dynamic = true;
  bool long_run = true;
  /// Issue 20's floor runs: a map trained on the scene's coverage run, replayed on roams of the
  /// floor that the coverage run never drove (random_scene.hpp).
  bool floor = false;
  int roams = 2;          ///< roams of the floor (each 8 poses, other lighting and noise)
  int floor_kidnaps = 5;  ///< kidnaps in one more roam of the floor (0: none)
  /// The floor's map trained with heading terms (harmoloc-train --heading-terms).
  bool heading_terms = false;
  /// The maps keep the bearings over the axle's place, as without the camera's offset
  /// (harmoloc-train --camera-forward-m 0), for comparison.
  bool axle_bearings = false;
  /// The maps take the area's gain by column out of the harmonic features (harmoloc-train
  /// --column-gain).
  bool column_gain = false;
  bool visibility = false;     ///< floor: visibility asked for (harmoloc-train --visibility)
  bool no_visibility = false;  ///< floor: no visibility (harmoloc-train --no-visibility)
  /// floor: the visibility tables from the fitted geometry, the camera's height the scene's
  /// (as harmoloc-train with the camera's height known); false: from the frames near each place
  /// (harmoloc-train --visibility-from-frames).
  bool visibility_from_geometry = true;
  double geometry_noise_ratio = 1.0;  ///< GeometryTablesOptions::kernel_noise_ratio
  /// The floor map's column-to-angle law triangulated from the frames, not the fitted camera's
  /// (TrainOptions::law_from_geometry off).
  bool law_from_frames = false;
  bool refine_headings = false;
  /// The floor map projects the geometry's boards' bearings (harmoloc-train --projected-bearings).
  bool projected_bearings = true;
  /// With projected_bearings: their areas as well (harmoloc-train --projected-areas).
  bool projected_areas = true;
  int kidnaps = 20;            ///< kidnaps in the kidnap run (each >= 1 m)
  double long_minutes = 10.0;  ///< length of the long nominal run
  std::uint64_t filter_seed = 1;
  /// Errors count from this long after the first fix (the start-up target: under 5 cm within it).
  double settle_s = 2.0;
  /// The firmware's configuration the runs use (each scene's colour windows replace its
  /// thresholds, filter_seed its filter seed, the scene's robot its geometry).
  firmware::FirmwareConfig config = firmware::default_config();
  /// When set, each run's frames are written there as CSV (`seed-N-PART.csv`, write_trace).
  std::string trace_dir;
};

/// What one scene scored. Distances in metres, MSE in m^2; -1 where not measured.
struct SceneResult {
  std::uint64_t seed = 0;
  std::string summary;  ///< the scene in a line (resolution, boards, lens, route)
  std::string error;    ///< non-empty when a step failed (the message)
  // Training.
  double train_ms = 0.0;
  std::size_t train_frames = 0;
  double placement_rmse_m = -1.0;
  double placement_heading_rmse_deg = -1.0;
  /// The same for the floor's coverage run: how far the trainer placed its frames from the truth.
  double floor_placement_rmse_m = -1.0;
  double floor_placement_max_m = -1.0;
  double floor_placement_heading_rmse_deg = -1.0;
  double cv_rmse_x_m = -1.0, cv_rmse_y_m = -1.0;
  /// The map's centroid-column weight (0: areas only, docs/training.md).
  double column_weight = 0.0;
  /// The area's gain by column the trainer measured (0 and 0: none) and its observations.
  double column_gain_c2 = 0.0, column_gain_c4 = 0.0;
  std::size_t column_gain_observations = 0;
  /// The training run's ForwardMapReport::pass_heading_spread_rad.
  double pass_heading_spread_rad = -1.0;
  std::string boards_used;
  // Boards placed from their centroid columns (TrainReport::bearings), against the scene's board
  // centres; -1 when the calibration was not ok.
  std::size_t bearing_boards_placed = 0;
  double board_place_median_m = -1.0, board_place_max_m = -1.0;
  double bearing_residual_deg = -1.0;
  double bearing_half_fov_deg = -1.0;
  double bearings_ms = 0.0;
  // Nominal test run.
  double fix_mse_x_m2 = -1.0, fix_mse_y_m2 = -1.0;  ///< every frame with a fix
  double fix_known_fraction = -1.0;                 ///< of those, flagged a known place
  double no_board_fraction = -1.0;  ///< of the usable frames, those without a board: no fix
  double fix_known_mse_x_m2 = -1.0, fix_known_mse_y_m2 = -1.0;
  double first_fix_s = -1.0;   ///< run time of the first known-place fix
  double startup_s = -1.0;     ///< from the first fix until under 5 cm (for at least 1 s)
  double converge_s = -1.0;    ///< from the first fix until the error stays under 5 cm for good
  double fused_rmse_m = -1.0;  ///< after first fix + settle_s
  double fused_heading_rmse_deg = -1.0;
  double fused_max_m = -1.0;  ///< after first fix + settle_s
  /// Particles per cycle while the filter ran (the firmware's stats, filter.particles_mean): the
  /// capacity unless KLD-sampling (filter.kld) is on.
  double particles_mean = -1.0;
  // Kidnap run.
  std::size_t kidnaps = 0, kidnaps_detected = 0, kidnaps_recovered_1s = 0;
  double kidnap_mean_recovery_s = -1.0;
  std::vector<double> kidnap_misses_t_s;  ///< run times of the kidnaps not back within 1 s
  // Dynamic run (a person walks through, a board is moved).
  double dynamic_max_m = -1.0;
  double dynamic_rmse_m = -1.0;
  // Long nominal run.
  double long_minutes = 0.0;
  std::size_t long_false_alarms = 0;
  double long_max_m = -1.0;
  double long_rmse_m = -1.0;
  // Floor runs (SweepOptions::floor): the coverage run's training and the roams, pooled.
  std::string floor_error;  ///< non-empty when the floor part failed (the message)
  std::string floor_summary;
  std::size_t floor_train_frames = 0;
  double floor_train_ms = 0.0;
  double floor_cv_rmse_x_m = -1.0, floor_cv_rmse_y_m = -1.0;
  double floor_pass_heading_spread_rad = -1.0;  ///< the coverage run's
  /// The coverage run's forward map: its heading terms' ridge (0: none), its validation RMS
  /// (feature units, over the modelled boards) and the same without heading terms.
  double floor_heading_ridge = 0.0;
  /// --visibility-from-geometry: the floor map's boards whose visibility tables come from the
  /// fitted geometry, and those the fit gave tables for (the others keep the kernel's).
  int floor_geometry_boards = 0;
  int floor_projected_boards = 0;  ///< boards whose bearings the floor map projects
  int floor_geometry_candidates = 0;
  /// The fitted geometry against the scene's truth (-1 or NaN: not fitted): the fitted boards'
  /// centres from the true ones (median and largest, metres), and the camera's field of view
  /// (pinhole, degrees), pitch (degrees) and offset ahead of the axle (metres), fitted less true.
  double floor_geometry_board_error_median_m = -1.0;
  double floor_geometry_board_error_max_m = -1.0;
  double floor_geometry_fov_error_deg = std::numeric_limits<double>::quiet_NaN();
  double floor_geometry_pitch_error_deg = std::numeric_limits<double>::quiet_NaN();
  double floor_geometry_forward_error_m = std::numeric_limits<double>::quiet_NaN();
  /// --refine-headings: rounds whose refit held, and the RMS of the coverage run's heading moves.
  int floor_heading_rounds = 0;
  double floor_heading_offset_rms_deg = 0.0;
  /// The floor map's column-to-angle law is the fitted camera's (GeometryReport::law_from_camera),
  /// and the optical axis's image angle under it, where the map's angle gain is centred (degrees
  /// right of the centre column; NaN: not taken).
  bool floor_law_from_camera = false;
  double floor_law_axis_deg = std::numeric_limits<double>::quiet_NaN();
  double floor_heading_bandwidth_m = 0.0;  ///< their wide kernel (0: the narrow one)
  double floor_validation_rmse = -1.0, floor_mean_validation_rmse = -1.0;
  /// The share of the circle of headings the floor map covers near the coverage run (-1: none).
  double floor_covered_heading_fraction = -1.0;
  double floor_roam_s = 0.0;  ///< the roams' run time
  /// The nearby pose test's draws in the roams, not the kidnap roam (filter.nearby_draws).
  std::uint64_t floor_nearby_draws = 0;
  /// The filter's particles a cycle in the roams, on average (filter.particles_mean): the
  /// capacity unless KLD-sampling adapts the count (-1: no roam cycle).
  double floor_particles_mean = -1.0;
  double floor_fix_mse_x_m2 = -1.0, floor_fix_mse_y_m2 = -1.0;  ///< every frame with a fix
  double floor_rmse_m = -1.0;  ///< after first fix + settle_s, every roam's frames
  double floor_heading_rmse_deg = -1.0;
  double floor_max_m = -1.0;
  /// Share of those frames reported nominal (health) with an error above 10 cm.
  double floor_nominal_over_10cm = -1.0;
  /// The same with a published quality above 0 as well (ODOMETRY's quality: a position spread
  /// under 10 cm): the frames whose error the pose's own figures do not own up to.
  double floor_vouched_over_10cm = -1.0;
  /// Share of those frames reported nominal at all: a health that says "nominal" less often
  /// lowers the share above, and this says how much of the floor it still vouches for.
  double floor_nominal_share = -1.0;
  /// A roam with kidnaps to anywhere on the floor (SweepOptions::floor_kidnaps): how many, and
  /// how many the filter confirmed and brought back under 10 cm within 2 s (for 0.5 s).
  std::size_t floor_kidnaps = 0, floor_kidnaps_recovered_2s = 0;
  /// In that roam, from the first fix + settle_s: the share of its frames reported nominal with
  /// an error above 10 cm, and of those with a quality above 0 (a kidnapped robot's pose before
  /// the filter finds it again; -1: no such roam).
  double floor_kidnap_nominal_over_10cm = -1.0;
  double floor_kidnap_vouched_over_10cm = -1.0;
  double seconds = 0.0;  ///< wall time of the scene's evaluation
};

using SweepProgress = std::function<void(const std::string& step)>;

/// Evaluates the random scene @p seed.
SceneResult evaluate_random_scene(std::uint64_t seed, const SweepOptions& options,
                                  const SweepProgress& progress = nullptr);

/// Evaluates an explicit scene with the given colour windows (the project's own default scene
/// is evaluated this way beside the random ones).
SceneResult evaluate_scene(const Scenario& scene, const algorithms::ThresholdSet& thresholds,
                           std::uint64_t seed, const SweepOptions& options,
                           const SweepProgress& progress = nullptr);

}  // namespace harmoloc::sim_host
