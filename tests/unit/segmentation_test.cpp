// Threshold area segmentation (Wu & Qin 2010): BoardClassifier's 8-bit HSV (OpenCV's units: H
// 0..179 in 2-degree steps, S and V 0..255), the mapping of degree windows onto those steps (with
// the wrap through 0 for reds), and pixel counts on synthetic RGB24 and YUYV frames with known
// contents. Bit-exactness against OpenCV itself is proven in segmentation_opencv_test.cpp.
#include "harmoloc/algorithms/segmentation.hpp"

#include <gtest/gtest.h>

#if defined(__linux__)
#include <sys/mman.h>
#include <unistd.h>
#endif

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include "harmoloc/algorithms/random.hpp"
#include "test_support.hpp"

namespace ha = harmoloc::algorithms;
namespace ht = harmoloc::test;

namespace {

// Reference HSV by the textbook hexcone formula in double precision, written independently
// (hue in degrees from the sector of the maximum channel, ties resolved r > g > b).
struct RefHsv {
  double h_deg, s, v;
};
RefHsv reference_hsv(int r, int g, int b) {
  const double rf = r / 255.0, gf = g / 255.0, bf = b / 255.0;
  const double mx = std::max({rf, gf, bf});
  const double mn = std::min({rf, gf, bf});
  const double c = mx - mn;
  RefHsv out{0.0, 0.0, mx * 255.0};
  if (mx <= 0.0 || c <= 0.0) return out;
  out.s = 255.0 * c / mx;
  double hp;  // hue / 60 degrees
  if (mx == rf) {
    hp = std::fmod((gf - bf) / c + 6.0, 6.0);
  } else if (mx == gf) {
    hp = (bf - rf) / c + 2.0;
  } else {
    hp = (rf - gf) / c + 4.0;
  }
  out.h_deg = 60.0 * hp;
  if (out.h_deg >= 360.0) out.h_deg -= 360.0;
  return out;
}

ha::ColourThreshold window(float h0, float h1, std::uint8_t s_min, std::uint8_t v_min,
                           std::uint8_t v_max) {
  return ha::ColourThreshold{h0, h1, s_min, v_min, v_max};
}

ha::ThresholdSet one_board(const ha::ColourThreshold& t) {
  ha::ThresholdSet set;
  set.boards[0] = t;
  set.count = 1;
  return set;
}

struct Rgb {
  std::uint8_t r, g, b;
};

// Whether the pixel @p c falls in board 0 of @p classifier.
bool in_board0(const ha::BoardClassifier& classifier, Rgb c) {
  return (classifier.classify(c.r, c.g, c.b) & 1U) != 0;
}

// The OpenCV H of @p c (to check that a test colour sits where the test says it does).
int opencv_h(const ha::BoardClassifier& classifier, Rgb c) {
  return classifier.to_hsv(c.r, c.g, c.b).h;
}

// The H steps (0..179) a degree window admits, by the documented rule written out directly:
// [ceil(min / 2), floor(max / 2)], wrapping through 0 when min > max.
bool h_in_window(int h, float min_deg, float max_deg) {
  const double lo = std::ceil(static_cast<double>(min_deg) / 2.0);
  const double hi = std::floor(static_cast<double>(max_deg) / 2.0);
  if (min_deg <= max_deg) return h >= lo && h <= hi;
  return h >= lo || h <= hi;
}

// The 1530 fully saturated, full-value colours around the hue circle (one channel 255, one 0).
std::vector<Rgb> pure_hues() {
  std::vector<Rgb> out;
  for (int i = 0; i < 255; ++i) {
    const auto u = static_cast<std::uint8_t>(i);
    const auto d = static_cast<std::uint8_t>(255 - i);
    out.push_back({255, u, 0});
    out.push_back({d, 255, 0});
    out.push_back({0, 255, u});
    out.push_back({0, d, 255});
    out.push_back({u, 0, 255});
    out.push_back({255, 0, d});
  }
  return out;
}

// Rows of pixels @p stride bytes apart in one buffer, as the segmenters take them.
class StridedImage {
 public:
  const std::uint8_t* data() const { return data_.data(); }
  std::uint32_t width() const { return w_; }
  std::uint32_t height() const { return h_; }
  std::uint32_t stride() const { return stride_; }

 protected:
  StridedImage(std::uint32_t w, std::uint32_t h, std::uint32_t stride, std::uint8_t fill)
      : w_(w), h_(h), stride_(stride), data_(static_cast<std::size_t>(stride) * h, fill) {}
  // Byte @p offset of row @p y.
  std::uint8_t* row(std::uint32_t y, std::uint32_t offset = 0) {
    return data_.data() + static_cast<std::size_t>(y) * stride_ + offset;
  }

 private:
  std::uint32_t w_, h_, stride_;
  std::vector<std::uint8_t> data_;
};

// An RGB24 image with a stride, padding filled with a colour that must never be counted.
class RgbImage : public StridedImage {
 public:
  RgbImage(std::uint32_t w, std::uint32_t h, std::uint32_t stride, Rgb background, Rgb padding)
      : StridedImage(w, h, stride, 0) {
    const std::uint8_t ch[3] = {padding.r, padding.g, padding.b};
    for (std::uint32_t y = 0; y < h; ++y) {
      for (std::uint32_t b = w * 3; b < stride; ++b) *row(y, b) = ch[(b - w * 3) % 3];
    }
    fill(0, 0, w, h, background);
  }
  void set(std::uint32_t x, std::uint32_t y, Rgb c) {
    std::uint8_t* p = row(y, 3U * x);
    p[0] = c.r;
    p[1] = c.g;
    p[2] = c.b;
  }
  void fill(std::uint32_t x0, std::uint32_t y0, std::uint32_t w, std::uint32_t h, Rgb c) {
    for (std::uint32_t y = y0; y < y0 + h; ++y) {
      for (std::uint32_t x = x0; x < x0 + w; ++x) set(x, y, c);
    }
  }
};

// A YUYV frame: macro-pixels (Y0 U Y1 V) with a stride; padding bytes are 0xEE.
class YuyvImage : public StridedImage {
 public:
  YuyvImage(std::uint32_t w, std::uint32_t h, std::uint32_t stride)
      : StridedImage(w, h, stride, 0xEE) {
    for (std::uint32_t y = 0; y < h; ++y) {
      for (std::uint32_t x = 0; x < w; x += 2) set_pair(x, y, 128, 128, 128, 128);  // grey
    }
  }
  void set_pair(std::uint32_t x, std::uint32_t y, std::uint8_t y0, std::uint8_t u, std::uint8_t y1,
                std::uint8_t v) {
    std::uint8_t* p = row(y, 2U * x);
    p[0] = y0;
    p[1] = u;
    p[2] = y1;
    p[3] = v;
  }
};

}  // namespace

// --- HSV -----------------------------------------------------------------------------------------

