// The report's board-area view (from the area log, with the filter's distrusted periods) and the
// comparison of several runs on one page (harmoloc-report --compare).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "harmoloc/dataset/tum.hpp"
#include "harmoloc/sim_host/comparison.hpp"
#include "harmoloc/sim_host/report.hpp"

namespace hs = harmoloc::sim_host;
namespace hd = harmoloc::dataset;
using harmoloc::algorithms::Pose2;

namespace {

std::size_t count_of(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto i = text.find(what); i != std::string::npos; i = text.find(what, i + 1)) ++n;
  return n;
}

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

void write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

/// A folder of its own per test, removed at the end.
struct Dir {
  std::filesystem::path path;
  explicit Dir(const std::string& name)
      : path(std::filesystem::temp_directory_path() / ("harmoloc_" + name)) {
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
  }
  ~Dir() { std::filesystem::remove_all(path); }
};

/// Truth along x at 1 m/s for 2 s (10 Hz); an estimate offset by (dx, dy).
std::vector<hd::StampedPose> line(double dx, double dy) {
  std::vector<hd::StampedPose> poses;
  for (int k = 0; k <= 20; ++k) poses.push_back({0.1 * k, Pose2{0.1 * k + dx, dy, 0.0}});
  return poses;
}

/// Two boards over 0..2 s at 10 Hz in a 100x100 frame: red 10% of the frame, blue 0..4%
/// rising; blue distrusted from 0.5 s to 0.9 s (frames 5..8) and again at 1.5 s (frame 15).
hd::AreaLog sample_areas() {
  hd::AreaLog log;
  log.image_width_px = 100;
  log.image_height_px = 100;
  log.board_names = {"red", "blue"};
  log.has_distrust = true;
  for (int k = 0; k <= 20; ++k) {
    log.timestamp_ns.push_back(static_cast<std::uint64_t>(k) * 100'000'000ULL);
    harmoloc::algorithms::AreaVector a;
    a.count = 2;
    a.pixels[0] = 1000;
    a.pixels[1] = static_cast<std::uint32_t>(20 * k);
    log.areas.push_back(a);
    log.distrusted_mask.push_back((k >= 5 && k <= 8) || k == 15 ? 2U : 0U);
  }
  return log;
}

}  // namespace

TEST(ReportAreas, DistrustedSpansAreRunsOfFrames) {
  const hd::AreaLog log = sample_areas();
  EXPECT_TRUE(hs::distrusted_spans(log, 0).empty());
  const std::vector<hs::TimeSpan> blue = hs::distrusted_spans(log, 1);
  ASSERT_EQ(blue.size(), 2u);
  EXPECT_NEAR(blue[0].start_s, 0.5, 1e-9);
  EXPECT_NEAR(blue[0].end_s, 0.9, 1e-9);  // frames 5..8: up to frame 9's time
  EXPECT_NEAR(blue[1].start_s, 1.5, 1e-9);
  EXPECT_NEAR(blue[1].end_s, 1.6, 1e-9);
  // The last frame of the log: its own time plus the interval before it.
  hd::AreaLog tail = log;
  tail.distrusted_mask.back() = 1U;
  const std::vector<hs::TimeSpan> red = hs::distrusted_spans(tail, 0);
  ASSERT_EQ(red.size(), 1u);
  EXPECT_NEAR(red[0].start_s, 2.0, 1e-9);
  EXPECT_NEAR(red[0].end_s, 2.1, 1e-9);
  // A log from before the column: nothing.
  hd::AreaLog old = log;
  old.has_distrust = false;
  old.distrusted_mask.clear();
  EXPECT_TRUE(hs::distrusted_spans(old, 1).empty());
}

