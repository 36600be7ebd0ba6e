#include "run_recording.hpp"

#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <system_error>
#include <vector>

namespace harmoloc::boards {

void add_record_options(CLI::App& app, RecordOptions& o, const char* dropping) {
  app.add_option(
      "--record", o.dir,
      std::string("record the run as a dataset folder (new or empty) that harmoloc-train "
                  "takes\nand the host board replays: frames, encoders.csv, areas.csv, "
                  "metadata.toml\nand, with --map, estimate.tum "
                  "(docs/dataset-format.md).\n") +
          dropping);
  app.add_option("--record-every", o.frames.every_n,
                 "with --record: keep every Nth frame (default 1: all)")
      ->check(CLI::Range(1U, 1000000U));
  app.add_option("--record-max-mb", o.max_mb,
                 "with --record: stop recording frames after this many MB (0: no limit)")
      ->check(CLI::Range(0.0, 1e9));
  app.add_option("--record-seconds", o.max_seconds,
                 "with --record: stop recording frames this long after the first (0: no limit)")
      ->check(CLI::Range(0.0, 1e9));
}

std::string RunRecording::start(const RecordOptions& options, dataset::DatasetMetadata meta,
                                const firmware::FirmwareConfig& config, bool with_pose,
                                hal::Camera& camera, hal::WheelEncoders& encoders) {
  camera_ = &camera;
  encoders_ = &encoders;
  if (options.dir.empty()) return "";
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path dir(options.dir);
  // A recording never overwrites one: the folder must be new or empty.
  if (fs::exists(dir, ec)) {
    if (!fs::is_directory(dir, ec)) return options.dir + ": exists and is not a folder";
    if (!fs::is_empty(dir, ec)) return options.dir + ": not empty (a recording needs a new folder)";
  } else if (!fs::create_directories(dir, ec)) {
    return options.dir + ": cannot create (" + ec.message() + ")";
  }
  dir_ = options.dir;
  drivers::FrameRecorderOptions frame_options = options.frames;
  frame_options.max_bytes = static_cast<std::uint64_t>(options.max_mb * 1e6);
  frame_options.max_duration_ns = static_cast<std::uint64_t>(options.max_seconds * 1e9);
  meta.name =
      dir.filename().empty() ? dir.parent_path().filename().string() : dir.filename().string();
  meta.seed = 0;
  meta.frames_index = "frames.csv";
  meta.encoder_source = dataset::EncoderSource::kGpio;
  meta.encoder_log = "encoders.csv";
  meta.ground_truth.clear();
  // The config's mounting, where it gives one, over a replayed dataset's.
  if (std::isfinite(config.camera.mount_height_m))
    meta.camera_height_m = config.camera.mount_height_m;
  if (std::isfinite(config.camera.mount_forward_m))
    meta.camera_forward_m = config.camera.mount_forward_m;
  meta_ = meta;
  try {
    dataset::write_metadata(dir_, meta_);
  } catch (const std::exception& e) {
    return e.what();
  }
  if (const std::string e = frames_.start(dir_, meta.image_width_px, meta.image_height_px,
                                          meta.pixel_format, frame_options);
      !e.empty()) {
    return e;
  }
  const std::vector<std::string> names(config.board_names.names.begin(),
                                       config.board_names.names.end());
  const std::string areas_path = (dir / "areas.csv").string();
  if (!areas_.open(areas_path, meta.image_width_px, meta.image_height_px, config.thresholds,
                   names)) {
    return areas_path + ": cannot write";
  }
  const std::string encoders_path = (dir / "encoders.csv").string();
  encoder_recorder_.emplace(encoders);
  if (!encoder_recorder_->open(encoders_path)) return encoders_path + ": cannot write";
  with_pose_ = with_pose;
  if (with_pose_) {
    const std::string pose_path = (dir / "estimate.tum").string();
    if (!pose_.open(pose_path)) return pose_path + ": cannot write";
  }
  recording_camera_.emplace(camera, frames_);
  camera_ = &*recording_camera_;
  encoders_ = &*encoder_recorder_;
  started_ = true;
  return "";
}

void RunRecording::after_cycle(const firmware::LocalizationCycle& cycle) {
  if (!started_) return;
  const firmware::PoseOutput& out = cycle.pose();
  const firmware::FixOutput& fix = cycle.last_fix();
  if (fix.present) areas_.write(out.data_time_ns, fix.areas, fix.distrusted_mask);
  if (with_pose_ && out.valid) pose_.write(out.data_time_ns, out.pose);
}

firmware::RecordingCounters RunRecording::stats() const {
  firmware::RecordingCounters r;
  if (!recording_camera_) return r;  // built last in start(): nothing was recorded
  const drivers::FrameRecorderCounters c = frames_.counters();
  r.active = true;
  r.frames = c.recorded;
  r.dropped = c.dropped;
  r.skipped = c.skipped;
  r.bytes = c.bytes;
  r.stopped = drivers::recording_stop_name(frames_.stop_reason());
  return r;
}

unsigned RunRecording::finish(bool quiet, std::FILE* err, bool text_outputs) {
  if (!started_) return 0;
  started_ = false;
  frames_.stop();
  unsigned failed = 0;
  const auto said = [&](const std::string& path, int error) {
    std::fprintf(err, "harmoloc: %s: write failed (%s)\n", path.c_str(),
                 std::strerror(error != 0 ? error : EIO));
    ++failed;
  };
  const bool areas_ok = areas_.close();
  const bool encoders_ok = encoder_recorder_->close();
  const bool pose_ok = !with_pose_ || pose_.close();
  if (text_outputs) {
    if (!areas_ok) said(areas_.output().path(), areas_.output().error());
    if (!encoders_ok) said(encoder_recorder_->output().path(), encoder_recorder_->output().error());
    if (!pose_ok) said(pose_.output().path(), pose_.output().error());
  }
  if (frames_.stop_reason() == drivers::RecordingStop::kWriteFailed)
    said(frames_.failed_path(), frames_.error());
  // The counter width the recording's samples have (the bus's, or 32 for GPIO).
  if (encoder_recorder_->counter_bits() != 0)
    meta_.encoder_layout.counter_bits = encoder_recorder_->counter_bits();
  try {
    dataset::write_metadata(dir_, meta_);
  } catch (const std::exception& e) {
    std::fprintf(err, "harmoloc: %s\n", e.what());
    ++failed;
  }
  if (!quiet) {
    const drivers::FrameRecorderCounters c = frames_.counters();
    const char* stopped = drivers::recording_stop_name(frames_.stop_reason());
    std::fprintf(err,
                 "harmoloc: recorded %s: %llu frames (%.1f MB; %llu dropped: disk too slow, %llu "
                 "left out by --record-every), %llu encoder samples%s%s%s\n",
                 dir_.c_str(), static_cast<unsigned long long>(c.recorded),
                 static_cast<double>(c.bytes) / 1e6, static_cast<unsigned long long>(c.dropped),
                 static_cast<unsigned long long>(c.skipped),
                 static_cast<unsigned long long>(encoder_recorder_->samples_written()),
                 with_pose_ ? ", poses in estimate.tum" : "",
                 *stopped != 0 ? "; frames stopped: " : "", stopped);
  }
  return failed;
}

}  // namespace harmoloc::boards
