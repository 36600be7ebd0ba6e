#include "harmoloc/sim_host/report.hpp"
#include "harmoloc/sim_host/svg.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <system_error>
#include <vector>

namespace hs = harmoloc::sim_host;
namespace hd = harmoloc::dataset;
using harmoloc::algorithms::kPi;
using harmoloc::algorithms::Pose2;

namespace {

constexpr double kDeg = 180.0 / kPi;

hd::StampedPose at(double t, double x, double y, double yaw = 0.0) {
  hd::StampedPose p;
  p.t_s = t;
  p.pose = Pose2{x, y, yaw};
  return p;
}

/// A fresh, empty directory for one test, removed when the test ends.
class ScratchDir {
 public:
  ScratchDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = std::filesystem::temp_directory_path() /
            (std::string("harmoloc_report_test_") + info->test_suite_name() + "_" + info->name());
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

void write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

std::size_t count_of(const std::string& text, const std::string& needle) {
  std::size_t n = 0;
  for (auto pos = text.find(needle); pos != std::string::npos;
       pos = text.find(needle, pos + needle.size())) {
    ++n;
  }
  return n;
}

/// Number of "x,y" pairs in the points attribute of the polyline with class @p css_class.
std::size_t polyline_points(const std::string& svg, const std::string& css_class) {
  const auto start = svg.find("<polyline class=\"" + css_class + "\"");
  if (start == std::string::npos) return 0;
  const auto attr = svg.find(" points=\"", start);
  const auto end = svg.find('"', attr + 9);
  std::istringstream points(svg.substr(attr + 9, end - attr - 9));
  std::size_t n = 0;
  std::string pair;
  while (points >> pair) {
    const auto comma = pair.find(',');
    if (comma == std::string::npos) return 0;
    std::stod(pair.substr(0, comma));
    std::stod(pair.substr(comma + 1));
    ++n;
  }
  return n;
}

/// A small well-formedness check: every tag closes in order, attributes quoted, nothing after
/// the root. Returns an empty string when fine, else what is wrong.
std::string check_markup(const std::string& text, bool html) {
  std::vector<std::string> open;
  std::size_t i = 0;
  const std::vector<std::string> voids = {"meta", "img", "br", "hr", "link", "input"};
  while ((i = text.find('<', i)) != std::string::npos) {
    if (text.compare(i, 4, "<!--") == 0) {
      i = text.find("-->", i);
      if (i == std::string::npos) return "unterminated comment";
      continue;
    }
    const auto end = text.find('>', i);
    if (end == std::string::npos) return "unterminated tag";
    const std::string tag = text.substr(i + 1, end - i - 1);
    i = end + 1;
    if (tag.empty()) return "empty tag";
    if (tag[0] == '?' || tag[0] == '!') continue;
    if (count_of(tag, "\"") % 2 != 0) return "odd quotes in <" + tag + ">";
    if (tag[0] == '/') {
      const std::string name = tag.substr(1);
      if (open.empty() || open.back() != name) {
        return "</" + name + "> closes " + (open.empty() ? "nothing" : open.back());
      }
      open.pop_back();
      continue;
    }
    const std::string name = tag.substr(0, tag.find_first_of(" \t\n/"));
    if (tag.back() == '/') continue;
    if (html && std::find(voids.begin(), voids.end(), name) != voids.end()) continue;
    if (name == "style") {  // CSS may hold '>' characters
      i = text.find("</style>", i);
      if (i == std::string::npos) return "unterminated style";
      i += 8;
      continue;
    }
    open.push_back(name);
  }
  if (!open.empty()) return "<" + open.back() + "> never closed";
  return "";
}

const char* const kStatsJson = R"({
  "harmoloc_version": "0.1.0", "board": "host", "cycles": 1000, "frames": 998,
  "budget_us": 15000, "overruns": 2, "rate_hz": 30,
  "stages": {
    "cycle":    {"median_us": 800, "p99_us": 1200, "p999_us": 1500, "max_us": 16000, "mean_us": 820},
    "segment":  {"median_us": 400, "p99_us": 700, "p999_us": 800, "max_us": 900, "mean_us": 410},
    "kidnap":   {"median_us": 1, "p99_us": 2},
    "acquire":  {"median_us": 1.2, "p99_us": 3.4, "p999_us": 4.0, "max_us": 5.1, "mean_us": 1.3}
  },
  "cycle_histogram": {"upper_us": [250, 500, 750, 1000, 1250, 1500, 20000],
                      "counts":   [0, 0, 300, 600, 90, 8, 1, 1]},
  "degraded": {"odometry_only": 3, "vision_only": 0, "invalid": 1},
  "camera": {"frames": 998, "errors": {"truncated": 2}},
  "localizer": {"fixes": 990, "unknown_place": 10}
})";

