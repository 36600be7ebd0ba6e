#pragma once
/// @file The run statistics as JSON (`harmoloc --stats`): per-stage timing, overruns, frames,
/// degraded-mode counts and the hal counters. Schema in docs/stats-format.md.

#include <array>
#include <memory>
#include <string>

#include "harmoloc/firmware/localization_cycle.hpp"
#include "harmoloc/firmware/stats_document.hpp"

namespace harmoloc::firmware {

/// `harmoloc --record DIR`: what the recording kept (boards/common/run_recording.hpp).
struct RecordingCounters {
  bool active = false;
  std::uint64_t frames = 0;   ///< frame files written and listed in frames.csv
  std::uint64_t dropped = 0;  ///< frames the disk could not take in time
  std::uint64_t skipped = 0;  ///< frames left out by --record-every
  std::uint64_t bytes = 0;    ///< bytes of frame files
  const char* stopped = "";   ///< "", "size limit", "time limit" or "write failed"
};

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
  /// How the run ended: "end of the recording", "SIGTERM", "cycle limit", ...
  const char* ended = "end of the recording";
  /// Outputs (trajectory, recordings) whose writes failed.
  unsigned outputs_failed = 0;
  RecordingCounters recording;
};

/// Everything the stats file is made of, copied out of the cycle (about 10 KB, fixed size): taken
/// in the run loop without allocating, turned into the file elsewhere (a writer thread on
/// SIGUSR1, boards/common/stats_dumper.hpp), so the cycle never waits for a file.
struct StatsSnapshot {
  CycleCounters counters;
  std::array<LatencyHistogram, kStageCount> stages{};
  LatencyHistogram capture_to_send;
  LatencyHistogram wakeup_latency;  ///< RunCounters::wakeup_latency points here when set
  mavlink::InboundCounters inbound;
  std::uint64_t budget_ns = 0;
  bool uses_boards = false;
  RunCounters run;
};

/// Copies the cycle's and the run's counters into @p out. Never allocates.
void take_snapshot(const LocalizationCycle& cycle, const RunCounters& run, StatsSnapshot& out);

/// The run's statistics (allocates).
stats::Document stats_document(const StatsSnapshot& snapshot);
stats::Document stats_document(const LocalizationCycle& cycle, const RunCounters& run);
/// stats_document() as the file's text (stats::dump).
std::string stats_json(const StatsSnapshot& snapshot);
std::string stats_json(const LocalizationCycle& cycle, const RunCounters& run);

/// Writes @p json to @p path (created or truncated). Returns an empty string, or "PATH: write
/// failed (reason)".
std::string write_stats(const std::string& path, const std::string& json);

/// Exit statuses of the board mains (docs/architecture.md): a completed run, one whose
/// outputs failed to be written, bad input at start-up, and a run that never produced a pose.
constexpr int kExitOk = 0;
constexpr int kExitOutputFailed = 1;
constexpr int kExitBadInput = 2;
constexpr int kExitNeverLocalized = 3;

}  // namespace harmoloc::firmware