TEST(ReportAreas, PlotTableAndSummary) {
  Dir dir("report_areas");
  hs::Report r = hs::build_report({}, line(0.0, 0.0), line(0.01, 0.0), {}, std::nullopt);
  r.areas = sample_areas();
  const std::vector<std::string> written = hs::write_report(r, dir.path);
  EXPECT_NE(std::find(written.begin(), written.end(), "areas.svg"), written.end());
  const std::string svg = read_text(dir.path / "areas.svg");
  // One panel a board, each with its line of 21 frames; blue's two distrusted spans shaded.
  EXPECT_EQ(count_of(svg, "class=\"area\""), 2u);
  EXPECT_EQ(count_of(svg, "<g class=\"distrusted\" data-board=\"red\""), 1u);
  const auto blue = svg.find("<g class=\"distrusted\" data-board=\"blue\"");
  ASSERT_NE(blue, std::string::npos);
  EXPECT_EQ(count_of(svg.substr(blue, svg.find("</g>", blue) - blue), "<rect"), 2u);
  EXPECT_NE(svg.find("red: mean 10.00% of the frame, distrusted 0.0 s"), std::string::npos);
  EXPECT_NE(svg.find("blue: mean 2.00% of the frame, distrusted 0.5 s (25.0%)"), std::string::npos);
  EXPECT_NE(svg.find("stroke=\"#d62728\""), std::string::npos);  // red drawn red
  EXPECT_NE(svg.find("distrusted by the filter"), std::string::npos);

  const std::string html = read_text(dir.path / "index.html");
  EXPECT_NE(html.find("<img src=\"areas.svg\""), std::string::npos);
  EXPECT_NE(html.find("Boards (from the area log)"), std::string::npos);
  const nlohmann::json j = nlohmann::json::parse(read_text(dir.path / "summary.json"));
  ASSERT_EQ(j["areas"]["boards"].size(), 2u);
  EXPECT_EQ(j["areas"]["boards"][1]["name"], "blue");
  EXPECT_NEAR(j["areas"]["boards"][1]["distrusted_s"].get<double>(), 0.5, 1e-9);
  EXPECT_NEAR(j["areas"]["boards"][0]["mean_percent"].get<double>(), 10.0, 1e-9);
  EXPECT_NE(read_text(dir.path / "summary.txt").find("distrusted     red 0.0 s, blue 0.5 s"),
            std::string::npos);

  // A log without the column: the plot says so and shades nothing; without a log, no plot.
  r.areas->has_distrust = false;
  r.areas->distrusted_mask.clear();
  const std::string plain = hs::areas_svg(r);
  const auto plain_blue = plain.find("<g class=\"distrusted\" data-board=\"blue\"");
  ASSERT_NE(plain_blue, std::string::npos);
  EXPECT_EQ(
      count_of(plain.substr(plain_blue, plain.find("</g>", plain_blue) - plain_blue), "<rect"), 0u);
  EXPECT_NE(plain.find("no distrusted_mask column"), std::string::npos);
  EXPECT_EQ(plain.find("distrusted by the filter"), std::string::npos);
  r.areas.reset();
  hs::write_report(r, dir.path);
  EXPECT_FALSE(std::filesystem::exists(dir.path / "areas.svg"));
}

TEST(ReportAreas, LoadReportReadsTheAreaLog) {
  Dir dir("report_areas_load");
  hd::write_tum((dir.path / "gt.tum").string(), line(0.0, 0.0));
  hd::write_tum((dir.path / "est.tum").string(), line(0.0, 0.02));
  write_text(dir.path / "areas.csv",
             "# harmoloc area log v1: pixels of each board per frame\n"
             "# width_px=10 height_px=10 thresholds_crc32=0x00000001\n"
             "timestamp_ns,red,green,distrusted_mask\n"
             "0,10,20,0\n500000000,10,20,2\n1000000000,10,20,0\n");
  hs::ReportInputs in;
  in.truth_path = (dir.path / "gt.tum").string();
  in.estimate_path = (dir.path / "est.tum").string();
  in.areas_path = (dir.path / "areas.csv").string();
  const hs::Report r = hs::load_report(in);
  ASSERT_TRUE(r.areas.has_value());
  const std::vector<hs::BoardAreaSummary> b = hs::board_area_summary(r);
  ASSERT_EQ(b.size(), 2u);
  EXPECT_NEAR(b[1].distrusted_s, 0.5, 1e-9);
  EXPECT_NEAR(b[0].mean_percent, 10.0, 1e-9);
  EXPECT_EQ(b[0].frames, 3u);
}