/// A circle of radius 1 m around (2, 1) in 20 s at 10 Hz, an estimate off by a constant
/// 3 cm in x, and fixes off by 4 cm in y.
struct Circle {
  std::vector<hd::StampedPose> truth, estimate, fixes;
  Circle() {
    for (int i = 0; i <= 200; ++i) {
      const double t = 0.1 * i;
      const double a = 2.0 * kPi * t / 20.0;
      truth.push_back(at(t, 2.0 + std::cos(a), 1.0 + std::sin(a), a + kPi / 2.0));
      if (i % 2 == 0) {
        estimate.push_back(at(t, 2.03 + std::cos(a), 1.0 + std::sin(a), a + kPi / 2.0 + 0.01));
      }
      if (i % 4 == 1) fixes.push_back(at(t, 2.0 + std::cos(a), 1.04 + std::sin(a)));
    }
  }
};

}  // namespace

// ---------------------------------------------------------------------------------------------
// Evaluation
// ---------------------------------------------------------------------------------------------

TEST(ReportEvaluate, HandComputedErrors) {
  // Truth along x at 1 m/s; estimates at t = 1, 4, 6 inside, t = -1 and 12 outside.
  const std::vector<hd::StampedPose> truth = {at(0, 0, 0), at(10, 10, 0)};
  const std::vector<hd::StampedPose> estimate = {at(-1, -1, 0), at(1, 1.03, 0.04, 0.1),
                                                 at(4, 4.0, 0.0, 0.0), at(6, 5.94, -0.08, -0.2),
                                                 at(12, 12, 0)};
  const hs::TrajectoryErrors e = hs::evaluate(truth, estimate);
  ASSERT_EQ(e.count, 3u);
  EXPECT_EQ(e.outside_truth, 2u);
  EXPECT_EQ(e.skipped, 0u);
  // dx = 0.03, 0, -0.06; dy = 0.04, 0, -0.08; |d| = 0.05, 0, 0.10.
  EXPECT_NEAR(e.mse_x_cm2, (9.0 + 0.0 + 36.0) / 3.0, 1e-9);
  EXPECT_NEAR(e.mse_y_cm2, (16.0 + 0.0 + 64.0) / 3.0, 1e-9);
  EXPECT_NEAR(e.rmse_x_m, std::sqrt(0.0045 / 3.0), 1e-12);
  EXPECT_NEAR(e.rmse_y_m, std::sqrt(0.0080 / 3.0), 1e-12);
  EXPECT_NEAR(e.rmse_position_m, std::sqrt((0.0025 + 0.0 + 0.01) / 3.0), 1e-12);
  EXPECT_NEAR(e.mean_position_m, 0.05, 1e-12);
  EXPECT_NEAR(e.max_position_m, 0.10, 1e-12);
  EXPECT_NEAR(e.p95_position_m, 0.05 + 0.9 * 0.05, 1e-12);  // rank 1.9 of {0, .05, .10}
  EXPECT_NEAR(e.rmse_heading_deg, std::sqrt((0.01 + 0.0 + 0.04) / 3.0) * kDeg, 1e-9);
  EXPECT_NEAR(e.max_heading_deg, 0.2 * kDeg, 1e-9);
  ASSERT_EQ(e.samples.size(), 3u);
  EXPECT_DOUBLE_EQ(e.samples[0].t_s, 1.0);
  EXPECT_NEAR(e.samples[0].dx_m, 0.03, 1e-12);
  EXPECT_NEAR(e.samples[2].dy_m, -0.08, 1e-12);
  EXPECT_NEAR(e.samples[2].position_m, 0.10, 1e-12);
  EXPECT_NEAR(e.samples[2].heading_rad, -0.2, 1e-12);
}

TEST(ReportEvaluate, InterpolatesTruthBetweenPoses) {
  const std::vector<hd::StampedPose> truth = {at(0, 0, 0, 0.0), at(2, 2, 4, 0.4)};
  const hs::TrajectoryErrors e = hs::evaluate(truth, {at(1, 1, 2, 0.2), at(1.5, 1.5, 3.1, 0.3)});
  ASSERT_EQ(e.count, 2u);
  EXPECT_NEAR(e.samples[0].position_m, 0.0, 1e-12);
  EXPECT_NEAR(e.samples[0].heading_rad, 0.0, 1e-12);
  EXPECT_NEAR(e.samples[1].dy_m, 0.1, 1e-12);
  EXPECT_NEAR(e.max_position_m, 0.1, 1e-12);
}

