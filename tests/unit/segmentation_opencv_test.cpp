// BoardClassifier and the segmenters against OpenCV itself (tests/reference: cvtColor to HSV,
// inRange per board, countNonZero). RGB24 must agree exactly: the HSV of all 2^24 colours, the
// board classes of every colour for the default and adversarial windows, simulated and
// adversarial frames. YUYV too, since segment_yuyv decodes as OpenCV does (the bounds below were
// measured when it did not). Every segmenter is compared: the HSV arithmetic, and the colour and
// YUYV tables on every path this CPU runs (scalar, AVX2).
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <initializer_list>
#include <iterator>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "harmoloc/algorithms/random.hpp"
#include "harmoloc/algorithms/segmentation.hpp"
#include "harmoloc/sim_host/route.hpp"
#include "harmoloc/sim_host/scenario.hpp"
#include "harmoloc/sim_host/scene_renderer.hpp"
#include "opencv_reference.hpp"
#include "test_support.hpp"

namespace ha = harmoloc::algorithms;
namespace hr = harmoloc::reference;
namespace hs = harmoloc::sim_host;
namespace ht = harmoloc::test;

namespace {

constexpr int kSide = 4096;  // 4096 x 4096 = 2^24 pixels

/// Whether segment_yuyv decodes YUYV as OpenCV does (opencv_yuv_to_rgb below). While false it
/// uses its own 8-bit BT.601 formula (firmware_yuv_to_rgb) and the YUYV tests hold it to the
/// measured differences; set true when it switches, and every YUYV area must then be equal.
constexpr bool kYuyvDecodesAsOpencv = true;

/// A measured YUYV area difference, or 0 once the decoders agree.
constexpr std::uint32_t yuyv_bound(std::uint32_t measured) {
  return kYuyvDecodesAsOpencv ? 0U : measured;
}

std::uint8_t u8(int v) {
  return static_cast<std::uint8_t>(v);
}
std::uint8_t clamp_u8(int v) {
  return static_cast<std::uint8_t>(std::clamp(v, 0, 255));
}

// --- images --------------------------------------------------------------------------------------

/// Every RGB colour once: pixel i (row-major) is (i >> 16, i >> 8 & 255, i & 255).
const cv::Mat& all_colours() {
  static const cv::Mat img = [] {
    cv::Mat m(kSide, kSide, CV_8UC3);
    std::uint8_t* p = m.ptr<std::uint8_t>(0);
    for (int i = 0; i < kSide * kSide; ++i, p += 3) {
      p[0] = u8(i >> 16);
      p[1] = u8((i >> 8) & 0xFF);
      p[2] = u8(i & 0xFF);
    }
    return m;
  }();
  return img;
}

/// OpenCV's HSV of all_colours().
const cv::Mat& all_colours_hsv() {
  static const cv::Mat hsv = [] {
    cv::Mat m;
    cv::cvtColor(all_colours(), m, cv::COLOR_RGB2HSV);
    return m;
  }();
  return hsv;
}

/// An RGB24 frame with rows @p stride bytes apart; the padding is pure red, which most window
/// sets count, so reading it would show.
struct Frame {
  int width = 0, height = 0, stride = 0;
  std::vector<std::uint8_t> bytes;

  Frame(int w, int h, int stride_bytes)
      : width(w),
        height(h),
        stride(stride_bytes),
        bytes(static_cast<std::size_t>(stride_bytes) * static_cast<std::size_t>(h), 0) {
    for (int y = 0; y < h; ++y) {
      for (int b = w * 3; b < stride; ++b) at_byte(y, b) = (b - w * 3) % 3 == 0 ? 255 : 0;
    }
  }
  std::uint8_t& at_byte(int y, int b) {
    return bytes[static_cast<std::size_t>(y) * static_cast<std::size_t>(stride) +
                 static_cast<std::size_t>(b)];
  }
  void set(int x, int y, std::uint8_t r, std::uint8_t g, std::uint8_t b) {
    at_byte(y, 3 * x) = r;
    at_byte(y, 3 * x + 1) = g;
    at_byte(y, 3 * x + 2) = b;
  }
  void fill(std::uint8_t r, std::uint8_t g, std::uint8_t b) {
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < width; ++x) set(x, y, r, g, b);
    }
  }
};

// --- window sets ---------------------------------------------------------------------------------

ha::ColourThreshold win(float h0, float h1, int s_min = 110, int v_min = 60, int v_max = 255) {
  return ha::ColourThreshold{h0, h1, u8(s_min), u8(v_min), u8(v_max)};
}

ha::ThresholdSet make_set(std::initializer_list<ha::ColourThreshold> boards) {
  ha::ThresholdSet set;
  for (const ha::ColourThreshold& t : boards) set.boards[set.count++] = t;
  return set;
}

constexpr std::size_t kWindowSets = 5;  // how many window_sets() returns

struct NamedSet {
  std::string name;
  ha::ThresholdSet set;
};

