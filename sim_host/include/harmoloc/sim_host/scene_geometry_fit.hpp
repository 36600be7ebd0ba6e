#pragma once
/// @file The camera and every board fitted together to a training run's sightings. The trainer
/// knows the camera only roughly (the field of view a bearing calibration implies, a typical lens,
/// a guess of the pitch); the boards' projections over a run seen from many places and headings
/// pin both down: the camera's field of view, lens (k1, k2), principal point, pitch and forward
/// offset, and each board's centre, size and facing. The camera's height stays as
/// given: a camera and a scene both scaled in height about the floor look alike only through
/// the height, so it is the fit's gauge (a tape measure gives it to a centimetre).
///
/// First each board is fitted alone under the rough camera (its residual scales widened 8 times,
/// facings tried all round); then the camera and all boards seen from enough places are fitted
/// at once (robust Levenberg-Marquardt, the scales narrowed 8, 4, 2 and 1 times); last each board
/// is refitted alone under the fitted camera for its own figures.
#include <cstddef>
#include <vector>

#include "harmoloc/sim_host/board_geometry_fit.hpp"

namespace harmoloc::sim_host {

struct SceneFitOptions {
  BoardFitOptions board;
  /// Of the joint fit's last run (a quarter of it for each of the three wide runs before).
  int max_iterations = 40;
  /// The camera and the boards' starts are a fit already (heading_refinement.hpp fits again
  /// after moving the headings a little): no boards alone under the rough camera and no widened
  /// runs, only the last joint run and the boards' own figures.
  bool from_fit = false;
};

struct SceneGeometryFit {
  bool ok = false;  ///< at least two boards fitted, and the camera with them
  CameraSpec camera;
  std::vector<BoardFit> boards;  ///< one per board, in order
  int rounds = 0;                ///< joint fits run
  /// Over the fitted boards' sightings within Huber's threshold.
  double rms_sqrt_area = 0.0;
  double rms_column_px = 0.0;
  double rms_row_px = 0.0;
};

/// Fits @p camera_start (all but its height, resolution and light) and @p board_starts
/// (start_board_geometry) to @p sightings (one list per board).
SceneGeometryFit fit_scene_geometry(const CameraSpec& camera_start,
                                    const std::vector<std::vector<BoardSighting>>& sightings,
                                    const std::vector<BoardSpec>& board_starts,
                                    const SceneFitOptions& options = {});

}  // namespace harmoloc::sim_host