TEST(ReportEvaluate, HeadingErrorWrapsAroundPi) {
  const std::vector<hd::StampedPose> truth = {at(0, 0, 0, 3.1), at(1, 0, 0, 3.1)};
  const hs::TrajectoryErrors e = hs::evaluate(truth, {at(0.5, 0, 0, -3.1)});
  ASSERT_EQ(e.count, 1u);
  EXPECT_NEAR(e.samples[0].heading_rad, 2.0 * kPi - 6.2, 1e-12);
  EXPECT_NEAR(e.rmse_heading_deg, (2.0 * kPi - 6.2) * kDeg, 1e-9);
  // Truth interpolated across +-pi: 3.0 -> -3.0 passes through pi, not through 0.
  const std::vector<hd::StampedPose> across = {at(0, 0, 0, 3.0), at(2, 0, 0, -3.0)};
  const hs::TrajectoryErrors f = hs::evaluate(across, {at(1, 0, 0, kPi)});
  ASSERT_EQ(f.count, 1u);
  EXPECT_NEAR(std::fabs(f.samples[0].heading_rad), 0.0, 1e-9);
}

TEST(ReportEvaluate, SkipInitialIsAnchoredOnTheTruthStart) {
  std::vector<hd::StampedPose> truth, estimate;
  for (int i = 0; i <= 10; ++i) {
    truth.push_back(at(100 + i, i, 0));
    estimate.push_back(at(100 + i, i, i < 3 ? 1.0 : 0.01));  // 1 m off while converging
  }
  const hs::TrajectoryErrors all = hs::evaluate(truth, estimate);
  const hs::TrajectoryErrors late = hs::evaluate(truth, estimate, {3.0});
  EXPECT_EQ(all.count, 11u);
  EXPECT_EQ(late.count, 8u);
  EXPECT_EQ(late.skipped, 3u);
  EXPECT_DOUBLE_EQ(late.samples.front().t_s, 103.0);
  EXPECT_NEAR(late.rmse_position_m, 0.01, 1e-12);
  EXPECT_NEAR(late.max_position_m, 0.01, 1e-12);
  EXPECT_NEAR(all.max_position_m, 1.0, 1e-12);
  EXPECT_DOUBLE_EQ(late.skip_initial_s, 3.0);
}

TEST(ReportEvaluate, NoOverlapGivesZeroCount) {
  const hs::TrajectoryErrors e =
      hs::evaluate({at(0, 0, 0), at(1, 1, 0)}, {at(5, 0, 0), at(6, 0, 0)});
  EXPECT_EQ(e.count, 0u);
  EXPECT_EQ(e.outside_truth, 2u);
  EXPECT_EQ(e.rmse_position_m, 0.0);
  EXPECT_EQ(hs::evaluate({}, {at(0, 0, 0)}).count, 0u);
}

TEST(ReportEvaluate, Percentile) {
  std::vector<double> v;
  for (int i = 20; i >= 1; --i) v.push_back(i);        // unsorted on purpose
  EXPECT_NEAR(hs::percentile(v, 95.0), 19.05, 1e-12);  // rank 18.05
  EXPECT_DOUBLE_EQ(hs::percentile(v, 0.0), 1.0);
  EXPECT_DOUBLE_EQ(hs::percentile(v, 100.0), 20.0);
  EXPECT_DOUBLE_EQ(hs::percentile({1, 2, 3, 4}, 50.0), 2.5);
  EXPECT_DOUBLE_EQ(hs::percentile({7.0}, 95.0), 7.0);
  EXPECT_DOUBLE_EQ(hs::percentile({}, 95.0), 0.0);
}

// ---------------------------------------------------------------------------------------------
// Stats
// ---------------------------------------------------------------------------------------------