/// The firmware's six boards, then sets chosen to catch off-by-one mappings: windows ending on
/// odd and even degrees (odd degrees fall between two H steps), fractional ends, wrapping and
/// degenerate windows, and saturation and value extremes.
std::vector<NamedSet> window_sets() {
  return {
      {"default", ht::board_windows()},
      {"odd-even ends", make_set({win(100, 145), win(101, 145), win(100, 144), win(101, 143),
                                  win(99, 146), win(340, 15), win(341, 15), win(340, 14)})},
      {"wrapping and degenerate",
       make_set({win(341, 13), win(359, 0), win(358, 2), win(0, 360), win(0, 0), win(1, 1),
                 win(200, 199), win(179.5F, 180.5F)})},
      {"fractional ends", make_set({win(99.9F, 145.1F), win(100.1F, 144.9F), win(339.5F, 15.5F),
                                    win(44.99F, 70.01F), win(215.5F, 249.5F), win(284.9F, 320.1F),
                                    win(170.25F, 199.75F), win(0.5F, 359.5F)})},
      {"saturation and value extremes",
       make_set({win(0, 360, 0, 0, 255), win(0, 360, 255, 0, 255), win(340, 15, 1, 1, 254),
                 win(100, 145, 0, 0, 0), win(100, 145, 0, 255, 255), win(215, 250, 0, 128, 128),
                 win(45, 70, 255, 129, 128), win(170, 200, 254, 255, 255)})},
  };
}

// --- tables --------------------------------------------------------------------------------------

std::vector<ha::SegmentPath> supported_paths() {
  std::vector<ha::SegmentPath> out;
  for (ha::SegmentPath p :
       {ha::SegmentPath::kScalar, ha::SegmentPath::kAvx2, ha::SegmentPath::kNeon})
    if (ha::segment_path_supported(p)) out.push_back(p);
  return out;
}

/// The colour and YUYV tables of a window set, built once per set (16 MiB each).
struct SetTables {
  std::vector<std::uint8_t> rgb_storage, yuyv_storage;
  ha::ColourTable rgb;
  ha::YuyvTable yuyv;
};

SetTables& tables_for(const ha::ThresholdSet& set) {
  static std::vector<std::pair<ha::ThresholdSet, std::unique_ptr<SetTables>>> cache;
  for (auto& entry : cache) {
    if (entry.first == set) return *entry.second;
  }
  auto t = std::make_unique<SetTables>();
  t->rgb_storage.resize(ha::MaskTable::kStorageBytes);
  t->yuyv_storage.resize(ha::MaskTable::kStorageBytes);
  const ha::BoardClassifier classifier(set);
  t->rgb.build(classifier, t->rgb_storage.data());
  t->yuyv.build(classifier, t->yuyv_storage.data());
  cache.emplace_back(set, std::move(t));
  return *cache.back().second;
}

/// Areas of an RGB24 (@p yuyv false) or YUYV frame with @p set's table on @p path.
ha::AreaVector table_areas(const std::uint8_t* data, int w, int h, int stride, bool yuyv,
                           const ha::ThresholdSet& set, ha::SegmentPath path) {
  SetTables& t = tables_for(set);
  ha::AreaVector areas;
  areas.pixels.fill(999U);
  const auto uw = static_cast<std::uint32_t>(w), uh = static_cast<std::uint32_t>(h),
             us = static_cast<std::uint32_t>(stride);
  if (yuyv) {
    EXPECT_TRUE(t.yuyv.set_path(path));
    ha::segment_yuyv(data, uw, uh, us, t.yuyv, areas);
  } else {
    EXPECT_TRUE(t.rgb.set_path(path));
    ha::segment_rgb24(data, uw, uh, us, t.rgb, areas);
  }
  return areas;
}

// --- comparisons ---------------------------------------------------------------------------------

std::string areas_text(const ha::AreaVector& a) {
  std::string s = "[";
  for (std::size_t k = 0; k < a.count; ++k) s += (k ? " " : "") + std::to_string(a.pixels[k]);
  return s + "]";
}

/// Segments the RGB24 frame with both overloads, the colour table on every path, and OpenCV;
/// expects equal areas. Returns ours.
ha::AreaVector expect_same_rgb_areas(const std::uint8_t* data, int w, int h, int stride,
                                     const NamedSet& ns, const std::string& what) {
  SCOPED_TRACE(what + ", windows '" + ns.name + "'");
  const ha::BoardClassifier classifier(ns.set);
  ha::AreaVector ours, ours_set, theirs;
  ours.pixels.fill(999U);
  const auto uw = static_cast<std::uint32_t>(w), uh = static_cast<std::uint32_t>(h);
  ha::segment_rgb24(data, uw, uh, static_cast<std::uint32_t>(stride), classifier, ours);
  ha::segment_rgb24(data, uw, uh, static_cast<std::uint32_t>(stride), ns.set, ours_set);
  hr::OpencvScratch scratch;
  hr::opencv_segment_rgb24(data, w, h, stride, ns.set, theirs, scratch);
  EXPECT_EQ(ours.count, theirs.count);
  EXPECT_EQ(ours.pixels, theirs.pixels)
      << "ours " << areas_text(ours) << " OpenCV " << areas_text(theirs);
  EXPECT_EQ(ours_set.pixels, ours.pixels);
  for (std::size_t k = ours.count; k < ha::kMaxBoards; ++k) EXPECT_EQ(ours.pixels[k], 0U) << k;
  for (ha::SegmentPath path : supported_paths()) {
    const ha::AreaVector t = table_areas(data, w, h, stride, false, ns.set, path);
    EXPECT_EQ(t.count, theirs.count);
    EXPECT_EQ(t.pixels, theirs.pixels) << "colour table, path " << ha::segment_path_name(path)
                                       << ": " << areas_text(t) << " OpenCV " << areas_text(theirs);
  }
  return ours;
}

