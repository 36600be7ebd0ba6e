#include "harmoloc/sim_host/simulate.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "harmoloc/dataset/candump_log.hpp"
#include "harmoloc/dataset/frame_index.hpp"
#include "harmoloc/dataset/metadata.hpp"
#include "harmoloc/dataset/tum.hpp"
#include "harmoloc/sim_host/scenario_run.hpp"

namespace harmoloc::sim_host {

namespace fs = std::filesystem;

SimulationSummary simulate_dataset(const Scenario& scenario, std::uint64_t seed,
                                   const std::string& out_dir,
                                   const std::function<void(std::size_t, std::size_t)>& progress) {
  ScenarioRun run(scenario, seed);
  fs::create_directories(fs::path(out_dir) / "frames");
  SimulationSummary summary;
  summary.route = run.route();
  const Scenario& s = run.scenario();

  // Frames and ground truth.
  const std::size_t frame_count = run.frame_count();
  std::vector<dataset::FrameEntry> index;
  std::vector<dataset::StampedPose> truth;
  index.reserve(frame_count);
  truth.reserve(frame_count);
  std::vector<std::uint8_t> rgb;
  char name[32];
  for (std::size_t k = 0; k < frame_count; ++k) {
    run.render(k, rgb);
    std::snprintf(name, sizeof name, "frames/%06zu.ppm", k);
    dataset::write_ppm((fs::path(out_dir) / name).string(), s.camera.width_px, s.camera.height_px,
                       rgb.data());
    const std::uint64_t stamp = run.frame_timestamp_ns(k);
    index.push_back(dataset::FrameEntry{stamp, name});
    truth.push_back(dataset::StampedPose{static_cast<double>(stamp) * 1e-9, run.truth(k)});
    if (progress && (k % 50 == 0 || k + 1 == frame_count)) progress(k + 1, frame_count);
  }
  dataset::write_frame_index((fs::path(out_dir) / "frames.csv").string(), index);
  dataset::write_tum((fs::path(out_dir) / "groundtruth.tum").string(), truth);
  summary.frames = frame_count;

  // Wheel encoders on the CAN bus, as `candump -l` logs them.
  {
    std::ofstream log(fs::path(out_dir) / "encoders.log");
    if (!log) throw std::runtime_error(out_dir + "/encoders.log: cannot write");
    for (const algorithms::CanFrame& frame : run.encoder_frames())
      log << dataset::format_candump_line(frame, "can0") << '\n';
    if (!log) throw std::runtime_error(out_dir + "/encoders.log: write failed");
    summary.encoder_frames = run.counter_frame_count();
  }

  // Labels: a few poses from an external reference (an overhead camera, a few mm of error).
  dataset::write_tum((fs::path(out_dir) / "labels.tum").string(), run.labels());
  summary.labels = run.labels().size();

  // Kidnaps, when there are any: where the robot was lifted and where it was put down.
  const fs::path kidnaps_path = fs::path(out_dir) / "kidnaps.csv";
  summary.kidnaps = run.kidnaps().size();
  if (!run.kidnaps().empty()) {
    std::ofstream csv(kidnaps_path);
    if (!csv) throw std::runtime_error(kidnaps_path.string() + ": cannot write");
    csv << "t_s,from_x_m,from_y_m,from_yaw_rad,to_x_m,to_y_m,to_yaw_rad\n";
    char line[256];
    for (const KidnapEvent& k : run.kidnaps()) {
      std::snprintf(line, sizeof line, "%llu.%09llu,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f\n",
                    static_cast<unsigned long long>(k.timestamp_ns / 1000000000ULL),
                    static_cast<unsigned long long>(k.timestamp_ns % 1000000000ULL), k.from.x_m,
                    k.from.y_m, k.from.yaw_rad, k.to.x_m, k.to.y_m, k.to.yaw_rad);
      csv << line;
    }
    if (!csv) throw std::runtime_error(kidnaps_path.string() + ": write failed");
  } else {
    std::error_code ec;
    fs::remove(kidnaps_path, ec);  // not a stale one from an earlier run into the same folder
  }

  dataset::DatasetMetadata meta;
  meta.name = s.name;
  meta.seed = seed;
  meta.image_width_px = s.camera.width_px;
  meta.image_height_px = s.camera.height_px;
  meta.pixel_format = hal::PixelFormat::kRgb24;
  meta.frame_rate_hz = s.camera.rate_hz;
  meta.geometry = s.robot;
  meta.camera_forward_m = s.camera.forward_offset_m;
  meta.camera_height_m = s.camera.height_m;
  meta.encoder_layout = s.can_layout;
  meta.ground_truth = "groundtruth.tum";
  dataset::write_metadata(out_dir, meta);
  std::ofstream(fs::path(out_dir) / "scenario.toml") << scenario_to_toml(s);
  return summary;
}

}  // namespace harmoloc::sim_host