TEST(BoardClassifierHsv, PrimaryAndSecondaryColoursInOpencvUnits) {
  struct Case {
    Rgb c;
    int h, s, v;
  };
  const Case cases[] = {
      {{255, 0, 0}, 0, 255, 255},      // red
      {{0, 255, 0}, 60, 255, 255},     // green: 120 degrees / 2
      {{0, 0, 255}, 120, 255, 255},    // blue: 240 / 2
      {{255, 255, 0}, 30, 255, 255},   // yellow: 60 / 2
      {{0, 255, 255}, 90, 255, 255},   // cyan: 180 / 2
      {{255, 0, 255}, 150, 255, 255},  // magenta: 300 / 2
      {{128, 0, 0}, 0, 255, 128},      // dark red: value is the max channel
      {{255, 128, 128}, 0, 127, 255},  // pink: s = 255 * 127 / 255
      {{255, 0, 85}, 170, 255, 255},   // 340 degrees exactly
      {{255, 63, 0}, 7, 255, 255},     // 14.82 degrees: 7.41 rounds down
      {{240, 60, 0}, 8, 255, 240},     // 15 degrees exactly: 7.5 rounds up
      {{220, 30, 30}, 0, 220, 220},    // the scenarios' red board: s = 255 * 190 / 220 = 220.2
      {{30, 180, 40}, 62, 213, 180},   // green board: 124 degrees, s = 255 * 150 / 180 = 212.5
      {{30, 60, 220}, 115, 220, 220},  // blue board: 230.5 degrees
  };
  const ha::BoardClassifier classifier;
  for (const Case& k : cases) {
    SCOPED_TRACE(testing::Message() << int{k.c.r} << "," << int{k.c.g} << "," << int{k.c.b});
    const ha::Hsv8 hsv = classifier.to_hsv(k.c.r, k.c.g, k.c.b);
    EXPECT_EQ(int{hsv.h}, k.h);
    EXPECT_EQ(int{hsv.s}, k.s);
    EXPECT_EQ(int{hsv.v}, k.v);
  }
}

TEST(BoardClassifierHsv, GreysHaveNoSaturationAndZeroHue) {
  const ha::BoardClassifier classifier;
  for (int g : {0, 1, 77, 128, 254, 255}) {
    const auto u = static_cast<std::uint8_t>(g);
    const ha::Hsv8 hsv = classifier.to_hsv(u, u, u);
    EXPECT_EQ(int{hsv.s}, 0) << g;
    EXPECT_EQ(int{hsv.h}, 0) << g;
    EXPECT_EQ(int{hsv.v}, g) << g;
  }
}

TEST(BoardClassifierHsv, RoundsTheTextbookFormulaAndStaysInRange) {
  // OpenCV's fixed point (12-bit reciprocal tables, then round) lands within half a step of the
  // exact value plus the tables' own rounding: at most 0.64 of an H step and 0.53 of S over all
  // colours. A wrong sector or scale is off by far more.
  const ha::BoardClassifier classifier;
  ha::Pcg32 rng(12345);
  for (int i = 0; i < 50000; ++i) {
    const auto r = static_cast<int>(rng.next_u32() & 0xFFU);
    const auto g = static_cast<int>(rng.next_u32() & 0xFFU);
    const auto b = static_cast<int>(rng.next_u32() & 0xFFU);
    const ha::Hsv8 hsv = classifier.to_hsv(
        static_cast<std::uint8_t>(r), static_cast<std::uint8_t>(g), static_cast<std::uint8_t>(b));
    const RefHsv ref = reference_hsv(r, g, b);
    ASSERT_LT(int{hsv.h}, 180) << r << "," << g << "," << b;
    // H compared on the circle of 180 steps (179.9 and 0 are neighbours).
    double dh = std::fabs(hsv.h - ref.h_deg / 2.0);
    dh = std::min(dh, 180.0 - dh);
    ASSERT_LE(dh, 0.65) << r << "," << g << "," << b;
    ASSERT_LE(std::fabs(hsv.s - ref.s), 0.53) << r << "," << g << "," << b;
    ASSERT_EQ(int{hsv.v}, std::max({r, g, b})) << r << "," << g << "," << b;
  }
}

TEST(BoardClassifierHsv, EveryHueStepIsReachedInOrderAroundTheCircle) {
  // Walking the saturated colours around the circle, H never steps back (except once through
  // 0) and takes every value 0..179.
  const ha::BoardClassifier classifier;
  std::vector<Rgb> hues = pure_hues();
  std::vector<bool> seen(180, false);
  for (const Rgb& c : hues) {
    const ha::Hsv8 hsv = classifier.to_hsv(c.r, c.g, c.b);
    ASSERT_LT(int{hsv.h}, 180);
    EXPECT_EQ(int{hsv.s}, 255);
    EXPECT_EQ(int{hsv.v}, 255);
    seen[hsv.h] = true;
  }
  for (int h = 0; h < 180; ++h) EXPECT_TRUE(seen[static_cast<std::size_t>(h)]) << h;
}

// --- windows -------------------------------------------------------------------------------------

TEST(BoardClassifierWindow, GreenWindowIsHFiftyToSeventyTwoInclusive) {
  // [100, 145] degrees -> H in [ceil(50), floor(72.5)] = [50, 72].
  const ha::BoardClassifier c(one_board(window(100.0F, 145.0F, 110, 60, 255)));
  struct Case {
    Rgb colour;
    int h;
    bool in;
  };
  const Case cases[] = {
      {{93, 255, 0}, 49, false},   // 98.1 degrees
      {{90, 255, 0}, 49, false},   // 98.8 degrees: 49.41, the last colour of max 255 below 50
      {{89, 255, 0}, 50, true},    // 99.1 degrees: 49.53 rounds to 50, inside though below 100
      {{84, 240, 0}, 50, true},    // 99 degrees exactly: 49.5 rounds to 50
      {{80, 240, 0}, 50, true},    // 100 degrees exactly
      {{0, 255, 0}, 60, true},     // the middle
      {{0, 255, 102}, 72, true},   // 144 degrees exactly
      {{0, 255, 106}, 72, true},   // 144.9 degrees
      {{0, 255, 107}, 73, false},  // 145.2 degrees
      {{0, 240, 100}, 73, false},  // 145 degrees exactly: 72.5 rounds to 73, outside
      {{0, 255, 110}, 73, false},
  };
  for (const Case& k : cases) {
    SCOPED_TRACE(testing::Message()
                 << int{k.colour.r} << "," << int{k.colour.g} << "," << int{k.colour.b});
    ASSERT_EQ(opencv_h(c, k.colour), k.h);
    EXPECT_EQ(in_board0(c, k.colour), k.in);
  }
}

TEST(BoardClassifierWindow, RedWindowWrapsThroughZero) {
  // [340, 15] degrees -> H >= 170 or H <= 7.
  const ha::BoardClassifier c(one_board(window(340.0F, 15.0F, 100, 50, 255)));
  struct Case {
    Rgb colour;
    int h;
    bool in;
  };
  const Case cases[] = {
      {{255, 0, 0}, 0, true},     {{255, 63, 0}, 7, true},  // 14.8 degrees
      {{255, 64, 0}, 8, false},                             // 15.1 degrees
      {{240, 60, 0}, 8, false},    // 15 degrees exactly: 7.5 rounds to 8, outside
      {{255, 0, 85}, 170, true},   // 340 degrees exactly
      {{255, 0, 89}, 170, true},   // 339.1 degrees: 169.53 rounds to 170
      {{255, 0, 90}, 169, false},  // 338.8 degrees
      {{255, 0, 30}, 176, true},   // 352.9 degrees
      {{0, 255, 255}, 90, false},  // cyan, opposite
  };
  for (const Case& k : cases) {
    SCOPED_TRACE(testing::Message()
                 << int{k.colour.r} << "," << int{k.colour.g} << "," << int{k.colour.b});
    ASSERT_EQ(opencv_h(c, k.colour), k.h);
    EXPECT_EQ(in_board0(c, k.colour), k.in);
  }

  // The same window without the wrap, 15..340 degrees: H 8..170, everything but the reds, and
  // 170 (340 degrees) belongs to both.
  const ha::BoardClassifier not_red(one_board(window(15.0F, 340.0F, 100, 50, 255)));
  EXPECT_FALSE(in_board0(not_red, {255, 0, 0}));
  EXPECT_FALSE(in_board0(not_red, {255, 63, 0}));
  EXPECT_TRUE(in_board0(not_red, {255, 64, 0}));
  EXPECT_TRUE(in_board0(not_red, {0, 255, 255}));
  EXPECT_TRUE(in_board0(not_red, {255, 0, 85}));
  EXPECT_FALSE(in_board0(not_red, {255, 0, 30}));
}