std::uint32_t total(const ha::AreaVector& a) {
  std::uint32_t t = 0;
  for (std::size_t k = 0; k < a.count; ++k) t += a.pixels[k];
  return t;
}

// --- simulated frames ----------------------------------------------------------------------------

struct SimFrame {
  std::string what;
  int width, height;
  std::vector<std::uint8_t> rgb;
};

/// desk-shuttle at four poses along its route (start, a quarter, the far end, three quarters),
/// each at light gains 1.0, 0.7 and 1.3, with the scenario's pixel noise.
const std::vector<SimFrame>& simulated_frames() {
  static const std::vector<SimFrame> frames = [] {
    std::vector<SimFrame> out;
    const hs::Scenario base = hs::load_scenario("desk-shuttle");
    ha::Pcg32 wander(3);
    const std::vector<hs::MotionSample> run = hs::simulate_motion(base, 0.01, wander, nullptr);
    for (double gain : {1.0, 0.7, 1.3}) {
      hs::Scenario s = base;
      s.camera.light_gain = gain;
      const hs::SceneRenderer renderer(s);
      for (double at : {0.0, 0.25, 0.5, 0.75}) {
        const std::size_t i = static_cast<std::size_t>(at * static_cast<double>(run.size() - 1));
        ha::Pcg32 noise(100 + i);
        SimFrame f{"desk-shuttle sample " + std::to_string(i) + " gain " + std::to_string(gain),
                   static_cast<int>(s.camera.width_px),
                   static_cast<int>(s.camera.height_px),
                   {}};
        renderer.render(run[i].pose, noise, f.rgb);
        out.push_back(std::move(f));
      }
    }
    return out;
  }();
  return frames;
}

// --- YUYV ----------------------------------------------------------------------------------------

struct Rgb8 {
  std::uint8_t r, g, b;
};

/// segment_yuyv's decoder, as algorithms/src/segmentation.cpp documents it: BT.601 limited range
/// with 8-bit coefficients (298, 409, 100, 208, 516), rounded, arithmetic shift, clamped.
Rgb8 firmware_yuv_to_rgb(int y, int u, int v) {
  const int c = 298 * (y - 16);
  const int du = u - 128, dv = v - 128;
  return {clamp_u8((c + 409 * dv + 128) >> 8), clamp_u8((c - 100 * du - 208 * dv + 128) >> 8),
          clamp_u8((c + 516 * du + 128) >> 8)};
}

/// OpenCV's COLOR_YUV2RGB_YUYV (modules/imgproc/src/color_yuv.simd.hpp, uvToRGBuv and
/// yRGBuvToRGBA): 20-bit coefficients, luma below 16 clamped to 16 before scaling.
Rgb8 opencv_yuv_to_rgb(int y, int u, int v) {
  const int yy = std::max(0, y - 16) * 1220542;
  const int du = u - 128, dv = v - 128;
  const int half = 1 << 19;
  return {clamp_u8((yy + half + 1673527 * dv) >> 20),
          clamp_u8((yy + half - 852492 * dv - 409993 * du) >> 20),
          clamp_u8((yy + half + 2116026 * du) >> 20)};
}

/// Every (Y, U, V) once as a 4096 x 4096 YUYV frame: pixel pair j holds U = j >> 15,
/// V = (j >> 7) & 255 and lumas 2 (j & 127) and 2 (j & 127) + 1.
const cv::Mat& all_yuv_triples() {
  static const cv::Mat img = [] {
    cv::Mat m(kSide, kSide, CV_8UC2);
    std::uint8_t* p = m.ptr<std::uint8_t>(0);
    for (int j = 0; j < kSide * kSide / 2; ++j, p += 4) {
      p[0] = u8((j & 127) * 2);
      p[1] = u8(j >> 15);
      p[2] = u8((j & 127) * 2 + 1);
      p[3] = u8((j >> 7) & 255);
    }
    return m;
  }();
  return img;
}

/// BT.601 limited-range encoding of an RGB24 frame into YUYV (the camera's side; integer, the
/// pair's chroma is the mean of its two pixels').
std::vector<std::uint8_t> to_yuyv(const std::vector<std::uint8_t>& rgb, int w, int h) {
  std::vector<std::uint8_t> out(static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * 2U);
  for (std::size_t p = 0; p + 1 < static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
       p += 2) {
    int u = 0, v = 0;
    for (std::size_t k = 0; k < 2; ++k) {
      const int r = rgb[(p + k) * 3], g = rgb[(p + k) * 3 + 1], b = rgb[(p + k) * 3 + 2];
      out[(p + k) * 2] = clamp_u8(((66 * r + 129 * g + 25 * b + 128) >> 8) + 16);
      u += ((-38 * r - 74 * g + 112 * b + 128) >> 8) + 128;
      v += ((112 * r - 94 * g - 18 * b + 128) >> 8) + 128;
    }
    out[p * 2 + 1] = clamp_u8((u + 1) / 2);
    out[p * 2 + 3] = clamp_u8((v + 1) / 2);
  }
  return out;
}

