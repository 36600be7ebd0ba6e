// The report's views added for bring-up: the link recording read back (health timeline, spread),
// the x/y error plot, the 2-sigma plot, the health plot, the histogram's true bucket widths and
// budget line, and the relative error in the summaries.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "harmoloc/firmware/latency_histogram.hpp"
#include "harmoloc/firmware/mavlink_v2.hpp"
#include "harmoloc/firmware/pose_messages.hpp"
#include "harmoloc/sim_host/link_log.hpp"
#include "harmoloc/sim_host/report.hpp"
#include "histogram_edges.hpp"

namespace hs = harmoloc::sim_host;
namespace hd = harmoloc::dataset;
namespace fw = harmoloc::firmware;
namespace mv = harmoloc::firmware::mavlink;
using fw::Health;
using harmoloc::algorithms::Pose2;

namespace {

/// Writes a link as the firmware does: STATUSTEXT on a change, then that cycle's ODOMETRY.
class LinkWriter {
 public:
  void heartbeat(std::uint8_t status) {
    mv::Heartbeat hb;
    hb.system_status = status;
    append(encoder_.heartbeat(hb, buffer_));
  }
  void health(Health h) {
    append(encoder_.statustext(mv::kSeverityInfo, fw::health_text(h, fw::HealthCause::kInputs).text,
                               buffer_));
  }
  void pose(double t_s, Pose2 pose, double sigma_m, Health h) {
    fw::PoseOutput out;
    out.data_time_ns = static_cast<std::uint64_t>(std::llround(t_s * 1e9));
    out.pose = pose;
    out.covariance(0, 0) = sigma_m * sigma_m;
    out.covariance(1, 1) = sigma_m * sigma_m;
    out.covariance(2, 2) = 0.01;
    out.health = h;
    out.valid = true;
    append(encoder_.odometry(fw::odometry_message(out, out.data_time_ns, 0), buffer_));
  }
  void garbage(std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) bytes.push_back(static_cast<std::uint8_t>(0xFD ^ i));
  }
  std::vector<std::uint8_t> bytes;

 private:
  void append(std::size_t n) { bytes.insert(bytes.end(), buffer_.begin(), buffer_.begin() + n); }
  mv::Encoder encoder_{1, 197};
  mv::FrameBuffer buffer_{};
};

/// 0..1.5 s at 10 Hz: nominal; odometry only from 0.5 s; invalid (no pose) after 0.9 s; nominal
/// again at 1.0 s. Spread 2 cm, 10 cm while odometry only.
LinkWriter sample_link() {
  LinkWriter w;
  w.heartbeat(mv::kMavStateStandby);
  w.garbage(7);
  for (int k = 0; k <= 15; ++k) {
    const double t = 0.1 * k;
    if (k == 0) w.health(Health::kNominal);
    if (k == 5) w.health(Health::kOdometryOnly);
    if (k == 10) {
      w.health(Health::kInvalid);  // the cycle at 0.95 s: no pose published
      w.health(Health::kNominal);
    }
    const Health h = k >= 5 && k < 10 ? Health::kOdometryOnly : Health::kNominal;
    w.pose(t, Pose2{0.1 * k + 0.01, 0.02, 0.0}, h == Health::kNominal ? 0.02 : 0.10, h);
    if (k % 5 == 0) w.heartbeat(mv::kMavStateActive);
  }
  w.bytes.push_back(0xFD);  // a frame cut short at the end of the file
  w.bytes.push_back(40);
  return w;
}

std::size_t count_of(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto i = text.find(what); i != std::string::npos; i = text.find(what, i + 1)) ++n;
  return n;
}

std::size_t polyline_points(const std::string& svg, const std::string& css_class) {
  const auto at = svg.find("class=\"" + css_class + "\"");
  if (at == std::string::npos) return 0;
  const auto points = svg.find("points=\"", at) + 8;
  const auto end = svg.find('"', points);
  std::size_t n = 0;
  for (auto i = points; i < end; ++i) n += svg[i] == ',';
  return n;
}

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

