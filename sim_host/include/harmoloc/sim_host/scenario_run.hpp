#pragma once
/// @file One simulated run of a scenario, in memory: the robot's motion (with its kidnaps), the
/// CAN frames of the wheel encoders, the labels and the ground truth are computed up front; frames
/// are rendered on demand, in order. simulate_dataset writes exactly this to a dataset folder;
/// SimCamera and LogEncoders replay it without a disk (long runs would need tens of GB of PPM).

#include <cstdint>
#include <vector>

#include "harmoloc/algorithms/can_encoder_layout.hpp"
#include "harmoloc/algorithms/geometry.hpp"
#include "harmoloc/dataset/tum.hpp"
#include "harmoloc/sim_host/route.hpp"
#include "harmoloc/sim_host/scenario.hpp"
#include "harmoloc/sim_host/scene_renderer.hpp"

namespace harmoloc::sim_host {

class ScenarioRun {
 public:
  /// Simulates the motion (with kidnaps), the encoder frames and the labels of @p scenario's run
  /// with @p seed; no frame is rendered yet. The random streams are those of the dataset: motion
  /// (seed, 1), image noise (seed, 2), encoders (seed, 3), labels (seed, 4), kidnap targets
  /// (seed, 5). Throws std::runtime_error with one line on a scenario that cannot run (no boards,
  /// a kidnap after the end of the run or without a place far enough).
  ScenarioRun(const Scenario& scenario, std::uint64_t seed);

  std::size_t frame_count() const { return truth_.size(); }
  /// Capture time of frame @p k on the dataset's clock (scenario.start_time_s epoch).
  std::uint64_t frame_timestamp_ns(std::size_t k) const { return stamps_ns_.at(k); }
  /// Run time of frame @p k: seconds from the start.
  double frame_time_s(std::size_t k) const;
  /// The true pose at frame @p k (what groundtruth.tum holds).
  const algorithms::Pose2& truth(std::size_t k) const { return truth_.at(k); }

  /// Renders frame @p k (RGB24, width * height * 3 bytes; @p rgb is resized, so a buffer of that
  /// size is reused). Frames must be rendered in order 0, 1, 2, ... because the image noise is
  /// one sequential stream: throws std::logic_error otherwise, or past the last frame.
  void render(std::size_t k, std::vector<std::uint8_t>& rgb);
  /// The frame render() will accept next.
  std::size_t next_frame() const { return next_frame_; }

  /// Renders frame @p k with @p renderer, a SceneRenderer of this run's scenario() that the
  /// caller owns (one per thread): the same bytes render(k) gives, in any order and from any
  /// number of threads at once (each frame's noise key is drawn up front, in frame order, from the
  /// image stream). Sets @p renderer's time to the frame's.
  void render_frame(std::size_t k, SceneRenderer& renderer, std::vector<std::uint8_t>& rgb) const;

  /// The true pixel count of each board in frame @p k (before noise), with the scene as it is at
  /// that frame's time (board moves, occluders): what a perfect segmentation would count. Any
  /// order; does not touch the image noise.
  std::vector<std::uint32_t> visible_board_pixels(std::size_t k);

  /// What encoders.log holds, in time order: the counter frames at the encoder rate and the motor
  /// controller's status frames (another ID, to be ignored).
  const std::vector<algorithms::CanFrame>& encoder_frames() const { return encoder_frames_; }
  /// Counter frames only (without the status frames).
  std::size_t counter_frame_count() const { return counter_frames_; }
  /// The labelled poses (labels.tum): a few evenly spread frames' true poses plus 3 mm noise.
  const std::vector<dataset::StampedPose>& labels() const { return labels_; }
  const std::vector<KidnapEvent>& kidnaps() const { return kidnaps_; }
  const RouteStats& route() const { return route_; }
  const Scenario& scenario() const { return scenario_; }
  std::uint64_t seed() const { return seed_; }
  /// The motion at 1 ms steps (pose, wheel travel, route clock).
  const std::vector<MotionSample>& motion() const { return motion_; }

  /// The motion's sample step.
  static constexpr double kMotionStep_s = 0.001;

 private:
  Scenario scenario_;
  std::uint64_t seed_;
  RouteStats route_;
  std::vector<MotionSample> motion_;
  std::vector<KidnapEvent> kidnaps_;
  std::vector<algorithms::Pose2> truth_;
  std::vector<std::uint64_t> stamps_ns_;
  std::vector<algorithms::CanFrame> encoder_frames_;
  std::size_t counter_frames_ = 0;
  std::vector<dataset::StampedPose> labels_;
  std::vector<std::uint64_t> noise_keys_;  ///< per frame, from the image stream (seed, 2)
  SceneRenderer renderer_;
  std::size_t next_frame_ = 0;
};

}  // namespace harmoloc::sim_host