/// Largest |ours - OpenCV| over the boards of a YUYV frame; both area vectors through @p ours and
/// @p theirs. The YUYV table on every path must give exactly @p ours.
std::uint32_t yuyv_area_difference(const std::uint8_t* data, int w, int h, int stride,
                                   const ha::ThresholdSet& set, ha::AreaVector& ours,
                                   ha::AreaVector& theirs) {
  ha::segment_yuyv(data, static_cast<std::uint32_t>(w), static_cast<std::uint32_t>(h),
                   static_cast<std::uint32_t>(stride), set, ours);
  hr::OpencvScratch scratch;
  hr::opencv_segment_yuyv(data, w, h, stride, set, theirs, scratch);
  EXPECT_EQ(ours.count, theirs.count);
  for (ha::SegmentPath path : supported_paths()) {
    const ha::AreaVector t = table_areas(data, w, h, stride, true, set, path);
    EXPECT_EQ(t.count, ours.count);
    EXPECT_EQ(t.pixels, ours.pixels) << "YUYV table, path " << ha::segment_path_name(path) << ": "
                                     << areas_text(t) << ", decoded " << areas_text(ours);
  }
  std::uint32_t worst = 0;
  for (std::size_t k = 0; k < set.count; ++k) {
    const std::uint32_t d = ours.pixels[k] > theirs.pixels[k] ? ours.pixels[k] - theirs.pixels[k]
                                                              : theirs.pixels[k] - ours.pixels[k];
    worst = std::max(worst, d);
  }
  return worst;
}

}  // namespace

// --- (a) HSV of every colour ---------------------------------------------------------------------

TEST(OpencvHsv, EveryRgbColourMatchesCvtColorExactly) {
  const cv::Mat& rgb = all_colours();
  const cv::Mat& hsv = all_colours_hsv();
  ASSERT_TRUE(rgb.isContinuous() && hsv.isContinuous());
  const ha::BoardClassifier classifier;
  const std::uint8_t* p = rgb.ptr<std::uint8_t>(0);
  const std::uint8_t* q = hsv.ptr<std::uint8_t>(0);
  std::size_t mismatches = 0;
  for (int i = 0; i < kSide * kSide; ++i, p += 3, q += 3) {
    const ha::Hsv8 ours = classifier.to_hsv(p[0], p[1], p[2]);
    if (ours.h == q[0] && ours.s == q[1] && ours.v == q[2]) continue;
    if (mismatches++ == 0) {
      ADD_FAILURE() << "first mismatch at RGB (" << int{p[0]} << ", " << int{p[1]} << ", "
                    << int{p[2]} << "): ours HSV (" << int{ours.h} << ", " << int{ours.s} << ", "
                    << int{ours.v} << "), OpenCV (" << int{q[0]} << ", " << int{q[1]} << ", "
                    << int{q[2]} << ")";
    }
  }
  EXPECT_EQ(mismatches, 0U) << "of " << kSide * kSide << " colours";
}

// --- (b) board classes of every colour -----------------------------------------------------------

// One test per window set (each runs the 2^24 colours; separate tests run in parallel).
class OpencvBoards : public testing::TestWithParam<std::size_t> {};

TEST_P(OpencvBoards, EveryColourIsClassifiedAsTheWindowsSay) {
  // Per pixel: classify()'s bit k is set exactly where OpenCV's own HSV of the colour lies in
  // board k's box H [ceil(min / 2), floor(max / 2)] (wrapping when min > max), S >= s_min,
  // v_min <= V <= v_max, the rule written out here per channel; and segment_rgb24's areas equal
  // the reference's (cvtColor, inRange, countNonZero).
  ASSERT_EQ(window_sets().size(), kWindowSets);
  const NamedSet ns = window_sets().at(GetParam());
  SCOPED_TRACE("windows '" + ns.name + "'");
  std::uint8_t hue[180] = {}, sat[256] = {}, val[256] = {};
  for (std::size_t k = 0; k < ns.set.count; ++k) {
    const ha::ColourThreshold& t = ns.set.boards[k];
    const auto bit = static_cast<std::uint8_t>(1U << k);
    const double lo = std::ceil(static_cast<double>(t.hue_min_deg) / 2.0);
    const double hi = std::floor(static_cast<double>(t.hue_max_deg) / 2.0);
    for (int h = 0; h < 180; ++h) {
      const bool in = t.hue_min_deg <= t.hue_max_deg ? lo <= h && h <= hi : lo <= h || h <= hi;
      if (in) hue[h] = static_cast<std::uint8_t>(hue[h] | bit);
    }
    for (int x = 0; x < 256; ++x) {
      if (x >= t.saturation_min) sat[x] = static_cast<std::uint8_t>(sat[x] | bit);
      if (x >= t.value_min && x <= t.value_max) val[x] = static_cast<std::uint8_t>(val[x] | bit);
    }
  }
  const cv::Mat& rgb = all_colours();
  const cv::Mat& hsv = all_colours_hsv();
  const ha::BoardClassifier classifier(ns.set);
  const std::uint8_t* p = rgb.ptr<std::uint8_t>(0);
  const std::uint8_t* q = hsv.ptr<std::uint8_t>(0);
  std::size_t mismatches = 0;
  for (int i = 0; i < kSide * kSide; ++i, p += 3, q += 3) {
    const std::uint8_t ours = classifier.classify(p[0], p[1], p[2]);
    const auto expected = static_cast<std::uint8_t>(hue[q[0]] & sat[q[1]] & val[q[2]]);
    if (ours == expected) continue;
    if (mismatches++ == 0) {
      ADD_FAILURE() << "first mismatch at RGB (" << int{p[0]} << ", " << int{p[1]} << ", "
                    << int{p[2]} << ") = OpenCV HSV (" << int{q[0]} << ", " << int{q[1]} << ", "
                    << int{q[2]} << "): ours boards 0x" << std::hex << int{ours} << ", expected 0x"
                    << int{expected} << std::dec;
    }
  }
  EXPECT_EQ(mismatches, 0U);

  const ha::AreaVector a =
      expect_same_rgb_areas(rgb.ptr<std::uint8_t>(0), kSide, kSide, kSide * 3, ns, "all colours");
  EXPECT_GT(total(a), 0U);
  if (ns.name == "default") {
    // Guards the guard: the six boards' areas are large, so equal is not equal by being empty.
    for (std::size_t k = 0; k < 6; ++k) EXPECT_GT(a.pixels[k], 100000U) << k;
  }
}