/// Truth along x at 1 m/s for 1.5 s (10 Hz), an estimate 1 cm off in x and 2 cm off in y.
struct Line {
  std::vector<hd::StampedPose> truth, estimate;
  Line() {
    for (int k = 0; k <= 15; ++k) {
      truth.push_back({0.1 * k, Pose2{0.1 * k, 0.0, 0.0}});
      estimate.push_back({0.1 * k, Pose2{0.1 * k + 0.01, 0.02, 0.0}});
    }
  }
};

}  // namespace

TEST(LinkLog, HealthSpansFollowTheTexts) {
  const hs::LinkLog log = hs::parse_link_log(sample_link().bytes);
  ASSERT_EQ(log.poses.size(), 16u);
  EXPECT_EQ(log.health_texts, 4u);
  EXPECT_NEAR(log.poses[0].sigma_m, 0.02, 1e-6);
  EXPECT_NEAR(log.poses[7].sigma_m, 0.10, 1e-6);
  EXPECT_NEAR(log.poses[3].pose.x_m, 0.31, 1e-6);  // the map frame, as the TUM files
  EXPECT_NEAR(log.poses[3].pose.y_m, 0.02, 1e-6);
  EXPECT_EQ(log.poses[0].quality, 80);
  EXPECT_EQ(log.poses[6].health, Health::kOdometryOnly);
  // nominal 0..0.5, odometry only 0.5..0.9, invalid in the gap 0.9..1.0, nominal 1.0..1.5
  ASSERT_EQ(log.health.size(), 4u);
  const Health expected[] = {Health::kNominal, Health::kOdometryOnly, Health::kInvalid,
                             Health::kNominal};
  const double starts[] = {0.0, 0.5, 0.9, 1.0};
  const double ends[] = {0.5, 0.9, 1.0, 1.5};
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(log.health[i].health, expected[i]) << i;
    EXPECT_NEAR(log.health[i].start_s, starts[i], 1e-9) << i;
    EXPECT_NEAR(log.health[i].end_s, ends[i], 1e-9) << i;
  }
}

TEST(LinkLog, HeartbeatGivesTheStartAndBadFilesSayWhy) {
  LinkWriter w;
  w.heartbeat(mv::kMavStateActive);
  w.pose(0.0, Pose2{}, 0.01, Health::kNominal);
  w.pose(0.1, Pose2{}, 0.01, Health::kNominal);
  const hs::LinkLog log = hs::parse_link_log(w.bytes);
  ASSERT_EQ(log.health.size(), 1u);
  EXPECT_EQ(log.health[0].health, Health::kNominal);
  EXPECT_EQ(hs::parse_link_log({}).poses.size(), 0u);

  const auto path = std::filesystem::temp_directory_path() / "harmoloc_report_views_empty.link";
  std::ofstream(path) << "not mavlink";
  try {
    hs::read_link_log(path.string());
    FAIL() << "no error";
  } catch (const hs::ReportError& e) {
    EXPECT_NE(std::string(e.what()).find("no ODOMETRY"), std::string::npos) << e.what();
  }
  std::filesystem::remove(path);
}