TEST(ReportStats, ParsesTheFirmwareSchema) {
  const hs::RunStats s = hs::parse_stats(kStatsJson);
  EXPECT_EQ(s.harmoloc_version, "0.1.0");
  EXPECT_EQ(s.board, "host");
  EXPECT_EQ(s.cycles, 1000u);
  EXPECT_EQ(s.frames, 998u);
  EXPECT_EQ(s.overruns, 2u);
  EXPECT_DOUBLE_EQ(s.budget_us, 15000.0);
  ASSERT_TRUE(s.rate_hz);
  EXPECT_DOUBLE_EQ(*s.rate_hz, 30.0);
  // Display order: known stages first, unknown ones next, the cycle last.
  ASSERT_EQ(s.stages.size(), 4u);
  EXPECT_EQ(s.stages[0].name, "acquire");
  EXPECT_EQ(s.stages[1].name, "segment");
  EXPECT_EQ(s.stages[2].name, "kidnap");
  EXPECT_EQ(s.stages[3].name, "cycle");
  EXPECT_DOUBLE_EQ(s.stages[0].p99_us, 3.4);
  EXPECT_TRUE(std::isnan(s.stages[2].max_us));  // missing numbers are NaN
  ASSERT_NE(s.stage("cycle"), nullptr);
  EXPECT_DOUBLE_EQ(s.stage("cycle")->max_us, 16000.0);
  EXPECT_EQ(s.stage("publish"), nullptr);
  ASSERT_TRUE(s.cycle_histogram);
  EXPECT_EQ(s.cycle_histogram->upper_us.size(), 7u);
  EXPECT_EQ(s.cycle_histogram->total(), 1000u);
  EXPECT_EQ(s.cycle_histogram->overflow(), 1u);
  ASSERT_EQ(s.degraded.size(), 3u);
  EXPECT_EQ(s.degraded[0].first, "odometry_only");
  EXPECT_EQ(s.degraded[0].second, 3u);
  EXPECT_EQ(s.localizer_fixes, 990u);
  EXPECT_EQ(s.localizer_unknown_place, 10u);
  bool camera = false;
  for (const hs::StatsSection& section : s.sections) {
    if (section.name != "camera") continue;
    camera = true;
    ASSERT_EQ(section.entries.size(), 2u);
    EXPECT_EQ(section.entries[1].first, "errors.truncated");
    EXPECT_EQ(section.entries[1].second, "2");
  }
  EXPECT_TRUE(camera);
}

TEST(ReportStats, OptionalSectionsMayBeMissing) {
  const hs::RunStats s = hs::parse_stats(R"({"stages": {"cycle": {"median_us": 5}}})");
  EXPECT_FALSE(s.cycles);
  EXPECT_FALSE(s.overruns);
  EXPECT_FALSE(s.cycle_histogram);
  EXPECT_TRUE(s.degraded.empty());
  EXPECT_DOUBLE_EQ(s.budget_us, 15000.0);
  ASSERT_EQ(s.stages.size(), 1u);
  EXPECT_DOUBLE_EQ(s.stages[0].median_us, 5.0);
  EXPECT_TRUE(std::isnan(s.stages[0].p99_us));
}

TEST(ReportStats, RejectsBadFiles) {
  const auto message = [](const std::string& text) {
    try {
      hs::parse_stats(text, "S.json");
    } catch (const hs::ReportError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message("not json").rfind("S.json: not valid JSON", 0), 0u) << message("not json");
  EXPECT_EQ(message("").rfind("S.json: not valid JSON", 0), 0u);
  EXPECT_EQ(message("[1, 2]"), "S.json: not a JSON object");
  EXPECT_NE(message(R"({"cycles": 3})").find("no \"stages\""), std::string::npos);
  EXPECT_NE(message(R"({"stages": 3})").find("not an object"), std::string::npos);
  EXPECT_NE(message(R"({"stages": {"cycle": {"median_us": "fast"}}})")
                .find("stages.cycle.median_us is not a number"),
            std::string::npos);
  EXPECT_NE(message(R"({"stages": {}, "cycles": -4})").find("cycles is negative"),
            std::string::npos);
  EXPECT_NE(message(R"({"stages": {}, "cycle_histogram": {"upper_us": [1, 2], "counts": [1]}})")
                .find("1 counts for 2 buckets"),
            std::string::npos);
  EXPECT_NE(message(R"({"stages": {}, "cycle_histogram": {"upper_us": [2, 1], "counts": [1, 1]}})")
                .find("increasing"),
            std::string::npos);
  EXPECT_NE(message(R"({"stages": {}, "budget_us": 0})").find("budget_us"), std::string::npos);
  for (const std::string& m : {message("{"), message("not json")}) {
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
  }
}

TEST(ReportStats, ReadStatsNamesAMissingFile) {
  try {
    hs::read_stats("/nonexistent/stats.json");
    FAIL() << "no error";
  } catch (const hs::ReportError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("/nonexistent/stats.json: cannot open", 0), 0U)
        << e.what();
  }
}