INSTANTIATE_TEST_SUITE_P(WindowSets, OpencvBoards, testing::Range<std::size_t>(0, kWindowSets),
                         [](const testing::TestParamInfo<std::size_t>& param) {
                           std::string name = window_sets().at(param.param).name;
                           for (char& c : name) {
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           }
                           return name;
                         });

// --- (c) simulated frames ------------------------------------------------------------------------

TEST(OpencvFrames, SimulatedDeskShuttleFramesHaveEqualAreas) {
  const std::vector<SimFrame>& frames = simulated_frames();
  ASSERT_EQ(frames.size(), 12U);
  const std::vector<NamedSet> sets = window_sets();
  for (const SimFrame& f : frames) {
    for (const NamedSet& ns : sets) {
      const ha::AreaVector a =
          expect_same_rgb_areas(f.rgb.data(), f.width, f.height, f.width * 3, ns, f.what);
      if (ns.name == "default") {  // boards are in view
        EXPECT_GT(total(a), 1000U) << f.what;
      }
    }
  }
}

// --- (d) adversarial frames ----------------------------------------------------------------------

TEST(OpencvFrames, UniformFramesBlackWhiteAndSaturatedColours) {
  const std::vector<NamedSet> sets = window_sets();
  const Rgb8 colours[] = {{0, 0, 0},       {255, 255, 255}, {255, 0, 0},   {0, 255, 0},
                          {0, 0, 255},     {255, 255, 0},   {0, 255, 255}, {255, 0, 255},
                          {128, 128, 128}, {1, 0, 0},       {0, 0, 1},     {254, 255, 255}};
  for (const Rgb8& c : colours) {
    Frame f(64, 48, 64 * 3);
    f.fill(c.r, c.g, c.b);
    const std::string what = "uniform (" + std::to_string(c.r) + ", " + std::to_string(c.g) + ", " +
                             std::to_string(c.b) + ")";
    for (const NamedSet& ns : sets) expect_same_rgb_areas(f.bytes.data(), 64, 48, 64 * 3, ns, what);
  }
  // Stripes of the saturated primaries and secondaries, one colour a column.
  Frame stripes(6 * 7, 5, 6 * 7 * 3 + 9);
  for (int x = 0; x < stripes.width; ++x) {
    const Rgb8& c = colours[2 + x % 6];
    for (int y = 0; y < stripes.height; ++y) stripes.set(x, y, c.r, c.g, c.b);
  }
  for (const NamedSet& ns : sets) {
    const ha::AreaVector a = expect_same_rgb_areas(stripes.bytes.data(), stripes.width,
                                                   stripes.height, stripes.stride, ns, "stripes");
    if (ns.name == "default") {
      for (std::size_t k = 0; k < 6; ++k) EXPECT_EQ(a.pixels[k], 7U * 5U) << k;
    }
  }
}

TEST(OpencvFrames, RandomNoiseOddWidthsAndWideStrides) {
  const std::vector<NamedSet> sets = window_sets();
  ha::Pcg32 rng(20240607);
  struct Shape {
    int w, h, pad;
  };
  const Shape shapes[] = {{1, 1, 0},     {1, 7, 5},      {3, 5, 0},     {7, 3, 1},
                          {333, 217, 0}, {333, 217, 29}, {640, 480, 0}, {17, 300, 300}};
  for (const Shape& s : shapes) {
    Frame f(s.w, s.h, s.w * 3 + s.pad);
    for (int y = 0; y < s.h; ++y) {
      for (int x = 0; x < s.w; ++x) {
        const std::uint32_t r = rng.next_u32();
        f.set(x, y, u8(r & 0xFF), u8((r >> 8) & 0xFF), u8((r >> 16) & 0xFF));
      }
    }
    const std::string what = "noise " + std::to_string(s.w) + "x" + std::to_string(s.h) +
                             " stride " + std::to_string(f.stride);
    for (const NamedSet& ns : sets)
      expect_same_rgb_areas(f.bytes.data(), s.w, s.h, f.stride, ns, what);
  }
}