TEST(ReportCompare, RunSpecsNameAFileOrARunFolder) {
  Dir dir("report_compare_spec");
  hd::write_tum((dir.path / "a.tum").string(), line(0.0, 0.0));
  std::filesystem::create_directories(dir.path / "run");
  hd::write_tum((dir.path / "run" / "trajectory.tum").string(), line(0.0, 0.0));
  write_text(dir.path / "run" / "stats.json", "{}");
  const hs::RunSpec file = hs::parse_run_spec("map A=" + (dir.path / "a.tum").string());
  EXPECT_EQ(file.name, "map A");
  EXPECT_EQ(file.estimate_path, (dir.path / "a.tum").string());
  EXPECT_TRUE(file.stats_path.empty());
  const hs::RunSpec folder = hs::parse_run_spec("B=" + (dir.path / "run").string());
  EXPECT_EQ(folder.estimate_path, (dir.path / "run" / "trajectory.tum").string());
  EXPECT_EQ(folder.stats_path, (dir.path / "run" / "stats.json").string());
  std::filesystem::create_directories(dir.path / "empty");
  for (const std::string& bad :
       {std::string("noequals"), std::string("=x"), std::string("A="),
        "A=" + (dir.path / "missing.tum").string(), "A=" + (dir.path / "empty").string()}) {
    EXPECT_THROW(hs::parse_run_spec(bad), hs::ReportError) << bad;
  }
}

