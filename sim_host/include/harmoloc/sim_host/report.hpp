#pragma once
/// @file The run report: evaluation of a replayed trajectory against ground truth, the firmware's
/// timing statistics, and the hand-written SVG plots and HTML page that `harmoloc-report` writes.
/// Host only; allocates freely.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "harmoloc/dataset/tum.hpp"

namespace harmoloc::sim_host {

/// Bad input to the report (no overlap in time, malformed stats, ...). The message is one line.
class ReportError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// ---------------------------------------------------------------------------------------------
// Trajectory evaluation
// ---------------------------------------------------------------------------------------------

/// The error of one estimated pose against the ground truth interpolated at its time.
/// dx, dy = estimate - truth; heading = wrap(estimate yaw - truth yaw), in [-pi, pi).
struct ErrorSample {
  double t_s = 0.0;
  double dx_m = 0.0;
  double dy_m = 0.0;
  double position_m = 0.0;
  double heading_rad = 0.0;
};

struct EvaluateOptions {
  /// Leaves out the estimate poses earlier than truth.front().t_s + skip_initial_s (the filter's
  /// convergence). The window is anchored on the ground truth's start so that the fused estimate
  /// and the raw fixes are scored on the same stretch of time.
  double skip_initial_s = 0.0;
};

struct TrajectoryErrors {
  std::size_t count = 0;          ///< Poses scored.
  std::size_t outside_truth = 0;  ///< Estimate poses outside the truth's time span (not scored).
  std::size_t skipped = 0;        ///< Poses inside the span but within skip_initial_s.
  double skip_initial_s = 0.0;
  double rmse_x_m = 0.0;
  double rmse_y_m = 0.0;
  double rmse_position_m = 0.0;  ///< sqrt(mean(dx^2 + dy^2)).
  double mse_x_cm2 = 0.0;        ///< mean(dx^2), in cm^2 (as the harmonic-localizer paper reports).
  double mse_y_cm2 = 0.0;
  double mean_position_m = 0.0;
  double max_position_m = 0.0;
  double p95_position_m = 0.0;  ///< percentile(position errors, 95), see percentile().
  double rmse_heading_deg = 0.0;
  double max_heading_deg = 0.0;      ///< Largest |heading error|.
  std::vector<ErrorSample> samples;  ///< The scored poses, in time order.
};

/// Scores @p estimate against @p truth (both in time order, as read_tum returns them). Every
/// estimate pose whose time lies in the truth's span is compared with the truth interpolated at
/// that time. With no pose to score, returns count == 0 and zeros (the caller decides whether
/// that is an error).
TrajectoryErrors evaluate(const std::vector<dataset::StampedPose>& truth,
                          const std::vector<dataset::StampedPose>& estimate,
                          const EvaluateOptions& options = {});

/// The p-th percentile (0..100) of @p values with linear interpolation between closest ranks
/// (numpy's default): rank = p/100 * (n - 1). Returns 0 for an empty vector.
double percentile(std::vector<double> values, double p);

// ---------------------------------------------------------------------------------------------
// Firmware statistics (`harmoloc --stats OUT.json`)
// ---------------------------------------------------------------------------------------------

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

  /// The stage called @p name, or nullptr.
  const StageTiming* stage(const std::string& name) const;
};

/// Parses the stats JSON text. Throws ReportError ("ORIGIN: reason") when the text is not JSON,
/// is not an object, lacks "stages", or a present field has the wrong type. Missing optional
/// sections are left empty.
RunStats parse_stats(const std::string& text, const std::string& origin = "stats");

/// Reads and parses a stats file; throws ReportError ("PATH: reason") on any failure.
RunStats read_stats(const std::string& path);

// ---------------------------------------------------------------------------------------------
// The report
// ---------------------------------------------------------------------------------------------

struct ReportInputs {
  std::string title;  ///< Free text shown under the page title; may be empty.
  std::string truth_path;
  std::string estimate_path;
  std::string fixes_path;  ///< Empty: no harmonic fixes.
  std::string stats_path;  ///< Empty: no timing.
  double skip_initial_s = 0.0;
};

struct Report {
  ReportInputs inputs;
  std::vector<dataset::StampedPose> truth;
  std::vector<dataset::StampedPose> estimate;
  std::vector<dataset::StampedPose> fixes;  ///< Empty when inputs.fixes_path is empty.
  TrajectoryErrors estimate_all;
  std::optional<TrajectoryErrors> estimate_converged;  ///< Only with skip_initial_s > 0.
  std::optional<TrajectoryErrors> fixes_all;
  std::optional<TrajectoryErrors> fixes_converged;
  std::optional<RunStats> stats;
};

/// Scores the loaded trajectories (and keeps @p stats). Throws ReportError when the estimate (or
/// the fixes) has no pose in the truth's time span, or the skip leaves none, or truth has fewer
/// than two poses.
Report build_report(ReportInputs inputs, std::vector<dataset::StampedPose> truth,
                    std::vector<dataset::StampedPose> estimate,
                    std::vector<dataset::StampedPose> fixes, std::optional<RunStats> stats);

/// Reads the files named in @p inputs and calls build_report. Throws std::runtime_error (one
/// line) on missing or malformed files.
Report load_report(const ReportInputs& inputs);

/// The short human summary (several lines, newline-terminated). @p index_path, when not empty,
/// is printed on the last line ("report  PATH").
std::string summary_text(const Report& report, const std::string& index_path = "");

/// The numbers as JSON text (pretty-printed). Lengths in cm, angles in degrees, times in us.
std::string summary_json(const Report& report);

/// The plots. Each returns a complete standalone SVG document.
std::string trajectory_svg(const Report& report);
std::string error_svg(const Report& report);
std::string timing_svg(const RunStats& stats);  ///< Requires stats.cycle_histogram.
std::string stages_svg(const RunStats& stats);

/// The self-contained HTML page; @p images are the SVG file names (relative to the page).
std::string index_html(const Report& report, const std::vector<std::string>& images);

/// Writes index.html, summary.json, summary.txt and the SVGs into @p dir (created if needed).
/// Returns the names of the files written. Throws std::runtime_error on an I/O failure.
std::vector<std::string> write_report(const Report& report, const std::filesystem::path& dir);

}  // namespace harmoloc::sim_host
