#include "harmoloc/sim_host/simulate.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "harmoloc/sim_host/candump_log.hpp"
#include "harmoloc/sim_host/frame_index.hpp"
#include "harmoloc/sim_host/metadata.hpp"
#include "harmoloc/sim_host/scene_renderer.hpp"
#include "harmoloc/sim_host/tum.hpp"

namespace harmoloc::sim_host {

namespace fs = std::filesystem;
using algorithms::kPi;
using algorithms::Pose2;

namespace {

constexpr double kMotionStep_s = 0.001;
constexpr std::uint32_t kStatusFrameId = 0x281;  // another message of the motor controller

const MotionSample& sample_at(const std::vector<MotionSample>& motion, double t_s) {
  const auto i = static_cast<std::size_t>(std::llround(t_s / kMotionStep_s));
  return motion[std::min(i, motion.size() - 1)];
}

std::uint64_t to_ns(double start_s, double t_s) {
  const auto start_ns = static_cast<std::uint64_t>(std::llround(start_s * 1e6)) * 1000ULL;
  return start_ns + static_cast<std::uint64_t>(std::llround(t_s * 1e9));
}

}  // namespace

SimulationSummary simulate_dataset(const Scenario& scenario, std::uint64_t seed,
                                   const std::string& out_dir,
                                   const std::function<void(std::size_t, std::size_t)>& progress) {
  if (scenario.boards.empty()) throw std::runtime_error("scenario has no boards");
  fs::create_directories(fs::path(out_dir) / "frames");
  SimulationSummary summary;

  algorithms::Pcg32 motion_rng(seed, 1), image_rng(seed, 2), encoder_rng(seed, 3),
      label_rng(seed, 4);
  const std::vector<MotionSample> motion =
      simulate_motion(scenario, kMotionStep_s, motion_rng, &summary.route);
  const double duration = summary.route.duration_s;

  // Frames and ground truth.
  const SceneRenderer renderer(scenario);
  const auto frame_count =
      static_cast<std::size_t>(std::floor(duration * scenario.camera.rate_hz)) + 1;
  std::vector<FrameEntry> index;
  std::vector<StampedPose> truth;
  std::vector<std::uint8_t> rgb;
  char name[32];
  for (std::size_t k = 0; k < frame_count; ++k) {
    const double t = static_cast<double>(k) / scenario.camera.rate_hz;
    const Pose2 pose = sample_at(motion, t).pose;
    renderer.render(pose, image_rng, rgb);
    std::snprintf(name, sizeof name, "frames/%06zu.ppm", k);
    write_ppm((fs::path(out_dir) / name).string(), scenario.camera.width_px,
              scenario.camera.height_px, rgb.data());
    const std::uint64_t stamp = to_ns(scenario.start_time_s, t);
    index.push_back(FrameEntry{stamp, name});
    truth.push_back(StampedPose{static_cast<double>(stamp) * 1e-9, pose});
    if (progress && (k % 50 == 0 || k + 1 == frame_count)) progress(k + 1, frame_count);
  }
  write_frame_index((fs::path(out_dir) / "frames.csv").string(), index);
  write_tum((fs::path(out_dir) / "groundtruth.tum").string(), truth);
  summary.frames = frame_count;

  // Wheel encoders on the CAN bus, as `candump -l` logs them.
  {
    std::ofstream log(fs::path(out_dir) / "encoders.log");
    if (!log) throw std::runtime_error(out_dir + "/encoders.log: cannot write");
    const EncoderSpec& e = scenario.encoders;
    const double ticks_per_m =
        scenario.robot.ticks_per_rev / (2.0 * kPi * scenario.robot.wheel_radius_m);
    const std::uint64_t mask = scenario.can_layout.counter_bits >= 32
                                   ? 0xFFFFFFFFULL
                                   : (1ULL << scenario.can_layout.counter_bits) - 1ULL;
    double left_ticks = 0.0, right_ticks = 0.0, last_left_m = 0.0, last_right_m = 0.0;
    const auto steps = static_cast<std::size_t>(std::floor(duration * e.rate_hz)) + 1;
    for (std::size_t j = 0; j < steps; ++j) {
      const double t = static_cast<double>(j) / e.rate_hz;
      const MotionSample& m = sample_at(motion, t);
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
      const std::uint64_t stamp = to_ns(scenario.start_time_s, t);
      const algorithms::CanFrame frame =
          algorithms::encode_encoder_frame(scenario.can_layout, counter(e.initial_left, left_ticks),
                                           counter(e.initial_right, right_ticks), stamp);
      log << format_candump_line(frame, "can0") << '\n';
      ++summary.encoder_frames;
      if (j % 10 == 5) {  // the controller's status message: not ours, must be ignored
        algorithms::CanFrame status;
        status.id = kStatusFrameId;
        status.length = 8;
        status.data = {0x01, 0x00, 0x30, 0x0C, 0x00, 0x00, 0x00, static_cast<std::uint8_t>(j / 10)};
        status.timestamp_ns = stamp + 200000ULL;
        log << format_candump_line(status, "can0") << '\n';
      }
    }
    if (!log) throw std::runtime_error(out_dir + "/encoders.log: write failed");
  }

  // Labels: a few poses from an external reference (an overhead camera, a few mm of error).
  {
    std::vector<StampedPose> labels;
    const std::size_t n =
        std::min<std::size_t>(static_cast<std::size_t>(scenario.labelled_frames), truth.size());
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t k = n > 1 ? (i * (truth.size() - 1) + (n - 1) / 2) / (n - 1) : 0;
      StampedPose p = truth[k];
      p.pose.x_m += 0.003 * label_rng.normal();
      p.pose.y_m += 0.003 * label_rng.normal();
      labels.push_back(p);
    }
    write_tum((fs::path(out_dir) / "labels.tum").string(), labels);
    summary.labels = labels.size();
  }

  DatasetMetadata meta;
  meta.name = scenario.name;
  meta.seed = seed;
  meta.image_width_px = scenario.camera.width_px;
  meta.image_height_px = scenario.camera.height_px;
  meta.pixel_format = hal::PixelFormat::kRgb24;
  meta.frame_rate_hz = scenario.camera.rate_hz;
  meta.geometry = scenario.robot;
  meta.encoder_layout = scenario.can_layout;
  meta.ground_truth = "groundtruth.tum";
  write_metadata(out_dir, meta);
  std::ofstream(fs::path(out_dir) / "scenario.toml") << scenario_to_toml(scenario);
  return summary;
}

}  // namespace harmoloc::sim_host