TEST(OpencvFrames, EveryPixelOnAThresholdEdge) {
  // Colours whose OpenCV HSV sits exactly on a default window's edge or one step outside it: H on
  // ceil(min / 2) - 1, ceil(min / 2), floor(max / 2), floor(max / 2) + 1 with S and V well inside;
  // and S on s_min - 1 or s_min, or V on v_min - 1 or v_min, with H inside. Taken from the
  // all-colours image (OpenCV's own HSV), laid out in an odd-width frame with a wide stride.
  const ha::ThresholdSet defaults = ht::board_windows();
  std::vector<bool> h_edge(180, false), h_in(180, false);
  for (std::size_t k = 0; k < defaults.count; ++k) {
    const ha::ColourThreshold& t = defaults.boards[k];
    const int lo = static_cast<int>(std::ceil(static_cast<double>(t.hue_min_deg) / 2.0));
    const int hi = static_cast<int>(std::floor(static_cast<double>(t.hue_max_deg) / 2.0));
    for (int h : {lo - 1, lo, hi, hi + 1}) h_edge[static_cast<std::size_t>((h + 180) % 180)] = true;
    for (int h = lo; h != (hi + 1) % 180; h = (h + 1) % 180)
      h_in[static_cast<std::size_t>(h)] = true;
  }
  const std::uint8_t s_min = defaults.boards[0].saturation_min;
  const std::uint8_t v_min = defaults.boards[0].value_min;
  const cv::Mat& rgb = all_colours();
  const cv::Mat& hsv = all_colours_hsv();
  std::vector<Rgb8> hue_edges, sv_edges;
  const std::uint8_t* p = rgb.ptr<std::uint8_t>(0);
  const std::uint8_t* q = hsv.ptr<std::uint8_t>(0);
  for (int i = 0; i < kSide * kSide; ++i, p += 3, q += 3) {
    const bool s_edge = q[1] == s_min || q[1] == s_min - 1;
    const bool v_edge = q[2] == v_min || q[2] == v_min - 1;
    if (h_edge[q[0]] && q[1] >= s_min && q[2] >= v_min) hue_edges.push_back({p[0], p[1], p[2]});
    if (h_in[q[0]] && (s_edge || v_edge)) sv_edges.push_back({p[0], p[1], p[2]});
  }
  ASSERT_GT(hue_edges.size(), 100000U);
  ASSERT_GT(sv_edges.size(), 10000U);
  const std::vector<NamedSet> sets = window_sets();
  for (const auto* colours : {&hue_edges, &sv_edges}) {
    const int w = 1021;
    const int h = static_cast<int>((colours->size() + w - 1) / w);
    Frame f(w, h, w * 3 + 11);
    for (std::size_t i = 0; i < static_cast<std::size_t>(w) * static_cast<std::size_t>(h); ++i) {
      const Rgb8& c = (*colours)[i % colours->size()];
      f.set(static_cast<int>(i % w), static_cast<int>(i / w), c.r, c.g, c.b);
    }
    const std::string what = colours == &hue_edges ? "H edges" : "S and V edges";
    for (const NamedSet& ns : sets) {
      const ha::AreaVector a = expect_same_rgb_areas(f.bytes.data(), w, h, f.stride, ns, what);
      if (ns.name == "default") {
        EXPECT_GT(total(a), 10000U) << what;
      }
    }
  }
}

// --- (e) YUYV ------------------------------------------------------------------------------------

TEST(OpencvYuyv, TwentyBitFormulaIsCvtColorForEveryTriple) {
  // opencv_yuv_to_rgb() above is exactly what cvtColor(COLOR_YUV2RGB_YUYV) computes, for all
  // 2^24 (Y, U, V): the formula segment_yuyv would need to match OpenCV bit for bit.
  const cv::Mat& yuyv = all_yuv_triples();
  cv::Mat rgb;
  cv::cvtColor(yuyv, rgb, cv::COLOR_YUV2RGB_YUYV);
  ASSERT_TRUE(rgb.isContinuous());
  const std::uint8_t* s = yuyv.ptr<std::uint8_t>(0);
  const std::uint8_t* o = rgb.ptr<std::uint8_t>(0);
  std::size_t mismatches = 0;
  for (int j = 0; j < kSide * kSide / 2; ++j, s += 4) {
    for (int i = 0; i < 2; ++i, o += 3) {
      const Rgb8 c = opencv_yuv_to_rgb(s[2 * i], s[1], s[3]);
      if (c.r == o[0] && c.g == o[1] && c.b == o[2]) continue;
      if (mismatches++ == 0) {
        ADD_FAILURE() << "first mismatch at YUV (" << int{s[2 * i]} << ", " << int{s[1]} << ", "
                      << int{s[3]} << "): formula (" << int{c.r} << ", " << int{c.g} << ", "
                      << int{c.b} << "), cvtColor (" << int{o[0]} << ", " << int{o[1]} << ", "
                      << int{o[2]} << ")";
      }
    }
  }
  EXPECT_EQ(mismatches, 0U);
}

