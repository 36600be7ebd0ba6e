// The comparison's page, its summary.json and summary.txt, and the folder they go to.
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "format.hpp"
#include "harmoloc/sim_host/comparison.hpp"
#include "harmoloc/sim_host/svg.hpp"
#include "page_style.hpp"

namespace harmoloc::sim_host {

using report_text::write_file;

using report_text::cell;
using report_text::format;
using report_text::seconds;
using svg::escape;

namespace {

using Json = nlohmann::ordered_json;

Json number_or_null(double v) {
  return std::isfinite(v) ? Json(v) : Json(nullptr);
}

bool with_skip(const std::vector<ComparedRun>& runs) {
  return runs.front().report.inputs.skip_initial_s > 0.0 &&
         runs.front().report.estimate_converged.has_value();
}

void numbers_table(std::string& out, const std::vector<ComparedRun>& runs, bool after_skip) {
  out +=
      "<table class=\"runs\">\n<tr><th>run</th><th>poses</th><th>RMSE (cm)</th>"
      "<th>median (cm)</th><th>max (cm)</th><th>RPE 1 m RMSE (cm)</th><th>RPE 1 s RMSE (cm)</th>"
      "<th>cycle p99 (µs)</th><th>p99 / budget</th></tr>\n";
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const RunNumbers n = run_numbers(runs[i], after_skip);
    out += format("<tr><td class=\"run\"><span class=\"swatch\" style=\"background:%s\"></span>",
                  run_colour(i)) +
           escape(runs[i].name) + "</td>";
    for (const std::string& c :
         {std::to_string(n.poses), cell(n.rmse_cm, 2), cell(n.median_cm, 2), cell(n.max_cm, 2),
          cell(n.rpe_1m_rmse_cm, 2), cell(n.rpe_1s_rmse_cm, 2), cell(n.cycle_p99_us, 1),
          std::isfinite(n.cycle_p99_us) ? cell(n.cycle_p99_us / n.budget_us * 100.0, 2) + " %"
                                        : std::string("n/a")}) {
      out += "<td>" + escape(c) + "</td>";
    }
    out += "</tr>\n";
  }
  out += "</table>\n";
}

Json numbers_json(const RunNumbers& n) {
  return {{"poses", n.poses},
          {"rmse_position_cm", n.rmse_cm},
          {"median_position_cm", n.median_cm},
          {"max_position_cm", n.max_cm},
          {"rpe_1m_rmse_cm", number_or_null(n.rpe_1m_rmse_cm)},
          {"rpe_1s_rmse_cm", number_or_null(n.rpe_1s_rmse_cm)},
          {"cycle_p99_us", number_or_null(n.cycle_p99_us)}};
}

}  // namespace

std::string comparison_html(const std::vector<ComparedRun>& runs,
                            const std::vector<std::string>& images) {
  const ReportInputs& common = runs.front().report.inputs;
  std::string out =
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      "<title>harmoloc run comparison</title>\n<style>";
  out += kPageCss;
  out += "</style>\n</head>\n<body>\n<h1>harmoloc run comparison</h1>\n";
  if (!common.title.empty()) out += "<p class=\"subtitle\">" + escape(common.title) + "</p>\n";
  out += "<h2>Runs against the same ground truth</h2>\n";
  numbers_table(out, runs, false);
  if (with_skip(runs)) {
    out += "<h2>After the first " + escape(seconds(common.skip_initial_s)) + "</h2>\n";
    numbers_table(out, runs, true);
  }
  out += "<p class=\"note\">" +
         escape(
             "Position error against the ground truth interpolated at each pose's time (no "
             "alignment). RPE: relative error over 1 m and 1 s, as evo_rpe reports it "
             "(docs/report.md). Cycle p99 from each run's stats.json, n/a without one.") +
         "</p>\n";
  for (const std::string& image : images) {
    const std::string caption = image == "compare_error.svg"
                                    ? "Position error over time, one colour a run."
                                    : "Ground truth and each run's trajectory in the map frame.";
    out += "<figure><img src=\"" + escape(image) + "\" alt=\"" + escape(caption) +
           "\"><figcaption>" + escape(caption) + "</figcaption></figure>\n";
  }
  out += "<h2>Inputs</h2>\n<table class=\"files\">\n<tr><td>ground truth</td><td>" +
         escape(common.truth_path) + "</td></tr>\n";
  for (const ComparedRun& r : runs) {
    out += "<tr><td>" + escape(r.name) + "</td><td>" + escape(r.report.inputs.estimate_path);
    if (!r.report.inputs.stats_path.empty()) out += ", " + escape(r.report.inputs.stats_path);
    out += "</td></tr>\n";
  }
  out +=
      "</table>\n<p class=\"note\">Written by harmoloc-report --compare. The numbers are also in "
      "<a href=\"summary.json\">summary.json</a> and <a href=\"summary.txt\">summary.txt</a>."
      "</p>\n</body>\n</html>\n";
  return out;
}

