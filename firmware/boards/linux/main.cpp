// harmoloc for the Linux board: the firmware's cycle on real devices. The camera is a V4L2
// capture device or a libcamera camera, the wheel encoders come from a SocketCAN bus or from
// quadrature lines on GPIO, the pose goes out on a serial line; all chosen by the config
// (docs/drivers.md). The cycle is the host board's, paced by the camera or by a timer
// (cycle.pacing; docs/architecture.md, "Pacing and overruns").
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include <CLI/CLI.hpp>

#include "board_run.hpp"
#include "health_log.hpp"
#include "run_recording.hpp"

#include "harmoloc/dataset/encoder_csv.hpp"
#include "harmoloc/drivers/monotonic_clock.hpp"
#include "harmoloc/drivers/realtime_setup.hpp"
#include "harmoloc/drivers/record_file.hpp"
#include "harmoloc/drivers/serial_link.hpp"
#include "harmoloc/drivers/service_notifier.hpp"
#include "harmoloc/drivers/socketcan_encoders.hpp"
#include "harmoloc/drivers/stop_signals.hpp"
#include "harmoloc/drivers/v4l2_camera.hpp"
#include "harmoloc/firmware/cli.hpp"
#include "harmoloc/firmware/config.hpp"
#include "harmoloc/firmware/cycle_pacer.hpp"
#include "harmoloc/firmware/eigen_guard.hpp"
#include "harmoloc/firmware/localization_cycle.hpp"
#include "harmoloc/firmware/map_loader.hpp"
#include "harmoloc/firmware/stats_report.hpp"
#ifdef HARMOLOC_WITH_GPIOD
#include "harmoloc/drivers/gpio_quadrature_encoders.hpp"
#endif
#ifdef HARMOLOC_WITH_LIBCAMERA
#include "harmoloc/drivers/libcamera_camera.hpp"
#endif

