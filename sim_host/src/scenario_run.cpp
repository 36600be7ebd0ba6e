#include "harmoloc/sim_host/scenario_run.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace harmoloc::sim_host {

using algorithms::kPi;
using algorithms::Pose2;

namespace {

constexpr std::uint32_t kStatusFrameId = 0x281;  // another message of the motor controller

const MotionSample& sample_at(const std::vector<MotionSample>& motion, double t_s) {
  const auto i = static_cast<std::size_t>(std::llround(t_s / ScenarioRun::kMotionStep_s));
  return motion[std::min(i, motion.size() - 1)];
}

Scenario checked(const Scenario& scenario) {
  if (scenario.boards.empty()) throw std::runtime_error("scenario has no boards");
  return scenario;
}

}  // namespace

ScenarioRun::ScenarioRun(const Scenario& scenario, std::uint64_t seed)
    : scenario_(checked(scenario)), seed_(seed), renderer_(scenario_) {
  algorithms::Pcg32 motion_rng(seed, 1), image_rng(seed, 2), encoder_rng(seed, 3),
      label_rng(seed, 4), kidnap_rng(seed, 5);
  motion_ = simulate_motion(scenario_, kMotionStep_s, motion_rng, &route_, &kidnap_rng, &kidnaps_);
  const double duration = route_.duration_s;

  // Ground truth at each frame.
  const auto frames = static_cast<std::size_t>(std::floor(duration * scenario_.camera.rate_hz)) + 1;
  truth_.reserve(frames);
  stamps_ns_.reserve(frames);
  for (std::size_t k = 0; k < frames; ++k) {
    const double t = frame_time_s(k);
    truth_.push_back(sample_at(motion_, t).pose);
    stamps_ns_.push_back(dataset_time_ns(scenario_.start_time_s, t));
    // Each frame's noise key, in frame order (as SceneRenderer::render(pose, rng, rgb) draws it).
    const std::uint64_t hi = image_rng.next_u32();
    noise_keys_.push_back((hi << 32U) | image_rng.next_u32());
  }

  // Wheel encoders on the CAN bus: free-running counters with slip and a radius error.
  const EncoderSpec& e = scenario_.encoders;
  const double ticks_per_m =
      scenario_.robot.ticks_per_rev / (2.0 * kPi * scenario_.robot.wheel_radius_m);
  const std::uint64_t mask = scenario_.can_layout.counter_bits >= 32
                                 ? 0xFFFFFFFFULL
                                 : (1ULL << scenario_.can_layout.counter_bits) - 1ULL;
  double left_ticks = 0.0, right_ticks = 0.0, last_left_m = 0.0, last_right_m = 0.0;
  const auto steps = static_cast<std::size_t>(std::floor(duration * e.rate_hz)) + 1;
  encoder_frames_.reserve(steps + steps / 10 + 1);
  for (std::size_t j = 0; j < steps; ++j) {
    const double t = static_cast<double>(j) / e.rate_hz;
    const MotionSample& m = sample_at(motion_, t);
    const double dl = m.left_m - last_left_m, dr = m.right_m - last_right_m;
    last_left_m = m.left_m;
    last_right_m = m.right_m;
    left_ticks +=
        dl * (1.0 + e.left_scale_error + e.slip_sigma * encoder_rng.normal()) * ticks_per_m;
    right_ticks +=
        dr * (1.0 + e.right_scale_error + e.slip_sigma * encoder_rng.normal()) * ticks_per_m;
    const auto counter = [mask](std::uint32_t initial, double ticks) {
      const auto whole = static_cast<std::int64_t>(std::floor(ticks));
      return static_cast<std::uint32_t>(
          (static_cast<std::uint64_t>(initial) + static_cast<std::uint64_t>(whole)) & mask);
    };
    const std::uint64_t stamp = dataset_time_ns(scenario_.start_time_s, t);
    encoder_frames_.push_back(
        algorithms::encode_encoder_frame(scenario_.can_layout, counter(e.initial_left, left_ticks),
                                         counter(e.initial_right, right_ticks), stamp));
    ++counter_frames_;
    if (j % 10 == 5) {  // the controller's status message: not ours, must be ignored
      algorithms::CanFrame status;
      status.id = kStatusFrameId;
      status.length = 8;
      status.data = {0x01, 0x00, 0x30, 0x0C, 0x00, 0x00, 0x00, static_cast<std::uint8_t>(j / 10)};
      status.timestamp_ns = stamp + 200000ULL;
      encoder_frames_.push_back(status);
    }
  }

  // Labels: a few poses from an external reference (an overhead camera, a few mm of error).
  const std::size_t n =
      std::min<std::size_t>(static_cast<std::size_t>(scenario_.labelled_frames), frames);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t k = n > 1 ? (i * (frames - 1) + (n - 1) / 2) / (n - 1) : 0;
    dataset::StampedPose p{static_cast<double>(stamps_ns_[k]) * 1e-9, truth_[k]};
    p.pose.x_m += 0.003 * label_rng.normal();
    p.pose.y_m += 0.003 * label_rng.normal();
    if (!scenario_.labels_with_heading) p.pose.yaw_rad = 0.0;  // a position-only reference
    labels_.push_back(p);
  }
}

double ScenarioRun::frame_time_s(std::size_t k) const {
  return static_cast<double>(k) / scenario_.camera.rate_hz;
}

void ScenarioRun::render(std::size_t k, std::vector<std::uint8_t>& rgb) {
  if (k != next_frame_ || k >= frame_count()) {
    throw std::logic_error(
        "ScenarioRun::render: frame " + std::to_string(k) + " asked, " +
        (next_frame_ < frame_count()
             ? "frame " + std::to_string(next_frame_) + " is next (frames render in order)"
             : "all " + std::to_string(frame_count()) + " frames are rendered"));
  }
  render_frame(k, renderer_, rgb);
  ++next_frame_;
}

void ScenarioRun::render_frame(std::size_t k, SceneRenderer& renderer,
                               std::vector<std::uint8_t>& rgb) const {
  renderer.set_time(frame_time_s(k));
  renderer.render(truth_.at(k), noise_keys_.at(k), rgb);
}

std::vector<std::uint32_t> ScenarioRun::visible_board_pixels(std::size_t k) {
  renderer_.set_time(frame_time_s(k));
  return renderer_.visible_board_pixels(truth_.at(k));
}

}  // namespace harmoloc::sim_host