// ---------------------------------------------------------------------------------------------
// Report building
// ---------------------------------------------------------------------------------------------

TEST(ReportBuild, ScoresEstimateAndFixes) {
  const Circle c;
  hs::ReportInputs in;
  in.fixes_path = "fixes.tum";
  in.skip_initial_s = 5.0;
  const hs::Report r = hs::build_report(in, c.truth, c.estimate, c.fixes, std::nullopt);
  EXPECT_EQ(r.estimate_all.count, 101u);
  EXPECT_NEAR(r.estimate_all.rmse_x_m, 0.03, 1e-9);
  EXPECT_NEAR(r.estimate_all.rmse_y_m, 0.0, 1e-9);
  EXPECT_NEAR(r.estimate_all.mse_x_cm2, 9.0, 1e-6);
  EXPECT_NEAR(r.estimate_all.rmse_heading_deg, 0.01 * kDeg, 1e-6);
  ASSERT_TRUE(r.estimate_converged);
  EXPECT_EQ(r.estimate_converged->count, 76u);  // t = 5.0 .. 20.0 every 0.2 s
  ASSERT_TRUE(r.fixes_all);
  EXPECT_EQ(r.fixes_all->count, c.fixes.size());
  EXPECT_NEAR(r.fixes_all->rmse_y_m, 0.04, 1e-9);
  EXPECT_NEAR(r.fixes_all->mse_y_cm2, 16.0, 1e-6);
  ASSERT_TRUE(r.fixes_converged);

  const std::string text = hs::summary_text(r, "out/index.html");
  EXPECT_NE(text.find("position RMSE  x 3.00 cm  y 0.00 cm  xy 3.00 cm"), std::string::npos)
      << text;
  EXPECT_NE(text.find("over 101 poses"), std::string::npos);
  EXPECT_NE(text.find("after 5 s"), std::string::npos);
  EXPECT_NE(text.find("harmonic fixes RMSE 4.00 cm"), std::string::npos) << text;
  EXPECT_NE(text.find("report         out/index.html\n"), std::string::npos);
  EXPECT_EQ(text.find("cycle time"), std::string::npos);  // no stats given
}