TEST(OpencvYuyv, FirmwareFormulaDiffersFromOpencvWithinTheMeasuredBound) {
  // firmware_yuv_to_rgb() (segment_yuyv's 8-bit formula) against OpenCV's for every triple.
  // Measured with OpenCV 4.6: 3,022,173 of the 2^24 triples decode differently, 1,973,821 of
  // them with Y >= 16 and 1,404,892 in the legal range (Y 16..235, U and V 16..240). With luma
  // in 16..255 the difference is at most 1 a channel (rounding of the 8-bit coefficients); below
  // 16 OpenCV clamps Y - 16 to 0 and the firmware does not: up to 19 apart (Y = 0).
  std::size_t differ = 0, differ_from_16 = 0, differ_legal = 0;
  int worst = 0, worst_from_16 = 0;
  for (int y = 0; y < 256; ++y) {
    for (int u = 0; u < 256; ++u) {
      for (int v = 0; v < 256; ++v) {
        const Rgb8 a = firmware_yuv_to_rgb(y, u, v);
        const Rgb8 b = opencv_yuv_to_rgb(y, u, v);
        const int d = std::max({std::abs(a.r - b.r), std::abs(a.g - b.g), std::abs(a.b - b.b)});
        if (d == 0) continue;
        ++differ;
        worst = std::max(worst, d);
        if (y >= 16) {
          ++differ_from_16;
          worst_from_16 = std::max(worst_from_16, d);
        }
        if (y >= 16 && y <= 235 && u >= 16 && u <= 240 && v >= 16 && v <= 240) ++differ_legal;
      }
    }
  }
  std::printf(
      "YUYV decode: %zu of 16777216 triples differ from OpenCV (%zu with Y >= 16, %zu in the "
      "legal range Y 16..235, U and V 16..240); max channel difference %d, %d for Y >= 16\n",
      differ, differ_from_16, differ_legal, worst, worst_from_16);
  EXPECT_LE(worst_from_16, 1);
  EXPECT_LE(worst, 19);
  EXPECT_LE(differ, 3022173U);
  EXPECT_LE(differ_from_16, 1973821U);
  EXPECT_LE(differ_legal, 1404892U);
}

TEST(OpencvYuyv, FirmwareFormulaIsWhatSegmentYuyvComputes) {
  // Ties firmware_yuv_to_rgb() to the library: segment_yuyv of the all-triples frame equals
  // segment_rgb24 of that frame decoded by the formula, for the default and the odd-even window
  // sets (each 2^24 pixels twice). Fails if segment_yuyv's decoder changes without
  // kYuyvDecodesAsOpencv following.
  const cv::Mat& yuyv = all_yuv_triples();
  std::vector<std::uint8_t> rgb(static_cast<std::size_t>(kSide) * kSide * 3U);
  const std::uint8_t* s = yuyv.ptr<std::uint8_t>(0);
  for (std::size_t j = 0; j < static_cast<std::size_t>(kSide) * kSide / 2U; ++j, s += 4) {
    for (std::size_t i = 0; i < 2; ++i) {
      const Rgb8 c = kYuyvDecodesAsOpencv ? opencv_yuv_to_rgb(s[2 * i], s[1], s[3])
                                          : firmware_yuv_to_rgb(s[2 * i], s[1], s[3]);
      std::uint8_t* o = rgb.data() + (2 * j + i) * 3U;
      o[0] = c.r;
      o[1] = c.g;
      o[2] = c.b;
    }
  }
  const std::vector<NamedSet> sets = window_sets();
  for (const NamedSet& ns : {sets.at(0), sets.at(1)}) {
    SCOPED_TRACE("windows '" + ns.name + "'");
    ha::AreaVector from_yuyv, from_rgb;
    ha::segment_yuyv(yuyv.ptr<std::uint8_t>(0), kSide, kSide, kSide * 2, ns.set, from_yuyv);
    ha::segment_rgb24(rgb.data(), kSide, kSide, kSide * 3, ns.set, from_rgb);
    EXPECT_EQ(from_yuyv.pixels, from_rgb.pixels)
        << "segment_yuyv " << areas_text(from_yuyv) << ", formula " << areas_text(from_rgb);
  }
}

TEST(OpencvYuyv, AllTriplesAreasWithinTheMeasuredBound) {
  // segment_yuyv against opencv_segment_yuyv on the all-triples frame. The decoders differ (see
  // above), mostly for Y < 16 where OpenCV clamps, so areas differ where a decoded colour lands on
  // the other side of an edge. Largest per-board difference measured with OpenCV 4.6, of 2^24:
  // default windows 26556 (green: 2594746 ours, 2621302 OpenCV); saturation and value extremes
  // 13313. 0 once segment_yuyv decodes as OpenCV does.
  const cv::Mat& yuyv = all_yuv_triples();
  const std::vector<NamedSet> sets = window_sets();
  const struct {
    const NamedSet& ns;
    std::uint32_t max_diff;
  } cases[] = {{sets.at(0), yuyv_bound(26556U)}, {sets.at(4), yuyv_bound(13313U)}};
  for (const auto& c : cases) {
    ha::AreaVector ours, theirs;
    const std::uint32_t d = yuyv_area_difference(yuyv.ptr<std::uint8_t>(0), kSide, kSide, kSide * 2,
                                                 c.ns.set, ours, theirs);
    std::printf("all triples, windows '%s': ours %s OpenCV %s, max difference %u\n",
                c.ns.name.c_str(), areas_text(ours).c_str(), areas_text(theirs).c_str(), d);
    EXPECT_LE(d, c.max_diff) << c.ns.name;
    EXPECT_GT(total(theirs), 0U) << c.ns.name;
  }
}

