#pragma once
/// @file The map trainer (Wu & Qin 2010, offline half): measures the board areas of a recorded run
/// (or reads them from an area log), takes the frames whose timestamps carry a label as labelled
/// and an evenly spread subset of the rest as unlabelled, chooses the feature boards, the graph
/// and the kernel widths by cross-validation, solves eq. 8 and writes the map
/// (docs/training.md).

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "harmoloc/algorithms/bearing_calibration.hpp"
#include "harmoloc/algorithms/harmonic_selection.hpp"
#include "harmoloc/algorithms/map_codec.hpp"
#include "harmoloc/algorithms/odometry_calibration.hpp"
#include "harmoloc/algorithms/segmentation.hpp"
#include "harmoloc/dataset/tum.hpp"
#include "harmoloc/sim_host/forward_map_geometry.hpp"
#include "harmoloc/sim_host/forward_map_training.hpp"
#include "harmoloc/sim_host/heading_refinement.hpp"
#include "harmoloc/sim_host/label_offset.hpp"
#include "harmoloc/sim_host/scene_geometry_fit.hpp"
#include "harmoloc/sim_host/training_odometry.hpp"

namespace harmoloc::sim_host {

/// How eq. 8 is posed.
enum class TrainMethod {
  kNeighbourGraph,  ///< k-nearest-neighbour graph, combinatorial Laplacian (the default)
  kPaper,           ///< Wu & Qin 2010 as written: complete graph, normalised Laplacian
};

struct TrainOptions {
  std::string dataset_dir;  ///< a dataset folder to segment, or
  std::string areas_path;   ///< an area log recorded by the firmware (harmoloc --record-areas)
  /// With an area log: the run's encoder log (candump log or GPIO recording), decoded with
  /// can_layout and geometry (the config's). A dataset folder brings its own.
  std::string encoders_path;
  algorithms::EncoderFrameLayout can_layout;
  algorithms::DiffDriveGeometry geometry;
  std::string labels_path;
  /// Added to every label's time: the external reference's clock against the robot's.
  double label_offset_s = 0.0;
  /// Estimate that offset from the run's wheel odometry instead (label_offset.hpp).
  bool label_offset_auto = false;
  /// Without odometry, a label names the frame whose timestamp is within this of its own.
  std::uint64_t label_tolerance_ns = 500'000;
  /// Place every frame by the wheel odometry between the labels (when the run has odometry):
  /// the forward map and, where cross-validation prefers it, the harmonic map use every frame.
  bool use_odometry = true;
  /// Placement: a label farther than this from where the odometry between its neighbours puts
  /// it, and farther than label_outlier_ratio x the labels' median such distance, is refused.
  double label_outlier_m = 0.10;
  double label_outlier_ratio = 8.0;
  /// Frames before the first label or after the last are used while the odometry has carried
  /// them at most this far from it.
  double max_extrapolation_m = 0.5;
  /// Harmonic samples when every frame is placed (evenly spread over the run; capacity 4096).
  int max_placed_samples = 2048;
  /// Also try the kernel with each board in units of its noise (kept where CV prefers it).
  bool noise_weighted_kernel = true;
  /// Also try eq. 9's local linear correction (kept, with the ridge CV prefers, where it beats
  /// the plain kernel average by 5% or more).
  bool local_linear = true;
  /// Also try the boards' centroid columns in the kernel (HarmonicModel::column_weight; kept,
  /// with the weight CV prefers, where CV improves by 5% or more). Off for a co-processor's map.
  bool column_features = true;
  /// Measure the area's gain by column on the run's passes and remove it from the harmonic
  /// features (algorithms/column_gain.hpp; map format 13). Off by default (plain areas, as before
  /// it): on the random scenes it recovered more kidnaps and bettered the fused pose, but on the
  /// strongest barrel lens a few fixes at a turn went far off, and one dynamic run broke its
  /// 10 cm target (docs/sweep.md, 2026-12-02 (morning)).
  bool column_gain = false;
  /// Frames held out in cross-validation (evenly spread).
  int max_cv_queries = 400;
  /// Cross-validation leaves out a held-out frame's own pass: the frames within this much
  /// travel of it.
  double same_pass_m = 0.10;
  algorithms::ThresholdSet thresholds;
  int unlabelled = -1;            ///< how many unlabelled frames; -1: ratio x labelled
  double unlabelled_ratio = 2.2;  ///< Wu & Qin's best: 64 labelled + 140 unlabelled
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
  /// With the forward map from frames placed by odometry: also each board's bearing (the lens's
  /// law learnt from the run, docs/bearings.md).
  bool bearings = true;
  /// Also fit the camera and the boards' geometry to the placed frames (scene_geometry_fit.hpp)
  /// and report it, on any map. Needs the bearings, row sums in the areas and the camera's
  /// height (the fit's gauge). Takes seconds to tens of seconds.
  bool fit_geometry = false;
  /// A floor map's visibility tables from the geometry fitted to the run (fitted for them when
  /// fit_geometry is off), board by board where it predicts the run's areas better than the
  /// kernel means (forward_map_geometry.hpp). Where the camera's height is not known, or the fit
  /// fails, the kernel's tables stay and GeometryReport says why. No effect on a route's map.
  bool visibility_from_geometry = true;
  /// With visibility_from_geometry: an unknown camera height is an error (thrown before any
  /// work), not a fall back to the kernel's tables (`harmoloc-train --visibility-from-geometry`).
  bool geometry_tables_required = false;
  /// Where a map takes visibility tables from the geometry: its column-to-angle law from the
  /// fitted camera too (GeometryReport::law_from_camera), the forward map trained again with it.
  /// false: the law triangulated from the frames (calibrate_bearings) stays.
  bool law_from_geometry = true;
  /// Where boards take visibility tables from the geometry: the map also stores the fitted
  /// camera and those boards' outlines (map version 15), and the filter projects their bearings
  /// from each particle's pose instead of reading the cells' (projected_bearing.hpp).
  bool projected_bearings = true;
  /// With projected_bearings: the projected boards' areas from the projection too, where it
  /// predicts the run's areas at least as closely as their tables (map version 17). On by
  /// default with the bearings: on the 30 random floors 4.7 / 18.2 cm RMSE median / worst
  /// against 7.0 / 22.7 without (docs/sweep.md, 2026-12-06 late).
  bool projected_areas = true;
  GeometryTablesOptions geometry_tables;
  /// The camera's optical centre above the floor (metres); 0: the run's (the dataset's
  /// camera.height_m), else unknown.
  double camera_height_m = 0.0;
  SceneFitOptions geometry_fit;
  /// Where the geometry is fitted: refine the placed frames' headings by the boards it holds
  /// (heading_refinement.hpp), and train the forward map and its tables with them. Experimental.
  bool refine_headings = false;
  HeadingRefinementOptions heading_refinement;
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

/// How the frames were placed by odometry between the labels.
struct PlacementReport {
  bool used = false;
  std::size_t frames = 0;         ///< frames placed (with a board in view)
  std::size_t beyond_labels = 0;  ///< of the run's frames, too far outside the labelled stretch
  double travel_m = 0.0;          ///< distance driven over the run
  double label_spacing_m = 0.0;   ///< median travel between consecutive labels
  double median_label_residual_m = 0.0;  ///< leave-one-out, see algorithms::PlacementResult
  double worst_label_residual_m = 0.0;
  int worst_label = -1;  ///< 0-based index into the labels
  /// The odometry measured against the labels (algorithms/odometry_calibration.hpp): the scales
  /// the placement used and the map carries, the stretches' misfit before and after.
  algorithms::OdometryCalibration odometry;
  bool harmonic_from_placed = false;  ///< the harmonic map uses every placed frame
  double cv_rmse_placed_x_m = 0, cv_rmse_placed_y_m = 0;  ///< on the labelled frames
  double cv_rmse_labels_x_m = 0, cv_rmse_labels_y_m = 0;  ///< the labels-only model, same test
  std::vector<algorithms::Pose2> poses;                   ///< per frame of the run (where placed)
  std::vector<double> times_s;  ///< per frame of the run, the dataset clock
  std::vector<bool> placed;
};

/// The area's gain by column measured on the run's passes (algorithms/column_gain.hpp).
struct ColumnGainReport {
  /// False with too few observations or a fit beyond a factor of 4: the map keeps plain areas.
  bool fitted = false;
  std::size_t pairs = 0;         ///< pairs of frames over one place at one heading
  std::size_t observations = 0;  ///< boards whole in both frames of a pair
  algorithms::ColumnGain gain;
};

/// The camera and the boards fitted to the run (TrainOptions::fit_geometry).
struct GeometryReport {
  bool tried = false;
  std::string skipped;  ///< why it was not tried, when asked for
  CameraSpec camera_start;
  SceneGeometryFit fit;
  /// The fit's residual scales were taken to the run's frame size (for_frame): with the
  /// 320 x 240 frame's scales fewer than two boards fitted.
  bool frame_scales = false;
  double ms = 0.0;
  /// TrainOptions::refine_headings: rounds whose refit held (0: the headings are the
  /// placement's), the heading each placed frame moved by (counter-clockwise, one per frame the
  /// trainer placed, 0 for a frame without row sums) and its RMS.
  int heading_rounds = 0;
  std::vector<double> heading_offset_rad;
  double heading_offset_rms_rad = 0.0;
  /// TrainOptions::visibility_from_geometry: what the map took from the fit.
  bool tables_asked = false;
  GeometryTablesReport tables;
  /// TrainOptions::law_from_geometry: the map's column-to-angle law is the fitted camera's (the
  /// tables took at least one board from the geometry with it), and that law.
  bool law_from_camera = false;
  double law_a1_rad = 0.0, law_a3_rad = 0.0;
  /// The fitted camera's optical axis, as an image angle under its law (radians, positive to the
  /// right of the centre column): the principal point's offset; the map's visibility_axis_rad.
  double law_axis_rad = 0.0;
  /// The rows the law was fitted at (column_law_of): the deciles of the rows the training
  /// frames saw the boards at, as fractions of the height; empty: the middle rows.
  std::vector<double> law_rows;
  /// TrainOptions::projected_bearings: boards whose bearings the map projects (0: none), and per
  /// board how far the projection misses the run's measured angles (projected_bearing_spread).
  std::size_t projected_boards = 0;
  std::vector<double> projected_spread_rad;
  /// TrainOptions::projected_areas: per board the projected areas' noise
  /// (project_areas_from_geometry; 0: not fitted), and how many boards took them.
  std::vector<double> projected_area_sigma;
  std::vector<char> projected_area_taken;
  std::size_t projected_area_boards = 0;
};

struct TrainReport {
  std::size_t frames = 0, labelled = 0, unlabelled = 0, labels_unmatched = 0, empty_frames = 0;
  AxisReport x, y;
  std::vector<int> boards;           ///< chosen feature boards, 0-based
  std::vector<int> constant_boards;  ///< boards left out because their area never changed
  std::vector<BoardStep> board_steps;
  double known_place_bound = 0;    ///< nearest-sample distance bound, feature units
  double dissimilarity_bound = 0;  ///< Bray-Curtis bound to the nearest sample
  /// The per-sample fix errors stored in the map (HarmonicModel::fix_error_m): median and
  /// largest over the samples (metres; 0 when the map has none).
  double local_fix_error_median_m = 0, local_fix_error_max_m = 0;
  double segment_ms = 0, train_ms = 0;
  PlacementReport placement;
  bool noise_weighted = false;  ///< the kernel weighs each board by its noise (CV preferred it)
  /// Ridge of eq. 9's local linear correction (0: the plain kernel average), and the CV RMS
  /// error per axis the plain average had (metres), for the report.
  double local_linear_ridge = 0.0;
  double kernel_average_cv_rmse_x_m = 0.0, kernel_average_cv_rmse_y_m = 0.0;
  /// The centroid columns' weight CV chose (0: areas only), and the CV RMS error per axis
  /// without them (metres; 0 when columns were not tried).
  double column_weight = 0.0;
  double areas_only_cv_rmse_x_m = 0.0, areas_only_cv_rmse_y_m = 0.0;
  ColumnGainReport column_gain;
  bool has_forward_map = false;
  ForwardMapReport forward;
  /// The offset added to the labels' times, and the estimate when it was estimated.
  double label_offset_s = 0.0;
  bool label_offset_estimated = false;
  LabelOffsetEstimate label_offset;
  /// Whether the labels carry a heading (a non-zero yaw), which the placement then follows.
  bool labels_have_yaw = false;
  double forward_ms = 0;
  /// The boards' places and the column-to-angle law, learnt from the placed frames' centroid
  /// columns (algorithms/bearing_calibration.hpp; not yet in the map). Not ok when the run's
  /// areas have no columns, the frames were not placed by odometry, or fewer than two boards
  /// could be placed.
  algorithms::BearingCalibration bearings;
  double bearings_ms = 0;
  GeometryReport geometry;
};

/// The board areas of every frame of a run, in time order.
struct AreaSeries {
  std::uint32_t image_width_px = 0, image_height_px = 0;
  std::vector<std::uint64_t> timestamp_ns;
  std::vector<algorithms::AreaVector> areas;
  double segment_ms = 0;
  OdometryTrack odometry;  ///< the run's wheel odometry; empty when unknown
  /// The camera's offset ahead of the axle (metres; the dataset's camera.forward_offset_m); NaN
  /// when unknown. TrainOptions::forward.camera_forward_m, when given, comes first.
  double camera_forward_m = std::numeric_limits<double>::quiet_NaN();
  /// The camera's height above the floor (metres; the dataset's camera.height_m); NaN when
  /// unknown. TrainOptions::camera_height_m, when given, comes first.
  double camera_height_m = std::numeric_limits<double>::quiet_NaN();
};

/// Segments a dataset folder with @p thresholds (the firmware's own segmentation).
AreaSeries segment_dataset(const std::string& dataset_dir,
                           const algorithms::ThresholdSet& thresholds);
/// Reads an area log, checking that it was measured with @p thresholds.
AreaSeries read_area_series(const std::string& areas_path,
                            const algorithms::ThresholdSet& thresholds);

/// Trains on measured areas; fills @p map. Throws std::runtime_error with one line on bad input.
TrainReport train_on_areas(const AreaSeries& run, const std::vector<dataset::StampedPose>& labels,
                           const TrainOptions& options, algorithms::MapFile& map);

/// Refuses a map no robot should use, with one line naming the reason: coordinates outside the
/// labelled region (plus the extrapolation margin), or a cross-validated error above a quarter of
/// the labels' extent.
void check_trained_map(const TrainReport& report, const std::vector<dataset::StampedPose>& labels,
                       const algorithms::MapFile& map, const TrainOptions& options);

/// Reads the run (dataset_dir or areas_path) and the labels, trains, and checks the map
/// (check_trained_map).
TrainReport train_map(const TrainOptions& options, algorithms::MapFile& map);

}  // namespace harmoloc::sim_host
