// harmoloc-colours' library: the firmware's hue steps and wrap-around windows, the clustering
// of the automatic mode on synthetic runs, the guided mode, the warnings, the TOML it writes, and
// the automatic mode on random simulated scenes against their true windows (docs/colours.md).
#include <cmath>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "harmoloc/dataset/frame_index.hpp"
#include "harmoloc/dataset/metadata.hpp"
#include "harmoloc/firmware/config.hpp"
#include "harmoloc/sim_host/colour_preview.hpp"
#include "harmoloc/sim_host/colour_windows.hpp"
#include "harmoloc/sim_host/random_scene.hpp"
#include "harmoloc/sim_host/scenario_run.hpp"
#include "harmoloc/sim_host/scene_renderer.hpp"

namespace {

namespace alg = harmoloc::algorithms;
namespace hs = harmoloc::sim_host;
namespace hc = harmoloc::sim_host::colours;

// A colour of the given 8-bit hue step, saturation and value (the textbook HSV to RGB; the
// firmware's conversion gives the step back within one, which the tests allow for).
std::array<std::uint8_t, 3> colour_of(int h8, int s, int v) {
  const double h = std::fmod(2.0 * h8, 360.0) / 60.0, c = v * s / 255.0;
  const double x = c * (1.0 - std::fabs(std::fmod(h, 2.0) - 1.0)), m = v - c;
  std::array<double, 3> rgb{};
  switch (static_cast<int>(h)) {
    case 0:
      rgb = {c, x, 0};
      break;
    case 1:
      rgb = {x, c, 0};
      break;
    case 2:
      rgb = {0, c, x};
      break;
    case 3:
      rgb = {0, x, c};
      break;
    case 4:
      rgb = {x, 0, c};
      break;
    default:
      rgb = {c, 0, x};
      break;
  }
  return {static_cast<std::uint8_t>(std::lround(rgb[0] + m)),
          static_cast<std::uint8_t>(std::lround(rgb[1] + m)),
          static_cast<std::uint8_t>(std::lround(rgb[2] + m))};
}

TEST(ColourWindows, TestColoursHaveTheirHue) {
  const alg::BoardClassifier cls;
  for (int h8 = 0; h8 < 180; ++h8) {
    const auto c = colour_of(h8, 220, 180);
    EXPECT_LE(hc::hue_distance_h8(cls.to_hsv(c[0], c[1], c[2]).h, h8), 1) << h8;
  }
}

TEST(ColourWindows, WindowsAreTheFirmwaresStepsIncludingWrapThroughZero) {
  for (const hc::HueRange r : {hc::HueRange{172, 5}, hc::HueRange{50, 72}, hc::HueRange{0, 7},
                               hc::HueRange{170, 179}, hc::HueRange{90, 90}}) {
    const alg::ColourThreshold t = hc::to_threshold(r, 100, 50);
    const hc::HueRange back = hc::hue_steps_of(t);
    EXPECT_EQ(back.lo_h8, r.lo_h8);
    EXPECT_EQ(back.hi_h8, r.hi_h8);
    EXPECT_EQ(t.hue_min_deg > t.hue_max_deg, r.lo_h8 > r.hi_h8);
    alg::ThresholdSet set;
    set.boards[0] = t;
    set.count = 1;
    const alg::BoardClassifier cls(set);
    // Every colour the firmware puts in the window is in the range, and the reverse.
    for (int rr = 0; rr < 256; rr += 5) {
      for (int g = 0; g < 256; g += 5) {
        for (int b = 0; b < 256; b += 5) {
          const auto R = static_cast<std::uint8_t>(rr), G = static_cast<std::uint8_t>(g),
                     B = static_cast<std::uint8_t>(b);
          const alg::Hsv8 p = cls.to_hsv(R, G, B);
          const bool inside = r.contains(p.h) && p.s >= 100 && p.v >= 50;
          ASSERT_EQ(cls.classify(R, G, B) != 0, inside) << int{p.h} << " " << int{p.s};
        }
      }
    }
  }
  EXPECT_EQ((hc::HueRange{172, 5}.width_h8()), 14);
  EXPECT_EQ(hc::hue_distance_h8(178, 2), 4);
  EXPECT_EQ(hc::hue_name(1), "red");
  EXPECT_EQ(hc::hue_name(178), "red");
  EXPECT_EQ(hc::hue_name(60), "green");
}

// A synthetic run: a grey, noisy room; a red board (hue through 0) that grows as the robot
// comes closer and a green one that slides across, turning away; a blue strip that never changes
// (part of the robot); scattered saturated specks of every hue (sensor noise).
hc::MemoryFrames synthetic_run(std::size_t frames, bool with_strip = true) {
  const auto red_a = colour_of(178, 220, 180), red_b = colour_of(2, 220, 180);
  const auto green = colour_of(60, 200, 170), blue = colour_of(115, 230, 160);
  hc::MemoryFrames run;
  std::uint32_t state = 12345;
  const auto rnd = [&state]() {
    state = state * 1664525U + 1013904223U;
    return state >> 8;
  };
  for (std::size_t k = 0; k < frames; ++k) {
    hc::RgbImage img;
    img.width_px = 160;
    img.height_px = 120;
    img.rgb.resize(160 * 120 * 3);
    for (std::size_t i = 0; i < 160 * 120; ++i) {
      const auto grey = static_cast<std::uint8_t>(120 + static_cast<int>(rnd() % 11) - 5);
      img.rgb[3 * i] = static_cast<std::uint8_t>(grey + 6);
      img.rgb[3 * i + 1] = grey;
      img.rgb[3 * i + 2] = static_cast<std::uint8_t>(grey - 4);
      if (rnd() % 2000 == 0) {  // a speck of any saturated colour
        const auto c = colour_of(static_cast<int>(rnd() % 180), 200, 200);
        std::copy(c.begin(), c.end(), img.rgb.begin() + static_cast<std::ptrdiff_t>(3 * i));
      }
    }
    const auto fill = [&](int x0, int y0, int w, int h, const auto& colour, const auto* alt) {
      for (int y = y0; y < y0 + h; ++y)
        for (int x = x0; x < x0 + w; ++x) {
          if (x < 0 || y < 0 || x >= 160 || y >= 120) continue;
          const auto& c = alt != nullptr && (x + y) % 2 == 0 ? *alt : colour;
          std::copy(c.begin(), c.end(),
                    img.rgb.begin() + static_cast<std::ptrdiff_t>(3 * (y * 160 + x)));
        }
    };
    const int grow = static_cast<int>(k * 30 / frames);
    fill(20, 20, 10 + grow, 8 + grow, red_a, &red_b);
    const auto no_alt = static_cast<const std::array<std::uint8_t, 3>*>(nullptr);
    fill(static_cast<int>(k * 150 / frames) - 10, 70, 20 - grow / 2, 16, green, no_alt);
    if (with_strip) fill(0, 112, 160, 8, blue, no_alt);
    run.add(1'000'000'000ULL + k * 33'333'333ULL, std::move(img));
  }
  return run;
}

TEST(ColourWindows, AutomaticFindsTheBoardsAndNotTheNoiseOrTheConstantStrip) {
  hc::MemoryFrames run = synthetic_run(40);
  hc::AutoOptions opt;
  opt.sample_frames = 40;
  const hc::AutoResult r = hc::propose_automatic(run, opt);
  std::string verdicts;
  for (const auto& c : r.clusters)
    verdicts += std::to_string(2 * c.peak_h8) + " deg: " + c.verdict + "\n";
  ASSERT_EQ(r.boards.size(), 2U) << verdicts;
  // Hue order: green (60 steps) before red (centred on 0; its peak may fall either side).
  const auto& red =
      hc::hue_distance_h8(r.boards[0].hue_centre_h8, 0) < 5 ? r.boards[0] : r.boards[1];
  const auto& green = &red == &r.boards[0] ? r.boards[1] : r.boards[0];
  EXPECT_EQ(red.name, "red");
  EXPECT_EQ(green.name, "green");
  EXPECT_GT(red.window.hue_min_deg, red.window.hue_max_deg) << "the red window wraps through 0";
  EXPECT_TRUE(hc::hue_steps_of(red.window).contains(178));
  EXPECT_TRUE(hc::hue_steps_of(red.window).contains(2));
  EXPECT_TRUE(hc::hue_steps_of(green.window).contains(60));
  EXPECT_FALSE(hc::hue_steps_of(green.window).contains(115));
  // The grey room's saturation (about 25) stays out; the boards' (200+) stay in.
  for (const auto& b : r.boards) {
    EXPECT_GT(b.window.saturation_min, 40);
    EXPECT_LT(b.window.saturation_min, 190)
        << b.name << ": background " << int{b.background_saturation_high} << ", board "
        << int{b.board_saturation_low};
  }
  bool strip_rejected = false;
  for (const auto& c : r.clusters) {
    if (c.range.contains(115)) {
      EXPECT_FALSE(c.is_board);
      EXPECT_NE(c.verdict.find("constant"), std::string::npos) << c.verdict;
      strip_rejected = true;
    }
  }
  EXPECT_TRUE(strip_rejected);

  // --boards 1: the one with the most blob pixels over the run.
  opt.boards = 1;
  const hc::AutoResult one = hc::propose_automatic(run, opt);
  ASSERT_EQ(one.boards.size(), 1U);
  EXPECT_EQ(one.boards[0].name, "red");

  // The windows catch each board's pixels and nothing of the room.
  const hc::RunAreas areas = hc::measure_run(run, hc::threshold_set_of(r.boards));
  for (std::size_t f = 0; f < 40; ++f) {
    const int grow = static_cast<int>(f * 30 / 40);
    const auto& red_area = areas.area_px[&red == &r.boards[0] ? 0 : 1][f];
    EXPECT_NEAR(static_cast<double>(red_area), (10 + grow) * (8 + grow), 12.0);
  }
  const std::vector<std::string> warnings = hc::window_warnings(areas, {"a", "b"});
  EXPECT_TRUE(warnings.empty()) << warnings.front();
}

TEST(ColourWindows, GuidedTakesTheColourInsideEachRectangle) {
  hc::MemoryFrames run = synthetic_run(20);
  hc::RgbImage frame;
  run.read(10, frame);
  hc::AutoOptions opt;
  // Loose rectangles: the wall around a board is in them too.
  const std::vector<hc::GuidedRect> rects{hc::parse_rect("mine:16,16,30,26"),
                                          hc::parse_rect("theirs:60,66,30,24")};
  const auto boards = hc::propose_guided(frame, rects, opt);
  ASSERT_EQ(boards.size(), 2U);
  EXPECT_EQ(boards[0].name, "mine");
  EXPECT_TRUE(hc::hue_steps_of(boards[0].window).contains(178));
  EXPECT_TRUE(hc::hue_steps_of(boards[0].window).contains(2));
  EXPECT_TRUE(hc::hue_steps_of(boards[1].window).contains(60));
  EXPECT_GT(boards[0].window.saturation_min, 40);
  hc::MemoryFrames one;
  one.add(0, frame);
  const hc::RunAreas r = hc::measure_run(one, hc::threshold_set_of(boards));
  EXPECT_NEAR(static_cast<double>(r.area_px[0][0]), 25 * 23, 8.0);  // grown by 15 at frame 10/20
  EXPECT_NEAR(static_cast<double>(r.area_px[1][0]), 13 * 16, 8.0);

  EXPECT_THROW(hc::propose_guided(frame, {hc::parse_rect("out:150,100,20,30")}, opt),
               std::runtime_error);
  EXPECT_THROW(hc::propose_guided(frame, {hc::parse_rect("grey:100,30,10,10")}, opt),
               std::runtime_error);
  EXPECT_THROW(hc::parse_rect("a:1,2,3"), std::invalid_argument);
  EXPECT_THROW(hc::parse_rect("a:1,2,3,x"), std::invalid_argument);
  EXPECT_THROW(hc::parse_rect("1,2,3,4"), std::invalid_argument);
  EXPECT_THROW(hc::parse_rect("a:1,2,0,4"), std::invalid_argument);
  EXPECT_EQ(hc::parse_rect("my: board:1,2,3,4").name, "my: board");
}

TEST(ColourWindows, WarnsOfBackgroundConstantAreaAndOverlap) {
  hc::RunAreas r;
  r.boards = 4;
  r.frame_px = 10000;
  r.area_px.assign(4, {});
  for (std::uint32_t f = 0; f < 100; ++f) {
    r.area_px[0].push_back(f % 50 * 4);        // a board: 0..196 px
    r.area_px[1].push_back(3000 + f % 7);      // background: 30% of the frame, nearly constant
    r.area_px[2].push_back(f < 50 ? 0 : 150);  // a board, half the run
    r.area_px[3].push_back(0);                 // never seen
  }
  r.total_px = {9800, 300000, 7500, 0};
  r.overlap_px.assign(4, std::vector<std::uint64_t>(4, 0));
  r.overlap_px[0][2] = r.overlap_px[2][0] = 1000;
  const auto w = hc::window_warnings(r, {"red", "desk", "green", "blue"});
  ASSERT_EQ(w.size(), 4U);
  EXPECT_NE(w[0].find("'desk' catches background"), std::string::npos) << w[0];
  EXPECT_NE(w[1].find("'desk' has a nearly constant area"), std::string::npos) << w[1];
  EXPECT_NE(w[2].find("'blue': no pixel"), std::string::npos) << w[2];
  EXPECT_NE(w[3].find("'red' and 'green' overlap"), std::string::npos) << w[3];
}

TEST(ColourWindows, TomlReadsBackAsTheFirmwaresConfig) {
  hc::ProposedBoard red, green;
  red.name = "red \"one\"";
  red.window = hc::to_threshold(hc::HueRange{172, 5}, 101, 40);
  green.name = "green";
  green.window = hc::to_threshold(hc::HueRange{50, 70}, 90, 33, 250);
  const auto dir = std::filesystem::temp_directory_path() / "harmoloc_colour_windows_test";
  std::filesystem::create_directories(dir);
  const std::string base =
      "[odometry]\nwheel_radius_m = 0.07\n\n[[board]]\nname = \"old\"\n"
      "hue_deg = [1, 2]\n";
  for (const std::string& b : {std::string(), base}) {
    const std::string path = (dir / "boards.toml").string();
    std::ofstream(path) << hc::boards_toml({red, green}, b);
    const harmoloc::firmware::FirmwareConfig c = harmoloc::firmware::load_config(path);
    ASSERT_EQ(c.thresholds.count, 2U);
    EXPECT_EQ(c.thresholds.boards[0], red.window);
    EXPECT_EQ(c.thresholds.boards[1], green.window);
    EXPECT_EQ(c.board_names.names[0], red.name);
    EXPECT_EQ(c.geometry.wheel_radius_m, b.empty() ? 0.05 : 0.07);
  }
  EXPECT_THROW(hc::boards_toml({red}, "[odometry\n"), std::runtime_error);
  std::filesystem::remove_all(dir);
}

TEST(ColourWindows, PngIsWellFormed) {
  const std::vector<std::uint8_t> px(4 * 3 * 2, 7);
  const auto png = hc::encode_png(4, 2, 3, std::vector<std::uint8_t>(px.begin(), px.begin() + 24));
  ASSERT_GT(png.size(), 8U + 25U + 12U + 12U);
  EXPECT_EQ(png[1], 'P');
  EXPECT_EQ(std::string(png.begin() + 12, png.begin() + 16), "IHDR");
  EXPECT_EQ(png[16 + 3], 4);  // width, big-endian
  EXPECT_EQ(std::string(png.end() - 8, png.end() - 4), "IEND");
  EXPECT_THROW(hc::encode_png(4, 3, 3, px), std::runtime_error);
}

// A simulated run's frames, rendered on demand in any order.
class RunFrames final : public hc::FrameSource {
 public:
  explicit RunFrames(hs::ScenarioRun& run) : run_(run), renderer_(run.scenario()) {}
  std::size_t size() const override { return run_.frame_count(); }
  std::uint64_t timestamp_ns(std::size_t k) const override { return run_.frame_timestamp_ns(k); }
  void read(std::size_t k, hc::RgbImage& out) override {
    out.width_px = run_.scenario().camera.width_px;
    out.height_px = run_.scenario().camera.height_px;
    run_.render_frame(k, renderer_, out.rgb);
  }

 private:
  hs::ScenarioRun& run_;
  hs::SceneRenderer renderer_;
};

// The automatic mode on random scenes (320x240) against the scene's true windows
// (thresholds_for: what a careful user sets): every true board is found, its mask matching the
// true window's on most frames where it shows, and nothing else is proposed.
TEST(ColourWindows, AutomaticFindsEveryBoardOfRandomScenes) {
  std::vector<std::uint64_t> seeds;
  for (std::uint64_t seed = 1; seeds.size() < 3 && seed < 60; ++seed)
    if (hs::random_scenario(seed).camera.width_px == 320) seeds.push_back(seed);
  ASSERT_EQ(seeds.size(), 3U);
  for (const std::uint64_t seed : seeds) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const hs::Scenario scene = hs::random_scenario(seed);
    hs::ScenarioRun run(scene, 1);
    RunFrames frames(run);
    hc::AutoOptions opt;
    opt.sample_frames = 100;
    const hc::AutoResult r = hc::propose_automatic(frames, opt);
    const auto truth = hs::threshold_set(hs::thresholds_for(scene));
    ASSERT_EQ(r.boards.size(), truth.count) << "boards proposed vs in the scene";
    const auto found = hc::threshold_set_of(r.boards);
    const alg::BoardClassifier true_cls(truth), found_cls(found);
    // Match each true board to the proposed window that shares most of its pixels, then IoU per
    // frame where the board shows at least 50 pixels.
    std::vector<std::vector<double>> shared(truth.count, std::vector<double>(found.count, 0.0));
    hc::RgbImage img;
    const std::size_t checks = 40;
    std::vector<std::vector<std::uint8_t>> true_bits(checks), found_bits(checks);
    for (std::size_t c = 0; c < checks; ++c) {
      frames.read(c * (frames.size() - 1) / (checks - 1), img);
      const std::size_t n = static_cast<std::size_t>(img.width_px) * img.height_px;
      true_bits[c].resize(n);
      found_bits[c].resize(n);
      for (std::size_t i = 0; i < n; ++i) {
        true_bits[c][i] = true_cls.classify(img.rgb[3 * i], img.rgb[3 * i + 1], img.rgb[3 * i + 2]);
        found_bits[c][i] =
            found_cls.classify(img.rgb[3 * i], img.rgb[3 * i + 1], img.rgb[3 * i + 2]);
        for (std::size_t t = 0; t < truth.count; ++t)
          for (std::size_t f = 0; f < found.count; ++f)
            if ((true_bits[c][i] >> t & 1U) != 0 && (found_bits[c][i] >> f & 1U) != 0)
              shared[t][f] += 1.0;
      }
    }
    std::vector<bool> used(found.count, false);
    for (std::size_t t = 0; t < truth.count; ++t) {
      const auto best = static_cast<std::size_t>(
          std::max_element(shared[t].begin(), shared[t].end()) - shared[t].begin());
      EXPECT_FALSE(used[best]) << "two true boards in one proposed window";
      used[best] = true;
      std::size_t frames_shown = 0, frames_good = 0;
      for (std::size_t c = 0; c < checks; ++c) {
        double both = 0, either = 0, in_truth = 0;
        for (std::size_t i = 0; i < true_bits[c].size(); ++i) {
          const bool a = (true_bits[c][i] >> t & 1U) != 0, b = (found_bits[c][i] >> best & 1U) != 0;
          both += a && b ? 1 : 0;
          either += a || b ? 1 : 0;
          in_truth += a ? 1 : 0;
        }
        if (in_truth < 50) continue;
        ++frames_shown;
        frames_good += both / either > 0.8 ? 1 : 0;
      }
      EXPECT_GE(static_cast<double>(frames_good), 0.8 * static_cast<double>(frames_shown))
          << "board " << t << ": IoU > 0.8 on " << frames_good << " of " << frames_shown;
    }
  }
}

}  // namespace

