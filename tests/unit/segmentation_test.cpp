// Threshold area segmentation (seed 000): HSV conversion, threshold windows (with the hue wrap
// through 0 for reds), and pixel counts on synthetic RGB24 and YUYV frames with known contents.
#include "harmoloc/algorithms/segmentation.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "harmoloc/algorithms/random.hpp"
#include "test_support.hpp"

namespace ha = harmoloc::algorithms;
namespace ht = harmoloc::test;

namespace {

// Reference HSV by the textbook hexcone formula in double precision, written independently
// (hue from the sector of the maximum channel, ties resolved r > g > b as the header's H range).
struct RefHsv {
  double h, s, v;
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
  out.h = 60.0 * hp;
  if (out.h >= 360.0) out.h -= 360.0;
  return out;
}

ha::ColourThreshold window(float h0, float h1, std::uint8_t s_min, std::uint8_t v_min,
                           std::uint8_t v_max) {
  return ha::ColourThreshold{h0, h1, s_min, v_min, v_max};
}

// Whether the pixel (@p r, @p g, @p b) falls in the window @p t.
bool pixel_in(const ha::ColourThreshold& t, int r, int g, int b) {
  return ha::in_threshold(t,
                          ha::rgb_to_hsv(static_cast<std::uint8_t>(r), static_cast<std::uint8_t>(g),
                                         static_cast<std::uint8_t>(b)));
}

struct Rgb {
  std::uint8_t r, g, b;
};

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

TEST(RgbToHsv, PrimaryAndSecondaryColours) {
  struct Case {
    Rgb c;
    float h, s, v;
  };
  const Case cases[] = {
      {{255, 0, 0}, 0.0F, 255.0F, 255.0F},      // red
      {{0, 255, 0}, 120.0F, 255.0F, 255.0F},    // green
      {{0, 0, 255}, 240.0F, 255.0F, 255.0F},    // blue
      {{255, 255, 0}, 60.0F, 255.0F, 255.0F},   // yellow
      {{0, 255, 255}, 180.0F, 255.0F, 255.0F},  // cyan
      {{255, 0, 255}, 300.0F, 255.0F, 255.0F},  // magenta
      {{128, 0, 0}, 0.0F, 255.0F, 128.0F},      // dark red: value is the max channel
      {{255, 128, 128}, 0.0F, 127.0F, 255.0F},  // pink: s = 255 * 127 / 255
      {{240, 60, 0}, 15.0F, 255.0F, 240.0F},    // h = 60 * 60 / 240
      {{255, 0, 85}, 340.0F, 255.0F, 255.0F},   // h = 360 - 60 * 85 / 255
  };
  for (const Case& k : cases) {
    SCOPED_TRACE(testing::Message() << int{k.c.r} << "," << int{k.c.g} << "," << int{k.c.b});
    const ha::Hsv hsv = ha::rgb_to_hsv(k.c.r, k.c.g, k.c.b);
    EXPECT_NEAR(hsv.hue_deg, k.h, 1e-4);
    EXPECT_NEAR(hsv.saturation, k.s, 1e-4);
    EXPECT_NEAR(hsv.value, k.v, 1e-4);
  }
}

TEST(RgbToHsv, GreysHaveNoSaturationAndZeroHue) {
  for (int g : {0, 1, 77, 128, 254, 255}) {
    const auto u = static_cast<std::uint8_t>(g);
    const ha::Hsv hsv = ha::rgb_to_hsv(u, u, u);
    EXPECT_EQ(hsv.saturation, 0.0F) << g;
    EXPECT_EQ(hsv.hue_deg, 0.0F) << g;
    EXPECT_EQ(hsv.value, static_cast<float>(g)) << g;
  }
}

TEST(RgbToHsv, MatchesReferenceFormulaAndStaysInRange) {
  ha::Pcg32 rng(12345);
  for (int i = 0; i < 20000; ++i) {
    const auto r = static_cast<int>(rng.next_u32() & 0xFFU);
    const auto g = static_cast<int>(rng.next_u32() & 0xFFU);
    const auto b = static_cast<int>(rng.next_u32() & 0xFFU);
    const ha::Hsv hsv = ha::rgb_to_hsv(static_cast<std::uint8_t>(r), static_cast<std::uint8_t>(g),
                                       static_cast<std::uint8_t>(b));
    const RefHsv ref = reference_hsv(r, g, b);
    ASSERT_GE(hsv.hue_deg, 0.0F);
    ASSERT_LT(hsv.hue_deg, 360.0F);
    ASSERT_GE(hsv.saturation, 0.0F);
    ASSERT_LE(hsv.saturation, 255.0F);
    ASSERT_GE(hsv.value, 0.0F);
    ASSERT_LE(hsv.value, 255.0F);
    // Hue compared on the circle (359.9999 and 0 are neighbours).
    double dh = std::fabs(static_cast<double>(hsv.hue_deg) - ref.h);
    dh = std::min(dh, 360.0 - dh);
    ASSERT_LT(dh, 1e-3) << r << "," << g << "," << b;
    ASSERT_NEAR(hsv.saturation, ref.s, 1e-3) << r << "," << g << "," << b;
    ASSERT_NEAR(hsv.value, ref.v, 1e-9) << r << "," << g << "," << b;
  }
}

TEST(InThreshold, HueWindowWrappingThroughZero) {
  const ha::ColourThreshold red = window(340.0F, 15.0F, 100, 50, 255);
  auto hue = [](float h) { return ha::Hsv{h, 200.0F, 200.0F}; };
  EXPECT_TRUE(ha::in_threshold(red, hue(0.0F)));
  EXPECT_TRUE(ha::in_threshold(red, hue(10.0F)));
  EXPECT_TRUE(ha::in_threshold(red, hue(350.0F)));
  EXPECT_TRUE(ha::in_threshold(red, hue(359.9F)));
  EXPECT_TRUE(ha::in_threshold(red, hue(340.0F)));  // edges are inclusive
  EXPECT_TRUE(ha::in_threshold(red, hue(15.0F)));
  EXPECT_FALSE(ha::in_threshold(red, hue(15.01F)));
  EXPECT_FALSE(ha::in_threshold(red, hue(339.99F)));
  EXPECT_FALSE(ha::in_threshold(red, hue(20.0F)));
  EXPECT_FALSE(ha::in_threshold(red, hue(180.0F)));
  EXPECT_FALSE(ha::in_threshold(red, hue(330.0F)));

  // The same window without wrap: 15..340 is everything but the reds.
  const ha::ColourThreshold not_red = window(15.0F, 340.0F, 100, 50, 255);
  EXPECT_FALSE(ha::in_threshold(not_red, hue(0.0F)));
  EXPECT_FALSE(ha::in_threshold(not_red, hue(350.0F)));
  EXPECT_TRUE(ha::in_threshold(not_red, hue(180.0F)));
  EXPECT_TRUE(ha::in_threshold(not_red, hue(15.0F)));
}

TEST(InThreshold, HueEdgesFromRealPixels) {
  const ha::ColourThreshold red = window(340.0F, 15.0F, 100, 50, 255);
  auto in = [&](int r, int g, int b) { return pixel_in(red, r, g, b); };
  EXPECT_TRUE(in(240, 60, 0));   // hue exactly 15
  EXPECT_FALSE(in(240, 61, 0));  // hue 15.25
  EXPECT_TRUE(in(255, 0, 85));   // hue exactly 340
  EXPECT_FALSE(in(255, 0, 86));  // hue 339.76
}

TEST(InThreshold, SaturationAndValueBoundsAreInclusive) {
  const ha::ColourThreshold t = window(340.0F, 15.0F, 100, 50, 200);
  auto in = [&](int r, int g, int b) { return pixel_in(t, r, g, b); };
  // Saturation = 255 * (max - min) / max: (200, 121.6..) is awkward, so use max 255 where s =
  // delta.
  const ha::ColourThreshold s_only = window(340.0F, 15.0F, 100, 0, 255);
  EXPECT_TRUE(ha::in_threshold(s_only, ha::rgb_to_hsv(255, 155, 155)));   // s = 100 exactly
  EXPECT_FALSE(ha::in_threshold(s_only, ha::rgb_to_hsv(255, 156, 156)));  // s = 99
  EXPECT_TRUE(in(50, 0, 0));                                              // v = 50 = value_min
  EXPECT_FALSE(in(49, 0, 0));                                             // v below
  EXPECT_TRUE(in(200, 0, 0));                                             // v = 200 = value_max
  EXPECT_FALSE(in(201, 0, 0));                                            // v above
  EXPECT_FALSE(in(0, 0, 0));                                              // black is no colour
}

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
  img.fill(30, 0, 2, 2, Rgb{240, 60, 0});  // hue exactly 15, on red's edge: 4 px counted as red
  img.fill(30, 5, 3, 1, Rgb{240, 61, 0});  // hue 15.25, just outside: 3 px not red

