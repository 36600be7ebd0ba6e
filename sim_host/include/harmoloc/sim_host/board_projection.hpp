#pragma once
/// @file A board's image as a camera sees it, from geometry alone: the board's outline (a flat
/// rectangle or ellipse, BoardSpec) projected through the lens (lens.hpp) and clipped to the
/// frame. Where the renderer counts the pixels whose rays meet the board, this gives the same
/// area in closed form (no pixels, no occlusion by other objects), so that a model of the boards
/// and the camera fitted to a training run can predict a board's area and centroid column from
/// any pose and heading: also off the paths the run drove (issue 20, the floor's forward model).
#include "harmoloc/algorithms/geometry.hpp"
#include "harmoloc/sim_host/lens.hpp"
#include "harmoloc/sim_host/scenario.hpp"

namespace harmoloc::sim_host {

/// A board's frame in the map: its centre, the normal of its coloured face and the directions of
/// its width (horizontal) and height in the face's plane, as the renderer places it. Upright
/// (tilt 0) the tilt's terms are products with 0, so the arithmetic equals that before tilted
/// boards existed.
struct BoardAxes {
  double centre[3];
  double normal[3];
  double width_dir[3];
  double height_dir[3];
};
BoardAxes board_axes(const BoardSpec& board);

/// What the frame shows of one board.
struct BoardImage {
  double area_px = 0.0;  ///< of the outline's image inside the frame; 0 when none
  /// The image's centroid (pixel centres at whole numbers); 0 when there is no area.
  double centroid_u_px = 0.0;
  double centroid_v_px = 0.0;
  bool cut = false;  ///< the frame's border (or the lens's image circle) cuts the outline
};

/// Outline points per side of a rectangle (an ellipse gets four times as many round it): a lens
/// bends the board's straight edges, and the projected polygon follows the bend between them.
constexpr int kBoardOutlinePointsPerSide = 12;

/// The image of @p board for the robot at @p robot_pose, through @p camera (its pose on the robot,
/// intrinsics) and @p lens (LensModel(camera)). An outline point behind the camera or beyond the
/// lens's monotonic region (whose image would fold back into the frame) is pushed far outside
/// the frame along its direction; a board wholly behind the camera shows nothing.
BoardImage project_board(const CameraSpec& camera, const LensModel& lens, const BoardSpec& board,
                         const algorithms::Pose2& robot_pose);

}  // namespace harmoloc::sim_host