TEST(ReportBuild, RejectsUnusableInput) {
  const Circle c;
  hs::ReportInputs in;
  in.truth_path = "GT.tum";
  in.estimate_path = "EST.tum";
  const auto message = [&](std::vector<hd::StampedPose> truth,
                           std::vector<hd::StampedPose> estimate, double skip = 0.0) {
    hs::ReportInputs copy = in;
    copy.skip_initial_s = skip;
    try {
      hs::build_report(copy, std::move(truth), std::move(estimate), {}, std::nullopt);
    } catch (const hs::ReportError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  std::vector<hd::StampedPose> late = {at(100, 0, 0), at(101, 0, 0)};
  EXPECT_EQ(message(c.truth, late).rfind("EST.tum: no pose lies within the ground truth", 0), 0u)
      << message(c.truth, late);
  EXPECT_EQ(message({at(0, 0, 0)}, c.estimate).rfind("GT.tum: ground truth needs", 0), 0u);
  EXPECT_EQ(message(c.truth, {}), "EST.tum: no poses");
  EXPECT_NE(message(c.truth, c.estimate, 50.0).find("leaves no pose"), std::string::npos);
  EXPECT_NE(message(c.truth, c.estimate, -1.0).find("non-negative"), std::string::npos);
}

TEST(ReportBuild, LoadReportNamesTheBadFile) {
  const ScratchDir scratch;
  const auto& dir = scratch.path();
  hd::write_tum((dir / "gt.tum").string(), Circle().truth);
  write_text(dir / "bad.tum", "0 1 2 3\n");
  hs::ReportInputs in;
  in.truth_path = (dir / "gt.tum").string();
  in.estimate_path = (dir / "missing.tum").string();
  EXPECT_THROW(
      {
        try {
          hs::load_report(in);
        } catch (const std::runtime_error& e) {
          EXPECT_NE(std::string(e.what()).find("missing.tum: cannot open"), std::string::npos);
          throw;
        }
      },
      std::runtime_error);
  in.estimate_path = (dir / "bad.tum").string();
  EXPECT_THROW(hs::load_report(in), std::runtime_error);
  in.estimate_path = (dir / "gt.tum").string();
  in.stats_path = (dir / "bad.tum").string();
  EXPECT_THROW(hs::load_report(in), hs::ReportError);
}

// ---------------------------------------------------------------------------------------------
// Plots and the page
// ---------------------------------------------------------------------------------------------

TEST(ReportWrite, WritesWellFormedFiles) {
  const ScratchDir scratch;
  const auto dir = scratch.path() / "nested" / "report";
  const Circle c;
  hs::ReportInputs in;
  in.title = "circle <test> & more";
  in.truth_path = "GT.tum";
  in.estimate_path = "EST.tum";
  in.fixes_path = "FIXES.tum";
  in.stats_path = "STATS.json";
  in.skip_initial_s = 2.0;
  const hs::Report r =
      hs::build_report(in, c.truth, c.estimate, c.fixes, hs::parse_stats(kStatsJson));
  const std::vector<std::string> written = hs::write_report(r, dir);
  for (const char* name : {"trajectory.svg", "error.svg", "timing.svg", "stages.svg", "index.html",
                           "summary.json", "summary.txt"}) {
    EXPECT_TRUE(std::filesystem::is_regular_file(dir / name)) << name;
    EXPECT_NE(std::find(written.begin(), written.end(), name), written.end()) << name;
  }
  for (const char* name : {"trajectory.svg", "error.svg", "timing.svg", "stages.svg"}) {
    const std::string svg = read_text(dir / name);
    EXPECT_EQ(svg.rfind("<?xml", 0), 0u) << name;
    EXPECT_EQ(count_of(svg, "<svg "), 1u) << name;
    EXPECT_EQ(count_of(svg, "</svg>"), 1u) << name;
    EXPECT_EQ(check_markup(svg, false), "") << name;
    EXPECT_EQ(svg.find("nan"), std::string::npos) << name;
    EXPECT_EQ(svg.find("inf"), std::string::npos) << name;
  }

  const std::string trajectory = read_text(dir / "trajectory.svg");
  EXPECT_EQ(polyline_points(trajectory, "truth"), c.truth.size());
  EXPECT_EQ(polyline_points(trajectory, "estimate"), c.estimate.size());
  const auto fixes_group = trajectory.find("<g class=\"fixes\"");
  ASSERT_NE(fixes_group, std::string::npos);
  const std::string fixes_svg =
      trajectory.substr(fixes_group, trajectory.find("</g>", fixes_group) - fixes_group);
  EXPECT_EQ(count_of(fixes_svg, "<circle"), c.fixes.size());
  EXPECT_NE(trajectory.find("x (m)"), std::string::npos);
  EXPECT_NE(trajectory.find("y (m)"), std::string::npos);
  EXPECT_NE(trajectory.find("ground truth"), std::string::npos);

  const std::string error = read_text(dir / "error.svg");
  EXPECT_EQ(polyline_points(error, "position-error"), r.estimate_all.count);
  EXPECT_EQ(polyline_points(error, "heading-error"), r.estimate_all.count);
  EXPECT_NE(error.find("excluded (convergence)"), std::string::npos);

  const std::string timing = read_text(dir / "timing.svg");
  const auto bars = timing.find("<g class=\"bars\">");
  ASSERT_NE(bars, std::string::npos);
  // Occupied buckets 750, 1000, 1250, 1500 and the 20000 one; overflow is only in the caption.
  EXPECT_EQ(count_of(timing.substr(bars, timing.find("</g>", bars) - bars), "<rect"), 5u);
  EXPECT_NE(timing.find("median 800 µs"), std::string::npos);
  EXPECT_NE(timing.find("p99 1.20 ms"), std::string::npos);
  EXPECT_NE(timing.find("budget 15 ms"), std::string::npos);
  EXPECT_NE(timing.find("1 cycle above"), std::string::npos);

  const std::string stages = read_text(dir / "stages.svg");
  for (const char* stage : {">acquire<", ">segment<", ">kidnap<", ">cycle<"}) {
    EXPECT_NE(stages.find(stage), std::string::npos) << stage;
  }

  const std::string html = read_text(dir / "index.html");
  EXPECT_EQ(check_markup(html, true), "");
  EXPECT_NE(html.find("<title>harmoloc run report</title>"), std::string::npos);
  EXPECT_NE(html.find("circle &lt;test&gt; &amp; more"), std::string::npos);
  for (const char* image : {"trajectory.svg", "error.svg", "timing.svg", "stages.svg"}) {
    EXPECT_NE(html.find(std::string("<img src=\"") + image + "\""), std::string::npos) << image;
  }
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_EQ(html.find("http"), std::string::npos);  // self-contained: no external resources
  EXPECT_NE(html.find("MSE x (cm²)"), std::string::npos);
  EXPECT_NE(html.find("odometry_only"), std::string::npos);
  EXPECT_NE(html.find("class=\"over\">16000.0"), std::string::npos);  // cycle max over budget

  const nlohmann::json summary = nlohmann::json::parse(read_text(dir / "summary.json"));
  EXPECT_NEAR(summary["estimate"]["all"]["rmse_x_cm"].get<double>(), 3.0, 1e-6);
  EXPECT_NEAR(summary["estimate"]["all"]["mse_x_cm2"].get<double>(), 9.0, 1e-6);
  EXPECT_EQ(summary["estimate"]["all"]["count"].get<int>(), 101);
  EXPECT_TRUE(summary["estimate"].contains("after_convergence"));
  EXPECT_NEAR(summary["fixes"]["all"]["rmse_y_cm"].get<double>(), 4.0, 1e-6);
  EXPECT_FALSE(summary["fixes"]["all"].contains("rmse_heading_deg"));
  EXPECT_EQ(summary["timing"]["overruns"].get<int>(), 2);
  EXPECT_TRUE(summary["timing"]["stages"]["kidnap"]["max_us"].is_null());
  EXPECT_NEAR(summary["timing"]["cycle_p99_budget_percent"].get<double>(), 8.0, 1e-9);

  const std::string text = read_text(dir / "summary.txt");
  EXPECT_EQ(text, hs::summary_text(r, (dir / "index.html").string()));
  EXPECT_NE(text.find("cycle time     median 800 us  p99 1.20 ms  max 16.0 ms  (budget 15 ms, "
                      "8.0% used at p99), overruns 2"),
            std::string::npos)
      << text;
}

TEST(ReportWrite, WithoutStatsOrFixes) {
  const ScratchDir scratch;
  const auto& dir = scratch.path();
  write_text(dir / "timing.svg", "stale");
  const Circle c;
  const hs::Report r = hs::build_report({}, c.truth, c.estimate, {}, std::nullopt);
  const std::vector<std::string> written = hs::write_report(r, dir);
  // trajectory, error, error_xy (x/y components), index.html, summary.json, summary.txt
  EXPECT_EQ(written.size(), 6u);
  EXPECT_FALSE(std::filesystem::exists(dir / "timing.svg"));
  EXPECT_FALSE(std::filesystem::exists(dir / "stages.svg"));
  const std::string html = read_text(dir / "index.html");
  EXPECT_EQ(check_markup(html, true), "");
  EXPECT_EQ(html.find("timing.svg"), std::string::npos);
  EXPECT_EQ(read_text(dir / "trajectory.svg").find("<g class=\"fixes\""), std::string::npos);
}

TEST(ReportWrite, FarOutliersAreClippedNotZoomedOut) {
  Circle c;
  c.fixes.push_back(at(10.05, 500.0, -300.0));  // one wild fix
  hs::ReportInputs in;
  in.fixes_path = "f.tum";
  const hs::Report r = hs::build_report(in, c.truth, c.estimate, c.fixes, std::nullopt);
  const std::string svg = hs::trajectory_svg(r);
  EXPECT_NE(svg.find("1 point far off the route is outside the view"), std::string::npos);
  EXPECT_EQ(check_markup(svg, false), "");
  // The view stays near the 2 m circle: the widest axis label is a few metres, not hundreds.
  EXPECT_EQ(svg.find(">500<"), std::string::npos);
  EXPECT_EQ(svg.find(">-300<"), std::string::npos);
}

TEST(ReportWrite, TimingWithoutHistogramOrCycleStage) {
  const hs::RunStats s = hs::parse_stats(R"({"stages": {"segment": {"median_us": 10}}})");
  const std::string timing = hs::timing_svg(s);
  EXPECT_NE(timing.find("no cycle histogram"), std::string::npos);
  EXPECT_EQ(check_markup(timing, false), "");
  const std::string stages = hs::stages_svg(s);
  EXPECT_EQ(check_markup(stages, false), "");
  EXPECT_EQ(stages.find("nan"), std::string::npos);
}

TEST(ReportWrite, UnevenHistogramBuckets) {
  const hs::RunStats s = hs::parse_stats(R"({"stages": {"cycle": {"median_us": 700,
      "p99_us": 3000, "max_us": 4000}},
      "cycle_histogram": {"upper_us": [100, 200, 500, 1000, 2000, 5000, 10000, 20000],
                          "counts": [0, 5, 50, 400, 30, 10, 0, 0]}})");
  const std::string timing = hs::timing_svg(s);
  EXPECT_EQ(check_markup(timing, false), "");
  EXPECT_NE(timing.find("uneven buckets"), std::string::npos);
  const auto bars = timing.find("<g class=\"bars\">");
  EXPECT_EQ(count_of(timing.substr(bars, timing.find("</g>", bars) - bars), "<rect"), 5u);
}