  ha::ThresholdSet set = ht::board_windows(3);  // red, green, blue
  set.count = 4;
  set.boards[3] = window(0.0F, 360.0F, 0, 0, 255);  // everything: boards are counted independently

  ha::AreaVector areas;
  areas.pixels.fill(777U);  // stale values must be cleared
  ha::segment_rgb24(img.data(), img.width(), img.height(), img.stride(), set, areas);
  EXPECT_EQ(areas.count, 4U);
  EXPECT_EQ(areas.pixels[0], 50U + 4U);
  EXPECT_EQ(areas.pixels[1], 21U);
  EXPECT_EQ(areas.pixels[2], 2U);
  EXPECT_EQ(areas.pixels[3], 40U * 30U);
  for (std::size_t k = 4; k < ha::kMaxBoards; ++k) EXPECT_EQ(areas.pixels[k], 0U) << k;
}

TEST(SegmentRgb24, EmptyThresholdSetAndEmptyImage) {
  RgbImage img(8, 4, 24, Rgb{255, 0, 0}, Rgb{0, 0, 0});
  ha::ThresholdSet none;
  ha::AreaVector areas;
  ha::segment_rgb24(img.data(), img.width(), img.height(), img.stride(), none, areas);
  EXPECT_EQ(areas.count, 0U);
  const ha::ThresholdSet one = ht::board_windows(1);  // red
  ha::segment_rgb24(img.data(), 0, 0, img.stride(), one, areas);
  EXPECT_EQ(areas.pixels[0], 0U);
  ha::segment_rgb24(img.data(), img.width(), img.height(), img.stride(), one, areas);
  EXPECT_EQ(areas.pixels[0], 32U);
}

