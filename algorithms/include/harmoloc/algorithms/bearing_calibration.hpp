#pragma once
/// @file Where the boards stand and how a column of the frame turns into a bearing, learnt from a
/// training run alone (offline, host only). The firmware knows no camera intrinsics, and the lens
/// is distorted; the training run gives every frame's pose (labels and odometry) and each board's
/// centroid column (segmentation's column sums). A board seen from several places lies where the
/// rays through its centroids meet; the column-to-angle law is the one under which they meet best.
///
/// The law is odd in the column's offset from the frame's centre, t = (u - (W - 1) / 2) / W:
///   angle_rad(t) = a1 t + a3 t^3   (positive to the right of the optical axis),
/// which covers a pinhole (a3 < 0 only slightly) and barrel distortion (a3 > 0). A board's world
/// bearing from pose (x, y, yaw) is yaw - angle_rad(t). For each law on a grid (half field of view
/// 10-75 degrees, a3 / a1 from -0.5 to 1.5) every board is triangulated by linear least squares
/// over its rays (weighted by the inverse square of its range, so residuals are angles); the law
/// with the smallest angular residual is then refined on a finer grid. The camera's offset from
/// the pose and the board's own width (its centroid is not its centre seen at an angle) are left
/// in the residual.

#include <cstddef>
#include <vector>

#include "harmoloc/algorithms/geometry.hpp"
#include "harmoloc/algorithms/segmentation.hpp"

namespace harmoloc::algorithms {

/// One frame of the training run: where the robot was and what segmentation measured.
struct BearingFrame {
  Pose2 pose;
  AreaVector areas;  ///< columns_measured() required; other frames are skipped
};

struct BearingCalibrationOptions {
  /// A board needs this many usable frames, and rays spread over at least this angle, to be
  /// triangulated.
  std::size_t min_frames = 20;
  double min_ray_spread_rad = 0.05;
};

struct BoardPlacement {
  bool placed = false;
  double x_m = 0.0, y_m = 0.0;
  std::size_t frames = 0;  ///< rays used
  double rms_residual_rad = 0.0;
};

struct BearingCalibration {
  bool ok = false;      ///< a law and at least two placed boards
  double a1_rad = 0.0;  ///< angle_rad(t) = a1 t + a3 t^3
  double a3_rad = 0.0;
  std::size_t boards = 0;                  ///< board count of the run's areas
  std::vector<BoardPlacement> placements;  ///< one per board
  double rms_residual_rad = 0.0;           ///< over every ray of the placed boards
  std::size_t rays = 0;

  /// Angle of column @p u_px (to the right of the optical axis) in a frame @p width_px wide.
  double angle_rad(double u_px, std::uint32_t width_px) const;
  /// Half the horizontal field of view the law implies.
  double half_fov_rad() const { return 0.5 * a1_rad + 0.125 * a3_rad; }
};

/// Learns the law and the boards' places from @p frames (frames without measured columns, or
/// with a board cut by the frame's side, are left out per board). Not ok (and says nothing more)
/// when fewer than two boards can be triangulated.
BearingCalibration calibrate_bearings(const std::vector<BearingFrame>& frames,
                                      const BearingCalibrationOptions& options = {});

}  // namespace harmoloc::algorithms