TEST(ReportViews, WritesTheLinkViewsAndRelativeError) {
  const auto dir = std::filesystem::temp_directory_path() / "harmoloc_report_views_write";
  std::filesystem::remove_all(dir);
  const Line line;
  hs::Report r = hs::build_report({}, line.truth, line.estimate, {}, std::nullopt);
  r.link = hs::parse_link_log(sample_link().bytes);
  const std::vector<std::string> written = hs::write_report(r, dir);
  for (const char* f : {"error_xy.svg", "sigma.svg", "health.svg"}) {
    EXPECT_NE(std::find(written.begin(), written.end(), f), written.end()) << f;
  }
  const std::string xy = read_text(dir / "error_xy.svg");
  EXPECT_EQ(polyline_points(xy, "x-error"), line.estimate.size());
  EXPECT_EQ(polyline_points(xy, "y-error"), line.estimate.size());
  EXPECT_NE(xy.find("x error, RMSE 1.00 cm"), std::string::npos);
  EXPECT_NE(xy.find("y error, RMSE 2.00 cm"), std::string::npos);

  // Errors 1 cm and 2 cm; 2 sigma is 4 cm (20 cm while odometry only): all inside.
  const std::string sigma = read_text(dir / "sigma.svg");
  EXPECT_NE(sigma.find("x error: 100.0% of poses within ±2 sigma"), std::string::npos);
  EXPECT_EQ(count_of(sigma, "class=\"band\""), 2u);
  const hs::SigmaConsistency c = hs::sigma_consistency(r);
  EXPECT_EQ(c.poses, 16u);
  EXPECT_EQ(c.inside_y, 16u);

  const std::string health = read_text(dir / "health.svg");
  EXPECT_EQ(count_of(health, "data-health="), 4u);
  EXPECT_EQ(count_of(health, "data-health=\"invalid\""), 1u);
  EXPECT_EQ(polyline_points(health, "quality"), 16u);

  const std::string html = read_text(dir / "index.html");
  EXPECT_NE(html.find("Relative error (drift)"), std::string::npos);
  EXPECT_NE(html.find("RPE over 1 m: RMSE (cm)"), std::string::npos);
  EXPECT_NE(html.find("Health and spread (from the link)"), std::string::npos);
  for (const char* image : {"error_xy.svg", "sigma.svg", "health.svg"}) {
    EXPECT_NE(html.find(std::string("<img src=\"") + image + "\""), std::string::npos) << image;
  }

  // A constant offset: relative error 0 over 1 s (pairs (0,10)) and 1 m (pairs from 1 m on).
  const nlohmann::json j = nlohmann::json::parse(read_text(dir / "summary.json"));
  EXPECT_EQ(j["estimate"]["all"]["rpe_1s"]["pairs"].get<int>(), 1);
  EXPECT_NEAR(j["estimate"]["all"]["rpe_1s"]["rmse_cm"].get<double>(), 0.0, 1e-9);
  EXPECT_EQ(j["estimate"]["all"]["rpe_1m"]["pairs"].get<int>(), 0);
  EXPECT_TRUE(j["estimate"]["all"]["rpe_1m"]["rmse_cm"].is_null());
  EXPECT_NEAR(j["link"]["within_2sigma_x_percent"].get<double>(), 100.0, 1e-9);
  EXPECT_EQ(j["link"]["health_changes"].get<int>(), 3);
  const std::string text = read_text(dir / "summary.txt");
  EXPECT_NE(text.find("RPE 1 s        RMSE 0.00 cm"), std::string::npos) << text;
  EXPECT_NE(text.find("RPE 1 m        n/a"), std::string::npos) << text;
  EXPECT_NE(text.find("health (link)  nominal"), std::string::npos) << text;

  // Without the link, its plots go (a stale one from an earlier run too).
  r.link.reset();
  hs::write_report(r, dir);
  EXPECT_FALSE(std::filesystem::exists(dir / "sigma.svg"));
  EXPECT_FALSE(std::filesystem::exists(dir / "health.svg"));
  std::filesystem::remove_all(dir);
}

