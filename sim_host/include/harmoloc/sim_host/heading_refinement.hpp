#pragma once
/// @file The training run's headings refined by the boards it saw. The trainer places every frame
/// by the wheel odometry between the labels; the heading that placement gives drifts between two
/// labels as the wheels slip (on random floor 3, 1.0 degree RMS, for 0.1 to 0.3 on most floors).
/// At 1280 x 720 a degree is 13 pixels of centroid column, every board in the frame moved alike:
/// the geometry fit then turned the camera's principal point 37 px off and fitted two wall boards
/// as strips 6 m long, a better fit to those headings than the truth was (docs/sweep.md).
///
/// A frame's heading error moves every board's centroid column the same way, and the odometry's
/// error drifts over seconds rather than jumping. So, from a geometry fit: per frame the median
/// over the boards in view of the column's miss as an angle; the median of those over the frames
/// within a short window; the run's median taken out (a turn shared by every frame is the
/// camera's, and the labels hold the run's heading). The headings move by that, the camera and
/// boards are fitted again from where they were, and so on for a few rounds.
#include <cstddef>
#include <vector>

#include "harmoloc/sim_host/scene_geometry_fit.hpp"

namespace harmoloc::sim_host {

struct HeadingRefinementOptions {
  int rounds = 8;
  /// Frames up to this far either side pool their offsets (the median of them).
  double window_s = 0.5;
  /// A window needs this many frames with an offset; fewer leave the frame as it was.
  std::size_t min_frames = 3;
  /// A board's miss beyond this is not the heading (another colour, a board half hidden).
  double max_miss_rad = 0.09;
  /// Rounds stop once a round moves the headings by less than this (RMS over the frames).
  double converged_rad = 3.5e-4;  // 0.02 degrees
};

/// Per frame k (every list of @p sightings holds one entry a frame, or none for a board left
/// out; @p time_s gives the frames' times): the heading offset, in radians counter-clockwise,
/// that @p fit's camera and boards see (0 where the window has too few frames).
std::vector<double> heading_offsets_rad(const SceneGeometryFit& fit,
                                        const std::vector<std::vector<BoardSighting>>& sightings,
                                        const std::vector<double>& time_s,
                                        const BoardFitOptions& fit_options,
                                        const HeadingRefinementOptions& options = {});

struct HeadingRefinement {
  SceneGeometryFit fit;            ///< the last fit, from the refined headings
  std::vector<double> offset_rad;  ///< per frame, the sum over the rounds
  int rounds = 0;                  ///< rounds whose refit held
  double rms_offset_rad = 0.0;     ///< of offset_rad
};

/// Refines the headings of @p sightings in place from @p fit (ok), the joint fit run again after
/// each round (SceneFitOptions::from_fit). A round whose refit is not ok is undone and ends it.
HeadingRefinement refine_headings(const SceneGeometryFit& fit,
                                  std::vector<std::vector<BoardSighting>>& sightings,
                                  const std::vector<double>& time_s,
                                  const SceneFitOptions& fit_options,
                                  const HeadingRefinementOptions& options = {});

}  // namespace harmoloc::sim_host
