#pragma once
/// @file A floor map's visibility tables (algorithms/forward_map.hpp, map format 10) from the
/// camera and the boards fitted to the training run (scene_geometry_fit.hpp) instead of the
/// kernel means of the frames near each place. The kernel means hold only where the run drove
/// near a place and saw a board whole from there; the geometry gives every place on the grid a
/// board's area seen whole from it, its bearing and its angular half-width, also between the
/// lanes and at headings the run never drove (docs/training.md).
///
/// A board takes the geometry's areas when they, as the firmware predicts them from the new
/// tables at the training frames' poses, come as close to the frames as the kernel tables' do
/// against other passes (GeometryTablesOptions); it keeps the kernel's bearings where the kernel
/// had one if their spread was no wider than the geometry's. The map's angle gain becomes the
/// projection's, and the boards that keep the kernel's tables are rescaled to it.
#include <cstddef>
#include <string>
#include <vector>

#include "harmoloc/algorithms/forward_map.hpp"
#include "harmoloc/algorithms/segmentation.hpp"
#include "harmoloc/sim_host/forward_map_training.hpp"
#include "harmoloc/sim_host/scene_geometry_fit.hpp"

namespace harmoloc::sim_host {

struct GeometryTablesOptions {
  /// A board takes the geometry's tables when its noise with them is at most this times the
  /// kernel tables' noise. The kernel's is measured against frames of other passes over the same
  /// place: its best case, which holds near the lanes the run drove and not between them or at
  /// other headings; the geometry's holds everywhere (a few parameters per board, fitted to
  /// thousands of frames). Below 1 the geometry must also win near the lanes.
  double kernel_noise_ratio = 1.0;
};

struct GeometryTablesReport {
  bool applied = false;  ///< at least one board's tables come from the geometry
  std::string skipped;   ///< why none could, when none does
  /// Per board: whether its tables come from the geometry, its areas' noise (feature units,
  /// root mean square over the placed frames) with the kernel tables (the trainer's, measured
  /// against other passes) and with the geometry's (0: not fitted), and the spread of its
  /// bearings around the geometry's (radians, 1.4826 times the median absolute residual; 0: too
  /// few bearings).
  std::vector<char> from_geometry;
  std::vector<double> kernel_sigma;
  std::vector<double> geometry_sigma;
  std::vector<double> geometry_bearing_sigma_rad;
  std::vector<double> kernel_bearing_sigma_rad;  ///< the kernel's, against other passes
  /// Per board from the geometry: whether it keeps the kernel's bearings where the kernel had
  /// one (their spread at most the geometry's; the geometry's fill the other places).
  std::vector<char> kernel_bearings;
  std::size_t cells = 0;  ///< stored cells filled
  /// The map's angle gain as the kernel measured it, and as the geometry implies it (NaN: too
  /// few boards seen whole).
  double kernel_angle_gain = 0.0;
  double geometry_angle_gain = 0.0;
  double ms = 0.0;
};

/// Refills @p map's visibility tables from @p fit, board by board, where that predicts the run's
/// areas better (see the file's comment). @p areas are the run's frames (row sums not needed),
/// @p frames those placed by odometry, @p area_scale the features' scale (100 / frame pixels).
/// Needs a map with visibility and a fit that is ok; otherwise the map is left as it was and
/// the report says why.
GeometryTablesReport visibility_from_geometry(const SceneGeometryFit& fit,
                                              const std::vector<algorithms::AreaVector>& areas,
                                              const std::vector<PlacedFrame>& frames,
                                              float area_scale, algorithms::ForwardMap& map,
                                              const GeometryTablesOptions& options = {});

/// Gives @p map projected bearings (map version 15; algorithms/projected_bearing.hpp) for the
/// boards @p boards marks whose fit in @p fit holds and whose bearings the map models: the fitted
/// camera on the robot and each such board's outline (a rectangle's corners and the middle of
/// each side; round an ellipse, an octagon of its area). Returns how many boards it gave an
/// outline; 0 leaves the map without projection.
std::size_t project_bearings_from_geometry(const SceneGeometryFit& fit,
                                           const std::vector<char>& boards,
                                           algorithms::ForwardMap& map);

/// How far the projected bearings of @p map (project_bearings_from_geometry) miss the angles the
/// run's frames measured: per board (map.board_count of them), 1.4826 times the median absolute
/// difference between the projected image angle at each placed frame's pose and the measured
/// one, at least 0.1 degree, over the frames in which the board gives a bearing (radians; 0: not
/// projected, or fewer than 20 such frames), as the tables' bearing spread is measured. The placed
/// poses' own error is in it, as in the cells' spread.
std::vector<double> projected_bearing_spread(const algorithms::ForwardMap& map,
                                             const std::vector<algorithms::AreaVector>& areas,
                                             const std::vector<PlacedFrame>& frames);

/// The areas of @p map's projected boards from the projection (map version 17): per board with
/// an outline, the feature per projected pixel (least squares through 0 over the placed frames
/// that see the board whole) and the noise of the projected areas (root mean square over every
/// placed frame, as the tables' noise is measured). A board takes the projection's areas, and
/// the filter weighs them by that noise (BearingProjection::area_sigma), when it is at most the
/// map's sigma for the board (its tables' noise). Returns the projection's noise per board
/// (map.board_count of them; 0: no outline, or fewer than 20 frames see the board whole).
std::vector<double> project_areas_from_geometry(const std::vector<algorithms::AreaVector>& areas,
                                                const std::vector<PlacedFrame>& frames,
                                                float area_scale, algorithms::ForwardMap& map);
/// Takes the outline away from each board of @p map outside @p served (whose visibility tables
/// the geometry does not serve) whose areas the projection did not take
/// (project_areas_from_geometry): such a board was offered an outline for its areas alone, and
/// its bearing stays the cells'. Returns how many outlines it took away; a map left with none
/// has no projection.
std::size_t drop_untaken_outlines(const std::vector<char>& served, algorithms::ForwardMap& map);
}  // namespace harmoloc::sim_host
