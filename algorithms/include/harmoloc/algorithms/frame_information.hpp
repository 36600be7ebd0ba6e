#pragma once
/// @file How tightly one frame pins the pose down: the Fisher information of the boards' areas
/// and bearings about a pose, in their trained noise, and from it the position spread that the
/// frame leaves open once the heading is free.
///
/// The cloud's own spread is a different thing: successive frames share most of their error (the
/// same view, the same map error), and a cloud weighed frame after frame narrows along
/// directions no single frame tells apart. The sweep's trace writes this bound at the estimate
/// (frame_sigma_m) beside the error. It is not a health signal yet: on seven random floors
/// (docs/sweep.md, 2026-12-06 (evening)) a third to a half of the frames of the floors tracked
/// to 1-2 cm leave more than 5 cm open (32-44%), against 64% on the floor whose estimate sat
/// 15 cm off. Host only for now (algorithms/sources.cmake).

#include <cstdint>
#include <limits>

#include "harmoloc/algorithms/board_observation.hpp"
#include "harmoloc/algorithms/forward_map.hpp"
#include "harmoloc/algorithms/geometry.hpp"

namespace harmoloc::algorithms {

struct FrameInformation {
  /// The information about (x, y, yaw) in m^-2, m^-1 rad^-1 and rad^-2, row-major: the sum over
  /// the boards of g g^T / sigma^2, g the gradient of a board's expected area or image angle at
  /// the pose and sigma its trained noise.
  double information[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  /// The standard deviation of position along its least determined direction, the heading free
  /// (the square root of the largest eigenvalue of the position's marginal covariance, the
  /// inverse of the Schur complement of the heading's information); infinite where the frame
  /// fixes no position along some direction.
  double weak_sigma_m = std::numeric_limits<double>::infinity();
  /// That direction in the map frame (radians, modulo pi).
  double weak_axis_rad = 0.0;
  /// The boards whose area or bearing took part (bit b).
  std::uint32_t boards = 0;
};

/// The information the boards @p observed give about the pose @p at on @p map: each modelled
/// board's area (in its trained noise, widened for a board the frame's side cuts), and each
/// observed bearing the map holds (its trained spread), the gradients by central differences of
/// what the map expects over a cell's width and about a degree. Boards whose bit is set in
/// @p leave_out (those the filter has written off) do not count. Seven looks at the map a frame.
FrameInformation frame_information(const ForwardMap& map, const BoardFeatures& observed,
                                   const Pose2& at, const BoardModelParams& params,
                                   std::uint32_t leave_out = 0);

}  // namespace harmoloc::algorithms
