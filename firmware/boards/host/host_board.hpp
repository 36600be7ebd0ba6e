#pragma once
/// @file The host board's pieces for its main: its command line, a dataset folder as its devices
/// (drivers/host's fakes) and its pacing of the shared run loop (unpaced replay, or --realtime
/// on the recording's clock).

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>

#include "application.hpp"

#include "harmoloc/dataset/metadata.hpp"
#include "harmoloc/firmware/latency_histogram.hpp"
#include "harmoloc/host/file_camera.hpp"
#include "harmoloc/host/gpio_log_encoders.hpp"
#include "harmoloc/host/log_encoders.hpp"
#include "harmoloc/host/recorded_time_camera.hpp"

namespace harmoloc::boards {

struct HostOptions {
  AppOptions app;
  std::string dataset;
  bool realtime = false;
  std::uint32_t loops = 1;
};

void add_host_options(CLI::App& app, HostOptions& o);

/// A dataset folder as the camera and the encoder bus (a candump log or a GPIO recording).
class DatasetDevices {
 public:
  /// Reads metadata.toml; a config without [odometry] or [can] follows the recorded robot.
  /// Throws on bad input.
  void open_metadata(const std::string& dir, firmware::FirmwareConfig& config);
  const dataset::DatasetMetadata& metadata() const { return meta_; }
  /// The frames and the encoder records, every one checked; @p loops passes back to back.
  /// Throws on bad input.
  void open(const firmware::FirmwareConfig& config, std::uint32_t loops);
  hal::WheelEncoders& encoders() { return *encoders_; }
  host::FileCamera& file_camera() { return *camera_; }
  /// The camera the cycle reads: the recording's frames in order or, timer-paced, as a live
  /// camera would have them at their recorded times.
  hal::Camera& cycle_camera(bool timer_paced);
  host::RecordedTimeCamera& recorded_time_camera() { return *recorded_time_; }
  /// What a --record folder of this replay says about the robot.
  dataset::DatasetMetadata recorded(const firmware::FirmwareConfig& config) const;
  void say(const algorithms::MapFile& map, const firmware::FirmwareConfig& config, bool realtime,
           bool timer_paced) const;

 private:
  std::string dir_;
  dataset::DatasetMetadata meta_;
  std::unique_ptr<host::FileCamera> camera_;
  std::unique_ptr<host::LogEncoders> can_log_;
  std::unique_ptr<host::GpioLogEncoders> gpio_log_;
  std::optional<host::RecordedTimeCamera> recorded_time_;
  hal::WheelEncoders* encoders_ = nullptr;
  std::size_t encoder_records_ = 0;
};

/// Unpaced (as fast as it goes), or with --realtime paced by the recording's timestamps on
/// absolute deadlines (camera pacing) or by the cycle pacer's grid (timer pacing).
class HostLoop final : public BoardLoop {
 public:
  HostLoop(DatasetDevices& devices, firmware::CyclePacer& pacer, hal::Clock& clock, bool realtime,
           bool timer_paced, bool quiet)
      : devices_(devices),
        pacer_(pacer),
        clock_(clock),
        realtime_(realtime),
        timer_paced_(timer_paced),
        quiet_(quiet) {}
  firmware::CycleResult run_cycle(firmware::LocalizationCycle& cycle) override;
  void started(std::uint64_t start_ns) override;
  const char* after_cycle(const firmware::LocalizationCycle& cycle, std::uint64_t cycles) override;
  void stopping(const char* ended, std::uint64_t cycles) override;
  /// How late each wake-up was (with --realtime).
  const firmware::LatencyHistogram* wakeup_latency() const {
    return timer_paced_ ? &pacer_.wakeup_latency() : &wakeup_latency_;
  }

 private:
  DatasetDevices& devices_;
  firmware::CyclePacer& pacer_;
  hal::Clock& clock_;
  bool realtime_, timer_paced_, quiet_;
  std::uint64_t wall_start_ns_ = 0, data_start_ns_ = 0;
  firmware::LatencyHistogram wakeup_latency_;
};

}  // namespace harmoloc::boards