// The firmware writes the stats through the same definition the tools read them with
// (firmware/stats_document.hpp): what goes out comes back, in the documented layout.
TEST(ReportStats, FirmwareDocumentRoundTrips) {
  namespace fs = harmoloc::firmware::stats;
  fs::Document d;
  d.harmoloc_version = "0.1.0";
  d.board = "host";
  d.ended = "SIGTERM";
  d.outputs_failed = 1;
  d.rate_hz = 30.0;
  d.budget_us = 15000.0;
  d.cycles = 898;
  d.frames = 897;
  d.overruns = 0;
  d.pacing = fs::Pacing{"timer", 2, 1};
  d.stages = {{"acquire", {45.123, 67.6, 290.5, 290.5, 45.4}},
              {"cycle", {1000.001, 1200.0, 1500.0, 1600.0, 1010.5}}};
  d.cycle_histogram = fs::CycleHistogram{{1000.448, 1016.32}, {400, 498}};
  d.health_cycles = fs::HealthCycles{1, 890, 4, 2, 1};
  d.degraded = fs::Degraded{4, 2, 1};
  d.localizer = fs::Localizer{880, 10, 0, 1};
  d.wakeup_latency = fs::LatencySummary{462, 9.0, 28.1, 27.4, 57.3, 65.4, 65.4};
  const std::string text = fs::dump(d);
  EXPECT_NE(text.find("\n  \"pacing\": {\"mode\": \"timer\", \"skipped_ticks\": 2, "
                      "\"overrun_alarms\": 1},\n"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("\n    \"acquire\": {\"median_us\": 45.123, "), std::string::npos) << text;
  const hs::RunStats s = hs::parse_stats(text);
  const fs::Document& back = s.document;
  EXPECT_EQ(back.ended, "SIGTERM");
  EXPECT_EQ(back.outputs_failed, 1u);
  EXPECT_EQ(s.cycles, 898u);
  EXPECT_EQ(back.pacing->mode, "timer");
  EXPECT_EQ(back.pacing->skipped_ticks, 2u);
  ASSERT_EQ(back.stages.size(), 2u);
  EXPECT_EQ(back.stages[1].first, "cycle");
  EXPECT_EQ(back.stages[1].second.median_us, 1000.001);  // shortest round-trip digits: exact
  EXPECT_EQ(back.cycle_histogram->upper_us, d.cycle_histogram->upper_us);
  EXPECT_EQ(back.health_cycles->not_initialized, 1u);
  EXPECT_EQ(back.localizer->fixes, 880u);
  EXPECT_EQ(back.wakeup_latency->count, 462u);
  EXPECT_EQ(back.wakeup_latency->p999_us, 65.4);
  EXPECT_FALSE(back.capture_to_send);
  EXPECT_EQ(fs::dump(back).find("\"camera\""), fs::dump(d).find("\"camera\""));
}

TEST(ReportSvg, InlineSvgDropsTheXmlDeclarationOnly) {
  hs::svg::Canvas c(100.0, 50.0);
  c.text(10.0, 20.0, "a <b> & \"c\"");
  const std::string document = c.finish();
  ASSERT_EQ(document.rfind("<?xml", 0), 0U);
  const std::string inlined = hs::svg::inline_svg(document);
  EXPECT_EQ(inlined.rfind("<svg ", 0), 0U) << inlined;
  EXPECT_EQ(document.substr(document.size() - inlined.size()), inlined);
  EXPECT_NE(inlined.find("a &lt;b&gt; &amp; &quot;c&quot;"), std::string::npos) << inlined;
  EXPECT_EQ(hs::svg::inline_svg("<svg/>"), "<svg/>");
}
