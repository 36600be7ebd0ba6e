#include "application.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <vector>

#include "harmoloc/drivers/stop_signals.hpp"
#include "harmoloc/firmware/eigen_guard.hpp"
#include "harmoloc/firmware/map_loader.hpp"

namespace harmoloc::boards {

int fail(const std::string& why) {
  std::fprintf(stderr, "harmoloc: %s\n", why.c_str());
  return firmware::kExitBadInput;
}

drivers::RealtimeReport apply_realtime(const firmware::FirmwareConfig& config) {
  return drivers::apply_realtime(drivers::RealtimeOptions{
      config.realtime.enabled, config.realtime.priority, config.realtime.cpu,
      config.realtime.lock_memory, config.realtime.prefault_stack_kb});
}

std::string Application::load_config() {
  try {
    config_ = options_.config_path.empty() ? firmware::default_config()
                                           : firmware::load_config(options_.config_path);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

std::string Application::load_map(std::uint32_t width_px, std::uint32_t height_px,
                                  const char* no_map) {
  if (!options_.map_path.empty()) {
    if (std::string e = firmware::load_map(options_.map_path, map_); !e.empty()) return e;
  } else if (options_.records()) {
    // Recording a first run: segments every frame (the areas are recorded), localises none.
    map_.image_width_px = width_px;
    map_.image_height_px = height_px;
    map_.thresholds = config_.thresholds;
  } else {
    return no_map;
  }
  return firmware::check_map_matches(map_, config_, width_px, height_px);
}

std::string Application::open_outputs(const std::string& default_link, hal::WheelEncoders& encoders,
                                      std::uint32_t width_px, std::uint32_t height_px) {
  encoders_ = &encoders;
  const std::string& device = options_.link_path.empty() ? default_link : options_.link_path;
  if (std::string e = link_.open(device, config_.link.baud); !e.empty()) return "link " + e;
  if (!options_.link_in_path.empty()) {
    if (std::string e = link_.open_input(options_.link_in_path); !e.empty())
      return "link input " + e;
  }
  const auto cannot_write = [](const std::string& path) { return path + ": cannot write"; };
  if (!options_.trajectory_path.empty() && !trajectory_.open(options_.trajectory_path))
    return cannot_write(options_.trajectory_path);
  if (!options_.fixes_path.empty() && !fixes_.open(options_.fixes_path))
    return cannot_write(options_.fixes_path);
  if (!options_.areas_path.empty()) {
    const std::vector<std::string> names(config_.board_names.names.begin(),
                                         config_.board_names.names.end());
    if (!areas_.open(options_.areas_path, width_px, height_px, config_.thresholds, names))
      return cannot_write(options_.areas_path);
  }
  if (!options_.stats_path.empty() && !std::ofstream(options_.stats_path))
    return cannot_write(options_.stats_path);
  if (!options_.record_encoders_path.empty()) {
    encoder_recorder_.emplace(encoders);
    if (!encoder_recorder_->open(options_.record_encoders_path))
      return cannot_write(options_.record_encoders_path);
  }
  return "";
}

hal::WheelEncoders& Application::encoders() {
  return encoder_recorder_ ? static_cast<hal::WheelEncoders&>(*encoder_recorder_) : *encoders_;
}

std::string Application::start_cycle(const dataset::DatasetMetadata& recorded, hal::Camera& camera,
                                     hal::PixelFormat pixel_format) {
  camera_ = &camera;
  if (std::string e = recording_.start(options_.record, recorded, config_,
                                       !options_.map_path.empty(), camera, encoders());
      !e.empty()) {
    return e;
  }
  cycle_ = std::make_unique<firmware::LocalizationCycle>(
      config_, map_, recording_.camera(), recording_.encoders(), link_, clock_, pixel_format);
  pacer_.emplace(clock_, config_.cycle.pacing,
                 static_cast<std::uint64_t>(std::llround(1e9 / config_.cycle.rate_hz)));
  return start_signing(config_, *cycle_, signing_store_);
}

void Application::say_map_settings() const {
  if (const std::string odometry = firmware::odometry_summary(config_, map_.calibration);
      !odometry.empty()) {
    std::fprintf(stderr, "harmoloc: %s\n", odometry.c_str());
  }
  if (const std::string route = firmware::route_terms_summary(config_, map_.calibration);
      !route.empty()) {
    std::fprintf(stderr, "harmoloc: %s\n", route.c_str());
  }
  if (const std::string fix = firmware::fix_term_summary(config_, map_); !fix.empty())
    std::fprintf(stderr, "harmoloc: %s\n", fix.c_str());
  if (const std::string kld = firmware::kld_summary(config_, map_); !kld.empty())
    std::fprintf(stderr, "harmoloc: %s\n", kld.c_str());
}

void Application::run(BoardLoop& loop, bool progress_line) {
  long unused_peak = 0;
  read_memory(run_.rss_kb_start, unused_peak);
  run_.open_fds_start = count_open_fds();
  // From here a signal stops the run at the next cycle boundary, with every output written.
  drivers::install_stop_signals();
  if (options_.stats_on_request && !options_.stats_path.empty()) {
    // The signal's handler is the board main's first act (SIGUSR1 would otherwise end the
    // process): a request made during start-up is served after the first cycle.
    if (const std::string e = stats_dumper_.start(options_.stats_path, options_.quiet); !e.empty())
      std::fprintf(stderr, "harmoloc: no stats on SIGUSR1: %s\n", e.c_str());
  }
  bool stats_wanted = false;
  watch_.progress_line = progress_line;
  watch_.add(trajectory_.output());
  watch_.add(fixes_.output());
  watch_.add(areas_.output());
  if (encoder_recorder_) watch_.add(encoder_recorder_->output());
  if (recording_.active()) {
    watch_.add(recording_.areas_output());
    watch_.add(recording_.encoders_output());
    watch_.add(recording_.pose_output());
  }

  firmware::forbid_eigen_heap();  // Eigen may not allocate from here on (eigen_guard.hpp)
  start_ns_ = clock_.now_ns();
  loop.started(start_ns_);
  std::uint64_t cycles = 0;
  for (;;) {
    if (drivers::stop_signal() != 0) {
      run_.ended = drivers::signal_name(drivers::stop_signal());
      break;
    }
    if (loop.run_cycle(*cycle_) == firmware::CycleResult::kEnded) break;
    ++cycles;
    const firmware::PoseOutput& out = cycle_->pose();
    if (out.valid) {
      any_pose_ = true;
      trajectory_.write(out.data_time_ns, out.pose);
    }
    const firmware::FixOutput& fix = cycle_->last_fix();
    if (fix.present) areas_.write(out.data_time_ns, fix.areas, fix.distrusted_mask);
    recording_.after_cycle(*cycle_);
    if (fix.present && fix.fix.known_place)
      fixes_.write(out.data_time_ns, algorithms::Pose2{fix.fix.x_m, fix.fix.y_m, 0.0});
    // A failed write is said when it happens; the pose still goes out on the link.
    watch_.check();
    stats_wanted = stats_dumper_.running() && (drivers::take_stats_request() || stats_wanted);
    if (stats_wanted) {
      run_.camera = camera_->counters();
      run_.encoders = encoders().counters();
      run_.link = link_.counters();
      run_.skipped_ticks = pacer_->skipped_ticks();
      stats_wanted = !stats_dumper_.request(*cycle_, run_);  // busy: again after the next cycle
    }
    if (const char* why = loop.after_cycle(*cycle_, cycles)) {
      run_.ended = why;
      break;
    }
  }
  loop.stopping(run_.ended, cycles);
  stats_dumper_.stop();                            // before the final stats go to the same file
  read_memory(run_.rss_kb_end, run_.peak_rss_kb);  // before the outputs are closed
  run_.open_fds_end = count_open_fds();
  if (!options_.quiet && drivers::stop_signal() != 0)
    std::fprintf(stderr, "harmoloc: stopped by %s\n", run_.ended);
}

int Application::finish() {
  // Every output is flushed and closed whatever happened to the others, then the stats written.
  finish_signing(config_, *cycle_, signing_store_, run_);
  trajectory_.close();
  fixes_.close();
  areas_.close();
  const bool encoders_recorded = encoder_recorder_ && encoder_recorder_->close();
  // The recording's frames and metadata; its text files are watched with the others.
  run_.outputs_failed += recording_.finish(options_.quiet, stderr, false);
  run_.recording = recording_.stats();
  run_.outputs_failed += watch_.finish();
  if (kind_ == RunKind::kReplay && encoders_recorded && !options_.quiet) {
    std::fprintf(
        stderr,
        "harmoloc: recorded %llu encoder samples to %s (metadata: [encoders] source = "
        "\"gpio\", counter_bits = %u)\n",
        static_cast<unsigned long long>(encoder_recorder_->samples_written()),
        options_.record_encoders_path.c_str(),
        unsigned{encoder_recorder_->counter_bits() != 0 ? encoder_recorder_->counter_bits()
                                                        : config_.can_layout.counter_bits});
  }
  run_.rate_hz = config_.cycle.rate_hz;
  run_.camera = camera_->counters();
  run_.skipped_ticks = pacer_->skipped_ticks();
  run_.encoders = encoders().counters();
  run_.link = link_.counters();
  write_run_stats(*cycle_, options_.stats_path, run_);
  end_ns_ = clock_.now_ns();
  say_summary();
  std::fflush(stdout);
  return exit_status();
}

void Application::say_summary() const {
  const auto& c = cycle_->counters();
  const auto& h = cycle_->stage_histogram(firmware::Stage::kCycle);
  using ull = unsigned long long;
  const double median_us = static_cast<double>(h.quantile_ns(0.5)) / 1000.0;
  const double p99_us = static_cast<double>(h.quantile_ns(0.99)) / 1000.0;
  const double max_us = static_cast<double>(h.max_ns()) / 1000.0;
  if (kind_ == RunKind::kReplay) {
    std::printf(
        "harmoloc: %llu cycles, %llu fixes (%llu off the map), health not initialised %llu / "
        "nominal %llu / odometry-only %llu / vision-only %llu / invalid %llu; cycle median %.0f "
        "us, p99 %.0f us, max %.0f us, %llu overruns\n",
        ull{c.cycles}, ull{c.fixes_used}, ull{c.unknown_place}, ull{c.cycles_in_health[0]},
        ull{c.cycles_in_health[1]}, ull{c.cycles_in_health[2]}, ull{c.cycles_in_health[3]},
        ull{c.cycles_in_health[4]}, median_us, p99_us, max_us, ull{c.overruns});
    std::printf(
        "harmoloc: filter weighs %s; %llu frames without board consensus, %llu kidnaps confirmed "
        "(Yang et al. 2021 test fired %llu times), %llu lost\n",
        cycle_->uses_boards() ? "every board against the forward map" : "the harmonic fix",
        ull{c.no_consensus}, ull{c.kidnaps}, ull{c.kidnap_triggers}, ull{c.lost});
    return;
  }
  std::printf(
      "harmoloc: %llu cycles in %.1f s, %llu frames (%llu dropped, %llu corrupt), %llu encoder "
      "samples, %llu fixes (%llu off the map), %llu link frames sent (%llu dropped); cycle "
      "median %.0f us, p99 %.0f us, max %.0f us, %llu overruns, %llu skipped ticks\n",
      ull{c.cycles}, static_cast<double>(end_ns_ - start_ns_) * 1e-9, ull{c.frames},
      ull{run_.camera.dropped}, ull{run_.camera.corrupt}, ull{c.encoder_samples}, ull{c.fixes_used},
      ull{c.unknown_place}, ull{run_.link.frames_sent}, ull{run_.link.frames_dropped}, median_us,
      p99_us, max_us, ull{c.overruns}, ull{run_.skipped_ticks});
  std::printf(
      "harmoloc: health not initialised %llu / nominal %llu / odometry-only %llu / "
      "vision-only %llu / invalid %llu cycles; ended: %s\n",
      ull{c.cycles_in_health[0]}, ull{c.cycles_in_health[1]}, ull{c.cycles_in_health[2]},
      ull{c.cycles_in_health[3]}, ull{c.cycles_in_health[4]}, run_.ended);
}

int Application::exit_status() const {
  const bool replay = kind_ == RunKind::kReplay;
  if (run_.outputs_failed > 0) {
    if (replay) {
      std::fprintf(stderr, "harmoloc: %u output%s could not be written (see above)\n",
                   run_.outputs_failed, run_.outputs_failed == 1 ? "" : "s");
    }
    return firmware::kExitOutputFailed;
  }
  // Without a map the run only recorded: no pose was to be had.
  if (any_pose_ || options_.map_path.empty()) return firmware::kExitOk;
  const auto& c = cycle_->counters();
  if (replay) {
    std::fprintf(stderr,
                 "harmoloc: no pose in %llu cycles: the camera never showed a place of the map "
                 "(%llu frames, %llu fixes)\n",
                 static_cast<unsigned long long>(c.cycles),
                 static_cast<unsigned long long>(c.frames),
                 static_cast<unsigned long long>(c.fixes_used));
  } else {
    std::fprintf(stderr, "harmoloc: no pose in %llu cycles\n",
                 static_cast<unsigned long long>(c.cycles));
  }
  return firmware::kExitNeverLocalized;
}

void Application::OutputWatch::check() {
  for (std::size_t i = 0; i < count_; ++i) report(outputs_[i]);
}

unsigned Application::OutputWatch::finish() {
  unsigned failed = 0;
  for (std::size_t i = 0; i < count_; ++i) {
    report(outputs_[i]);
    if (outputs_[i].out->error() != 0) ++failed;
  }
  return failed;
}

void Application::OutputWatch::report(Watched& w) const {
  if (w.reported || w.out->error() == 0) return;
  w.reported = true;
  std::fprintf(stderr, "%sharmoloc: %s: write failed (%s)\n", progress_line ? "\n" : "",
               w.out->path().c_str(), std::strerror(w.out->error()));
}

}  // namespace harmoloc::boards
