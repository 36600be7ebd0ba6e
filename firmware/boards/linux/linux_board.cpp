#include "linux_board.hpp"

#include <cstdio>

namespace harmoloc::boards {
namespace {

drivers::FormatRequest format_request(const std::string& name) {
  if (name == "yuyv") return drivers::FormatRequest::kYuyv;
  if (name == "rgb24") return drivers::FormatRequest::kRgb24;
  return drivers::FormatRequest::kAuto;
}

// What V4L2 and libcamera are both asked for.
template <typename CameraOptions>
CameraOptions frame_request(const firmware::FirmwareConfig& config) {
  CameraOptions o;
  o.width_px = config.camera.width_px;
  o.height_px = config.camera.height_px;
  o.format = format_request(config.camera.format);
  o.buffers = config.camera.buffers;
  return o;
}

}  // namespace

void add_linux_options(CLI::App& app, LinuxOptions& l) {
  AppOptions& o = l.app;
  app.add_option("--map", o.map_path,
                 "map file from harmoloc-train (may be left out with --record, to record a\n"
                 "training run before any map exists: nothing is localised then)");
  app.add_option("--config", o.config_path,
                 "firmware config (TOML, docs/config-format.md); default: built-in");
  app.add_option("--link", o.link_path,
                 "serial device for the MAVLink v2 stream (overrides link.device); a file works");
  app.add_option("--stats", o.stats_path,
                 "write run statistics here at the end (JSON: per-stage timing, counters), and\n"
                 "on SIGUSR1 while running (replaced whole, never half-written)");
  app.add_option("--trajectory", o.trajectory_path,
                 "write the fused pose of every cycle here (TUM)");
  app.add_option("--record-encoders", o.record_encoders_path,
                 "record the wheel counters the cycle reads as a GPIO encoder recording (CSV\n"
                 "timestamp_ns,left_ticks,right_ticks; docs/dataset-format.md)");
  add_record_options(
      app, o.record,
      "A slow disk drops frames (counted), a full one stops the\nrecording, never the cycle");
  app.add_option("--duration", l.duration_s, "stop after this many seconds (0: run until a signal)")
      ->check(CLI::Range(0.0, 1e9));
  app.add_option("--cycles", l.max_cycles, "stop after this many cycles (0: no limit)");
  app.add_flag("--quiet", o.quiet, "no progress output");
}

std::string LinuxDevices::open_camera(const firmware::FirmwareConfig& config, hal::Clock& clock) {
  if (config.camera.driver == "v4l2") {
    v4l2_ = std::make_unique<drivers::V4l2Camera>(clock);
    auto o = frame_request<drivers::V4l2Options>(config);
    o.device = config.camera.device;
    o.reopen_interval_ms = config.camera.reopen_interval_ms;
    if (const std::string e = v4l2_->open(o); !e.empty()) return "camera " + e;
    camera_ = v4l2_.get();
    pixel_format_ = v4l2_->pixel_format();
    camera_text_ = "V4L2 " + config.camera.device + ": " + v4l2_->description();
    return "";
  }
#ifdef HARMOLOC_WITH_LIBCAMERA
  libcam_ = std::make_unique<drivers::LibcameraCamera>(clock);
  auto o = frame_request<drivers::LibcameraOptions>(config);
  o.camera_id = config.camera.device;
  if (const std::string e = libcam_->open(o); !e.empty()) return "camera " + e;
  camera_ = libcam_.get();
  pixel_format_ = libcam_->pixel_format();
  camera_text_ = "libcamera " + libcam_->description();
  return "";
#else
  return "camera.driver = \"libcamera\", but this harmoloc was built without libcamera";
#endif
}

std::string LinuxDevices::open_encoders(const firmware::FirmwareConfig& config) {
  if (config.encoders.driver == "can") {
    can_ = std::make_unique<drivers::SocketCanEncoders>();
    drivers::SocketCanOptions o;
    o.interface = config.can_interface;
    o.layout = config.can_layout;
    o.kernel_filter = config.encoders.can_kernel_filter;
    if (std::string e = can_->open(o); !e.empty()) return e;
    encoders_ = can_.get();
    char id[16];
    std::snprintf(id, sizeof id, "0x%X", config.can_layout.id);
    encoders_text_ = "SocketCAN " + config.can_interface + ", ID " + id;
    return "";
  }
#ifdef HARMOLOC_WITH_GPIOD
  gpio_ = std::make_unique<drivers::GpioQuadratureEncoders>();
  drivers::GpioEncoderOptions o;
  o.chip = config.encoders.gpio_chip;
  o.left_lines = config.encoders.left_lines;
  o.right_lines = config.encoders.right_lines;
  o.debounce_us = config.encoders.debounce_us;
  o.reader = config.encoders.gpio_reader == "cycle" ? drivers::GpioReader::kCycle
                                                    : drivers::GpioReader::kThread;
  if (std::string e = gpio_->open(o); !e.empty()) return e;
  encoders_ = gpio_.get();
  encoders_text_ = "GPIO " + gpio_->description();
  return "";
#else
  return "encoders.driver = \"gpio\", but this harmoloc was built without libgpiod";
#endif
}

dataset::DatasetMetadata LinuxDevices::recorded(const firmware::FirmwareConfig& config) const {
  dataset::DatasetMetadata recorded;
  recorded.image_width_px = config.camera.width_px;
  recorded.image_height_px = config.camera.height_px;
  recorded.pixel_format = pixel_format_;
  recorded.frame_rate_hz = config.cycle.rate_hz;
  recorded.can_interface = config.can_interface;
  recorded.geometry = config.geometry;
  recorded.encoder_layout = config.can_layout;
  return recorded;
}

void LinuxLoop::started(std::uint64_t start_ns) {
  if (options_.duration_s > 0.0)
    end_ns_ = start_ns + static_cast<std::uint64_t>(options_.duration_s * 1e9);
  char status[128];
  std::snprintf(status, sizeof status, "localizing at %.0f Hz, %zu particles, waiting for a fix",
                config_.cycle.rate_hz, config_.filter.particles);
  notifier_.ready(status);
}

const char* LinuxLoop::after_cycle(const firmware::LocalizationCycle& cycle, std::uint64_t cycles) {
  const std::uint64_t now_ns = clock_.now_ns();
  notifier_.feed(now_ns);
  if (!options_.app.quiet) {
    if (const char* line = health_log_.observe(cycle.pose().health, cycle.overrun_alarm(), now_ns))
      notifier_.status(line);
  }
  if (options_.max_cycles != 0 && cycles >= options_.max_cycles) return "cycle limit";
  if (end_ns_ != 0 && clock_.now_ns() >= end_ns_) return "duration";
  return nullptr;
}

void LinuxLoop::stopping(const char* ended, std::uint64_t /*cycles*/) {
  char status[96];
  std::snprintf(status, sizeof status, "stopping: %s", ended);
  notifier_.stopping(status);
}

}  // namespace harmoloc::boards
