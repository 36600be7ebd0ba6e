#pragma once
/// @file The run statistics file (`harmoloc --stats`, docs/stats-format.md) as plain structs, and
/// their one JSON mapping: the firmware writes it with to_json, the host tools (harmoloc-report,
/// harmoloc-budget) read it back with from_json, so the two cannot disagree on a key. Built and
/// written once after the cycle, where allocating is allowed.

#include <cstdint>
#include <limits>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "harmoloc/firmware/inbound_counters.hpp"
#include "harmoloc/hal/camera.hpp"
#include "harmoloc/hal/pose_link.hpp"
#include "harmoloc/hal/wheel_encoders.hpp"

namespace harmoloc::firmware::stats {

/// Key order is part of the file: people read it, and the report lists unknown stages and
/// sections in file order.
using Json = nlohmann::ordered_json;

/// A field of a stats file that cannot be read: "stages.cycle.median_us is not a number".
class FormatError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

constexpr double kMissing = std::numeric_limits<double>::quiet_NaN();

/// One stage's times, microseconds. A number missing from a file reads as NaN.
struct StageTiming {
  double median_us = kMissing;
  double p99_us = kMissing;
  double p999_us = kMissing;
  double max_us = kMissing;
  double mean_us = kMissing;
};

/// wakeup_latency and capture_to_send.
struct LatencySummary {
  std::uint64_t count = 0;
  double min_us = kMissing;
  double mean_us = kMissing;
  double median_us = kMissing;
  double p99_us = kMissing;
  double p999_us = kMissing;
  double max_us = kMissing;
};

struct Pacing {
  std::string mode;
  std::uint64_t skipped_ticks = 0;
  std::uint64_t overrun_alarms = 0;
};

/// The non-empty buckets of the whole-cycle histogram: counts[i] cycles took up to upper_us[i].
struct CycleHistogram {
  std::vector<double> upper_us;
  std::vector<std::uint64_t> counts;
};

/// Cycles per published health; `degraded` repeats the last three.
struct HealthCycles {
  std::uint64_t not_initialized = 0;
  std::uint64_t nominal = 0;
  std::uint64_t odometry_only = 0;
  std::uint64_t vision_only = 0;
  std::uint64_t invalid = 0;
};

struct Degraded {
  std::uint64_t odometry_only = 0;
  std::uint64_t vision_only = 0;
  std::uint64_t invalid = 0;
};

/// hal::CameraCounters and what the cycle saw of the frames.
struct Camera {
  hal::CameraCounters device;
  std::uint64_t no_frame_cycles = 0;
  std::uint64_t size_mismatch = 0;
  std::uint64_t stale = 0;
};

struct Encoders {
  hal::EncoderCounters device;
  std::uint64_t gaps_bridged = 0;
};

struct Localizer {
  std::optional<std::uint64_t> fixes;
  std::optional<std::uint64_t> unknown_place;
  std::uint64_t implausible_frames = 0;
  std::uint64_t off_map_cycles = 0;
  std::uint64_t uncovered_cycles = 0;    ///< not nominal: the map's coverage lacks the heading
  std::uint64_t cut_board_frames = 0;    ///< fixes without a board the frame's side cut
  std::uint64_t disagree_cycles = 0;     ///< not nominal: the boards disagreed with the pose
  std::uint64_t spread_wide_cycles = 0;  ///< not nominal: the cloud spread too wide
};

struct Filter {
  std::string observation;  ///< "boards" or "fix"
  std::uint64_t resamples = 0;
  /// Particles per cycle while the filter ran (KLD-sampling varies it; else the capacity).
  double particles_mean = 0.0;
  std::uint64_t particles_min = 0;
  std::uint64_t particles_max = 0;
  std::uint64_t no_consensus = 0;
  std::uint64_t distrusted_board_frames = 0;
  std::uint64_t fix_board_suspicions = 0;
  std::uint64_t kidnap_triggers = 0;
  std::uint64_t kidnaps = 0;
  std::uint64_t lost = 0;
  std::uint64_t nearby_draws = 0;  ///< draws at a nearby pose the boards preferred (times)
};

struct Recording {
  std::uint64_t frames = 0;
  std::uint64_t dropped = 0;
  std::uint64_t skipped = 0;
  std::uint64_t bytes = 0;
  std::string stopped;
};

struct Resources {
  long rss_kb_start = 0;
  long rss_kb_end = 0;
  long peak_rss_kb = 0;
  long open_fds_start = 0;
  long open_fds_end = 0;
};

/// The whole file. Optional members are sections or numbers a file may lack (an older firmware,
/// a hand-made file); the firmware fills the ones docs/stats-format.md lists as always present.
struct Document {
  std::string harmoloc_version;
  std::string board;
  std::string ended;
  std::uint64_t outputs_failed = 0;
  std::optional<double> rate_hz;
  std::optional<double> budget_us;
  std::optional<std::uint64_t> cycles;
  std::optional<std::uint64_t> frames;
  std::optional<std::uint64_t> overruns;
  std::optional<Pacing> pacing;
  /// In file order; the firmware writes its stages in cycle order, "cycle" last.
  std::vector<std::pair<std::string, StageTiming>> stages;
  std::optional<CycleHistogram> cycle_histogram;
  std::optional<HealthCycles> health_cycles;
  std::optional<Degraded> degraded;
  // Written for people and the generic section table of harmoloc-report, which shows every
  // section as the file has it; no tool reads these counters one by one, so from_json leaves them.
  Camera camera;
  Encoders encoders;
  hal::LinkCounters link;
  std::optional<Localizer> localizer;
  Filter filter;
  mavlink::InboundCounters inbound;
  std::optional<LatencySummary> wakeup_latency;
  std::optional<LatencySummary> capture_to_send;
  std::optional<Recording> recording;
  std::optional<Resources> resources;
};

void to_json(Json& j, const Document& d);
/// Throws FormatError naming the field when a present field has the wrong type or value, or the
/// file has no "stages" object; absent optional fields stay empty.
void from_json(const Json& j, Document& d);

/// The document laid out as docs/stats-format.md shows it: one top-level member a line, one stage
/// a line, every other section on one line.
std::string dump(const Document& d);

}  // namespace harmoloc::firmware::stats