TEST(BoardClassifierWindow, DegreeWindowsMapOntoHStepsForEveryH) {
  // For every H step and a range of windows (odd and even ends, fractions, empty, wrapping,
  // full circle), a saturated colour with that H is in exactly when the documented rule says.
  const ha::BoardClassifier probe;
  std::vector<Rgb> by_h(180, Rgb{0, 0, 0});
  for (const Rgb& c : pure_hues()) by_h[probe.to_hsv(c.r, c.g, c.b).h] = c;

  const float windows[][2] = {{100, 145},       {99, 145},       {101, 145}, {100, 144}, {100, 143},
                              {340, 15},        {341, 14},       {339, 16},  {0, 360},   {0, 359},
                              {0, 0},           {1, 1},          {2, 2},     {358, 2},   {359, 0},
                              {179.5F, 180.5F}, {99.9F, 100.1F}, {200, 199}, {45, 70},   {215, 250},
                              {285, 320},       {170, 200}};
  for (const auto& w : windows) {
    SCOPED_TRACE(testing::Message() << "[" << w[0] << ", " << w[1] << "]");
    const ha::BoardClassifier c(one_board(window(w[0], w[1], 0, 0, 255)));
    int inside = 0;
    for (int h = 0; h < 180; ++h) {
      const Rgb colour = by_h[static_cast<std::size_t>(h)];
      ASSERT_EQ(opencv_h(c, colour), h);
      EXPECT_EQ(in_board0(c, colour), h_in_window(h, w[0], w[1])) << "H " << h;
      inside += in_board0(c, colour) ? 1 : 0;
    }
    if (w[0] == 0.0F && w[1] == 360.0F) {
      EXPECT_EQ(inside, 180);
    }
    if (w[0] == 1.0F && w[1] == 1.0F) {
      EXPECT_EQ(inside, 0);  // ceil(0.5) = 1 > floor(0.5) = 0
    }
  }
}

TEST(BoardClassifierWindow, SaturationAndValueBoundsAreInclusive) {
  const ha::BoardClassifier t(one_board(window(340.0F, 15.0F, 100, 50, 200)));
  const ha::BoardClassifier s_only(one_board(window(340.0F, 15.0F, 100, 0, 255)));
  // Saturation = 255 * (max - min) / max: with max 255, s = max - min.
  EXPECT_TRUE(in_board0(s_only, {255, 155, 155}));   // s = 100 exactly
  EXPECT_FALSE(in_board0(s_only, {255, 156, 156}));  // s = 99
  EXPECT_TRUE(in_board0(t, {50, 0, 0}));             // v = 50 = value_min
  EXPECT_FALSE(in_board0(t, {49, 0, 0}));            // v below
  EXPECT_TRUE(in_board0(t, {200, 0, 0}));            // v = 200 = value_max
  EXPECT_FALSE(in_board0(t, {201, 0, 0}));           // v above
  EXPECT_FALSE(in_board0(t, {0, 0, 0}));             // black is no colour

  // A single admitted value, and an empty value range.
  const ha::BoardClassifier v_one(one_board(window(340.0F, 15.0F, 0, 128, 128)));
  EXPECT_TRUE(in_board0(v_one, {128, 0, 0}));
  EXPECT_FALSE(in_board0(v_one, {127, 0, 0}));
  EXPECT_FALSE(in_board0(v_one, {129, 0, 0}));
  const ha::BoardClassifier v_none(one_board(window(340.0F, 15.0F, 0, 129, 128)));
  EXPECT_FALSE(in_board0(v_none, {128, 0, 0}));
  EXPECT_FALSE(in_board0(v_none, {129, 0, 0}));
  // s_min 255 admits only colours with a zero channel; s_min 0 admits greys (H 0).
  const ha::BoardClassifier s_full(one_board(window(340.0F, 15.0F, 255, 0, 255)));
  EXPECT_TRUE(in_board0(s_full, {90, 0, 0}));
  EXPECT_FALSE(in_board0(s_full, {90, 1, 1}));
  const ha::BoardClassifier s_zero(one_board(window(340.0F, 15.0F, 0, 0, 255)));
  EXPECT_TRUE(in_board0(s_zero, {90, 90, 90}));
  EXPECT_TRUE(in_board0(s_zero, {0, 0, 0}));
}

TEST(BoardClassifierWindow, BoardsAreIndependentBitsAndRebuildingForgetsTheOldSet) {
  ha::ThresholdSet set = ht::board_windows();  // red, green, blue, yellow, magenta, cyan
  set.count = 8;
  set.boards[6] = window(0.0F, 360.0F, 0, 0, 255);   // everything
  set.boards[7] = window(100.0F, 145.0F, 0, 0, 40);  // dark greens only
  ha::BoardClassifier c(set);
  EXPECT_EQ(c.board_count(), 8U);
  EXPECT_EQ(int{c.classify(255, 0, 0)}, 0x01 | 0x40);
  EXPECT_EQ(int{c.classify(0, 255, 0)}, 0x02 | 0x40);
  EXPECT_EQ(int{c.classify(0, 0, 255)}, 0x04 | 0x40);  // H 120, inside blue's 108..125
  EXPECT_EQ(int{c.classify(30, 60, 220)}, 0x04 | 0x40);
  EXPECT_EQ(int{c.classify(255, 255, 0)}, 0x08 | 0x40);
  EXPECT_EQ(int{c.classify(255, 0, 255)}, 0x10 | 0x40);
  EXPECT_EQ(int{c.classify(0, 255, 255)}, 0x20 | 0x40);
  EXPECT_EQ(int{c.classify(0, 40, 0)}, 0x40 | 0x80);  // green but too dark for board 1
  EXPECT_EQ(int{c.classify(128, 128, 128)}, 0x40);

  c.build(ht::board_windows(1));  // red only
  EXPECT_EQ(c.board_count(), 1U);
  EXPECT_EQ(int{c.classify(255, 0, 0)}, 0x01);
  EXPECT_EQ(int{c.classify(0, 255, 0)}, 0);
  EXPECT_EQ(int{c.classify(0, 40, 0)}, 0);
  EXPECT_EQ(int{c.classify(128, 128, 128)}, 0);

  c.build(ha::ThresholdSet{});
  EXPECT_EQ(c.board_count(), 0U);
  EXPECT_EQ(int{c.classify(255, 0, 0)}, 0);
}

// --- segmentation --------------------------------------------------------------------------------

