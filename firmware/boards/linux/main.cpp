// harmoloc for the Linux board: the firmware's cycle on real devices. The camera is a V4L2
// capture device or a libcamera camera, the wheel encoders come from a SocketCAN bus or from
// quadrature lines on GPIO, the pose goes out on a serial line; all chosen by the config
// (docs/drivers.md). The cycle is the host board's, paced by the camera or by a timer
// (cycle.pacing; docs/architecture.md, "Pacing and overruns").
#include <cstdio>
#include <string>

#include <CLI/CLI.hpp>

#include "application.hpp"
#include "health_log.hpp"
#include "linux_board.hpp"

#include "harmoloc/drivers/service_notifier.hpp"
#include "harmoloc/drivers/stop_signals.hpp"
#include "harmoloc/firmware/cli.hpp"

int main(int argc, char** argv) {
  using namespace harmoloc;
  // First: SIGUSR1's default action ends the process, and a service manager may send it at any
  // time (stats_dumper.hpp).
  drivers::install_stats_signal();
  CLI::App cli{
      "harmoloc (Linux board): runs the firmware's fixed-rate localization cycle on the robot's\n"
      "devices: a V4L2 or libcamera camera, SocketCAN or GPIO quadrature wheel encoders, and a\n"
      "serial line for the MAVLink v2 pose stream (docs/drivers.md, docs/config-format.md).\n"
      "Runs until SIGTERM/SIGINT/SIGHUP (stops at the next cycle, writes every output),\n"
      "--duration or --cycles; SIGUSR1 writes --stats without stopping. Exit status 0 after a\n"
      "run, 1 if an output could not be written, 2 with a one-line reason on a bad config, map\n"
      "or a missing device, 3 if no pose was ever produced.",
      "harmoloc"};
  static boards::LinuxOptions o;
  boards::add_linux_options(cli, o);
  if (const auto status = harmoloc::cli::parse(cli, argc, argv)) return *status;
  o.app.stats_on_request = true;

  // ---- start-up: everything is read, checked, opened and reserved here ----
  static boards::Application app(boards::RunKind::kLive, o.app);
  firmware::FirmwareConfig& config = app.config();
  if (const std::string e = app.load_config(); !e.empty()) return boards::fail(e);
  if (const std::string e = app.load_map(
          config.camera.width_px, config.camera.height_px,
          "--map is required (or --record DIR to record a training run before a map exists)");
      !e.empty()) {
    return boards::fail(e);
  }
  static boards::LinuxDevices devices;
  if (const std::string e = devices.open_camera(config, app.clock()); !e.empty())
    return boards::fail(e);
  if (const std::string e = devices.open_encoders(config); !e.empty()) return boards::fail(e);
  if (const std::string e = app.open_outputs(config.link.device, devices.encoders(),
                                             config.camera.width_px, config.camera.height_px);
      !e.empty()) {
    return boards::fail(e);
  }
  // Real time: applied where permitted (said once on stderr), as the config asks.
  const drivers::RealtimeReport rt = boards::apply_realtime(config);
  if (const std::string e =
          app.start_cycle(devices.recorded(config), devices.camera(), devices.pixel_format());
      !e.empty()) {
    return boards::fail(e);
  }
  app.cycle().set_live_clock(true);
  app.cycle().set_overrun_alarm(true);
  if (!o.app.quiet) {
    std::fprintf(stderr, "harmoloc: camera %s\n", devices.camera_text().c_str());
    std::fprintf(stderr, "harmoloc: encoders %s\n", devices.encoders_text().c_str());
    std::fprintf(stderr, "harmoloc: link %s%s at %u baud\n",
                 (o.app.link_path.empty() ? config.link.device : o.app.link_path).c_str(),
                 app.link().is_tty() ? " (serial, raw)" : " (file)", config.link.baud);
    std::fprintf(
        stderr, "harmoloc: map of %u samples on %u boards, %zu particles, %.0f Hz, %s-paced\n",
        app.map().model.sample_count, app.map().model.feature_count, config.filter.particles,
        config.cycle.rate_hz, firmware::pacing_name(config.cycle.pacing));
    app.say_map_settings();
    std::fprintf(stderr, "harmoloc: %s\n", rt.summary.c_str());
  }

  // Type=notify: READY once everything above has been checked, the watchdog fed from the loop.
  static drivers::ServiceNotifier notifier;
  if (const std::string e = notifier.open(); !e.empty()) return boards::fail(e);
  static boards::HealthLog health_log;
  health_log.start();
  firmware::RunCounters& run = app.counters();
  run.board = "linux";
  run.pacing = firmware::pacing_name(config.cycle.pacing);
  if (config.cycle.pacing == firmware::Pacing::kTimer)
    run.wakeup_latency = &app.pacer().wakeup_latency();
  run.ended = "camera ended";
  static boards::LinuxLoop loop(o, config, app.pacer(), app.clock(), notifier, health_log);
  app.run(loop, false);
  return app.finish();
}
