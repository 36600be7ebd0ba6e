// harmoloc for the host board: the firmware's cycle with file-backed fakes of the camera and the
// encoder bus (a dataset folder), the pose link into a file or a serial device (a pty works).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include <CLI/CLI.hpp>

#include "board_run.hpp"
#include "run_recording.hpp"

#include "harmoloc/dataset/area_log.hpp"
#include "harmoloc/dataset/encoder_csv.hpp"
#include "harmoloc/dataset/metadata.hpp"
#include "harmoloc/dataset/tum_writer.hpp"
#include "harmoloc/drivers/monotonic_clock.hpp"
#include "harmoloc/drivers/realtime_setup.hpp"
#include "harmoloc/drivers/record_file.hpp"
#include "harmoloc/drivers/serial_link.hpp"
#include "harmoloc/drivers/stop_signals.hpp"
#include "harmoloc/firmware/cli.hpp"
#include "harmoloc/firmware/config.hpp"
#include "harmoloc/firmware/cycle_pacer.hpp"
#include "harmoloc/firmware/eigen_guard.hpp"
#include "harmoloc/firmware/localization_cycle.hpp"
#include "harmoloc/firmware/map_loader.hpp"
#include "harmoloc/firmware/stats_report.hpp"
#include "harmoloc/host/file_camera.hpp"
#include "harmoloc/host/gpio_log_encoders.hpp"
#include "harmoloc/host/log_encoders.hpp"
#include "harmoloc/host/recorded_time_camera.hpp"

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

dataset::TumWriter g_trajectory, g_fixes;
dataset::AreaLogWriter g_areas;

// The files the cycle appends to, checked after every cycle: a write that failed (a full disk,
// /dev/full) is said once, when it happens, naming its file; the run goes on (the pose still
// goes out on the link) and ends with exit status 1.
class OutputWatch {
 public:
  explicit OutputWatch(bool progress) : progress_(progress) {}
  void add(const dataset::BufferedOutput& out) { outputs_[count_++] = Watched{&out, false}; }
  void check() {
    for (std::size_t i = 0; i < count_; ++i) report(outputs_[i]);
  }
  /// After the outputs were closed: reports what failed at the end; returns how many failed.
  unsigned finish() {
    unsigned failed = 0;
    for (std::size_t i = 0; i < count_; ++i) {
      report(outputs_[i]);
      if (outputs_[i].out->error() != 0) ++failed;
    }
    return failed;
  }