TEST(ReportCompare, TableAndOverlaidPlots) {
  Dir dir("report_compare");
  const std::filesystem::path gt = dir.path / "gt.tum";
  hd::write_tum(gt.string(), line(0.0, 0.0));
  hd::write_tum((dir.path / "a.tum").string(), line(0.01, 0.0));  // 1 cm off
  std::filesystem::create_directories(dir.path / "b");
  hd::write_tum((dir.path / "b" / "trajectory.tum").string(), line(0.0, 0.03));  // 3 cm off
  write_text(dir.path / "b" / "stats.json",
             R"({"budget_us": 10000, "stages": {"cycle": {"median_us": 900, "p99_us": 1234,
                 "max_us": 1500}}})");
  hs::ReportInputs common;
  common.truth_path = gt.string();
  common.title = "two maps";
  const std::vector<hs::RunSpec> specs = {
      hs::parse_run_spec("map A=" + (dir.path / "a.tum").string()),
      hs::parse_run_spec("map <B>=" + (dir.path / "b").string())};
  const std::vector<hs::ComparedRun> runs = hs::load_comparison(common, specs);
  ASSERT_EQ(runs.size(), 2u);
  const hs::RunNumbers a = hs::run_numbers(runs[0], false);
  const hs::RunNumbers b = hs::run_numbers(runs[1], false);
  EXPECT_NEAR(a.rmse_cm, 1.0, 1e-6);
  EXPECT_NEAR(a.median_cm, 1.0, 1e-6);
  EXPECT_NEAR(b.rmse_cm, 3.0, 1e-6);
  EXPECT_NEAR(b.max_cm, 3.0, 1e-6);
  EXPECT_NEAR(b.rpe_1s_rmse_cm, 0.0, 1e-9);  // a constant offset: no drift
  EXPECT_TRUE(std::isnan(a.cycle_p99_us));
  EXPECT_NEAR(b.cycle_p99_us, 1234.0, 1e-9);

  const std::filesystem::path out = dir.path / "report";
  std::filesystem::create_directories(out);
  write_text(out / "error.svg", "stale");  // a single-run report in the same folder before
  const std::vector<std::string> written = hs::write_comparison(runs, out);
  for (const char* f : {"compare_error.svg", "compare_trajectory.svg", "index.html", "summary.json",
                        "summary.txt"}) {
    EXPECT_NE(std::find(written.begin(), written.end(), f), written.end()) << f;
  }
  EXPECT_FALSE(std::filesystem::exists(out / "error.svg"));
  const std::string error = read_text(out / "compare_error.svg");
  EXPECT_EQ(count_of(error, "class=\"run-error run-"), 2u);
  EXPECT_NE(error.find("stroke=\"" + std::string(hs::run_colour(1)) + "\""), std::string::npos);
  EXPECT_NE(error.find("map &lt;B&gt; (RMSE 3.00 cm)"), std::string::npos);  // legend, escaped
  const std::string trajectory = read_text(out / "compare_trajectory.svg");
  EXPECT_EQ(count_of(trajectory, "class=\"run-trajectory run-"), 2u);
  EXPECT_EQ(count_of(trajectory, "class=\"truth\""), 1u);
  const std::string html = read_text(out / "index.html");
  EXPECT_NE(html.find("<img src=\"compare_error.svg\""), std::string::npos);
  EXPECT_NE(html.find("<img src=\"compare_trajectory.svg\""), std::string::npos);
  EXPECT_NE(html.find("map &lt;B&gt;</td><td>21</td><td>3.00</td><td>3.00</td><td>3.00</td>"),
            std::string::npos)
      << html;
  EXPECT_NE(html.find("<td>1234.0</td><td>12.34 %</td>"), std::string::npos);
  const nlohmann::json j = nlohmann::json::parse(read_text(out / "summary.json"));
  ASSERT_EQ(j["runs"].size(), 2u);
  EXPECT_EQ(j["runs"][0]["name"], "map A");
  EXPECT_TRUE(j["runs"][0]["stats"].is_null());
  EXPECT_TRUE(j["runs"][0]["all"]["cycle_p99_us"].is_null());
  EXPECT_NEAR(j["runs"][1]["all"]["rmse_position_cm"].get<double>(), 3.0, 1e-6);
  EXPECT_NE(read_text(out / "summary.txt").find("map A"), std::string::npos);

  // With a skip, a second table after it.
  common.skip_initial_s = 0.5;
  const std::vector<hs::ComparedRun> late = hs::load_comparison(common, specs);
  EXPECT_EQ(hs::run_numbers(late[0], true).poses, 16u);  // 0.5 s .. 2 s
  EXPECT_NE(hs::comparison_html(late, {}).find("After the first 0.5 s"), std::string::npos);
}

TEST(ReportCompare, RefusesOneRunAndRepeatedNames) {
  Dir dir("report_compare_refuse");
  hd::write_tum((dir.path / "gt.tum").string(), line(0.0, 0.0));
  hd::write_tum((dir.path / "a.tum").string(), line(0.0, 0.0));
  hs::ReportInputs common;
  common.truth_path = (dir.path / "gt.tum").string();
  const hs::RunSpec a = hs::parse_run_spec("A=" + (dir.path / "a.tum").string());
  EXPECT_THROW(hs::load_comparison(common, {a}), hs::ReportError);
  EXPECT_THROW(hs::load_comparison(common, {a, a}), hs::ReportError);
  hs::RunSpec far = a;
  far.name = "late";
  write_text(dir.path / "late.tum", "100 0 0 0 0 0 0 1\n");
  far.estimate_path = (dir.path / "late.tum").string();
  try {
    hs::load_comparison(common, {a, far});
    FAIL() << "no error";
  } catch (const hs::ReportError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("run late: ", 0), 0u) << e.what();
  }
}