namespace {

using namespace harmoloc;

// The map: fixed capacity (1.8 MB with the forward map's tiles), allocated once when the program
// starts and never freed. As a static object it would be initialised data (its thresholds and
// feature weights default to non-zero), a 1.8 MB image of near-zeros in the executable.
algorithms::MapFile& g_map = *new algorithms::MapFile();

int fail(const std::string& why) {
  std::fprintf(stderr, "harmoloc: %s\n", why.c_str());
  return 2;
}

drivers::FormatRequest format_request(const std::string& name) {
  if (name == "yuyv") return drivers::FormatRequest::kYuyv;
  if (name == "rgb24") return drivers::FormatRequest::kRgb24;
  return drivers::FormatRequest::kAuto;
}

// The trajectory as TUM lines through a buffer reserved at start-up.
char g_trajectory_buffer[1 << 16];

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "harmoloc (Linux board): runs the firmware's fixed-rate localization cycle on the robot's\n"
      "devices: a V4L2 or libcamera camera, SocketCAN or GPIO quadrature wheel encoders, and a\n"
      "serial line for the MAVLink v2 pose stream (docs/drivers.md, docs/config-format.md).\n"
      "Runs until SIGTERM/SIGINT/SIGHUP (stops at the next cycle, writes every output),\n"
      "--duration or --cycles. Exit status 0 after a run, 1 if an output could not be written,\n"
      "2 with a one-line reason on a bad config, map or a missing device, 3 if no pose was ever\n"
      "produced.",
      "harmoloc"};
  std::string map_path, config_path, link_path, stats_path, trajectory_path, record_encoders_path;
  double duration_s = 0.0;
  std::uint64_t max_cycles = 0;
  bool quiet = false;
  boards::RecordOptions record;
  app.add_option("--map", map_path,
                 "map file from harmoloc-train (may be left out with --record, to record a\n"
                 "training run before any map exists: nothing is localised then)");
  app.add_option("--config", config_path,
                 "firmware config (TOML, docs/config-format.md); default: built-in");
  app.add_option("--link", link_path,
                 "serial device for the MAVLink v2 stream (overrides link.device); a file works");
  app.add_option("--stats", stats_path,
                 "write run statistics here at the end (JSON: per-stage timing, counters)");
  app.add_option("--trajectory", trajectory_path, "write the fused pose of every cycle here (TUM)");
  app.add_option("--record-encoders", record_encoders_path,
                 "record the wheel counters the cycle reads as a GPIO encoder recording (CSV\n"
                 "timestamp_ns,left_ticks,right_ticks; docs/dataset-format.md)");
  boards::add_record_options(
      app, record,
      "A slow disk drops frames (counted), a full one stops the\nrecording, never the cycle");
  app.add_option("--duration", duration_s, "stop after this many seconds (0: run until a signal)")
      ->check(CLI::Range(0.0, 1e9));
  app.add_option("--cycles", max_cycles, "stop after this many cycles (0: no limit)");
  app.add_flag("--quiet", quiet, "no progress output");
  if (const auto status = harmoloc::cli::parse(app, argc, argv)) return *status;

  // ---- start-up: everything is read, checked, opened and reserved here ----
  firmware::FirmwareConfig config;
  try {
    config = config_path.empty() ? firmware::default_config() : firmware::load_config(config_path);
  } catch (const std::exception& e) {
    return fail(e.what());
  }
  if (!map_path.empty()) {
    if (const std::string e = firmware::load_map(map_path, g_map); !e.empty()) return fail(e);
  } else if (!record.dir.empty()) {
    // Recording a training run: an empty map with the config's thresholds segments every frame
    // (the areas are recorded) and localises none.
    g_map.image_width_px = config.camera.width_px;
    g_map.image_height_px = config.camera.height_px;
    g_map.thresholds = config.thresholds;
  } else {
    return fail("--map is required (or --record DIR to record a training run before a map exists)");
  }
  if (const std::string e = firmware::check_map_matches(g_map, config, config.camera.width_px,
                                                        config.camera.height_px);
      !e.empty()) {
    return fail(e);
  }
  if (!stats_path.empty()) {
    std::ofstream probe(stats_path);
    if (!probe) return fail(stats_path + ": cannot write");
  }
  std::FILE* trajectory = nullptr;
  if (!trajectory_path.empty()) {
    trajectory = std::fopen(trajectory_path.c_str(), "w");
    if (trajectory == nullptr) return fail(trajectory_path + ": cannot write");
    std::setvbuf(trajectory, g_trajectory_buffer, _IOFBF, sizeof g_trajectory_buffer);
  }

  drivers::MonotonicClock clock;

  // Camera.
  std::unique_ptr<drivers::V4l2Camera> v4l2;
#ifdef HARMOLOC_WITH_LIBCAMERA
  std::unique_ptr<drivers::LibcameraCamera> libcam;
#endif
  hal::Camera* camera = nullptr;
  hal::PixelFormat pixel_format = hal::PixelFormat::kYuyv;
  std::string camera_text;
  if (config.camera.driver == "v4l2") {
    v4l2 = std::make_unique<drivers::V4l2Camera>(clock);
    drivers::V4l2Options o;
    o.device = config.camera.device;
    o.width_px = config.camera.width_px;
    o.height_px = config.camera.height_px;
    o.format = format_request(config.camera.format);
    o.buffers = config.camera.buffers;
    o.reopen_interval_ms = config.camera.reopen_interval_ms;
    if (const std::string e = v4l2->open(o); !e.empty()) return fail("camera " + e);
    camera = v4l2.get();
    pixel_format = v4l2->pixel_format();
    camera_text = "V4L2 " + config.camera.device + ": " + v4l2->description();
  } else {
#ifdef HARMOLOC_WITH_LIBCAMERA
    libcam = std::make_unique<drivers::LibcameraCamera>(clock);
    drivers::LibcameraOptions o;
    o.camera_id = config.camera.device;
    o.width_px = config.camera.width_px;
    o.height_px = config.camera.height_px;
    o.format = format_request(config.camera.format);
    o.buffers = config.camera.buffers;
    if (const std::string e = libcam->open(o); !e.empty()) return fail("camera " + e);
    camera = libcam.get();
    pixel_format = libcam->pixel_format();
    camera_text = "libcamera " + libcam->description();
#else
    return fail("camera.driver = \"libcamera\", but this harmoloc was built without libcamera");
#endif
  }

  // Wheel encoders.
  std::unique_ptr<drivers::SocketCanEncoders> can;