 private:
  struct Watched {
    const dataset::BufferedOutput* out;
    bool reported;
  };
  void report(Watched& w) const {
    if (w.reported || w.out->error() == 0) return;
    w.reported = true;
    std::fprintf(stderr, "%sharmoloc: %s: write failed (%s)\n", progress_ ? "\n" : "",
                 w.out->path().c_str(), std::strerror(w.out->error()));
  }
  Watched outputs_[8]{};
  std::size_t count_ = 0;
  bool progress_;  // a progress line ("\r  cycle N/M") may be open on stderr
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "harmoloc (host board): runs the firmware's fixed-rate localization cycle on a dataset "
      "folder.\n"
      "Frames and encoder frames are replayed from the dataset by their timestamps; the pose goes "
      "out as\n"
      "MAVLink v2 on --link, as TUM on --trajectory, and timing statistics go to --stats (JSON).\n"
      "Exit status 0 on a completed run, 2 with a one-line reason on bad input.",
      "harmoloc"};
  std::string dataset, map_path, config_path, trajectory_path, link_path, stats_path, fixes_path,
      link_in_path, areas_path, record_encoders_path;
  bool realtime = false, quiet = false;
  std::uint32_t loops = 1;
  boards::RecordOptions record;
  app.add_option("--dataset", dataset, "dataset folder (metadata.toml, frames.csv, encoders.log)")
      ->required();
  app.add_option("--map", map_path,
                 "map file from harmoloc-train (may be left out with --record or --record-areas,\n"
                 "to record a first run before any map exists: nothing is localised then)");
  app.add_option("--config", config_path,
                 "firmware config (TOML, docs/config-format.md); default: built-in");
  app.add_option("--trajectory", trajectory_path, "write the fused pose of every cycle here (TUM)");
  app.add_option("--link", link_path,
                 "MAVLink v2 output: a file, or a serial device or pty (raw, --config link.baud)");
  app.add_option("--link-in", link_in_path,
                 "read the link's inbound bytes (MAVLink commands) from this file or FIFO instead\n"
                 "of --link (a serial device or pty is read by itself)");
  app.add_option("--stats", stats_path,
                 "write run statistics here (JSON: per-stage timing, overruns, counters)");
  app.add_option("--fixes", fixes_path,
                 "write the harmonic localizer's own fixes here (TUM), for comparison");
  app.add_option("--record-areas", areas_path,
                 "write every frame's board areas here (area log, docs/dataset-format.md): with\n"
                 "a few labelled poses, harmoloc-train --areas makes a map from it");
  boards::add_record_options(app, record,
                             "Unpaced, every frame is recorded; with --realtime a slow disk\ndrops "
                             "frames (counted), as on a robot");

  app.add_option("--record-encoders", record_encoders_path,
                 "write every fresh encoder sample the cycle reads here, as a GPIO encoder\n"
                 "recording (encoders.csv, docs/dataset-format.md)");
  app.add_flag("--realtime", realtime,
               "pace the cycle at the recording's rate instead of as fast as possible\n"
               "(cycle.pacing: \"camera\" waits for each frame's recorded time, \"timer\" wakes\n"
               "every period and takes the frame that is due, if any)");
  app.add_option("--loop", loops,
                 "replay the dataset this many times back to back (soak runs); time and the\n"
                 "encoder counters run on across passes")
      ->check(CLI::Range(1U, 1000000U));
  app.add_flag("--quiet", quiet, "no progress output");
  if (const auto status = harmoloc::cli::parse(app, argc, argv)) return *status;

  // ---- start-up: everything is read, checked and reserved here ----
  firmware::FirmwareConfig config;
  dataset::DatasetMetadata meta;
  std::unique_ptr<host::FileCamera> camera;
  std::unique_ptr<host::LogEncoders> can_log;
  std::unique_ptr<host::GpioLogEncoders> gpio_log;
  hal::WheelEncoders* encoders = nullptr;
  std::size_t encoder_records = 0;
  std::uint64_t encoders_first_ns = 0, encoders_last_ns = 0;
  drivers::SerialLink link;
  try {
    config = config_path.empty() ? firmware::default_config() : firmware::load_config(config_path);
    meta = dataset::read_metadata(dataset);
    // The dataset describes the recorded robot; a config without these sections follows it.
    if (!config.has_odometry_section) config.geometry = meta.geometry;
    if (!config.has_can_section) config.can_layout = meta.encoder_layout;
    if (!map_path.empty()) {
      if (const std::string e = firmware::load_map(map_path, g_map); !e.empty()) return fail(e);
    } else if (!areas_path.empty() || !record.dir.empty()) {
      // Recording a first run: an empty map with the config's thresholds segments every frame
      // and localises none.
      g_map.image_width_px = meta.image_width_px;
      g_map.image_height_px = meta.image_height_px;
      g_map.thresholds = config.thresholds;
    } else {
      return fail(
          "--map is required (or --record DIR / --record-areas to record a run before a map "
          "exists)");
    }
    if (const std::string e =
            firmware::check_map_matches(g_map, config, meta.image_width_px, meta.image_height_px);
        !e.empty()) {
      return fail(e);
    }
    camera = std::make_unique<host::FileCamera>(dataset, meta);
    const std::string encoder_path = (std::filesystem::path(dataset) / meta.encoder_log).string();
    if (meta.encoder_source == dataset::EncoderSource::kGpio) {
      // A GPIO recording: its counter width is the metadata's (the config's [can] is the bus's).
      gpio_log =
          std::make_unique<host::GpioLogEncoders>(encoder_path, meta.encoder_layout.counter_bits);
      encoders = gpio_log.get();
      encoder_records = gpio_log->sample_count();
      encoders_first_ns = gpio_log->first_timestamp_ns();
      encoders_last_ns = gpio_log->last_timestamp_ns();
    } else {
      can_log = std::make_unique<host::LogEncoders>(encoder_path, config.can_layout);
      encoders = can_log.get();
      encoder_records = can_log->frame_count();
      encoders_first_ns = can_log->first_timestamp_ns();
      encoders_last_ns = can_log->last_timestamp_ns();
    }
    if (loops > 1) {
      // One pass lasts from the first to the last record, plus one frame period.
      const std::uint64_t first = encoder_records > 0
                                      ? std::min(camera->first_timestamp_ns(), encoders_first_ns)
                                      : camera->first_timestamp_ns();
      const std::uint64_t last = std::max(camera->last_timestamp_ns(), encoders_last_ns);
      const auto period = static_cast<std::uint64_t>(1e9 / meta.frame_rate_hz);
      camera->set_loops(loops, last - first + period);
      if (can_log) can_log->set_loops(loops, last - first + period);
      if (gpio_log) gpio_log->set_loops(loops, last - first + period);
    }
    if (const std::string e =
            link.open(link_path.empty() ? "/dev/null" : link_path, config.link.baud);
        !e.empty()) {
      return fail("link " + e);
    }
    if (!link_in_path.empty()) {
      if (const std::string e = link.open_input(link_in_path); !e.empty())
        return fail("link input " + e);
    }
    if (!trajectory_path.empty() && !g_trajectory.open(trajectory_path))
      return fail(trajectory_path + ": cannot write");
    if (!fixes_path.empty() && !g_fixes.open(fixes_path))
      return fail(fixes_path + ": cannot write");
    if (!areas_path.empty()) {
      const std::vector<std::string> names(config.board_names.names.begin(),
                                           config.board_names.names.end());
      if (!g_areas.open(areas_path, meta.image_width_px, meta.image_height_px, config.thresholds,
                        names)) {
        return fail(areas_path + ": cannot write");
      }
    }
  } catch (const std::exception& e) {
    return fail(e.what());
  }
  if (!stats_path.empty()) {
    std::ofstream probe(stats_path);
    if (!probe) return fail(stats_path + ": cannot write");
  }

  drivers::MonotonicClock clock;
  if (realtime) {
    const drivers::RealtimeReport rt = drivers::apply_realtime(drivers::RealtimeOptions{
        config.realtime.enabled, config.realtime.priority, config.realtime.cpu,
        config.realtime.lock_memory, config.realtime.prefault_stack_kb});
    if (!quiet) std::fprintf(stderr, "harmoloc: %s\n", rt.summary.c_str());
  }
  static firmware::LatencyHistogram wakeup_latency;
  // Timer pacing needs a clock to pace against: with --realtime only (a replay runs unpaced).
  const bool timer_paced = realtime && config.cycle.pacing == firmware::Pacing::kTimer;
  // Camera-paced (and unpaced) replays see a hole in the recording as a live camera's cycle
  // would: a no-frame cycle each period, so the health and the counters notice it. Timer pacing
  // has those cycles from its own clock.
  camera->set_fill_gaps(!timer_paced);
  static firmware::CyclePacer pacer(
      clock, config.cycle.pacing,
      static_cast<std::uint64_t>(std::llround(1e9 / config.cycle.rate_hz)));
  host::RecordedTimeCamera recorded_time_camera(*camera);
  hal::Camera& cycle_camera =
      timer_paced ? static_cast<hal::Camera&>(recorded_time_camera) : *camera;
  dataset::EncoderRecorder recorder(*encoders);
  if (!record_encoders_path.empty()) {
    if (!recorder.open(record_encoders_path)) return fail(record_encoders_path + ": cannot write");
    encoders = &recorder;
  }
  static boards::RunRecording recording;
  // Unpaced, the replay's clock is the data's: waiting for the disk loses nothing, so every frame
  // is recorded. Paced (--realtime), a slow disk drops frames as on a robot.
  record.frames.wait_for_disk = !realtime;
  {
    dataset::DatasetMetadata recorded = meta;
    recorded.geometry = config.geometry;
    recorded.encoder_layout = config.can_layout;
    if (const std::string e =
            recording.start(record, recorded, config, !map_path.empty(), cycle_camera, *encoders);
        !e.empty()) {
      return fail(e);
    }
  }
  auto cycle = std::make_unique<firmware::LocalizationCycle>(
      config, g_map, recording.camera(), recording.encoders(), link, clock, meta.pixel_format);
  cycle->set_overrun_alarm(realtime);
  static drivers::RecordFile signing_store;
  if (const std::string e = boards::start_signing(config, *cycle, signing_store); !e.empty())
    return fail(e);
  if (!quiet) {
    std::fprintf(stderr,
                 "harmoloc: %zu frames %ux%u, %zu encoder %s, map of %u samples on %u boards, "
                 "%zu particles%s\n",
                 camera->frame_count(), meta.image_width_px, meta.image_height_px, encoder_records,
                 gpio_log ? "samples (GPIO recording)" : "frames", g_map.model.sample_count,
                 g_map.model.feature_count, config.filter.particles,
                 !realtime     ? ""
                 : timer_paced ? ", real-time pacing (timer)"
                               : ", real-time pacing (camera)");
    if (const std::string odometry = firmware::odometry_summary(config, g_map.calibration);
        !odometry.empty())
      std::fprintf(stderr, "harmoloc: %s\n", odometry.c_str());
    if (link.can_receive()) {
      std::fprintf(stderr, "harmoloc: link commands %s\n",
                   config.link.has_signing_key ? "signed only (MAVLink 2 signing key loaded)"
                                               : "unsigned (no signing key configured)");
    }
  }

  firmware::RunCounters run;
  long unused_peak = 0;
  boards::read_memory(run.rss_kb_start, unused_peak);
  run.open_fds_start = boards::count_open_fds();
  // From here a signal stops the run at the next cycle boundary, with every output written.
  drivers::install_stop_signals();
  OutputWatch watch(!quiet);
  watch.add(g_trajectory.output());
  watch.add(g_fixes.output());
  watch.add(g_areas.output());
  watch.add(recorder.output());
  if (recording.active()) {
    watch.add(recording.areas_output());
    watch.add(recording.encoders_output());
    watch.add(recording.pose_output());
  }
  bool any_pose = false;

  // ---- the cycle; Eigen may not allocate from here on (it would stop the program) ----
  firmware::forbid_eigen_heap();
  const std::uint64_t wall_start = clock.now_ns();
  const std::uint64_t data_start = camera->first_timestamp_ns();
  std::size_t done = 0;
  recorded_time_camera.start(wall_start, data_start);
  for (;;) {
    if (drivers::stop_signal() != 0) {
      run.ended = drivers::signal_name(drivers::stop_signal());
      break;
    }
    if (timer_paced) {
      if (cycle->run_once(pacer.wait_for_cycle()) == firmware::CycleResult::kEnded) break;
    } else if (realtime && camera->next_timestamp_ns() >= data_start) {
      // Absolute deadlines from the start (clock_nanosleep TIMER_ABSTIME): no drift.
      const std::uint64_t deadline = wall_start + (camera->next_timestamp_ns() - data_start);
      clock.sleep_until(deadline);
      const std::uint64_t woke = clock.now_ns();
      wakeup_latency.record(woke > deadline ? woke - deadline : 0);
    }
    if (!timer_paced && cycle->run_once() == firmware::CycleResult::kEnded) break;
    const firmware::PoseOutput& out = cycle->pose();
    if (out.valid) {
      any_pose = true;
      g_trajectory.write(out.data_time_ns, out.pose);
    }
    const firmware::FixOutput& fix = cycle->last_fix();
    if (fix.present) g_areas.write(out.data_time_ns, fix.areas);
    recording.after_cycle(*cycle);
    if (fix.present && fix.fix.known_place) {
      g_fixes.write(out.data_time_ns, algorithms::Pose2{fix.fix.x_m, fix.fix.y_m, 0.0});
    }
    watch.check();
    if (!quiet && ++done % 300 == 0) {
      std::fprintf(stderr, "\r  cycle %zu/%zu", done, camera->frame_count());
    }
  }
  boards::read_memory(run.rss_kb_end, run.peak_rss_kb);  // before the outputs are closed
  run.open_fds_end = boards::count_open_fds();
  if (!quiet) std::fprintf(stderr, "\r  cycle %zu/%zu\n", done, camera->frame_count());
  if (!quiet && drivers::stop_signal() != 0)
    std::fprintf(stderr, "harmoloc: stopped by %s\n", run.ended);
  // Every output is flushed and closed whatever happened to the others, then the stats written.
  boards::finish_signing(config, *cycle, signing_store, run);
  g_trajectory.close();
  g_fixes.close();
  g_areas.close();
  const bool recorded = recorder.close();
  // The recording's frames and metadata; its text files are in the watch.
  run.outputs_failed += recording.finish(quiet, stderr, false);
  run.recording = recording.stats();
  run.outputs_failed += watch.finish();
  if (!record_encoders_path.empty() && recorded) {
    if (!quiet) {
      std::fprintf(stderr,
                   "harmoloc: recorded %llu encoder samples to %s (metadata: [encoders] source = "
                   "\"gpio\", counter_bits = %u)\n",
                   static_cast<unsigned long long>(recorder.samples_written()),
                   record_encoders_path.c_str(),
                   unsigned{recorder.counter_bits() != 0 ? recorder.counter_bits()
                                                         : config.can_layout.counter_bits});
    }
  }

  run.board = "host";
  run.rate_hz = config.cycle.rate_hz;
  run.camera = cycle_camera.counters();
  run.pacing = !realtime ? "replay" : firmware::pacing_name(config.cycle.pacing);
  run.skipped_ticks = pacer.skipped_ticks();
  run.encoders = encoders->counters();
  run.link = link.counters();
  if (realtime) run.wakeup_latency = timer_paced ? &pacer.wakeup_latency() : &wakeup_latency;
  boards::write_run_stats(*cycle, stats_path, run);
  const auto& c = cycle->counters();
  const auto& h = cycle->stage_histogram(firmware::Stage::kCycle);
  std::printf(
      "harmoloc: %llu cycles, %llu fixes (%llu off the map), health not initialised %llu / "
      "nominal %llu / odometry-only %llu / vision-only %llu / invalid %llu; cycle median %.0f us, "
      "p99 %.0f us, max %.0f us, %llu overruns\n",
      static_cast<unsigned long long>(c.cycles), static_cast<unsigned long long>(c.fixes_used),
      static_cast<unsigned long long>(c.unknown_place),
      static_cast<unsigned long long>(c.cycles_in_health[0]),
      static_cast<unsigned long long>(c.cycles_in_health[1]),
      static_cast<unsigned long long>(c.cycles_in_health[2]),
      static_cast<unsigned long long>(c.cycles_in_health[3]),
      static_cast<unsigned long long>(c.cycles_in_health[4]),
      static_cast<double>(h.quantile_ns(0.5)) / 1000.0,
      static_cast<double>(h.quantile_ns(0.99)) / 1000.0, static_cast<double>(h.max_ns()) / 1000.0,
      static_cast<unsigned long long>(c.overruns));
  std::printf(
      "harmoloc: filter weighs %s; %llu frames without board consensus, %llu kidnaps confirmed "
      "(Yang et al. 2021 test fired %llu times), %llu lost\n",
      cycle->uses_boards() ? "every board against the forward map" : "the harmonic fix",
      static_cast<unsigned long long>(c.no_consensus), static_cast<unsigned long long>(c.kidnaps),
      static_cast<unsigned long long>(c.kidnap_triggers), static_cast<unsigned long long>(c.lost));
  std::fflush(stdout);
  if (run.outputs_failed > 0) {
    std::fprintf(stderr, "harmoloc: %u output%s could not be written (see above)\n",
                 run.outputs_failed, run.outputs_failed == 1 ? "" : "s");
    return firmware::kExitOutputFailed;
  }
  if (!any_pose && (!areas_path.empty() || !record.dir.empty()) && map_path.empty())
    return firmware::kExitOk;
  if (!any_pose) {
    std::fprintf(stderr,
                 "harmoloc: no pose in %llu cycles: the camera never showed a place of the map "
                 "(%llu frames, %llu fixes)\n",
                 static_cast<unsigned long long>(c.cycles),
                 static_cast<unsigned long long>(c.frames),
                 static_cast<unsigned long long>(c.fixes_used));
    return firmware::kExitNeverLocalized;
  }
  return firmware::kExitOk;
}