TEST(SegmentRgb24, CountsRectanglesOfKnownSizeAndIgnoresRowPadding) {
  const Rgb grey{100, 100, 100};
  const Rgb red{220, 30, 30};
  const Rgb green{30, 180, 40};
  const Rgb blue{30, 60, 220};
  // 40x30 with 7 bytes of padding a row, all pure red: must not be counted.
  RgbImage img(40, 30, 40 * 3 + 7, grey, Rgb{255, 0, 0});
  img.fill(3, 4, 10, 5, red);              // 50 px
  img.fill(20, 10, 7, 3, green);           // 21 px
  img.set(39, 29, blue);                   // the very last pixel: 1 px
  img.set(0, 0, blue);                     // the very first pixel: 1 px
  img.fill(30, 0, 2, 2, Rgb{255, 63, 0});  // H 7, on red's last step: 4 px counted as red
  img.fill(30, 5, 3, 1, Rgb{240, 60, 0});  // 15 degrees exactly, H 8: 3 px not red
  img.fill(30, 7, 3, 1, Rgb{255, 0, 85});  // 340 degrees, H 170, red's first step: 3 px red
  img.fill(30, 9, 5, 1, Rgb{255, 0, 90});  // H 169, just outside: 5 px not red

  ha::ThresholdSet set = ht::board_windows(3);  // red, green, blue
  set.count = 4;
  set.boards[3] = window(0.0F, 360.0F, 0, 0, 255);  // everything: boards are counted independently

  ha::AreaVector areas;
  areas.pixels.fill(777U);  // stale values must be cleared
  ha::segment_rgb24(img.data(), img.width(), img.height(), img.stride(), set, areas);
  EXPECT_EQ(areas.count, 4U);
  EXPECT_EQ(areas.pixels[0], 50U + 4U + 3U);
  EXPECT_EQ(areas.pixels[1], 21U);
  EXPECT_EQ(areas.pixels[2], 2U);
  EXPECT_EQ(areas.pixels[3], 40U * 30U);
  for (std::size_t k = 4; k < ha::kMaxBoards; ++k) EXPECT_EQ(areas.pixels[k], 0U) << k;

  // Columns: red 5 rows of x 3..12, 2 rows of x 30..31, one row of x 30..32; green 3 rows of
  // x 20..26; blue the two corner pixels (x 0 and 39), both on a side; everything 30 rows of
  // x 0..39, 60 pixels on the sides.
  EXPECT_EQ(areas.width_px, 40U);
  EXPECT_TRUE(areas.columns_measured());
  EXPECT_EQ(areas.column_sum[0], 5U * 75U + 2U * 61U + 93U);
  EXPECT_EQ(areas.column_sum[1], 3U * 161U);
  EXPECT_EQ(areas.column_sum[2], 39U);
  EXPECT_EQ(areas.column_sum[3], 30U * 780U);
  EXPECT_DOUBLE_EQ(areas.centroid_column_px(3), 19.5);  // (width - 1) / 2
  EXPECT_DOUBLE_EQ(areas.centroid_column_px(1), 23.0);
  EXPECT_EQ(areas.side_pixels[0], 0U);
  EXPECT_EQ(areas.side_pixels[1], 0U);
  EXPECT_EQ(areas.side_pixels[2], 2U);
  EXPECT_EQ(areas.side_pixels[3], 60U);
  // Rows: red 10 pixels in each of rows 4..8, 2 in rows 0 and 1, 3 in row 7; green 7 in each of
  // rows 10..12; blue rows 0 and 29; everything 40 in each of rows 0..29.
  EXPECT_EQ(areas.height_px, 30U);
  EXPECT_TRUE(areas.rows_measured());
  EXPECT_EQ(areas.row_sum[0], 10U * 30U + 2U * 1U + 3U * 7U);
  EXPECT_EQ(areas.row_sum[1], 7U * 33U);
  EXPECT_EQ(areas.row_sum[2], 29U);
  EXPECT_EQ(areas.row_sum[3], 40U * 435U);
  EXPECT_DOUBLE_EQ(areas.centroid_row_px(3), 14.5);  // (height - 1) / 2
  EXPECT_DOUBLE_EQ(areas.centroid_row_px(1), 11.0);
  for (std::size_t k = 4; k < ha::kMaxBoards; ++k) {
    EXPECT_EQ(areas.column_sum[k], 0U) << k;
    EXPECT_EQ(areas.side_pixels[k], 0U) << k;
    EXPECT_EQ(areas.row_sum[k], 0U) << k;
  }

  // The classifier compiled once gives the same areas as the convenience overload.
  const ha::BoardClassifier classifier(set);
  ha::AreaVector again;
  again.pixels.fill(777U);
  again.column_sum.fill(777U);
  again.side_pixels.fill(777U);
  again.row_sum.fill(777U);
  ha::segment_rgb24(img.data(), img.width(), img.height(), img.stride(), classifier, again);
  EXPECT_EQ(again.count, areas.count);
  EXPECT_EQ(again.pixels, areas.pixels);
  EXPECT_EQ(again.column_sum, areas.column_sum);
  EXPECT_EQ(again.side_pixels, areas.side_pixels);
  EXPECT_EQ(again.row_sum, areas.row_sum);
  EXPECT_EQ(again.width_px, areas.width_px);
  EXPECT_EQ(again.height_px, areas.height_px);
}

TEST(SegmentRgb24, OneColumnFrameCountsItsPixelsOnceAsSidePixels) {
  RgbImage img(1, 5, 3, Rgb{220, 30, 30}, Rgb{0, 0, 0});
  ha::AreaVector areas;
  ha::segment_rgb24(img.data(), 1, 5, 3, ht::board_windows(1), areas);
  EXPECT_EQ(areas.pixels[0], 5U);
  EXPECT_EQ(areas.column_sum[0], 0U);
  EXPECT_EQ(areas.side_pixels[0], 5U);
  EXPECT_EQ(areas.width_px, 1U);
  EXPECT_EQ(areas.row_sum[0], 0U + 1U + 2U + 3U + 4U);
  EXPECT_EQ(areas.height_px, 5U);
}

TEST(SegmentRgb24, EmptyThresholdSetAndEmptyImage) {
  RgbImage img(8, 4, 24, Rgb{255, 0, 0}, Rgb{0, 0, 0});
  ha::ThresholdSet none;
  ha::AreaVector areas;
  ha::segment_rgb24(img.data(), img.width(), img.height(), img.stride(), none, areas);
  EXPECT_EQ(areas.count, 0U);
  const ha::ThresholdSet one = ht::board_windows(1);  // red
  ha::segment_rgb24(img.data(), 0, 0, img.stride(), one, areas);
  EXPECT_EQ(areas.count, 1U);
  EXPECT_EQ(areas.pixels[0], 0U);
  ha::segment_rgb24(img.data(), img.width(), img.height(), img.stride(), one, areas);
  EXPECT_EQ(areas.pixels[0], 32U);
}

