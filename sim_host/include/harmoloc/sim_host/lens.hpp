#pragma once
/// @file The simulated camera's lens: OpenCV's radial (k1, k2, k3) and tangential (p1, p2)
/// distortion in normalised coordinates, its inverse (what the renderer traces a pixel's ray
/// along), and the pinhole intrinsics a CameraSpec implies. A pixel whose distorted coordinates
/// have no preimage on the lens's monotonic region is outside the image circle: black.

#include <vector>

#include "harmoloc/algorithms/geometry.hpp"
#include "harmoloc/sim_host/scenario.hpp"

namespace harmoloc::sim_host {

class LensModel {
 public:
  LensModel() = default;
  LensModel(double k1, double k2, double k3, double p1, double p2);
  explicit LensModel(const CameraSpec& camera)
      : LensModel(camera.k1, camera.k2, camera.k3, camera.p1, camera.p2) {}

  /// Undistorted (x, y) -> distorted, normalised coordinates (the forward model).
  void distort(double x, double y, double& xd, double& yd) const;
  /// Distorted -> undistorted: false when (xd, yd) has no preimage with radius below
  /// max_radius() (outside the image circle). Radial lenses solve the radius in 1-D; with p1 or
  /// p2 a 2-D Newton iteration starts from the radial solution and is accepted only when the
  /// forward model maps it back within 1e-9 and the map is orientation-preserving there.
  bool undistort(double xd, double yd, double& x, double& y) const;
  /// The radius of the monotonic region: the first radius where d/dr [r (1 + k1 r^2 + k2 r^4 +
  /// k3 r^6)] reaches 0 (kNoLimit when it never does within that).
  double max_radius() const { return r_max_; }
  /// The radial factor's derivative d/dr [r (1 + k1 r^2 + ...)] at @p r (> 0: monotonic).
  double radial_slope(double r) const;
  bool radial_only() const { return p1_ == 0.0 && p2_ == 0.0; }

  static constexpr double kNoLimit = 1e9;

 private:
  bool undistort_radius(double rd, double& r) const;

  double k1_ = 0.0, k2_ = 0.0, k3_ = 0.0, p1_ = 0.0, p2_ = 0.0;
  double r_max_ = kNoLimit;
  double rd_max_ = kNoLimit;  ///< the distorted radius at r_max_
};

/// The camera's pinhole intrinsics: focal length (pixels, square pixels) and principal point.
struct Intrinsics {
  double focal_px;
  double cx_px, cy_px;
};
Intrinsics intrinsics_of(const CameraSpec& camera);

/// Where the camera is and how it is turned for the robot at a pose (map frame): its optical
/// centre and its axes (x right, y down, z forward, as the renderer's rays).
struct CameraFrame {
  double origin[3];
  double right[3];
  double down[3];
  double forward[3];
};
CameraFrame camera_frame_of(const CameraSpec& camera, const algorithms::Pose2& robot_pose);

/// Projects a map-frame point into the image: distorted pixel coordinates (@p u right, @p v
/// down, pixel centres at whole numbers). False when the point is behind the camera (less than
/// 1 cm ahead) or outside the lens's monotonic region (u, v are then not set).
bool project_point(const CameraSpec& camera, const LensModel& lens, const CameraFrame& frame,
                   const double point[3], double& u, double& v);

/// The firmware's column-to-angle law (forward_map.hpp: angle a1 t + a3 t^3 for the centroid
/// column u, t = (u - (W - 1) / 2) / W, positive to the right) that @p camera implies: the
/// least-squares a0 + a1 t + a3 t^3 over the frame's columns, at @p rows (fractions of the
/// frame's height, 0 the top row, 1 the bottom; empty: three rows about its middle), of the
/// angle between a pixel's ray and the robot's heading, seen from above. Under a pitch a
/// column's direction changes with the row: the rows the boards are seen at give their law.
struct ColumnLaw {
  bool ok = false;  ///< false: columns that do not turn one way, or a lens that cannot undistort
  double a1_rad = 0.0, a3_rad = 0.0;
  /// a0: the centre column's direction from the robot's heading (the principal point's offset
  /// and the mounting's yaw). The law leaves it out: it would add the same angle to every image
  /// angle the firmware measures and take it from every world bearing the trainer stores (the
  /// heading less the image angle), so it cancels in the filter's comparison of the two.
  double axis_rad = 0.0;
  /// The optical axis's image angle under the law (positive to the right of the centre column):
  /// where the lens's stretch and vignetting are centred (ForwardMap::visibility_axis_rad). The
  /// principal point's offset alone; without a mounting yaw, -axis_rad.
  double optical_axis_rad = 0.0;
};
ColumnLaw column_law_of(const CameraSpec& camera, const std::vector<double>& rows = {});

}  // namespace harmoloc::sim_host
