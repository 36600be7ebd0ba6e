#pragma once
/// @file The run report: a replayed trajectory scored against ground truth
/// (trajectory_evaluation.hpp), the firmware's timing statistics (run_stats.hpp), and the SVG
/// plots and HTML page that `harmoloc-report` writes. Host only; allocates freely.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "harmoloc/dataset/area_log.hpp"
#include "harmoloc/dataset/tum.hpp"
#include "harmoloc/sim_host/link_log.hpp"
#include "harmoloc/sim_host/relative_error.hpp"
#include "harmoloc/sim_host/report_error.hpp"
#include "harmoloc/sim_host/run_stats.hpp"
#include "harmoloc/sim_host/trajectory_evaluation.hpp"

namespace harmoloc::sim_host {

struct ReportInputs {
  std::string title;  ///< Free text shown under the page title; may be empty.
  std::string truth_path;
  std::string estimate_path;
  std::string fixes_path;  ///< Empty: no harmonic fixes.
  std::string stats_path;  ///< Empty: no timing.
  std::string link_path;   ///< Empty: no health timeline and no 2-sigma plot.
  std::string areas_path;  ///< Empty: no board areas (an area log, `harmoloc --record-areas`).
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
  /// The link recording (`harmoloc --link FILE`): health and spread over time. Set by the
  /// caller from read_link_log(inputs.link_path) (link_log.hpp, library harmoloc_report_link).
  std::optional<LinkLog> link;
  /// The area log (dataset/area_log.hpp): each board's area and distrust per frame.
  std::optional<dataset::AreaLog> areas;
  /// The fused estimate's Relative Pose Error (relative_error.hpp) over 1 m and over 1 s, on
  /// the poses estimate_all scores and, with a skip, on those estimate_converged scores.
  RelativeErrors rpe_1m;
  RelativeErrors rpe_1s;
  std::optional<RelativeErrors> rpe_1m_converged;
  std::optional<RelativeErrors> rpe_1s_converged;
};

/// How many poses on the link keep their x and y errors within 2 sigma.
struct SigmaConsistency {
  std::size_t poses = 0;  ///< Link poses within the truth's time span.
  std::size_t inside_x = 0;
  std::size_t inside_y = 0;
};
SigmaConsistency sigma_consistency(const Report& report);

/// A stretch of time [start_s, end_s), seconds on the data clock (as the TUM files).
struct TimeSpan {
  double start_s = 0.0;
  double end_s = 0.0;
};

/// The periods the filter distrusted board @p board in an area log: each run of frames with the
/// board's bit set, from its first frame to the frame after it (the log's last frame: plus the
/// interval before it). Empty when the log has no distrusted_mask column.
std::vector<TimeSpan> distrusted_spans(const dataset::AreaLog& log, std::size_t board);

/// One board's area over the ground truth's time span (percent of the frame) and the time the
/// filter distrusted it there.
struct BoardAreaSummary {
  std::string name;
  std::size_t frames = 0;  ///< Frames of the log within the truth's span.
  double mean_percent = 0.0;
  double min_percent = 0.0;
  double max_percent = 0.0;
  double distrusted_s = 0.0;  ///< Within the truth's span; 0 without the distrust column.
};
/// One entry per board of report.areas (empty without it).
std::vector<BoardAreaSummary> board_area_summary(const Report& report);

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
std::string xy_error_svg(const Report& report);  ///< x and y error components over time.
std::string health_svg(const Report& report);    ///< Requires report.link.
std::string sigma_svg(const Report& report);     ///< Requires report.link.
/// Each board's area (percent of the frame) over time, distrusted periods shaded.
std::string areas_svg(const Report& report);  ///< Requires report.areas.

/// The self-contained HTML page; @p images are the SVG file names (relative to the page).
std::string index_html(const Report& report, const std::vector<std::string>& images);

/// Writes index.html, summary.json, summary.txt and the SVGs into @p dir (created if needed).
/// Returns the names of the files written. Throws std::runtime_error on an I/O failure.
std::vector<std::string> write_report(const Report& report, const std::filesystem::path& dir);

}  // namespace harmoloc::sim_host
