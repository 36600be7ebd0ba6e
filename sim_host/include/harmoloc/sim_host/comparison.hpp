#pragma once
/// @file Several runs on one page (`harmoloc-report --compare NAME=PATH ...`): the same ground
/// truth scored against each run's estimate (two maps or two configs on the same test run), a
/// table of their numbers and overlaid error and trajectory plots, one colour a run. Host only;
/// allocates freely.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "harmoloc/sim_host/report.hpp"

namespace harmoloc::sim_host {

/// One run named on the command line: NAME=PATH, PATH a TUM trajectory or a run folder.
struct RunSpec {
  std::string name;
  std::string estimate_path;
  std::string stats_path;  ///< Empty: no timing for this run.
};

/// Parses "NAME=PATH". PATH is a TUM file (the estimate), or a folder holding trajectory.tum
/// (or estimate.tum, as `harmoloc --record` writes) and, when present, stats.json. Throws
/// ReportError (one line) on a missing name, an unknown path or a folder without a trajectory.
RunSpec parse_run_spec(const std::string& text);

struct ComparedRun {
  std::string name;
  Report report;  ///< Scored as a single report with the shared truth and skip.
};

/// One run's numbers as the comparison's table gives them (all poses, or after the skip).
struct RunNumbers {
  std::size_t poses = 0;
  double rmse_cm = 0.0;
  double median_cm = 0.0;
  double max_cm = 0.0;
  double rpe_1m_rmse_cm = 0.0;  ///< NaN with no pair.
  double rpe_1s_rmse_cm = 0.0;  ///< NaN with no pair.
  double cycle_p99_us = 0.0;    ///< NaN without stats (or no "cycle" stage).
  double budget_us = 0.0;       ///< NaN without stats.
};
/// @p after_skip: the numbers after --skip-initial (requires report.estimate_converged).
RunNumbers run_numbers(const ComparedRun& run, bool after_skip);

/// Scores each run against the truth at @p truth_path (ReportInputs.truth_path, skip and title
/// taken from @p common). Throws ReportError on fewer than two runs, a repeated name or any
/// error load_report gives (prefixed with the run's name).
std::vector<ComparedRun> load_comparison(const ReportInputs& common,
                                         const std::vector<RunSpec>& runs);

/// The colour of run @p index (a fixed palette, repeated after eight runs).
const char* run_colour(std::size_t index);

std::string comparison_error_svg(const std::vector<ComparedRun>& runs);
std::string comparison_trajectory_svg(const std::vector<ComparedRun>& runs);
std::string comparison_html(const std::vector<ComparedRun>& runs,
                            const std::vector<std::string>& images);
std::string comparison_json(const std::vector<ComparedRun>& runs);
std::string comparison_text(const std::vector<ComparedRun>& runs,
                            const std::string& index_path = "");

/// Writes index.html, compare_error.svg, compare_trajectory.svg, summary.json and summary.txt
/// into @p dir (created if needed) and removes the single-run plots an earlier report left
/// there. Returns the names written. Throws std::runtime_error on an I/O failure.
std::vector<std::string> write_comparison(const std::vector<ComparedRun>& runs,
                                          const std::filesystem::path& dir);

}  // namespace harmoloc::sim_host