// The firmware lists only non-empty buckets: a bucket's lower edge is its own, not the previous
// listed one, so an isolated slow cycle is a thin bar, not one milliseconds wide.
TEST(ReportViews, FirmwareHistogramBucketsHaveTheirOwnWidths) {
  using harmoloc::firmware::LatencyHistogram;
  hs::CycleHistogram h;
  for (const std::uint64_t ns : {900'000ULL, 1'000'000ULL, 12'000'000ULL}) {
    const std::size_t i = LatencyHistogram::bucket_of(ns);
    h.upper_us.push_back(static_cast<double>(LatencyHistogram::bucket_upper_ns(i)) / 1000.0);
    h.counts.push_back(10);
  }
  ASSERT_TRUE(hs::on_firmware_grid(h));
  const std::vector<double> lower = hs::bucket_lower_us(h);
  // 900 us and 1 ms lie in the octave [524288, 1048576) ns: 8192 ns buckets; 12 ms in
  // [8388608, 16777216): 131072 ns buckets.
  EXPECT_NEAR(h.upper_us[0] - lower[0], 8.192, 1e-9);
  EXPECT_NEAR(h.upper_us[1] - lower[1], 8.192, 1e-9);
  EXPECT_NEAR(h.upper_us[2] - lower[2], 131.072, 1e-9);
  // A hand-written histogram is read as documented, buckets end to end.
  hs::CycleHistogram plain;
  plain.upper_us = {100.0, 200.0, 500.0};
  plain.counts = {1, 1, 1};
  EXPECT_FALSE(hs::on_firmware_grid(plain));
  EXPECT_EQ(hs::bucket_lower_us(plain), (std::vector<double>{0.0, 100.0, 200.0}));
}

TEST(ReportViews, TimingDrawsTheBudget) {
  // Near the budget: one panel with the budget line on its axis.
  const hs::RunStats near = hs::parse_stats(R"({"budget_us": 15000,
      "stages": {"cycle": {"median_us": 9000, "p99_us": 12000, "max_us": 14000}},
      "cycle_histogram": {"upper_us": [8000, 10000, 12000, 14000], "counts": [5, 50, 10, 1]}})");
  const std::string a = hs::timing_svg(near);
  EXPECT_EQ(count_of(a, "class=\"budget\""), 1u);
  EXPECT_EQ(a.find("bars-budget"), std::string::npos);
  EXPECT_NE(a.find("drawn at their true widths"), std::string::npos);
  EXPECT_NE(a.find(">budget 15 ms<"), std::string::npos);
  // Far below it: a second panel shows the bars against the budget.
  const hs::RunStats far = hs::parse_stats(R"({"budget_us": 15000,
      "stages": {"cycle": {"median_us": 900, "p99_us": 1000, "max_us": 1000}},
      "cycle_histogram": {"upper_us": [800, 900, 1000], "counts": [5, 50, 10]}})");
  const std::string b = hs::timing_svg(far);
  EXPECT_EQ(count_of(b, "class=\"budget\""), 1u);
  EXPECT_NE(b.find("<g class=\"bars-budget\">"), std::string::npos);
  EXPECT_NE(b.find("the same cycles against the budget"), std::string::npos);
}

TEST(ReportViews, UnevenBucketsAreDensities) {
  // Buckets 0-100 (10 cycles) and 100-300 (10 cycles): the wide one is half as tall.
  const hs::RunStats s = hs::parse_stats(R"({"budget_us": 400,
      "stages": {"cycle": {"median_us": 100, "p99_us": 290, "max_us": 295}},
      "cycle_histogram": {"upper_us": [100, 300], "counts": [10, 10]}})");
  const std::string svg = hs::timing_svg(s);
  EXPECT_NE(svg.find("cycles per 100 µs"), std::string::npos);
  const auto bars = svg.find("<g class=\"bars\">");
  const std::string group = svg.substr(bars, svg.find("</g>", bars) - bars);
  std::vector<double> heights, widths;
  for (auto i = group.find("<rect"); i != std::string::npos; i = group.find("<rect", i + 1)) {
    const auto h = group.find("height=\"", i) + 8;
    const auto w = group.find("width=\"", i) + 7;
    heights.push_back(std::stod(group.substr(h)));
    widths.push_back(std::stod(group.substr(w)));
  }
  ASSERT_EQ(heights.size(), 2u);
  EXPECT_NEAR(heights[1] / heights[0], 0.5, 0.02);
  EXPECT_NEAR(widths[1] / widths[0], 2.0, 0.05);
}