std::string comparison_json(const std::vector<ComparedRun>& runs) {
  const ReportInputs& common = runs.front().report.inputs;
  Json j;
  j["title"] = common.title;
  j["truth"] = common.truth_path;
  j["skip_initial_s"] = common.skip_initial_s;
  j["units"] = "lengths in cm, times in microseconds";
  Json list = Json::array();
  for (const ComparedRun& r : runs) {
    Json run;
    run["name"] = r.name;
    run["estimate"] = r.report.inputs.estimate_path;
    run["stats"] =
        r.report.inputs.stats_path.empty() ? Json(nullptr) : Json(r.report.inputs.stats_path);
    run["all"] = numbers_json(run_numbers(r, false));
    if (with_skip(runs)) run["after_convergence"] = numbers_json(run_numbers(r, true));
    list.push_back(run);
  }
  j["runs"] = list;
  return j.dump(2) + "\n";
}

std::string comparison_text(const std::vector<ComparedRun>& runs, const std::string& index_path) {
  const bool skip = with_skip(runs);
  std::string out;
  const std::string& title = runs.front().report.inputs.title;
  if (!title.empty()) out += "harmoloc run comparison: " + title + "\n";
  out += format("%-16s %8s %10s %10s %10s %10s %10s %10s\n", "run", "poses", "RMSE cm", "median cm",
                "max cm", "RPE1m cm", "RPE1s cm", "p99 us");
  for (const bool after : {false, true}) {
    if (after && !skip) break;
    if (after) out += "after " + seconds(runs.front().report.inputs.skip_initial_s) + "\n";
    for (const ComparedRun& r : runs) {
      const RunNumbers n = run_numbers(r, after);
      out += format("%-16s %8zu %10s %10s %10s %10s %10s %10s\n", r.name.c_str(), n.poses,
                    cell(n.rmse_cm, 2).c_str(), cell(n.median_cm, 2).c_str(),
                    cell(n.max_cm, 2).c_str(), cell(n.rpe_1m_rmse_cm, 2).c_str(),
                    cell(n.rpe_1s_rmse_cm, 2).c_str(), cell(n.cycle_p99_us, 1).c_str());
    }
  }
  if (!index_path.empty()) out += "report " + index_path + "\n";
  return out;
}

std::vector<std::string> write_comparison(const std::vector<ComparedRun>& runs,
                                          const std::filesystem::path& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir)) {
    throw std::runtime_error(dir.string() + ": cannot create the report folder" +
                             (ec ? " (" + ec.message() + ")" : std::string()));
  }
  // A single-run report written to this folder before: its plots would sit beside ours.
  for (const char* stale : {"trajectory.svg", "error.svg", "error_xy.svg", "timing.svg",
                            "stages.svg", "health.svg", "sigma.svg", "areas.svg"}) {
    std::error_code ignored;
    std::filesystem::remove(dir / stale, ignored);
  }
  std::vector<std::string> written;
  const auto put = [&](const std::string& name, const std::string& content) {
    write_file(dir / name, content);
    written.push_back(name);
  };
  put("compare_error.svg", comparison_error_svg(runs));
  put("compare_trajectory.svg", comparison_trajectory_svg(runs));
  put("index.html", comparison_html(runs, {"compare_error.svg", "compare_trajectory.svg"}));
  put("summary.json", comparison_json(runs));
  put("summary.txt", comparison_text(runs, (dir / "index.html").string()));
  return written;
}

}  // namespace harmoloc::sim_host
