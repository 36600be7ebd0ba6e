#pragma once
/// @file A global pose from one frame on a floor map: a search over the whole trained floor.
///
/// On a floor (a map trained from a coverage run, without route terms) the harmonic localizer's
/// fix is poor (it was built for a route, where a place has one heading: on random floors its
/// error is tens of centimetres), so a kidnap to another place and heading is seen late or not
/// at all. The forward map itself can tell: where the map holds the boards' world bearings, the
/// image angles the frame shows give the heading at each candidate place (heading = the board's
/// world bearing there + its image angle, averaged over the boards), and the boards' areas and
/// bearings at that pose give the fit. The search scans the grid's places (every stride-th
/// cell, as the camera's place when the map's bearings are seen from it) a slice per cycle, so
/// that its cost per cycle is bounded, and refines the best of a pass on each frame around it.

#include <cstddef>
#include <cstdint>

#include "harmoloc/algorithms/board_observation.hpp"
#include "harmoloc/algorithms/forward_map.hpp"

namespace harmoloc::algorithms {

/// A pose the boards fit, and how well: the sum over the boards of log(exp(-r^2 / 2) + c), r the
/// residual of each board's area and of each observed bearing in the map's trained widths (the
/// robust term with every board trusted; c = BoardModelParams::outlier_floor). Nats: at most
/// ln(1 + c) a term (0.16 for eight boards' areas and bearings at c = 0.01), a perfect fit.
struct FloorPose {
  double x_m = 0.0, y_m = 0.0, yaw_rad = 0.0;
  double nats = 0.0;
  bool valid = false;  ///< false: no place tried, or no board gave a bearing
};

/// The better of two poses: the valid one, or of two valid ones the one with more nats (@p a on a
/// tie).
inline const FloorPose& better_of(const FloorPose& a, const FloorPose& b) {
  return b.valid && (!a.valid || b.nats > a.nats) ? b : a;
}

/// The fit of the boards @p observed at pose (@p x_m, @p y_m, @p yaw_rad) on @p map (FloorPose's
/// nats; boards whose bit is set in @p leave_out do not count). 0 for a map that is not present.
double floor_fit(const ForwardMap& map, const BoardFeatures& observed, double x_m, double y_m,
                 double yaw_rad, const BoardModelParams& params, std::uint32_t leave_out);

/// The best pose with its camera at (@p cx_m, @p cy_m): the heading from the observed bearings
/// there, then floor_fit. Invalid when no observed board has a bearing in the map there.
FloorPose floor_pose_seen_from(const ForwardMap& map, const BoardFeatures& observed, double cx_m,
                               double cy_m, const BoardModelParams& params,
                               std::uint32_t leave_out);

/// Whether the search can run on @p map: a forward map with bearings.
bool floor_search_possible(const ForwardMap& map);

/// The search's state between cycles: where the scan is and the best of the pass under way.
class FloorSearch {
 public:
  /// Starts a new pass; forgets the last one's result.
  void reset();

  /// Scans up to @p places places of the grid (every @p stride cells along each axis, at least
  /// 1), from where the last call stopped, against @p observed. When this completes a pass its
  /// best pose becomes last_pass() and the next call starts another. Returns whether a pass
  /// completed.
  bool step(const ForwardMap& map, const BoardFeatures& observed, const BoardModelParams& params,
            std::uint32_t leave_out, std::size_t places, std::uint32_t stride);

  /// The best pose of the last completed pass (invalid before one completes).
  const FloorPose& last_pass() const { return last_; }

  /// @p around refined on the current frame: the best pose with its camera within @p radius_m
  /// of @p around's camera place, on a grid of 5 x 5 places (@p around's own included). Each
  /// level beyond the first tries the 8 places around the best so far at half the last step: a
  /// board's area in its trained width changes by a width over a centimetre or two, finer than
  /// a pass's places.
  static FloorPose refine(const ForwardMap& map, const BoardFeatures& observed,
                          const FloorPose& around, double radius_m, const BoardModelParams& params,
                          std::uint32_t leave_out, int levels = 1);
  /// The places refine() tries with @p levels levels.
  static constexpr std::size_t refine_places(int levels) {
    return 25U + 8U * static_cast<std::size_t>(levels > 1 ? levels - 1 : 0);
  }

 private:
  std::uint64_t cursor_ = 0;  ///< the next place of the pass, row-major over the strided grid
  FloorPose best_{};          ///< the best of the pass under way
  FloorPose last_{};          ///< the best of the last completed pass
};

}  // namespace harmoloc::algorithms
