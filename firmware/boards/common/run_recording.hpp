#pragma once
/// @file `harmoloc --record DIR`: the run written as a dataset folder (docs/dataset-format.md)
/// that harmoloc-train takes and the host board replays as it is. Every board composes it the
/// same way: the camera's frames go to a FrameRecorder (writer thread, slots reserved at
/// start-up), the wheel counters the cycle reads to encoders.csv, the boards' areas to
/// areas.csv and, with a map, the fused pose to estimate.tum. None of it makes the cycle wait:
/// a slow disk drops frames (counted), a failed write stops the recording, not the run.

#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>

#include "harmoloc/dataset/area_log.hpp"
#include "harmoloc/dataset/encoder_csv.hpp"
#include "harmoloc/dataset/metadata.hpp"
#include "harmoloc/dataset/tum_writer.hpp"
#include "harmoloc/drivers/frame_recorder.hpp"
#include "harmoloc/drivers/recording_camera.hpp"
#include "harmoloc/firmware/config.hpp"
#include "harmoloc/firmware/localization_cycle.hpp"
#include "harmoloc/firmware/stats_report.hpp"

namespace harmoloc::boards {

struct RecordOptions {
  std::string dir;                         ///< new or empty folder; "" records nothing
  drivers::FrameRecorderOptions frames;    ///< every Nth frame, waiting for the disk
  double max_mb = 0.0, max_seconds = 0.0;  ///< the limits (0: none); frames' own are set from them
};

/// --record DIR, --record-every, --record-max-mb, --record-seconds on a board's command line;
/// @p dropping says what a slow disk does on that board.
void add_record_options(CLI::App& app, RecordOptions& options, const char* dropping);

class RunRecording {
 public:
  RunRecording() = default;
  RunRecording(const RunRecording&) = delete;
  RunRecording& operator=(const RunRecording&) = delete;

  /// Start-up. @p meta describes what is recorded (image size, pixel format, rate, robot); the
  /// encoder fields are set here. Creates the folder, writes metadata.toml and opens every file.
  /// Returns "" or one line saying why not.
  std::string start(const RecordOptions& options, dataset::DatasetMetadata meta,
                    const firmware::FirmwareConfig& config, bool with_pose, hal::Camera& camera,
                    hal::WheelEncoders& encoders);
  bool active() const { return started_; }

  /// What the cycle must read from while recording (the inputs given to start() otherwise).
  hal::Camera& camera() { return *camera_; }
  hal::WheelEncoders& encoders() { return *encoders_; }

  /// After each cycle: the frame's areas and the fused pose.
  void after_cycle(const firmware::LocalizationCycle& cycle);

  /// The text outputs, for a board that reports failed writes as they happen (after start()).
  const dataset::BufferedOutput& areas_output() const { return areas_.output(); }
  const dataset::BufferedOutput& encoders_output() const { return encoder_recorder_->output(); }
  const dataset::BufferedOutput& pose_output() const { return pose_.output(); }

  /// End of the run: the frame writer drained and stopped, every file closed, metadata.toml
  /// rewritten with the counter width seen. Says a summary line on @p err (unless quiet) and
  /// each failure; returns the number of outputs that failed. A board that watches the text
  /// outputs itself (areas_output() ...) passes @p text_outputs = false: they are closed but
  /// neither said nor counted here.
  unsigned finish(bool quiet, std::FILE* err, bool text_outputs = true);

  drivers::FrameRecorderCounters frame_counters() const { return frames_.counters(); }
  /// For the stats (after finish()); inactive when nothing was recorded.
  firmware::RecordingCounters stats() const;

 private:
  std::string dir_;
  dataset::DatasetMetadata meta_;
  drivers::FrameRecorder frames_;
  dataset::AreaLogWriter areas_;
  dataset::TumWriter pose_;
  bool with_pose_ = false;
  bool started_ = false;
  hal::Camera* camera_ = nullptr;
  hal::WheelEncoders* encoders_ = nullptr;
  // Built at start() around the board's devices.
  std::optional<drivers::RecordingCamera> recording_camera_;
  std::optional<dataset::EncoderRecorder> encoder_recorder_;
};

}  // namespace harmoloc::boards
