#include "harmoloc/sim_host/report.hpp"

#include <cmath>
#include <fstream>
#include <limits>
#include <system_error>

#include "format.hpp"

namespace harmoloc::sim_host {

using report_text::write_file;

using report_text::format;

Report build_report(ReportInputs inputs, std::vector<dataset::StampedPose> truth,
                    std::vector<dataset::StampedPose> estimate,
                    std::vector<dataset::StampedPose> fixes, std::optional<RunStats> stats) {
  const std::string truth_name = inputs.truth_path.empty() ? "truth" : inputs.truth_path;
  const std::string estimate_name =
      inputs.estimate_path.empty() ? "estimate" : inputs.estimate_path;
  const std::string fixes_name = inputs.fixes_path.empty() ? "fixes" : inputs.fixes_path;
  if (truth.size() < 2) {
    throw ReportError(format("%s: ground truth needs at least two poses (has %zu)",
                             truth_name.c_str(), truth.size()));
  }
  if (estimate.empty()) throw ReportError(estimate_name + ": no poses");
  if (!std::isfinite(inputs.skip_initial_s) || inputs.skip_initial_s < 0.0) {
    throw ReportError("the initial skip must be a non-negative number of seconds");
  }
  const bool with_fixes = !inputs.fixes_path.empty() || !fixes.empty();
  if (with_fixes && fixes.empty()) throw ReportError(fixes_name + ": no poses");

  const auto span_error = [&](const std::string& name,
                              const std::vector<dataset::StampedPose>& poses) {
    return ReportError(
        format("%s: no pose lies within the ground truth's time span (truth "
               "%.3f..%.3f s, %s %.3f..%.3f s)",
               name.c_str(), truth.front().t_s, truth.back().t_s,
               name == fixes_name ? "fixes" : "estimate", poses.front().t_s, poses.back().t_s));
  };
  const double skip = inputs.skip_initial_s;

  Report report;
  report.estimate_all = evaluate(truth, estimate);
  if (report.estimate_all.count == 0) throw span_error(estimate_name, estimate);
  if (skip > 0.0) {
    report.estimate_converged = evaluate(truth, estimate, {skip});
    if (report.estimate_converged->count == 0) {
      throw ReportError(
          format("%s: skipping the first %g s leaves no pose to score (the ground "
                 "truth lasts %.3f s)",
                 estimate_name.c_str(), skip, truth.back().t_s - truth.front().t_s));
    }
  }
  if (with_fixes) {
    report.fixes_all = evaluate(truth, fixes);
    if (report.fixes_all->count == 0) throw span_error(fixes_name, fixes);
    if (skip > 0.0) {
      TrajectoryErrors converged = evaluate(truth, fixes, {skip});
      if (converged.count > 0) report.fixes_converged = std::move(converged);
    }
  }
  // Relative error on the same poses as the absolute error (all, and after the skip).
  const double all_from_s = -std::numeric_limits<double>::infinity();
  const std::vector<PosePair> all_pairs = pair_with_truth(truth, estimate, all_from_s);
  report.rpe_1m = relative_errors(all_pairs, 1.0, DeltaUnit::kMetres);
  report.rpe_1s = relative_errors(all_pairs, 1.0, DeltaUnit::kSeconds);
  if (skip > 0.0) {
    const std::vector<PosePair> late = pair_with_truth(truth, estimate, truth.front().t_s + skip);
    report.rpe_1m_converged = relative_errors(late, 1.0, DeltaUnit::kMetres);
    report.rpe_1s_converged = relative_errors(late, 1.0, DeltaUnit::kSeconds);
  }
  report.inputs = std::move(inputs);
  report.truth = std::move(truth);
  report.estimate = std::move(estimate);
  report.fixes = std::move(fixes);
  report.stats = std::move(stats);
  return report;
}

Report load_report(const ReportInputs& inputs) {
  for (const std::string* path : {&inputs.truth_path, &inputs.estimate_path, &inputs.fixes_path,
                                  &inputs.stats_path, &inputs.link_path, &inputs.areas_path}) {
    std::error_code ec;
    if (!path->empty() && std::filesystem::is_directory(*path, ec)) {
      throw ReportError(*path + ": is a directory, expected a file");
    }
  }
  std::vector<dataset::StampedPose> truth = dataset::read_tum(inputs.truth_path);
  std::vector<dataset::StampedPose> estimate = dataset::read_tum(inputs.estimate_path);
  std::vector<dataset::StampedPose> fixes;
  if (!inputs.fixes_path.empty()) fixes = dataset::read_tum(inputs.fixes_path);
  std::optional<RunStats> stats;
  if (!inputs.stats_path.empty()) stats = read_stats(inputs.stats_path);
  Report report = build_report(inputs, std::move(truth), std::move(estimate), std::move(fixes),
                               std::move(stats));
  if (!inputs.areas_path.empty()) report.areas = dataset::read_area_log(inputs.areas_path);
  return report;
}

std::vector<std::string> write_report(const Report& report, const std::filesystem::path& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir)) {
    throw std::runtime_error(dir.string() + ": cannot create the report folder" +
                             (ec ? " (" + ec.message() + ")" : std::string()));
  }
  std::vector<std::string> images;
  std::vector<std::string> written;
  const auto put = [&](const std::string& name, const std::string& content) {
    write_file(dir / name, content);
    written.push_back(name);
  };
  const auto drop = [&](const std::string& name) {
    std::error_code ignored;
    std::filesystem::remove(dir / name, ignored);  // a stale plot of an earlier run
  };
  drop("compare_error.svg");  // a comparison written to this folder before
  drop("compare_trajectory.svg");
  put("trajectory.svg", trajectory_svg(report));
  images.push_back("trajectory.svg");
  put("error.svg", error_svg(report));
  images.push_back("error.svg");
  put("error_xy.svg", xy_error_svg(report));
  images.push_back("error_xy.svg");
  if (report.link) {
    put("sigma.svg", sigma_svg(report));
    images.push_back("sigma.svg");
    put("health.svg", health_svg(report));
    images.push_back("health.svg");
  } else {
    drop("sigma.svg");
    drop("health.svg");
  }
  if (report.areas) {
    put("areas.svg", areas_svg(report));
    images.push_back("areas.svg");
  } else {
    drop("areas.svg");
  }
  if (report.stats && report.stats->cycle_histogram) {
    put("timing.svg", timing_svg(*report.stats));
    images.push_back("timing.svg");
  } else {
    drop("timing.svg");
  }
  if (report.stats && !report.stats->stages.empty()) {
    put("stages.svg", stages_svg(*report.stats));
    images.push_back("stages.svg");
  } else {
    drop("stages.svg");
  }
  put("index.html", index_html(report, images));
  put("summary.json", summary_json(report));
  put("summary.txt", summary_text(report, (dir / "index.html").string()));
  return written;
}

}  // namespace harmoloc::sim_host
