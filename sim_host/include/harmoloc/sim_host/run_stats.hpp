#pragma once
/// @file The firmware's run statistics (`harmoloc --stats OUT.json`, docs/stats-format.md) as the
/// host tools read them back. Host only; allocates freely.

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "harmoloc/firmware/stats_document.hpp"
#include "harmoloc/sim_host/report_error.hpp"

namespace harmoloc::sim_host {

/// Stage names in display order ("cycle", the whole cycle, last). Stages found in the file but
/// not listed here are shown in file order before "cycle".
extern const char* const kStageOrder[8];

/// Timing of one stage of the cycle, microseconds. A number missing from the file is NaN.
struct StageTiming {
  std::string name;
  double median_us = 0.0;
  double p99_us = 0.0;
  double p999_us = 0.0;
  double max_us = 0.0;
  double mean_us = 0.0;
};

/// The whole-cycle time histogram: counts[i] cycles took (upper_us[i-1], upper_us[i]] (the first
/// bucket starts at 0). When counts has one entry more than upper_us, the last one counts the
/// cycles above upper_us.back().
struct CycleHistogram {
  std::vector<double> upper_us;
  std::vector<std::uint64_t> counts;
  std::uint64_t overflow() const;
  std::uint64_t total() const;
};

/// A flat view of one other section of the stats (camera, link, ...): "key" -> printed value.
/// Nested objects are flattened with dots ("rx.frames").
struct StatsSection {
  std::string name;
  std::vector<std::pair<std::string, std::string>> entries;
};

struct RunStats {
  std::string harmoloc_version;  ///< Empty when missing.
  std::string board;
  std::optional<std::uint64_t> cycles;
  std::optional<std::uint64_t> frames;
  std::optional<std::uint64_t> overruns;
  std::optional<double> rate_hz;
  double budget_us = 15000.0;       ///< 15 ms when the file does not say.
  std::vector<StageTiming> stages;  ///< In display order (kStageOrder first).
  std::optional<CycleHistogram> cycle_histogram;
  /// degraded-mode counts in file order (odometry_only, vision_only, invalid, ...).
  std::vector<std::pair<std::string, std::uint64_t>> degraded;
  std::optional<std::uint64_t> localizer_fixes;
  std::optional<std::uint64_t> localizer_unknown_place;
  /// Every other object-valued top-level section (camera, encoders, link, localizer, ...).
  std::vector<StatsSection> sections;

  /// The file as read (firmware/stats_document.hpp): pacing, health cycles, latencies.
  firmware::stats::Document document;

  /// The stage called @p name, or nullptr.
  const StageTiming* stage(const std::string& name) const;
};

/// Parses the stats JSON text. Throws ReportError ("ORIGIN: reason") when the text is not JSON,
/// is not an object, lacks "stages", or a present field has the wrong type. Missing optional
/// sections are left empty.
RunStats parse_stats(const std::string& text, const std::string& origin = "stats");

/// Reads and parses a stats file; throws ReportError ("PATH: reason") on any failure.
RunStats read_stats(const std::string& path);

}  // namespace harmoloc::sim_host
