// The runs of a comparison: what NAME=PATH names, and each run scored against the shared truth.
#include <limits>
#include <set>
#include <system_error>

#include "format.hpp"
#include "harmoloc/sim_host/comparison.hpp"

namespace harmoloc::sim_host {

RunSpec parse_run_spec(const std::string& text) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0 || eq + 1 == text.size()) {
    throw ReportError("--compare expects NAME=PATH (a TUM trajectory or a run folder), got '" +
                      text + "'");
  }
  RunSpec spec;
  spec.name = text.substr(0, eq);
  const std::filesystem::path path = text.substr(eq + 1);
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    for (const char* name : {"trajectory.tum", "estimate.tum"}) {
      if (std::filesystem::is_regular_file(path / name, ec)) {
        spec.estimate_path = (path / name).string();
        break;
      }
    }
    if (spec.estimate_path.empty()) {
      throw ReportError(path.string() + ": run folder has no trajectory.tum or estimate.tum");
    }
    if (std::filesystem::is_regular_file(path / "stats.json", ec)) {
      spec.stats_path = (path / "stats.json").string();
    }
  } else if (std::filesystem::exists(path, ec)) {
    spec.estimate_path = path.string();
  } else {
    throw ReportError(path.string() + ": no such file or folder");
  }
  return spec;
}

std::vector<ComparedRun> load_comparison(const ReportInputs& common,
                                         const std::vector<RunSpec>& runs) {
  if (runs.size() < 2) throw ReportError("--compare needs at least two runs");
  std::set<std::string> names;
  std::vector<ComparedRun> out;
  for (const RunSpec& spec : runs) {
    if (!names.insert(spec.name).second) {
      throw ReportError("--compare: the name '" + spec.name + "' is given twice");
    }
    ReportInputs inputs;
    inputs.title = common.title;
    inputs.truth_path = common.truth_path;
    inputs.skip_initial_s = common.skip_initial_s;
    inputs.estimate_path = spec.estimate_path;
    inputs.stats_path = spec.stats_path;
    ComparedRun run;
    run.name = spec.name;
    try {
      run.report = load_report(inputs);
    } catch (const std::exception& e) {
      throw ReportError("run " + spec.name + ": " + e.what());
    }
    out.push_back(std::move(run));
  }
  return out;
}

RunNumbers run_numbers(const ComparedRun& run, bool after_skip) {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  const Report& r = run.report;
  const TrajectoryErrors& e = after_skip ? *r.estimate_converged : r.estimate_all;
  const RelativeErrors& m = after_skip ? *r.rpe_1m_converged : r.rpe_1m;
  const RelativeErrors& s = after_skip ? *r.rpe_1s_converged : r.rpe_1s;
  RunNumbers n;
  n.poses = e.count;
  n.rmse_cm = e.rmse_position_m * 100.0;
  std::vector<double> errors;
  for (const ErrorSample& sample : e.samples) errors.push_back(sample.position_m * 100.0);
  n.median_cm = percentile(errors, 50.0);
  n.max_cm = e.max_position_m * 100.0;
  n.rpe_1m_rmse_cm = m.pairs == 0 ? kNaN : m.rmse_m * 100.0;
  n.rpe_1s_rmse_cm = s.pairs == 0 ? kNaN : s.rmse_m * 100.0;
  n.cycle_p99_us = kNaN;
  n.budget_us = kNaN;
  if (r.stats) {
    n.budget_us = r.stats->budget_us;
    if (const StageTiming* cycle = r.stats->stage("cycle")) n.cycle_p99_us = cycle->p99_us;
  }
  return n;
}

const char* run_colour(std::size_t index) {
  static constexpr const char* kColours[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728",
                                             "#9467bd", "#8c564b", "#e377c2", "#17becf"};
  return kColours[index % (sizeof kColours / sizeof kColours[0])];
}

}  // namespace harmoloc::sim_host
