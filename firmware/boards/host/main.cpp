// harmoloc for the host board: the firmware's cycle with file-backed fakes of the camera and the
// encoder bus (a dataset folder), the pose link into a file or a serial device (a pty works).
#include <cstdio>
#include <string>

#include <CLI/CLI.hpp>

#include "application.hpp"
#include "host_board.hpp"

#include "harmoloc/firmware/cli.hpp"

int main(int argc, char** argv) {
  using namespace harmoloc;
  CLI::App cli{
      "harmoloc (host board): runs the firmware's fixed-rate localization cycle on a dataset "
      "folder.\n"
      "Frames and encoder frames are replayed from the dataset by their timestamps; the pose goes "
      "out as\n"
      "MAVLink v2 on --link, as TUM on --trajectory, and timing statistics go to --stats (JSON).\n"
      "Exit status 0 on a completed run, 2 with a one-line reason on bad input.",
      "harmoloc"};
  boards::HostOptions o;
  boards::add_host_options(cli, o);
  if (const auto status = harmoloc::cli::parse(cli, argc, argv)) return *status;
  // Unpaced, the replay's clock is the data's: waiting for the disk loses nothing, so every frame
  // is recorded. Paced (--realtime), a slow disk drops frames as on a robot.
  o.app.record.frames.wait_for_disk = !o.realtime;

  // ---- start-up: everything is read, checked and reserved here ----
  static boards::Application app(boards::RunKind::kReplay, o.app);
  firmware::FirmwareConfig& config = app.config();
  static boards::DatasetDevices devices;
  try {
    if (const std::string e = app.load_config(); !e.empty()) return boards::fail(e);
    devices.open_metadata(o.dataset, config);
    const dataset::DatasetMetadata& meta = devices.metadata();
    if (const std::string e = app.load_map(
            meta.image_width_px, meta.image_height_px,
            "--map is required (or --record DIR / --record-areas to record a run before a map "
            "exists)");
        !e.empty()) {
      return boards::fail(e);
    }
    devices.open(config, o.loops);
    if (const std::string e = app.open_outputs("/dev/null", devices.encoders(), meta.image_width_px,
                                               meta.image_height_px);
        !e.empty()) {
      return boards::fail(e);
    }
  } catch (const std::exception& e) {
    return boards::fail(e.what());
  }
  if (o.realtime) {
    const drivers::RealtimeReport rt = boards::apply_realtime(config);
    if (!o.app.quiet) std::fprintf(stderr, "harmoloc: %s\n", rt.summary.c_str());
  }
  // Timer pacing needs a clock to pace against: with --realtime only (a replay runs unpaced).
  const bool timer_paced = o.realtime && config.cycle.pacing == firmware::Pacing::kTimer;
  if (const std::string e =
          app.start_cycle(devices.recorded(config), devices.cycle_camera(timer_paced),
                          devices.metadata().pixel_format);
      !e.empty()) {
    return boards::fail(e);
  }
  app.cycle().set_overrun_alarm(o.realtime);
  if (!o.app.quiet) {
    devices.say(app.map(), config, o.realtime, timer_paced);
    app.say_map_settings();
    if (app.link().can_receive()) {
      std::fprintf(stderr, "harmoloc: link commands %s\n",
                   config.link.has_signing_key ? "signed only (MAVLink 2 signing key loaded)"
                                               : "unsigned (no signing key configured)");
    }
  }

  static boards::HostLoop loop(devices, app.pacer(), app.clock(), o.realtime, timer_paced,
                               o.app.quiet);
  firmware::RunCounters& run = app.counters();
  run.board = "host";
  run.pacing = !o.realtime ? "replay" : firmware::pacing_name(config.cycle.pacing);
  if (o.realtime) run.wakeup_latency = loop.wakeup_latency();
  app.run(loop, !o.app.quiet);
  return app.finish();
}