#ifdef HARMOLOC_WITH_GPIOD
  std::unique_ptr<drivers::GpioQuadratureEncoders> gpio;
#endif
  hal::WheelEncoders* encoders = nullptr;
  std::string encoders_text;
  if (config.encoders.driver == "can") {
    can = std::make_unique<drivers::SocketCanEncoders>();
    drivers::SocketCanOptions o;
    o.interface = config.can_interface;
    o.layout = config.can_layout;
    o.kernel_filter = config.encoders.can_kernel_filter;
    if (const std::string e = can->open(o); !e.empty()) return fail(e);
    encoders = can.get();
    char id[16];
    std::snprintf(id, sizeof id, "0x%X", config.can_layout.id);
    encoders_text = "SocketCAN " + config.can_interface + ", ID " + id;
  } else {
#ifdef HARMOLOC_WITH_GPIOD
    gpio = std::make_unique<drivers::GpioQuadratureEncoders>();
    drivers::GpioEncoderOptions o;
    o.chip = config.encoders.gpio_chip;
    o.left_lines = config.encoders.left_lines;
    o.right_lines = config.encoders.right_lines;
    o.debounce_us = config.encoders.debounce_us;
    o.reader = config.encoders.gpio_reader == "cycle" ? drivers::GpioReader::kCycle
                                                      : drivers::GpioReader::kThread;
    if (const std::string e = gpio->open(o); !e.empty()) return fail(e);
    encoders = gpio.get();
    encoders_text = "GPIO " + gpio->description();
#else
    return fail("encoders.driver = \"gpio\", but this harmoloc was built without libgpiod");
#endif
  }

  // Recording the counters the cycle reads (a 64 KiB buffer reserved here).
  dataset::EncoderRecorder recorder(*encoders);
  if (!record_encoders_path.empty()) {
    if (!recorder.open(record_encoders_path)) return fail(record_encoders_path + ": cannot write");
    encoders = &recorder;
  }

  // Link.
  drivers::SerialLink link;
  const std::string link_device = link_path.empty() ? config.link.device : link_path;
  if (const std::string e = link.open(link_device, config.link.baud); !e.empty())
    return fail("link " + e);

  // Real time: applied where permitted (said once on stderr), as the config asks.
  const drivers::RealtimeReport rt = drivers::apply_realtime(drivers::RealtimeOptions{
      config.realtime.enabled, config.realtime.priority, config.realtime.cpu,
      config.realtime.lock_memory, config.realtime.prefault_stack_kb});

  // Recording (frame slots and text buffers reserved here).
  static boards::RunRecording recording;
  {
    dataset::DatasetMetadata recorded;
    recorded.image_width_px = config.camera.width_px;
    recorded.image_height_px = config.camera.height_px;
    recorded.pixel_format = pixel_format;
    recorded.frame_rate_hz = config.cycle.rate_hz;
    recorded.can_interface = config.can_interface;
    recorded.geometry = config.geometry;
    recorded.encoder_layout = config.can_layout;
    if (const std::string e =
            recording.start(record, recorded, config, !map_path.empty(), *camera, *encoders);
        !e.empty()) {
      return fail(e);
    }
  }

  auto cycle = std::make_unique<firmware::LocalizationCycle>(
      config, g_map, recording.camera(), recording.encoders(), link, clock, pixel_format);
  cycle->set_live_clock(true);
  cycle->set_overrun_alarm(true);
  static firmware::CyclePacer pacer(
      clock, config.cycle.pacing,
      static_cast<std::uint64_t>(std::llround(1e9 / config.cycle.rate_hz)));
  static drivers::RecordFile signing_store;
  if (const std::string e = boards::start_signing(config, *cycle, signing_store); !e.empty())
    return fail(e);
  if (!quiet) {
    std::fprintf(stderr, "harmoloc: camera %s\n", camera_text.c_str());
    std::fprintf(stderr, "harmoloc: encoders %s\n", encoders_text.c_str());
    std::fprintf(stderr, "harmoloc: link %s%s at %u baud\n", link_device.c_str(),
                 link.is_tty() ? " (serial, raw)" : " (file)", config.link.baud);
    std::fprintf(stderr,
                 "harmoloc: map of %u samples on %u boards, %zu particles, %.0f Hz, %s-paced\n",
                 g_map.model.sample_count, g_map.model.feature_count, config.filter.particles,
                 config.cycle.rate_hz, firmware::pacing_name(config.cycle.pacing));
    if (const std::string odometry = firmware::odometry_summary(config, g_map.calibration);
        !odometry.empty())
      std::fprintf(stderr, "harmoloc: %s\n", odometry.c_str());
    std::fprintf(stderr, "harmoloc: %s\n", rt.summary.c_str());
  }

  drivers::install_stop_signals();
  // Type=notify: READY once everything above has been checked, the watchdog fed from the loop.
  static drivers::ServiceNotifier notifier;
  if (const std::string e = notifier.open(); !e.empty()) return fail(e);
  static boards::HealthLog health_log;
  health_log.start();

  firmware::RunCounters run;
  long unused_peak = 0;
  boards::read_memory(run.rss_kb_start, unused_peak);
  run.open_fds_start = boards::count_open_fds();

  // ---- the cycle: camera-paced (acquire waits for the next frame, at most a period) or
  // timer-paced (wakes on an absolute grid, takes a ready frame or none) ----
  firmware::forbid_eigen_heap();  // Eigen may not allocate from here on (eigen_guard.hpp)
  const std::uint64_t start_ns = clock.now_ns();
  const auto end_ns =
      duration_s > 0.0 ? start_ns + static_cast<std::uint64_t>(duration_s * 1e9) : std::uint64_t{0};
  std::uint64_t done = 0;
  bool any_pose = false;
  int trajectory_error = 0;  // errno of the trajectory's first failed write
  run.ended = "camera ended";
  {
    char status[128];
    std::snprintf(status, sizeof status, "localizing at %.0f Hz, %zu particles, waiting for a fix",
                  config.cycle.rate_hz, config.filter.particles);
    notifier.ready(status);
  }
  for (;;) {
    if (drivers::stop_signal() != 0) {
      run.ended = drivers::signal_name(drivers::stop_signal());
      break;
    }
    if (cycle->run_once(pacer.wait_for_cycle()) == firmware::CycleResult::kEnded) break;
    ++done;
    const firmware::PoseOutput& out = cycle->pose();
    any_pose = any_pose || out.valid;
    const std::uint64_t now_ns = clock.now_ns();
    notifier.feed(now_ns);
    if (!quiet) {
      if (const char* line = health_log.observe(out.health, cycle->overrun_alarm(), now_ns))
        notifier.status(line);
    }
    recording.after_cycle(*cycle);
    if (trajectory != nullptr && out.valid) {
      const double yaw_half = 0.5 * out.pose.yaw_rad;
      if (std::fprintf(trajectory, "%.9f %.6f %.6f 0 0 0 %.9f %.9f\n",
                       static_cast<double>(out.data_time_ns) * 1e-9, out.pose.x_m, out.pose.y_m,
                       std::sin(yaw_half), std::cos(yaw_half)) < 0 &&
          trajectory_error == 0) {
        // Said when it happens, naming the file; the pose still goes out on the link.
        trajectory_error = errno != 0 ? errno : EIO;
        std::fprintf(stderr, "harmoloc: %s: write failed (%s)\n", trajectory_path.c_str(),
                     std::strerror(trajectory_error));
      }
    }
    if (max_cycles != 0 && done >= max_cycles) {
      run.ended = "cycle limit";
      break;
    }
    if (end_ns != 0 && clock.now_ns() >= end_ns) {
      run.ended = "duration";
      break;
    }
  }
  {
    char status[96];
    std::snprintf(status, sizeof status, "stopping: %s", run.ended);
    notifier.stopping(status);
  }
  boards::read_memory(run.rss_kb_end, run.peak_rss_kb);
  run.open_fds_end = boards::count_open_fds();
  if (!quiet && drivers::stop_signal() != 0)
    std::fprintf(stderr, "harmoloc: stopped by %s\n", run.ended);
  // Every output is flushed and closed whatever happened to the others, then the stats written.
  boards::finish_signing(config, *cycle, signing_store, run);
  if (trajectory != nullptr && std::fclose(trajectory) != 0 && trajectory_error == 0) {
    trajectory_error = errno != 0 ? errno : EIO;
    std::fprintf(stderr, "harmoloc: %s: write failed (%s)\n", trajectory_path.c_str(),
                 std::strerror(trajectory_error));
  }
  if (trajectory_error != 0) ++run.outputs_failed;
  if (!record_encoders_path.empty() && !recorder.close()) {
    std::fprintf(stderr, "harmoloc: %s: write failed (%s)\n", record_encoders_path.c_str(),
                 std::strerror(recorder.output().error() != 0 ? recorder.output().error() : EIO));
    ++run.outputs_failed;
  }

  run.outputs_failed += recording.finish(quiet, stderr);
  run.recording = recording.stats();

  run.board = "linux";
  run.rate_hz = config.cycle.rate_hz;
  run.camera = camera->counters();
  run.pacing = firmware::pacing_name(config.cycle.pacing);
  run.skipped_ticks = pacer.skipped_ticks();
  if (config.cycle.pacing == firmware::Pacing::kTimer) run.wakeup_latency = &pacer.wakeup_latency();
  run.encoders = encoders->counters();
  run.link = link.counters();
  boards::write_run_stats(*cycle, stats_path, run);
  const auto& c = cycle->counters();
  const auto& h = cycle->stage_histogram(firmware::Stage::kCycle);
  std::printf(
      "harmoloc: %llu cycles in %.1f s, %llu frames (%llu dropped, %llu corrupt), %llu encoder "
      "samples, %llu fixes (%llu off the map), %llu link frames sent (%llu dropped); cycle "
      "median %.0f us, p99 %.0f us, max %.0f us, %llu overruns, %llu skipped ticks\n",
      static_cast<unsigned long long>(c.cycles),
      static_cast<double>(clock.now_ns() - start_ns) * 1e-9,
      static_cast<unsigned long long>(c.frames),
      static_cast<unsigned long long>(run.camera.dropped),
      static_cast<unsigned long long>(run.camera.corrupt),
      static_cast<unsigned long long>(c.encoder_samples),
      static_cast<unsigned long long>(c.fixes_used),
      static_cast<unsigned long long>(c.unknown_place),
      static_cast<unsigned long long>(run.link.frames_sent),
      static_cast<unsigned long long>(run.link.frames_dropped),
      static_cast<double>(h.quantile_ns(0.5)) / 1000.0,
      static_cast<double>(h.quantile_ns(0.99)) / 1000.0, static_cast<double>(h.max_ns()) / 1000.0,
      static_cast<unsigned long long>(c.overruns),
      static_cast<unsigned long long>(pacer.skipped_ticks()));
  std::printf(
      "harmoloc: health not initialised %llu / nominal %llu / odometry-only %llu / "
      "vision-only %llu / invalid %llu cycles; ended: %s\n",
      static_cast<unsigned long long>(c.cycles_in_health[0]),
      static_cast<unsigned long long>(c.cycles_in_health[1]),
      static_cast<unsigned long long>(c.cycles_in_health[2]),
      static_cast<unsigned long long>(c.cycles_in_health[3]),
      static_cast<unsigned long long>(c.cycles_in_health[4]), run.ended);
  std::fflush(stdout);
  if (run.outputs_failed > 0) return firmware::kExitOutputFailed;
  if (!any_pose && !map_path.empty()) {
    std::fprintf(stderr, "harmoloc: no pose in %llu cycles\n",
                 static_cast<unsigned long long>(c.cycles));
    return firmware::kExitNeverLocalized;
  }
  return firmware::kExitOk;
}