TEST(SegmentRgb24, CountsEveryBoardForEveryHStep) {
  // One row of all 1530 saturated colours: each board's area is the number of those colours
  // whose H lies in its window, by the rule (the classifier's H is checked above).
  const std::vector<Rgb> hues = pure_hues();
  RgbImage img(static_cast<std::uint32_t>(hues.size()), 1,
               static_cast<std::uint32_t>(hues.size() * 3), Rgb{0, 0, 0}, Rgb{0, 0, 0});
  for (std::size_t x = 0; x < hues.size(); ++x) img.set(static_cast<std::uint32_t>(x), 0, hues[x]);
  const ha::ThresholdSet set = ht::board_windows();
  const ha::BoardClassifier probe;
  ha::AreaVector areas;
  ha::segment_rgb24(img.data(), img.width(), img.height(), img.stride(), set, areas);
  ASSERT_EQ(areas.count, 6U);
  for (std::size_t k = 0; k < 6; ++k) {
    std::uint32_t expected = 0;
    for (const Rgb& c : hues) {
      expected += h_in_window(probe.to_hsv(c.r, c.g, c.b).h, ht::kBoardHuesDeg[k][0],
                              ht::kBoardHuesDeg[k][1])
                      ? 1U
                      : 0U;
    }
    EXPECT_EQ(areas.pixels[k], expected) << "board " << k;
    EXPECT_GT(expected, 50U) << "board " << k;  // every board spans 12 or more H steps
  }
}

TEST(SegmentYuyv, CountsKnownColoursWithPerPixelLuma) {
  // BT.601 limited range, by hand (R = (298 (Y-16) + 409 (V-128) + 128) >> 8, and so on; OpenCV's
  // 20-bit coefficients give the same colours to within 1 and the same classes):
  //   Y=81  U=90  V=240 -> (255, 0, 0)    red, H 0
  //   Y=145 U=54  V=34  -> (0, 255, 1)    green, H 60
  //   Y=41  U=240 V=110 -> (0, 0, 255)    blue, H 120
  //   Y=235 U=90  V=240 -> (255, 179, 178) a pale pink: saturation 77, not red
  //   Y=128 U=128 V=128 -> (130, 130, 130) grey
  YuyvImage img(16, 4, 16 * 2 + 4);
  for (std::uint32_t x = 0; x < 8; x += 2) img.set_pair(x, 0, 81, 90, 81, 240);   // 8 red
  for (std::uint32_t x = 4; x < 8; x += 2) img.set_pair(x, 1, 145, 54, 145, 34);  // 4 green
  img.set_pair(14, 3, 41, 240, 41, 110);  // 2 blue (row end)
  img.set_pair(10, 2, 235, 90, 81, 240);  // shared red chroma: pink then red -> 1 red
  img.set_pair(12, 2, 81, 90, 235, 240);  // red then pink -> 1 red

  ha::ThresholdSet set = ht::board_windows(3);  // red, green, blue
  set.count = 4;
  set.boards[3] = window(0.0F, 360.0F, 0, 125, 135);  // the grey background (v = 130) only
  ha::AreaVector areas;
  ha::segment_yuyv(img.data(), img.width(), img.height(), img.stride(), set, areas);
  EXPECT_EQ(areas.count, 4U);
  EXPECT_EQ(areas.pixels[0], 8U + 2U);
  EXPECT_EQ(areas.pixels[1], 4U);
  EXPECT_EQ(areas.pixels[2], 2U);
  // 64 pixels, of which 8 red + 4 green + 2 blue + 4 in the two mixed pairs are not grey.
  EXPECT_EQ(areas.pixels[3], 64U - 18U);

  const ha::BoardClassifier classifier(set);
  ha::AreaVector again;
  ha::segment_yuyv(img.data(), img.width(), img.height(), img.stride(), classifier, again);
  EXPECT_EQ(again.pixels, areas.pixels);
}

TEST(SegmentYuyv, OddWidthUsesTheLastPairsFirstPixelOnly) {
  // Width 5: the third macro-pixel's second luma is beyond the image and must not be counted.
  YuyvImage img(5, 2, 16);
  img.set_pair(4, 0, 81, 90, 81, 240);   // red, red (second outside)
  img.set_pair(4, 1, 235, 90, 81, 240);  // pink, red (second outside)
  const ha::ThresholdSet set = ht::board_windows(1);
  ha::AreaVector areas;
  ha::segment_yuyv(img.data(), img.width(), img.height(), img.stride(), set, areas);
  EXPECT_EQ(areas.pixels[0], 1U);
}

TEST(SegmentYuyv, AgreesWithRgbOfTheSameFrame) {
  // Convert a YUYV frame to RGB with segment_yuyv's documented integer formula written out
  // independently in double precision, then segment both: the counts must agree exactly.
  const std::uint32_t w = 32, h = 8;
  YuyvImage img(w, h, w * 2);
  ha::Pcg32 rng(7);
  for (std::uint32_t y = 0; y < h; ++y) {
    for (std::uint32_t x = 0; x < w; x += 2) {
      img.set_pair(x, y, static_cast<std::uint8_t>(16 + rng.next_u32() % 220),
                   static_cast<std::uint8_t>(rng.next_u32()),
                   static_cast<std::uint8_t>(16 + rng.next_u32() % 220),
                   static_cast<std::uint8_t>(rng.next_u32()));
    }
  }
  std::vector<std::uint8_t> rgb(static_cast<std::size_t>(w) * h * 3);
  for (std::uint32_t y = 0; y < h; ++y) {
    for (std::uint32_t x = 0; x < w; ++x) {
      const std::uint8_t* p =
          img.data() + static_cast<std::size_t>(y) * img.stride() + 4U * (x / 2U);
      const int yy = p[(x % 2U) * 2U], u = p[1] - 128, v = p[3] - 128;
      // OpenCV's COLOR_YUV2RGB_YUYV in 20-bit fixed point, written out in double precision.
      const double c = std::max(0, yy - 16) * 1220542.0 + 524288.0;
      auto clamp = [](int q) { return static_cast<std::uint8_t>(std::clamp(q, 0, 255)); };
      auto div20 = [](double q) { return static_cast<int>(std::floor(q / 1048576.0)); };
      std::uint8_t* o = rgb.data() + (static_cast<std::size_t>(y) * w + x) * 3U;
      o[0] = clamp(div20(c + 1673527.0 * v));
      o[1] = clamp(div20(c - 852492.0 * v - 409993.0 * u));
      o[2] = clamp(div20(c + 2116026.0 * u));
    }
  }
  const ha::ThresholdSet set = ht::board_windows();  // the six boards
  ha::AreaVector from_yuyv, from_rgb;
  ha::segment_yuyv(img.data(), w, h, img.stride(), set, from_yuyv);
  ha::segment_rgb24(rgb.data(), w, h, w * 3, set, from_rgb);
  std::uint32_t total = 0;
  for (std::size_t k = 0; k < set.count; ++k) {
    EXPECT_EQ(from_yuyv.pixels[k], from_rgb.pixels[k]) << "board " << k;
    total += from_rgb.pixels[k];
  }
  EXPECT_GT(total, 0U);  // the random frame does hit some windows
}

// --- colour tables and SIMD paths ----------------------------------------------------------------
// Every path a table can take (scalar everywhere, AVX2 on x86-64 CPUs that have it, NEON on ARM)
// must give the areas the HSV arithmetic gives, on frames chosen to break the SIMD code: widths
// around its 32-pixel blocks and 256-pixel row chunks, padded, overlapping and zero strides,
// colours on the windows' edges, every board count (the kernels are compiled per count), and
// counters filled past their flush points.

