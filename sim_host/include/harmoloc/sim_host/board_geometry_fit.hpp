#pragma once
/// @file A board's geometry (centre, size, the way its face looks) fitted to what a training run
/// saw of it: at every pose, segmentation's pixel count and centroid column and row. The camera
/// (intrinsics, lens, pose on the robot) is given; scene_geometry_fit.hpp fits it with the boards.
/// The model is project_board (board_projection.hpp): the fitted board predicts the board's area
/// and centroid from any pose and heading, also where the run never drove. This is the trainer's
/// floor model in the making (issue 20, docs/sweep.md: the study of 2026-12-02 found such a fit
/// predicts the areas of untrained paths about five times closer than the floor map's tables).
///
/// Robust Levenberg-Marquardt on three residuals a sighting: sqrt(area) (so near and far boards
/// weigh alike) and the centroid's column and row, each over its scale; Huber weights keep
/// sightings of a partly hidden board (a person, another board, a stand) from pulling the fit.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "harmoloc/algorithms/geometry.hpp"
#include "harmoloc/sim_host/lens.hpp"
#include "harmoloc/sim_host/scenario.hpp"

namespace harmoloc::sim_host {

/// One frame's view of the board: the robot's pose and what segmentation measured.
struct BoardSighting {
  algorithms::Pose2 pose;
  double area_px = 0.0;
  double centroid_u_px = 0.0;  ///< column, pixel centres at whole numbers
  double centroid_v_px = 0.0;  ///< row
};

/// The pixel figures of BoardFitOptions are for a frame of this size; for_frame takes them to
/// another.
constexpr int kBoardFitReferenceWidthPx = 320;
constexpr int kBoardFitReferenceHeightPx = 240;

struct BoardFitOptions {
  /// Sightings with fewer pixels are left out: a few pixels' centroid says little.
  double min_area_px = 40.0;
  /// At most this many sightings are used, evenly spaced through the run (the fit's cost grows
  /// with them and consecutive frames add little).
  std::size_t max_sightings = 400;
  std::size_t min_sightings = 12;
  /// Residual scales: sqrt(pixels), and pixels for the centroid.
  double sqrt_area_scale = 1.0;
  double centroid_scale_px = 1.0;
  /// Huber's threshold in scaled units.
  double huber = 3.0;
  /// A board's sightings pin its area, centre and facing but hardly the ratio of its width to
  /// its height: the areas give their product and the centroids move with the ratio only by
  /// perspective and at the frame's edge. Above 0: one more residual a board, ln(width / height)
  /// over this scale, which keeps the ratio near 1 where the sightings leave it free (at ln 3, a
  /// board 3 times wider than tall costs what a sighting one scale off does). Off by default:
  /// at ln 3 the 30 random floors' roams came out no better (docs/sweep.md, 2026-12-07 (6)).
  double aspect_log_scale = 0.0;
  int max_iterations = 60;
  /// Also start with the facing turned by +-40 and +-80 degrees (off when the start is a fit
  /// already).
  bool other_facings = true;
};

struct BoardFit {
  bool ok = false;  ///< enough sightings and the fit converged to a board in front of them
  /// The start's name, colour, shape, tilt and stand with the fitted centre, size and facing.
  BoardSpec board;
  std::size_t sightings_used = 0;
  /// Root mean square of the unscaled residuals over the sightings within Huber's threshold.
  double rms_sqrt_area = 0.0;
  double rms_column_px = 0.0;
  double rms_row_px = 0.0;
  /// Share of the sightings beyond Huber's threshold in any residual.
  double outlier_share = 0.0;
};

/// @p options, whose pixel figures are for a 320 x 240 frame, for a frame of @p width_px x
/// @p height_px: the centroid's scale grows with the width, sqrt(area)'s with the square root of
/// the frame's area and the smallest area with the frame's area. Unchanged for a 320 x 240 frame
/// or a size of 0. With a 320 x 240 frame's scales, most sightings of a 1280 x 720 random floor
/// fell beyond the robust threshold and no board was fitted; yet where those tight scales fit,
/// they fitted closer (docs/sweep.md), so the trainer takes these only as a fallback.
BoardFitOptions for_frame(BoardFitOptions options, std::uint32_t width_px, std::uint32_t height_px);

/// A start for fit_board_geometry from a board's place on the floor (@p x_m, @p y_m, as
/// calibrate_bearings triangulates it): the height whose projection best matches the centroid
/// rows, a square of the size the areas imply at their ranges, facing the mean of the poses it was
/// seen from. @p like gives the name, colour and shape.
BoardSpec start_board_geometry(const CameraSpec& camera, const LensModel& lens,
                               const std::vector<BoardSighting>& sightings, double x_m, double y_m,
                               const BoardSpec& like, const BoardFitOptions& options = {});

/// The sightings a fit uses: those with options.min_area_px or more, at most
/// options.max_sightings of them evenly spaced through @p all.
std::vector<BoardSighting> usable_sightings(const std::vector<BoardSighting>& all,
                                            const BoardFitOptions& options);

/// Fits @p start's centre, width, height and facing to @p sightings, from @p start and (with
/// options.other_facings) from starts with the facing turned by +-40 and +-80 degrees; the best of
/// those.
BoardFit fit_board_geometry(const CameraSpec& camera, const LensModel& lens,
                            const std::vector<BoardSighting>& sightings, const BoardSpec& start,
                            const BoardFitOptions& options = {});

}  // namespace harmoloc::sim_host