TEST(SegmentYuyv, CountsKnownColoursWithPerPixelLuma) {
  // BT.601 limited range, by hand (R = (298 (Y-16) + 409 (V-128) + 128) >> 8, and so on):
  //   Y=81  U=90  V=240 -> (255, 0, 0)    red
  //   Y=145 U=54  V=34  -> (0, 255, 1)    green (hue 120.2)
  //   Y=41  U=240 V=110 -> (0, 0, 255)    blue
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
}

TEST(SegmentYuyv, AgreesWithRgbOfTheSameFrame) {
  // Convert a YUYV frame to RGB with the header's formula written out independently in double
  // precision, then segment both: counts must agree except where rounding lands on a threshold.
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
      const int c = 298 * (yy - 16);
      auto clamp = [](int q) { return static_cast<std::uint8_t>(std::clamp(q, 0, 255)); };
      // Floor division by 256 with rounding, as an arithmetic shift does for negatives.
      auto div256 = [](int q) {
        return static_cast<int>(std::floor(static_cast<double>(q) / 256.0));
      };
      std::uint8_t* o = rgb.data() + (static_cast<std::size_t>(y) * w + x) * 3U;
      o[0] = clamp(div256(c + 409 * v + 128));
      o[1] = clamp(div256(c - 100 * u - 208 * v + 128));
      o[2] = clamp(div256(c + 516 * u + 128));
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
