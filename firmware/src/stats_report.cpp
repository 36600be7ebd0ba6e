#include "harmoloc/firmware/stats_report.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>

#include "harmoloc/firmware/stats_document.hpp"

namespace harmoloc::firmware {

namespace {

double us(std::uint64_t ns) {
  return static_cast<double>(ns) / 1000.0;
}

// The mean to the nanosecond, as every other time here: its float digits below that are noise.
double mean_us(const LatencyHistogram& h) {
  return std::round(h.mean_ns()) / 1000.0;
}

stats::LatencySummary latency(const LatencyHistogram& h) {
  return {h.count(),
          us(h.min_ns()),
          mean_us(h),
          us(h.quantile_ns(0.5)),
          us(h.quantile_ns(0.99)),
          us(h.quantile_ns(0.999)),
          us(h.max_ns())};
}

}  // namespace

void take_snapshot(const LocalizationCycle& cycle, const RunCounters& run, StatsSnapshot& out) {
  out.counters = cycle.counters();
  for (std::size_t s = 0; s < kStageCount; ++s)
    out.stages[s] = cycle.stage_histogram(static_cast<Stage>(s));
  out.capture_to_send = cycle.capture_to_send();
  out.inbound = cycle.inbound_counters();
  out.budget_ns = cycle.budget_ns();
  out.uses_boards = cycle.uses_boards();
  out.run = run;
  if (run.wakeup_latency != nullptr) {
    out.wakeup_latency = *run.wakeup_latency;
    out.run.wakeup_latency = &out.wakeup_latency;
  }
}

stats::Document stats_document(const StatsSnapshot& snapshot) {
  const CycleCounters& c = snapshot.counters;
  const RunCounters& run = snapshot.run;
  stats::Document d;
  d.harmoloc_version = HARMOLOC_VERSION;
  d.board = run.board;
  d.ended = run.ended;
  d.outputs_failed = run.outputs_failed;
  d.rate_hz = run.rate_hz;
  d.budget_us = us(snapshot.budget_ns);
  d.cycles = c.cycles;
  d.frames = c.frames;
  d.overruns = c.overruns;
  d.pacing = stats::Pacing{run.pacing, run.skipped_ticks, c.overrun_alarms};
  for (std::size_t s = 0; s < kStageCount; ++s) {
    const LatencyHistogram& h = snapshot.stages[s];
    d.stages.emplace_back(stage_name(static_cast<Stage>(s)),
                          stats::StageTiming{us(h.quantile_ns(0.5)), us(h.quantile_ns(0.99)),
                                             us(h.quantile_ns(0.999)), us(h.max_ns()), mean_us(h)});
  }
  const LatencyHistogram& whole = snapshot.stages[static_cast<std::size_t>(Stage::kCycle)];
  stats::CycleHistogram histogram;
  for (std::size_t i = 0; i < LatencyHistogram::kBuckets; ++i) {
    if (whole.bucket_count(i) == 0) continue;
    histogram.upper_us.push_back(us(LatencyHistogram::bucket_upper_ns(i)));
    histogram.counts.push_back(whole.bucket_count(i));
  }
  d.cycle_histogram = histogram;
  const auto& health = c.cycles_in_health;
  d.health_cycles = stats::HealthCycles{health[0], health[1], health[2], health[3], health[4]};
  d.degraded = stats::Degraded{health[2], health[3], health[4]};
  d.camera = {run.camera, c.no_frame, c.frame_size_mismatch, c.stale_frames};
  d.encoders = {run.encoders, c.encoder_gaps_bridged};
  d.link = run.link;
  d.localizer = stats::Localizer{c.fixes_used,      c.unknown_place,     c.implausible_frames,
                                 c.off_map_cycles,  c.uncovered_cycles,  c.cut_board_frames,
                                 c.disagree_cycles, c.spread_wide_cycles};
  d.filter = {snapshot.uses_boards ? "boards" : "fix",
              c.resamples,
              c.particles_mean(),
              c.particles_min,
              c.particles_max,
              c.no_consensus,
              c.distrusted_boards,
              c.fix_board_suspicions,
              c.kidnap_triggers,
              c.kidnaps,
              c.lost,
              c.nearby_draws};
  d.inbound = snapshot.inbound;
  if (run.wakeup_latency != nullptr && run.wakeup_latency->count() > 0)
    d.wakeup_latency = latency(*run.wakeup_latency);
  if (snapshot.capture_to_send.count() > 0) d.capture_to_send = latency(snapshot.capture_to_send);
  if (run.recording.active) {
    const RecordingCounters& r = run.recording;
    d.recording = stats::Recording{r.frames, r.dropped, r.skipped, r.bytes, r.stopped};
  }
  if (run.rss_kb_end >= 0) {
    d.resources = stats::Resources{run.rss_kb_start, run.rss_kb_end, run.peak_rss_kb,
                                   run.open_fds_start, run.open_fds_end};
  }
  return d;
}

std::string stats_json(const StatsSnapshot& snapshot) {
  return stats::dump(stats_document(snapshot));
}

stats::Document stats_document(const LocalizationCycle& cycle, const RunCounters& run) {
  // 10 KB: on the heap, as this is the allocating side anyway.
  const auto snapshot = std::make_unique<StatsSnapshot>();
  take_snapshot(cycle, run, *snapshot);
  return stats_document(*snapshot);
}

std::string stats_json(const LocalizationCycle& cycle, const RunCounters& run) {
  return stats::dump(stats_document(cycle, run));
}

std::string write_stats(const std::string& path, const std::string& json) {
  errno = 0;
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) return path + ": cannot write (" + std::strerror(errno) + ")";
  const bool wrote = std::fwrite(json.data(), 1, json.size(), f) == json.size();
  int error = wrote ? 0 : errno;
  if (std::fclose(f) != 0 && error == 0) error = errno;
  if (!wrote || error != 0)
    return path + ": write failed (" + std::strerror(error != 0 ? error : EIO) + ")";
  return {};
}

}  // namespace harmoloc::firmware