TEST(OpencvYuyv, SimulatedFramesAreasWithinTheMeasuredBound) {
  // The simulated desk-shuttle frames encoded as YUYV (legal range, where the decoders differ by
  // at most 1 a channel): largest per-board area difference over the 12 frames, per window set,
  // measured with OpenCV 4.6 (of 76800 pixels a frame; how many of the 12 x count areas differ
  // in brackets): default 2 (2 of 72), odd-even ends 2 (6 of 96), wrapping and degenerate 18
  // (33 of 96), fractional ends 18 (14 of 96), saturation and value extremes 93 (12 of 96).
  // 0 once segment_yuyv decodes as OpenCV does.
  struct Bound {
    const char* set;
    std::uint32_t max_diff;
  };
  const Bound bounds[] = {{"default", yuyv_bound(2)},
                          {"odd-even ends", yuyv_bound(2)},
                          {"wrapping and degenerate", yuyv_bound(18)},
                          {"fractional ends", yuyv_bound(18)},
                          {"saturation and value extremes", yuyv_bound(93)}};
  const std::vector<NamedSet> sets = window_sets();
  ASSERT_EQ(sets.size(), std::size(bounds));
  std::vector<std::uint32_t> worst(sets.size(), 0U), differing(sets.size(), 0U);
  std::uint32_t compared = 0;
  for (const SimFrame& f : simulated_frames()) {
    const std::vector<std::uint8_t> yuyv = to_yuyv(f.rgb, f.width, f.height);
    for (std::size_t i = 0; i < sets.size(); ++i) {
      const NamedSet& ns = sets[i];
      ASSERT_EQ(ns.name, bounds[i].set);
      ha::AreaVector ours, theirs;
      const std::uint32_t d =
          yuyv_area_difference(yuyv.data(), f.width, f.height, f.width * 2, ns.set, ours, theirs);
      for (std::size_t k = 0; k < ns.set.count; ++k) {
        ++compared;
        differing[i] += ours.pixels[k] != theirs.pixels[k] ? 1U : 0U;
      }
      worst[i] = std::max(worst[i], d);
      EXPECT_LE(d, bounds[i].max_diff) << f.what << ", windows '" << ns.name << "': ours "
                                       << areas_text(ours) << " OpenCV " << areas_text(theirs);
      if (ns.name == "default") {
        EXPECT_GT(total(theirs), 1000U) << f.what;
      }
    }
  }
  for (std::size_t i = 0; i < sets.size(); ++i) {
    std::printf(
        "simulated YUYV frames, windows '%s': %u board areas differ from OpenCV, by at "
        "most %u pixels\n",
        sets[i].name.c_str(), differing[i], worst[i]);
  }
  std::printf("(%u board areas compared)\n", compared);
}

TEST(OpencvYuyv, AdversarialFramesOfEveryPathEqualOpencv) {
  // YUYV frames with widths around the SIMD blocks (even: OpenCV's decoder takes whole pairs),
  // padded strides, noise, luma below 16 and above 235, chroma at its extremes: the YUYV table on
  // every path gives OpenCV's areas exactly, for every window set.
  const std::vector<NamedSet> sets = window_sets();
  ha::Pcg32 rng(99);
  for (int w : {2, 30, 32, 34, 62, 64, 66, 96, 98, 334, 640}) {
    for (int pad : {0, 6}) {
      for (int content = 0; content < 4; ++content) {
        const int h = 7, stride = w * 2 + pad;
        std::vector<std::uint8_t> frame(static_cast<std::size_t>(stride) * h);
        for (std::size_t i = 0; i < frame.size(); ++i) {
          const std::uint32_t r = rng.next_u32();
          const bool chroma = i % 2 == 1;
          switch (content) {
            case 0:  // noise
              frame[i] = u8(static_cast<int>(r & 0xFF));
              break;
            case 1:  // dark: luma 0..20 (OpenCV clamps below 16), neutral-ish chroma
              frame[i] = chroma ? u8(118 + static_cast<int>(r % 21)) : u8(static_cast<int>(r % 21));
              break;
            case 2:  // bright: luma 230..255
              frame[i] =
                  chroma ? u8(static_cast<int>(r & 0xFF)) : u8(230 + static_cast<int>(r % 26));
              break;
            default:  // chroma at 0 or 255, any luma
              frame[i] = chroma ? u8((r & 1U) ? 255 : 0) : u8(static_cast<int>(r & 0xFF));
          }
        }
        for (const NamedSet& ns : sets) {
          ha::AreaVector ours, theirs;
          const std::uint32_t d =
              yuyv_area_difference(frame.data(), w, h, stride, ns.set, ours, theirs);
          EXPECT_EQ(d, 0U) << w << "x" << h << " stride " << stride << " content " << content
                           << ", windows '" << ns.name << "': ours " << areas_text(ours)
                           << " OpenCV " << areas_text(theirs);
        }
      }
    }
  }
}