namespace {

std::vector<ha::SegmentPath> supported_paths() {
  std::vector<ha::SegmentPath> out;
  for (ha::SegmentPath p :
       {ha::SegmentPath::kScalar, ha::SegmentPath::kAvx2, ha::SegmentPath::kNeon})
    if (ha::segment_path_supported(p)) out.push_back(p);
  return out;
}

// The six boards, then everything, then dark greens: boards overlap, so a pixel's class has up to
// 8 bits and each counts.
ha::ThresholdSet eight_boards() {
  ha::ThresholdSet set = ht::board_windows();
  set.count = 8;
  set.boards[6] = window(0.0F, 360.0F, 0, 0, 255);
  set.boards[7] = window(100.0F, 145.0F, 0, 0, 40);
  return set;
}

// The first @p count of eight_boards().
ha::ThresholdSet first_boards(std::size_t count) {
  ha::ThresholdSet set = eight_boards();
  set.count = count;
  return set;
}

// Both tables of a threshold set, built once per test binary (16 MiB each).
struct Tables {
  ha::BoardClassifier classifier;
  std::vector<std::uint8_t> rgb_storage, yuyv_storage;
  ha::ColourTable rgb;
  ha::YuyvTable yuyv;
  explicit Tables(const ha::ThresholdSet& set)
      : classifier(set),
        rgb_storage(ha::MaskTable::kStorageBytes),
        yuyv_storage(ha::MaskTable::kStorageBytes) {
    rgb.build(classifier, rgb_storage.data());
    yuyv.build(classifier, yuyv_storage.data());
  }
};

Tables& tables_with_boards(std::size_t count) {
  static std::vector<std::unique_ptr<Tables>> cache(ha::kMaxBoards + 1);
  auto& slot = cache.at(count);
  if (!slot) slot = std::make_unique<Tables>(first_boards(count));
  return *slot;
}

// Colours whose HSV lies on an edge of one of @p set's windows (H on ceil(min / 2) - 1,
// ceil(min / 2), floor(max / 2), floor(max / 2) + 1; S on s_min - 1 or s_min; V on v_min - 1,
// v_min, v_max or v_max + 1), taken from a lattice of colours.
std::vector<Rgb> edge_colours(const ha::ThresholdSet& set) {
  const ha::BoardClassifier probe;
  std::vector<bool> h_edge(180, false), s_edge(256, false), v_edge(256, false);
  for (std::size_t k = 0; k < set.count; ++k) {
    const ha::ColourThreshold& t = set.boards[k];
    const int lo = static_cast<int>(std::ceil(t.hue_min_deg / 2.0F));
    const int hi = static_cast<int>(std::floor(t.hue_max_deg / 2.0F));
    for (int h : {lo - 1, lo, hi, hi + 1}) h_edge[static_cast<std::size_t>((h + 180) % 180)] = true;
    for (int s : {t.saturation_min - 1, int{t.saturation_min}})
      if (s >= 0) s_edge[static_cast<std::size_t>(s)] = true;
    for (int v : {t.value_min - 1, int{t.value_min}, int{t.value_max}, t.value_max + 1})
      if (v >= 0 && v < 256) v_edge[static_cast<std::size_t>(v)] = true;
  }
  std::vector<Rgb> out;
  for (int r = 0; r < 256; r += 3) {
    for (int g = 1; g < 256; g += 3) {
      for (int b = 2; b < 256; b += 5) {
        const Rgb c{static_cast<std::uint8_t>(r), static_cast<std::uint8_t>(g),
                    static_cast<std::uint8_t>(b)};
        const ha::Hsv8 hsv = probe.to_hsv(c.r, c.g, c.b);
        if (h_edge[hsv.h] || s_edge[hsv.s] || v_edge[hsv.v]) out.push_back(c);
      }
    }
  }
  return out;
}

// (Y, U, V) triples that decode to a colour on an edge, from a lattice of triples.
std::vector<std::array<std::uint8_t, 3>> edge_triples(const ha::ThresholdSet& set) {
  const ha::BoardClassifier probe(set);
  std::vector<std::array<std::uint8_t, 3>> out;
  // A decoded colour counts as an edge when a neighbouring luma step changes its class.
  for (int y = 0; y < 256; y += 1) {
    for (int u = 0; u < 256; u += 7) {
      for (int v = 3; v < 256; v += 7) {
        const auto c0 =
            ha::yuv_to_rgb_opencv(static_cast<std::uint8_t>(y), static_cast<std::uint8_t>(u),
                                  static_cast<std::uint8_t>(v));
        const auto c1 =
            ha::yuv_to_rgb_opencv(static_cast<std::uint8_t>(std::min(y + 1, 255)),
                                  static_cast<std::uint8_t>(u), static_cast<std::uint8_t>(v));
        if (probe.classify(c0.r, c0.g, c0.b) != probe.classify(c1.r, c1.g, c1.b)) {
          out.push_back({static_cast<std::uint8_t>(y), static_cast<std::uint8_t>(u),
                         static_cast<std::uint8_t>(v)});
        }
      }
    }
  }
  return out;
}

enum class Content { kRandom, kBlack, kWhite, kSaturated, kEdges };
const char* content_name(Content c) {
  switch (c) {
    case Content::kRandom:
      return "random";
    case Content::kBlack:
      return "black";
    case Content::kWhite:
      return "white";
    case Content::kSaturated:
      return "saturated";
    case Content::kEdges:
      return "edges";
  }
  return "?";
}

// Fills @p n bytes of frame (@p yuyv or RGB24) with @p content; padding bytes get random values
// too, which a segmenter reading them would count.
void fill_frame(std::uint8_t* bytes, std::size_t n, bool yuyv, Content content, ha::Pcg32& rng,
                const std::vector<Rgb>& rgb_edges,
                const std::vector<std::array<std::uint8_t, 3>>& yuv_edges) {
  static const Rgb kSaturated[] = {{255, 0, 0},   {0, 255, 0},   {0, 0, 255},  {255, 255, 0},
                                   {0, 255, 255}, {255, 0, 255}, {220, 30, 30}};
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t r = rng.next_u32();
    switch (content) {
      case Content::kRandom:
        bytes[i] = static_cast<std::uint8_t>(r);
        break;
      case Content::kBlack:  // YUYV: luma 0 (below 16, clamped) and 16 alike; neutral chroma
        bytes[i] = yuyv ? static_cast<std::uint8_t>(i % 2 == 1 ? 128 : (r & 1U) * 16U) : 0;
        break;
      case Content::kWhite:
        bytes[i] = yuyv ? static_cast<std::uint8_t>(i % 2 == 1 ? 128 : 235 + r % 21) : 255;
        break;
      case Content::kSaturated:
        if (yuyv) {  // chroma at its extremes
          bytes[i] = static_cast<std::uint8_t>(i % 2 == 1 ? ((r & 1U) ? 255 : 0) : r % 256);
        } else {
          const Rgb& c = kSaturated[(i / 3) % std::size(kSaturated)];
          bytes[i] = i % 3 == 0 ? c.r : i % 3 == 1 ? c.g : c.b;
        }
        break;
      case Content::kEdges:
        if (yuyv) {
          // Pairs Y0 U Y1 V: both lumas and the chroma from edge triples sharing it.
          const auto& t = yuv_edges[(i / 4) % yuv_edges.size()];
          const std::size_t k = i % 4;
          bytes[i] = k == 1 ? t[1] : k == 3 ? t[2] : static_cast<std::uint8_t>(t[0] + (k == 2));
        } else {
          const Rgb& c = rgb_edges[(i / 3 * 7919) % rgb_edges.size()];
          bytes[i] = i % 3 == 0 ? c.r : i % 3 == 1 ? c.g : c.b;
        }
        break;
    }
  }
}

