#pragma once
/// @file Renders what the robot's camera sees: a room (optionally with a desk), colour boards
/// (rectangles or ellipses, upright or tilted, on walls or on stands; they may be moved during the
/// run) and occluders (people walking through), through a pinhole with OpenCV's radial and
/// tangential distortion (lens.hpp). Pixels outside the lens's image circle are black. Every
/// pixel's ray is traced; the frame is cut into tiles, and each tile tests only the objects whose
/// bounding spheres meet the cone of its pixels' rays (the culling is conservative: the picture is
/// the same as testing everything). Brightness follows the lighting over time and the lens's
/// vignetting; the pixel noise comes from a Gaussian table indexed by a counter-based hash.

#include <cstdint>
#include <vector>

#include "harmoloc/algorithms/geometry.hpp"
#include "harmoloc/algorithms/random.hpp"
#include "harmoloc/sim_host/lens.hpp"
#include "harmoloc/sim_host/scenario.hpp"

namespace harmoloc::sim_host {

/// The scene at one moment of the run: set_time() applies the board moves in effect, places the
/// occluders (upright cylinders) where their paths put them and sets the lighting. A new renderer
/// shows the scene at time 0.
class SceneRenderer {
 public:
  /// Keeps its own copy of @p scenario.
  explicit SceneRenderer(const Scenario& scenario);

  /// Sets the run time (seconds from the start) the next renders and visible_board_pixels show.
  void set_time(double t_s);
  double time_s() const { return time_s_; }
  /// The brightness factor at the current time (light_gain_at).
  double light_gain() const { return gain_; }
  /// The boards as they stand at the current time (moves applied), in the scenario's order.
  const std::vector<BoardSpec>& boards() const { return boards_; }
  /// How many occluders are in the room at the current time.
  std::size_t occluders_present() const { return occluders_present_; }

  /// Renders RGB24 (width * height * 3 bytes) for the robot at @p robot_pose. Draws 64 bits from
  /// @p rng (the frame's noise key); each pixel's noise is a function of that key and the pixel's
  /// index only.
  void render(const algorithms::Pose2& robot_pose, algorithms::Pcg32& rng,
              std::vector<std::uint8_t>& rgb) const;
  /// The same with the frame's noise key given: what render() does after drawing it as
  /// (next_u32() << 32) | next_u32().
  void render(const algorithms::Pose2& robot_pose, std::uint64_t noise_key,
              std::vector<std::uint8_t>& rgb) const;

  /// How many pixels of each board are visible (before noise): the true areas, for tests.
  std::vector<std::uint32_t> visible_board_pixels(const algorithms::Pose2& robot_pose) const;

  /// Pixels inside the lens's image circle (those with a ray).
  std::size_t valid_pixels() const { return valid_pixels_; }
  /// The relative illumination of pixel @p index (vignetting; 1 without).
  float vignetting(std::size_t index) const { return vignette_[index]; }

  /// Tile edge in pixels (the unit of culling).
  static constexpr std::uint32_t kTile = 16;

 private:
  struct Ray {
    double x, y;  ///< camera frame (z = 1): x right, y down
  };
  struct Tile {
    std::uint32_t u0, v0, u1, v1;  ///< pixel rectangle [u0, u1) x [v0, v1)
    double axis[3];                ///< unit, camera frame (x right, y down, z forward)
    double cos_half, sin_half;     ///< of the cone's half-angle around the axis
    bool any_valid;
  };
  struct PlacedBoard {
    double c[3], n[3], u[3], v[3];  ///< centre, face normal, width and height axes
    double half_w, half_h;
    BoardShape shape;
    Rgb colour;
  };
  struct PlacedCylinder {
    double x_m, y_m, radius_m, height_m;
    Rgb colour;
  };
  struct Sphere {
    double c[3], r;
    std::uint16_t object;  ///< kDesk, kBoard0 + board, kCylinder0 + cylinder (see the .cpp)
  };
  struct Hit;

  int trace(const double o[3], const double d[3], const std::uint16_t* objects, std::size_t count,
            Rgb& colour) const;
  /// The objects of each tile for a camera at @p o with axes @p r, @p dn, @p f: tile t's are
  /// objects[begin[t] .. begin[t + 1]).
  void cull(const double o[3], const double r[3], const double dn[3], const double f[3],
            std::vector<std::uint32_t>& begin, std::vector<std::uint16_t>& objects) const;

  Scenario scenario_;
  Intrinsics intrinsics_{};
  std::vector<Ray> rays_;
  std::vector<std::uint8_t> valid_;
  std::vector<float> vignette_;
  std::vector<Tile> tiles_;
  std::size_t valid_pixels_ = 0;
  std::vector<float> noise_;  ///< pixel_noise times standard normal quantiles
  double time_s_ = 0.0;
  double gain_ = 1.0;
  std::vector<BoardSpec> boards_;
  std::vector<PlacedBoard> placed_;
  std::vector<PlacedCylinder> cylinders_;  ///< occluders present, then the boards' stands
  std::size_t occluders_present_ = 0;
  std::vector<Sphere> spheres_;  ///< bounding spheres of desk, boards, cylinders, in that order
};

}  // namespace harmoloc::sim_host
