#pragma once
/// @file What every board's main shares around the cycle: the process's memory and descriptors
/// for the stats, the MAVLink signing state at start and at the end, and the stats file. A board
/// main wires its devices, runs the cycle with its own pacing and says its own summary.

#include <string>

#include "harmoloc/drivers/record_file.hpp"
#include "harmoloc/firmware/config.hpp"
#include "harmoloc/firmware/localization_cycle.hpp"
#include "harmoloc/firmware/stats_report.hpp"

namespace harmoloc::boards {

/// Resident and peak memory (kB) from /proc/self/status; -1 where unavailable.
void read_memory(long& rss_kb, long& peak_kb);

/// Open file descriptors of the process (-1 where /proc is unavailable).
long count_open_fds();

/// Start-up of the link's signing: the signing clock starts at the wall time (MAVLink signing
/// timestamps are wall-clock based), unless the board has no clock (link.signing_clock = "peer":
/// the first signed frame sets it); with a key, the replay protection carries on from what the
/// previous run persisted into @p store. Returns a one-line error, or "".
std::string start_signing(const firmware::FirmwareConfig& config,
                          firmware::LocalizationCycle& cycle, drivers::RecordFile& store);

/// At the end of a run, with a signing key: the store stopped and the signing state written.
/// A failure is said on stderr and counted in run.outputs_failed.
void finish_signing(const firmware::FirmwareConfig& config,
                    const firmware::LocalizationCycle& cycle, drivers::RecordFile& store,
                    firmware::RunCounters& run);

/// The stats (docs/stats-format.md) written to @p stats_path, unless it is empty. A failure is
/// said on stderr and counted in run.outputs_failed.
void write_run_stats(const firmware::LocalizationCycle& cycle, const std::string& stats_path,
                     firmware::RunCounters& run);

}  // namespace harmoloc::boards