// Segments the frame on every supported path of @p tables and with the HSV arithmetic; all equal.
// Returns the pixels counted over all boards (to check that a frame does hit windows).
std::uint64_t expect_paths_agree(const std::uint8_t* data, std::uint32_t w, std::uint32_t h,
                                 std::uint32_t stride, bool yuyv, Tables& tables,
                                 const std::string& what) {
  ha::AreaVector reference;
  if (yuyv)
    ha::segment_yuyv(data, w, h, stride, tables.classifier, reference);
  else
    ha::segment_rgb24(data, w, h, stride, tables.classifier, reference);
  for (ha::SegmentPath path : supported_paths()) {
    ha::AreaVector areas;
    areas.pixels.fill(12345U);  // stale values must be cleared
    areas.column_sum.fill(12345U);
    areas.side_pixels.fill(12345U);
    areas.row_sum.fill(12345U);
    if (yuyv) {
      EXPECT_TRUE(tables.yuyv.set_path(path));
      ha::segment_yuyv(data, w, h, stride, tables.yuyv, areas);
    } else {
      EXPECT_TRUE(tables.rgb.set_path(path));
      ha::segment_rgb24(data, w, h, stride, tables.rgb, areas);
    }
    EXPECT_EQ(areas.count, reference.count) << what;
    EXPECT_EQ(areas.pixels, reference.pixels)
        << what << ", path " << ha::segment_path_name(path) << ", areas [0] " << areas.pixels[0]
        << " expected " << reference.pixels[0];
    EXPECT_EQ(areas.column_sum, reference.column_sum)
        << what << ", path " << ha::segment_path_name(path) << ", columns [0] "
        << areas.column_sum[0] << " expected " << reference.column_sum[0];
    EXPECT_EQ(areas.side_pixels, reference.side_pixels)
        << what << ", path " << ha::segment_path_name(path);
    EXPECT_EQ(areas.row_sum, reference.row_sum)
        << what << ", path " << ha::segment_path_name(path) << ", rows [0] " << areas.row_sum[0]
        << " expected " << reference.row_sum[0];
    EXPECT_EQ(areas.width_px, w) << what;
    EXPECT_EQ(areas.height_px, h) << what;
  }
  tables.rgb.set_path(ha::best_segment_path());
  tables.yuyv.set_path(ha::best_segment_path());
  std::uint64_t total = 0;
  for (std::size_t k = 0; k < reference.count; ++k) total += reference.pixels[k];
  return total;
}

std::uint32_t row_bytes(std::uint32_t w, bool yuyv) {
  return yuyv ? 4U * ((w + 1U) / 2U) : 3U * w;
}

// Widths around the AVX2 path's 32-pixel blocks and 15-block flushes and the NEON path's
// 256-pixel chunks and 16-byte vectors.
const std::uint32_t kWidths[] = {1,   2,   3,   4,   5,   7,   8,   15,  16,  17,  31,  32,
                                 33,  34,  47,  63,  64,  65,  95,  96,  97,  100, 127, 128,
                                 129, 255, 256, 257, 479, 480, 481, 500, 513, 640, 1000};

}  // namespace

TEST(SegmentPaths, ScalarAlwaysAndTheBestIsSupported) {
  EXPECT_TRUE(ha::segment_path_supported(ha::SegmentPath::kScalar));
  EXPECT_TRUE(ha::segment_path_supported(ha::best_segment_path()));
#if defined(__aarch64__)
  EXPECT_EQ(ha::best_segment_path(), ha::SegmentPath::kNeon);  // every AArch64 CPU has NEON
#endif
#if !defined(__x86_64__)
  EXPECT_FALSE(ha::segment_path_supported(ha::SegmentPath::kAvx2));
#endif
#if !defined(__ARM_NEON)
  EXPECT_FALSE(ha::segment_path_supported(ha::SegmentPath::kNeon));
#endif
  std::printf("segmentation paths here:");
  for (ha::SegmentPath p : supported_paths()) std::printf(" %s", ha::segment_path_name(p));
  std::printf(" (best %s)\n", ha::segment_path_name(ha::best_segment_path()));

  Tables& t = tables_with_boards(6);
  EXPECT_EQ(t.rgb.path(), ha::best_segment_path());
  EXPECT_EQ(t.yuyv.path(), ha::best_segment_path());
  for (ha::SegmentPath p : {ha::SegmentPath::kAvx2, ha::SegmentPath::kNeon}) {
    if (ha::segment_path_supported(p)) continue;
    EXPECT_FALSE(t.rgb.set_path(p));  // refused, and the path stays
    EXPECT_EQ(t.rgb.path(), ha::best_segment_path());
  }
  ha::ColourTable unbuilt;
  EXPECT_FALSE(unbuilt.ready());
  ha::AreaVector areas;
  const std::uint8_t pixel[3] = {255, 0, 0};
  ha::segment_rgb24(pixel, 1, 1, 3, unbuilt, areas);  // no table: no areas, no crash
  EXPECT_EQ(areas.count, 0U);
}

TEST(ColourTables, EveryColourAndEveryTripleAsTheArithmetic) {
  // The RGB table holds classify() of every colour; the YUYV table classify() of the colour
  // OpenCV decodes every (Y, U, V) to.
  Tables& t = tables_with_boards(8);
  std::size_t rgb_mismatches = 0, yuv_mismatches = 0;
  for (int a = 0; a < 256; ++a) {
    for (int b = 0; b < 256; ++b) {
      for (int c = 0; c < 256; ++c) {
        const auto x = static_cast<std::uint8_t>(a), y = static_cast<std::uint8_t>(b),
                   z = static_cast<std::uint8_t>(c);
        rgb_mismatches += t.rgb.classify(x, y, z) != t.classifier.classify(x, y, z) ? 1U : 0U;
        const ha::Rgb8 rgb = ha::yuv_to_rgb_opencv(x, y, z);
        yuv_mismatches +=
            t.yuyv.classify(x, y, z) != t.classifier.classify(rgb.r, rgb.g, rgb.b) ? 1U : 0U;
      }
    }
  }
  EXPECT_EQ(rgb_mismatches, 0U);
  EXPECT_EQ(yuv_mismatches, 0U);
  // Spot checks of the decode against BT.601 by hand (see SegmentYuyv above).
  const ha::Rgb8 red = ha::yuv_to_rgb_opencv(81, 90, 240);
  EXPECT_GE(int{red.r}, 254);
  EXPECT_LE(int{red.g}, 1);
  EXPECT_LE(int{red.b}, 1);
  const ha::Rgb8 black = ha::yuv_to_rgb_opencv(0, 128, 128);  // luma below 16 clamps
  EXPECT_EQ(int{black.r} + black.g + black.b, 0);
}