namespace {

// A robot's recording is YUYV: decoded as OpenCV (and the firmware's segmentation) decode it,
// and every frame file checked when the folder is opened.
TEST(ColourWindows, ReadsYuyvRecordingsAndRefusesBadFrames) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "harmoloc_colour_windows_yuyv";
  fs::remove_all(dir);
  fs::create_directories(dir / "frames");
  harmoloc::dataset::DatasetMetadata meta;
  meta.image_width_px = 4;
  meta.image_height_px = 2;
  meta.pixel_format = harmoloc::hal::PixelFormat::kYuyv;
  harmoloc::dataset::write_metadata(dir.string(), meta);
  const std::vector<std::uint8_t> yuyv{16, 90,  235, 240, 81,  90,  145, 54,
                                       41, 240, 210, 16,  128, 128, 128, 128};
  std::ofstream(dir / "frames" / "000000.yuv", std::ios::binary)
      .write(reinterpret_cast<const char*>(yuyv.data()), 16);
  harmoloc::dataset::write_frame_index((dir / "frames.csv").string(),
                                       {{1'000'000'000ULL, "frames/000000.yuv"}});
  hc::DatasetFrames frames(dir.string());
  ASSERT_EQ(frames.size(), 1U);
  hc::RgbImage img;
  frames.read(0, img);
  for (std::size_t p = 0; p < 8; ++p) {
    const std::uint8_t* q = &yuyv[4 * (p / 2)];
    const alg::Rgb8 c = alg::yuv_to_rgb_opencv(q[2 * (p % 2)], q[1], q[3]);
    EXPECT_EQ(img.rgb[3 * p], c.r);
    EXPECT_EQ(img.rgb[3 * p + 1], c.g);
    EXPECT_EQ(img.rgb[3 * p + 2], c.b);
  }
  std::ofstream(dir / "frames" / "000000.yuv", std::ios::binary).write("short", 5);
  EXPECT_THROW(hc::DatasetFrames{dir.string()}, std::runtime_error);
  EXPECT_THROW(hc::DatasetFrames{(dir / "nothing").string()}, std::runtime_error);
  fs::remove_all(dir);
}

}  // namespace
