#include "host_board.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>

namespace harmoloc::boards {

void add_host_options(CLI::App& app, HostOptions& h) {
  AppOptions& o = h.app;
  app.add_option("--dataset", h.dataset, "dataset folder (metadata.toml, frames.csv, encoders.log)")
      ->required();
  app.add_option("--map", o.map_path,
                 "map file from harmoloc-train (may be left out with --record or --record-areas,\n"
                 "to record a first run before any map exists: nothing is localised then)");
  app.add_option("--config", o.config_path,
                 "firmware config (TOML, docs/config-format.md); default: built-in");
  app.add_option("--trajectory", o.trajectory_path,
                 "write the fused pose of every cycle here (TUM)");
  app.add_option("--link", o.link_path,
                 "MAVLink v2 output: a file, or a serial device or pty (raw, --config link.baud)");
  app.add_option("--link-in", o.link_in_path,
                 "read the link's inbound bytes (MAVLink commands) from this file or FIFO instead\n"
                 "of --link (a serial device or pty is read by itself)");
  app.add_option("--stats", o.stats_path,
                 "write run statistics here (JSON: per-stage timing, overruns, counters)");
  app.add_option("--fixes", o.fixes_path,
                 "write the harmonic localizer's own fixes here (TUM), for comparison");
  app.add_option("--record-areas", o.areas_path,
                 "write every frame's board areas here (area log, docs/dataset-format.md): with\n"
                 "a few labelled poses, harmoloc-train --areas makes a map from it");
  add_record_options(app, o.record,
                     "Unpaced, every frame is recorded; with --realtime a slow disk\ndrops "
                     "frames (counted), as on a robot");
  app.add_option("--record-encoders", o.record_encoders_path,
                 "write every fresh encoder sample the cycle reads here, as a GPIO encoder\n"
                 "recording (encoders.csv, docs/dataset-format.md)");
  app.add_flag("--realtime", h.realtime,
               "pace the cycle at the recording's rate instead of as fast as possible\n"
               "(cycle.pacing: \"camera\" waits for each frame's recorded time, \"timer\" wakes\n"
               "every period and takes the frame that is due, if any)");
  app.add_option("--loop", h.loops,
                 "replay the dataset this many times back to back (soak runs); time and the\n"
                 "encoder counters run on across passes")
      ->check(CLI::Range(1U, 1000000U));
  app.add_flag("--quiet", o.quiet, "no progress output");
}

void DatasetDevices::open_metadata(const std::string& dir, firmware::FirmwareConfig& config) {
  dir_ = dir;
  meta_ = dataset::read_metadata(dir);
  if (!config.has_odometry_section) config.geometry = meta_.geometry;
  if (!config.has_can_section) config.can_layout = meta_.encoder_layout;
}

void DatasetDevices::open(const firmware::FirmwareConfig& config, std::uint32_t loops) {
  camera_ = std::make_unique<host::FileCamera>(dir_, meta_);
  const std::string encoder_path = (std::filesystem::path(dir_) / meta_.encoder_log).string();
  std::uint64_t encoders_first_ns = 0, encoders_last_ns = 0;
  if (meta_.encoder_source == dataset::EncoderSource::kGpio) {
    // A GPIO recording: its counter width is the metadata's (the config's [can] is the bus's).
    gpio_log_ =
        std::make_unique<host::GpioLogEncoders>(encoder_path, meta_.encoder_layout.counter_bits);
    encoders_ = gpio_log_.get();
    encoder_records_ = gpio_log_->sample_count();
    encoders_first_ns = gpio_log_->first_timestamp_ns();
    encoders_last_ns = gpio_log_->last_timestamp_ns();
  } else {
    can_log_ = std::make_unique<host::LogEncoders>(encoder_path, config.can_layout);
    encoders_ = can_log_.get();
    encoder_records_ = can_log_->frame_count();
    encoders_first_ns = can_log_->first_timestamp_ns();
    encoders_last_ns = can_log_->last_timestamp_ns();
  }
  recorded_time_.emplace(*camera_);
  if (loops <= 1) return;
  // One pass lasts from the first to the last record, plus one frame period.
  const std::uint64_t first = encoder_records_ > 0
                                  ? std::min(camera_->first_timestamp_ns(), encoders_first_ns)
                                  : camera_->first_timestamp_ns();
  const std::uint64_t last = std::max(camera_->last_timestamp_ns(), encoders_last_ns);
  const auto period = static_cast<std::uint64_t>(1e9 / meta_.frame_rate_hz);
  camera_->set_loops(loops, last - first + period);
  if (can_log_) can_log_->set_loops(loops, last - first + period);
  if (gpio_log_) gpio_log_->set_loops(loops, last - first + period);
}

hal::Camera& DatasetDevices::cycle_camera(bool timer_paced) {
  // Camera-paced (and unpaced) replays see a hole in the recording as a live camera's cycle
  // would: a no-frame cycle each period, so the health and the counters notice it. Timer pacing
  // has those cycles from its own clock.
  camera_->set_fill_gaps(!timer_paced);
  return timer_paced ? static_cast<hal::Camera&>(*recorded_time_) : *camera_;
}

dataset::DatasetMetadata DatasetDevices::recorded(const firmware::FirmwareConfig& config) const {
  dataset::DatasetMetadata recorded = meta_;
  recorded.geometry = config.geometry;
  recorded.encoder_layout = config.can_layout;
  return recorded;
}

void DatasetDevices::say(const algorithms::MapFile& map, const firmware::FirmwareConfig& config,
                         bool realtime, bool timer_paced) const {
  std::fprintf(stderr,
               "harmoloc: %zu frames %ux%u, %zu encoder %s, map of %u samples on %u boards, "
               "%zu particles%s\n",
               camera_->frame_count(), meta_.image_width_px, meta_.image_height_px,
               encoder_records_, gpio_log_ ? "samples (GPIO recording)" : "frames",
               map.model.sample_count, map.model.feature_count, config.filter.particles,
               !realtime     ? ""
               : timer_paced ? ", real-time pacing (timer)"
                             : ", real-time pacing (camera)");
}

firmware::CycleResult HostLoop::run_cycle(firmware::LocalizationCycle& cycle) {
  if (timer_paced_) return cycle.run_once(pacer_.wait_for_cycle());
  host::FileCamera& camera = devices_.file_camera();
  if (realtime_ && camera.next_timestamp_ns() >= data_start_ns_) {
    // Absolute deadlines from the start (clock_nanosleep TIMER_ABSTIME): no drift.
    const std::uint64_t deadline = wall_start_ns_ + (camera.next_timestamp_ns() - data_start_ns_);
    clock_.sleep_until(deadline);
    const std::uint64_t woke = clock_.now_ns();
    wakeup_latency_.record(woke > deadline ? woke - deadline : 0);
  }
  return cycle.run_once();
}

void HostLoop::started(std::uint64_t start_ns) {
  wall_start_ns_ = start_ns;
  data_start_ns_ = devices_.file_camera().first_timestamp_ns();
  devices_.recorded_time_camera().start(wall_start_ns_, data_start_ns_);
}

const char* HostLoop::after_cycle(const firmware::LocalizationCycle& /*cycle*/,
                                  std::uint64_t cycles) {
  if (!quiet_ && cycles % 300 == 0) {
    std::fprintf(stderr, "\r  cycle %zu/%zu", static_cast<std::size_t>(cycles),
                 devices_.file_camera().frame_count());
  }
  return nullptr;
}

void HostLoop::stopping(const char* /*ended*/, std::uint64_t cycles) {
  if (!quiet_) {
    std::fprintf(stderr, "\r  cycle %zu/%zu\n", static_cast<std::size_t>(cycles),
                 devices_.file_camera().frame_count());
  }
}

}  // namespace harmoloc::boards
