#pragma once
/// @file Board bearings projected from the camera and the boards fitted to the training run
/// (map version 15; docs/bearings.md). The forward map's bearing tables hold, per cell, the
/// bearing the training run saw a board at from near the cell: between the lanes it drove and at
/// headings it did not, they interpolate, and a board near the frame's edge is seen through the
/// lens's stretch, which a world bearing per place does not follow. The trainer fits the camera
/// (intrinsics, lens, pitch, mounting) and every board's outline to the run's sightings; where a
/// board's fit holds, the map stores its outline and the camera, and the filter projects the
/// outline from each particle's own pose: the board's predicted centroid column, put through the
/// map's column-to-angle law, is the image angle the particle expects.
///
/// The outline is a few points of the board's edge in the map frame (a rectangle's corners and
/// the middle of each side, which follow most of the lens's bend; an octagon of the ellipse's
/// area round an ellipse). Where the map projects a board's areas too (map version 17), the
/// outline's projected area inside the frame, times a factor fitted to the training run, is the
/// area the particle expects. The centroid of the projected polygon stands for the
/// centroid of the board's pixels: over twelve random scenes within 0.02-0.3 degrees at the 90th
/// percentile (docs/sweep.md). Only a board the frame shows whole gives a bearing, so the
/// polygon is not clipped: a particle from which the board's centroid falls outside the frame
/// expects it there, far from where the frame shows it; one from which the board lies behind the
/// camera, or beyond the lens's monotonic region, expects no board at all.

#include <array>
#include <cstddef>
#include <cstdint>

#include "harmoloc/algorithms/segmentation.hpp"

namespace harmoloc::algorithms {

/// The camera and the boards' outlines a map's projected bearings need.
struct BearingProjection {
  static constexpr std::size_t kMaxPoints = 8;  ///< outline points per board
  /// The camera on the robot (the robot's frame: x forward from the wheel axle's centre, y left,
  /// z up from the floor): its optical centre and its axes (x right, y down, z forward along the
  /// optical axis), unit vectors.
  std::array<float, 3> origin_m{};
  std::array<float, 3> right{};
  std::array<float, 3> down{};
  std::array<float, 3> forward{};
  /// Pinhole intrinsics (pixels; pixel centres at whole numbers) of the frame the map's
  /// thresholds and law were trained on, width_px wide.
  float focal_px = 0.0F;
  float cx_px = 0.0F;
  float cy_px = 0.0F;
  std::uint32_t width_px = 0;
  std::uint32_t height_px = 0;
  /// OpenCV's lens model in normalised coordinates (the simulator's and the trainer's fit).
  float k1 = 0.0F, k2 = 0.0F, k3 = 0.0F, p1 = 0.0F, p2 = 0.0F;
  /// The square of the normalised radius where the lens's radial factor stops increasing: a
  /// point beyond it would fold back into the frame.
  float max_radius2 = 0.0F;
  /// Per board: its outline's points (0: the board's bearings come from the tables), in order
  /// round the edge (map frame, metres), read through point_m.
  std::array<std::uint8_t, kMaxBoards> points{};
  /// Board b's x of every point, then its y, then its z (kMaxPoints each): a projection runs
  /// over the points in lanes.
  std::array<float, kMaxBoards * 3 * kMaxPoints> outline_m{};
  /// Per board with an outline: how far its projected bearing misses the measured one at the
  /// training run's placed poses (radians, map version 16), the spread the filter weighs it
  /// with; 0: the cells' spread (ForwardMap::bearing_sigma_rad; version 15 maps).
  std::array<float, kMaxBoards> sigma_rad{};
  /// Per board with an outline: its feature per pixel of the projected outline's area inside
  /// the frame (the features' area scale times how many pixels the segmentation counts per
  /// projected pixel, fitted to the training run; map version 17); 0: the board's areas come
  /// from the cells.
  std::array<float, kMaxBoards> area_per_px{};
  /// Per board whose areas are projected: how far the projected area misses the measured one at
  /// the training run's placed poses (feature units, root mean square; map version 17), the
  /// noise the filter weighs the area with. The floor search and the place comparisons keep the
  /// map's sigma: they compare places on a grid a few centimetres apart, where a projection this
  /// sharp would tell the places near the truth no better than any other.
  std::array<float, kMaxBoards> area_sigma{};

  /// Coordinate @p d (0 x, 1 y, 2 z) of point @p i of board @p b's outline.
  float& point_m(std::size_t b, std::size_t i, std::size_t d) {
    return outline_m[(b * 3 + d) * kMaxPoints + i];
  }
  float point_m(std::size_t b, std::size_t i, std::size_t d) const {
    return outline_m[(b * 3 + d) * kMaxPoints + i];
  }

  bool present() const {
    for (const std::uint8_t n : points)
      if (n != 0) return true;
    return false;
  }
};

/// The camera for a robot at (@p x_m, @p y_m) heading (@p cos_yaw, @p sin_yaw): its optical
/// centre and axes in the map frame, taken once per pose for all its boards.
struct CameraAtPose {
  float origin[3];
  float right[3];
  float down[3];
  float forward[3];
};

CameraAtPose camera_at_pose(const BearingProjection& p, float x_m, float y_m, float cos_yaw,
                            float sin_yaw);

/// Board @p b's outline projected once from @p camera: its centroid column
/// (projected_centroid_column) and, when @p area, its area in the frame (projected_area_px).
/// The filter needs both at a particle; projecting the points twice would double its cost.
struct ProjectedOutline {
  bool has_column = false;  ///< projected_centroid_column's answer
  bool has_area = false;    ///< projected_area_px's answer (false without @p area)
  float column_px = 0.0F;
  float area_px = 0.0F;
};

ProjectedOutline project_outline(const BearingProjection& p, const CameraAtPose& camera,
                                 std::size_t b, bool area);

/// The area of board @p b's outline projected from @p camera and clipped to the frame (pixels),
/// as the simulator's renderer counts a board's pixels (sim_host/board_projection.hpp). 0 for a
/// board wholly behind the camera. False when the board has no outline, or some of its points
/// lie behind the camera or beyond the lens's monotonic region while others do not: a few
/// points cannot follow such an image (its sides run far out of the frame), and the caller
/// keeps its other model.
bool projected_area_px(const BearingProjection& p, const CameraAtPose& camera, std::size_t b,
                       float& area_px);

/// Board @p b's outline projected from @p camera: the centroid column of the projected polygon
/// (pixels; not clipped to the frame). False when the board has no outline, a point lies behind
/// the camera or beyond the lens's monotonic region, or the polygon is seen edge-on.
bool projected_centroid_column(const BearingProjection& p, const CameraAtPose& camera,
                               std::size_t b, float& column_px);

}  // namespace harmoloc::algorithms