TEST(SegmentPaths, IdenticalOnAdversarialFramesOfEveryWidthAndStride) {
  const std::vector<Rgb> rgb_edges = edge_colours(eight_boards());
  const std::vector<std::array<std::uint8_t, 3>> yuv_edges = edge_triples(eight_boards());
  ASSERT_GT(rgb_edges.size(), 1000U);
  ASSERT_GT(yuv_edges.size(), 1000U);
  ha::Pcg32 rng(2024);
  std::vector<std::uint8_t> frame;
  std::uint64_t counted[2][5] = {};
  for (bool yuyv : {false, true}) {
    for (Content content : {Content::kRandom, Content::kBlack, Content::kWhite, Content::kSaturated,
                            Content::kEdges}) {
      for (std::size_t boards : {6U, 8U}) {
        Tables& tables = tables_with_boards(boards);
        for (std::uint32_t w : kWidths) {
          for (std::uint32_t pad : {0U, 1U, 7U, 64U}) {
            const std::uint32_t h = w < 100 ? 5 : 2;
            const std::uint32_t stride = row_bytes(w, yuyv) + pad;
            // Exactly the frame's bytes: the last row ends at the end of the buffer.
            frame.assign(static_cast<std::size_t>(stride) * (h - 1U) + row_bytes(w, yuyv), 0);
            fill_frame(frame.data(), frame.size(), yuyv, content, rng, rgb_edges, yuv_edges);
            const std::string what = std::string(yuyv ? "YUYV " : "RGB24 ") +
                                     content_name(content) + " " + std::to_string(w) + "x" +
                                     std::to_string(h) + " stride " + std::to_string(stride) +
                                     ", " + std::to_string(boards) + " boards";
            counted[yuyv][static_cast<int>(content)] +=
                expect_paths_agree(frame.data(), w, h, stride, yuyv, tables, what);
            if (HasFailure()) return;
          }
        }
      }
    }
  }
  // The frames do hit the windows (black hits the dark board, white the everything board).
  for (int f = 0; f < 2; ++f) {
    for (int c = 0; c < 5; ++c) EXPECT_GT(counted[f][c], 1000U) << f << " " << c;
  }
}

TEST(SegmentPaths, IdenticalForEveryBoardCountAndUnusualStrides) {
  // Each board count has its own compiled kernel. Strides of 0 (every row the same) and smaller
  // than a row (rows overlap) are legal frames too.
  ha::Pcg32 rng(77);
  std::vector<std::uint8_t> frame;
  for (std::size_t boards = 1; boards <= ha::kMaxBoards; ++boards) {
    Tables& tables = tables_with_boards(boards);
    for (bool yuyv : {false, true}) {
      for (std::uint32_t w : {1U, 33U, 97U, 257U, 640U, 1000U}) {
        const std::uint32_t row = row_bytes(w, yuyv);
        for (std::uint32_t stride : {row, row + 3U, 0U, row / 2U}) {
          const std::uint32_t h = 9;
          frame.resize(static_cast<std::size_t>(stride) * (h - 1U) + row);
          for (auto& b : frame) b = static_cast<std::uint8_t>(rng.next_u32());
          expect_paths_agree(frame.data(), w, h, stride, yuyv, tables,
                             std::string(yuyv ? "YUYV " : "RGB24 ") + std::to_string(w) +
                                 " stride " + std::to_string(stride) + ", " +
                                 std::to_string(boards) + " boards");
          if (HasFailure()) return;
        }
      }
    }
  }
}

TEST(SegmentPaths, CountersDoNotOverflowOnLargeUniformFrames) {
  // Every pixel in all 8 boards: each path's small counters are flushed often enough to count
  // millions of pixels exactly.
  ha::ThresholdSet all;
  all.count = 8;
  for (std::size_t k = 0; k < 8; ++k) all.boards[k] = window(0.0F, 360.0F, 0, 0, 255);
  Tables tables(all);
  for (bool yuyv : {false, true}) {
    for (std::uint32_t w : {4096U, 1000U, 33U}) {
      const std::uint32_t h = w == 33U ? 20000U : 700U;
      const std::uint32_t stride = row_bytes(w, yuyv);
      std::vector<std::uint8_t> frame(static_cast<std::size_t>(stride) * h, 200);
      for (ha::SegmentPath path : supported_paths()) {
        ha::AreaVector areas;
        if (yuyv) {
          tables.yuyv.set_path(path);
          ha::segment_yuyv(frame.data(), w, h, stride, tables.yuyv, areas);
        } else {
          tables.rgb.set_path(path);
          ha::segment_rgb24(frame.data(), w, h, stride, tables.rgb, areas);
        }
        // The column sums reach 20000 * 33 * 32 / 2 and 700 * 4096 * 4095 / 2 (5.9e9), the row
        // sums 33 * 20000 * 19999 / 2 (6.6e9) and 4096 * 700 * 699 / 2: either half of the scalar
        // path's packed sums must be split off before it carries.
        const std::uint64_t columns = std::uint64_t{h} * w * (w - 1U) / 2U;
        const std::uint64_t rows = std::uint64_t{w} * h * (h - 1U) / 2U;
        for (std::size_t k = 0; k < 8; ++k) {
          EXPECT_EQ(areas.pixels[k], w * h)
              << (yuyv ? "YUYV " : "RGB24 ") << w << "x" << h << " board " << k << ", path "
              << ha::segment_path_name(path);
          EXPECT_EQ(areas.column_sum[k], columns)
              << (yuyv ? "YUYV " : "RGB24 ") << w << "x" << h << " board " << k << ", path "
              << ha::segment_path_name(path);
          EXPECT_EQ(areas.side_pixels[k], 2U * h);
          EXPECT_EQ(areas.row_sum[k], rows)
              << (yuyv ? "YUYV " : "RGB24 ") << w << "x" << h << " board " << k << ", path "
              << ha::segment_path_name(path);
        }
      }
    }
  }
}

#if defined(__linux__)
TEST(SegmentPaths, NoPathReadsOutsideTheFrame) {
  // The frame is put right before, then right after, an inaccessible page: a read past its last
  // row or before its first byte faults.
  const std::size_t page = static_cast<std::size_t>(::sysconf(_SC_PAGESIZE));
  Tables& tables = tables_with_boards(6);
  ha::Pcg32 rng(5);
  for (bool yuyv : {false, true}) {
    for (std::uint32_t w : kWidths) {
      const std::uint32_t h = 3;
      const std::uint32_t stride = row_bytes(w, yuyv) + (w % 3U);
      const std::size_t size = static_cast<std::size_t>(stride) * (h - 1U) + row_bytes(w, yuyv);
      const std::size_t span = (size + page - 1U) / page * page;
      void* mem = ::mmap(nullptr, span + 2U * page, PROT_READ | PROT_WRITE,
                         MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
      ASSERT_NE(mem, MAP_FAILED);
      auto* base = static_cast<std::uint8_t*>(mem);
      ASSERT_EQ(::mprotect(base, page, PROT_NONE), 0);
      ASSERT_EQ(::mprotect(base + page + span, page, PROT_NONE), 0);
      for (std::uint8_t* frame : {base + page + span - size, base + page}) {
        for (std::size_t i = 0; i < size; ++i) frame[i] = static_cast<std::uint8_t>(rng.next_u32());
        expect_paths_agree(frame, w, h, stride, yuyv, tables,
                           std::string(yuyv ? "YUYV " : "RGB24 ") + std::to_string(w) +
                               (frame == base + page ? " after" : " before") + " a guard page");
      }
      ::munmap(mem, span + 2U * page);
      if (HasFailure()) return;
    }
  }
}
#endif
