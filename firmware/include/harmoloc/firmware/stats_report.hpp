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
  /// How late the cycle woke after its absolute deadline (paced runs only; nullptr otherwise).
  const LatencyHistogram* wakeup_latency = nullptr;
};

std::string stats_json(const LocalizationCycle& cycle, const RunCounters& run);

}  // namespace harmoloc::firmware
