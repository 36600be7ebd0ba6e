#pragma once
/// @file The run statistics as JSON (`harmoloc --stats`): per-stage timing, overruns, frames,
/// degraded-mode counts and the hal counters. Schema in docs/stats-format.md.

#include <string>

#include "harmoloc/firmware/localization_cycle.hpp"

namespace harmoloc::firmware {

struct RunCounters {
  const char* board = "host";
  double rate_hz = 30.0;
  hal::CameraCounters camera;
  hal::EncoderCounters encoders;
  hal::LinkCounters link;
  /// What started the cycles: "camera", "timer" or "replay" (unpaced, as fast as possible).
  const char* pacing = "replay";
  /// Timer pacing: grid points skipped because a cycle ran past them.
  std::uint64_t skipped_ticks = 0;
  /// How late the cycle woke after its absolute deadline (paced runs only; nullptr otherwise).
  const LatencyHistogram* wakeup_latency = nullptr;
  /// Process resources after start-up and at the end (negative: not measured).
  long rss_kb_start = -1, rss_kb_end = -1, peak_rss_kb = -1;
  long open_fds_start = -1, open_fds_end = -1;
};

std::string stats_json(const LocalizationCycle& cycle, const RunCounters& run);

}  // namespace harmoloc::firmware
