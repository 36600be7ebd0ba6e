/// harmoloc-report: turns a replay run's outputs into numbers and an HTML report with SVG plots.
///
/// Exit status: 0 on success, 2 on bad input or an output failure (one line on stderr starting
/// with "harmoloc-report: "), CLI11's usual codes on a usage error.

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "harmoloc/firmware/cli.hpp"
#include "harmoloc/sim_host/comparison.hpp"
#include "harmoloc/sim_host/link_log.hpp"
#include "harmoloc/sim_host/report.hpp"

namespace {

/// One line: newlines in a message (e.g. from a nested library) become spaces.
std::string one_line(std::string text) {
  for (char& c : text) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  return text;
}

int fail(const std::string& message) {
  std::cerr << "harmoloc-report: " << one_line(message) << '\n';
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "harmoloc-report: evaluates a replay run against ground truth and writes a report folder\n"
      "(index.html with SVG plots, summary.json, summary.txt). Trajectory files are TUM\n"
      "(`t x y z qx qy qz qw` a line, seconds and metres; planar: z = 0, yaw-only quaternion).\n"
      "Each estimate pose is compared with the ground truth interpolated at its time.\n"
      "With --compare NAME=PATH ... (instead of --estimate) it writes one page comparing several\n"
      "runs on the same ground truth (e.g. two maps or two configs).",
      "harmoloc-report"};
  harmoloc::sim_host::ReportInputs inputs;
  std::string out_dir;
  std::vector<std::string> compare;
  app.add_option("--truth", inputs.truth_path,
                 "ground-truth trajectory (TUM), e.g. the simulator's groundtruth.tum")
      ->required()
      ->type_name("GT.tum");
  app.add_option("--estimate", inputs.estimate_path,
                 "fused pose the firmware wrote (TUM), `harmoloc --trajectory OUT.tum` "
                 "(required unless --compare is given)")
      ->type_name("EST.tum");
  app.add_option("--compare", compare,
                 "instead of --estimate: two or more runs on the same ground truth, each NAME=PATH "
                 "with PATH a TUM trajectory or a run folder holding trajectory.tum (or "
                 "estimate.tum) and optionally stats.json; writes one page with a table (RMSE, "
                 "median, max, RPE, cycle p99 per run) and overlaid error and trajectory plots "
                 "(index.html, compare_error.svg, compare_trajectory.svg, summary.json, "
                 "summary.txt). Takes --truth, --skip-initial, --title and --out only")
      ->type_name("NAME=PATH")
      ->expected(1, -1);
  app.add_option("--fixes", inputs.fixes_path,
                 "optional: raw harmonic-localizer fixes (TUM; their heading is ignored), "
                 "drawn as dots and scored separately")
      ->type_name("FIXES.tum");
  app.add_option("--stats", inputs.stats_path,
                 "optional: the firmware's timing statistics, `harmoloc --stats OUT.json` "
                 "(per-stage timing, cycle histogram, overruns, degraded modes)")
      ->type_name("STATS.json");
  app.add_option("--link", inputs.link_path,
                 "optional: the firmware's recorded link, `harmoloc --link OUT` (MAVLink): adds "
                 "the health timeline and the claimed 2-sigma spread against the actual error")
      ->type_name("LINK");
  app.add_option("--areas", inputs.areas_path,
                 "optional: the firmware's area log, `harmoloc --record-areas FILE` (or areas.csv "
                 "of `harmoloc --record DIR`): each board's area over time with the periods the "
                 "filter distrusted it shaded")
      ->type_name("AREAS.csv");
  app.add_option("--out", out_dir,
                 "report folder to write (created if needed): index.html, trajectory.svg, "
                 "error.svg, error_xy.svg, timing.svg, stages.svg, health.svg, sigma.svg, "
                 "areas.svg, "
                 "summary.json, summary.txt")
      ->required()
      ->type_name("DIR");
  app.add_option("--title", inputs.title, "free text shown under the report's title")
      ->type_name("TEXT");
  app.add_option("--skip-initial,--skip", inputs.skip_initial_s,
                 "also report the errors without the first S seconds of the ground truth "
                 "(the filter's convergence)")
      ->check(
          [](const std::string& text) -> std::string {
            char* end = nullptr;
            const double v = std::strtod(text.c_str(), &end);
            if (end != text.c_str() && *end == '\0' && v >= 0.0 && std::isfinite(v)) return "";
            return "expected a non-negative number of seconds, got '" + text + "'";
          },
          "S >= 0")
      ->type_name("S");
  if (const auto status = harmoloc::cli::parse(app, argc, argv)) return *status;

  if (compare.empty() && inputs.estimate_path.empty()) {
    return fail("--estimate is required (or --compare NAME=PATH ...)");
  }
  if (!compare.empty()) {
    if (!inputs.estimate_path.empty() || !inputs.fixes_path.empty() || !inputs.stats_path.empty() ||
        !inputs.link_path.empty() || !inputs.areas_path.empty()) {
      return fail(
          "--compare takes the runs' estimates (and stats) from NAME=PATH: leave out "
          "--estimate, --fixes, --stats, --link and --areas");
    }
    try {
      std::vector<harmoloc::sim_host::RunSpec> specs;
      for (const std::string& text : compare)
        specs.push_back(harmoloc::sim_host::parse_run_spec(text));
      const auto runs = harmoloc::sim_host::load_comparison(inputs, specs);
      const std::filesystem::path dir(out_dir);
      harmoloc::sim_host::write_comparison(runs, dir);
      std::cout << harmoloc::sim_host::comparison_text(runs, (dir / "index.html").string());
      std::cout.flush();
      if (!std::cout) return fail("cannot write to standard output");
    } catch (const std::exception& e) {
      return fail(e.what());
    }
    return 0;
  }

  try {
    harmoloc::sim_host::Report report = harmoloc::sim_host::load_report(inputs);
    if (!inputs.link_path.empty())
      report.link = harmoloc::sim_host::read_link_log(inputs.link_path);
    const std::filesystem::path dir(out_dir);
    harmoloc::sim_host::write_report(report, dir);
    std::cout << harmoloc::sim_host::summary_text(report, (dir / "index.html").string());
    std::cout.flush();
    if (!std::cout) return fail("cannot write to standard output");
  } catch (const std::exception& e) {
    return fail(e.what());
  } catch (...) {
    return fail("unexpected error");
  }
  return 0;
}
