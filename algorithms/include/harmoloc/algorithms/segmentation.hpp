#pragma once
/// @file Threshold area segmentation of coloured landmark boards (Wu & Qin 2010): each board is a
/// range of hue with minimum saturation and a value window; its "area" is the number of pixels
/// of the raw, distorted frame inside that range. Do not undistort: the distortion is what makes
/// area depend on lateral position.

#include <array>
#include <cstddef>
#include <cstdint>

namespace harmoloc::algorithms {

constexpr std::size_t kMaxBoards = 8;

/// Colour window of one board, in HSV with H in degrees [0, 360) and S, V in [0, 255].
/// If hue_min_deg > hue_max_deg the window wraps through 0 (reds).
struct ColourThreshold {
  float hue_min_deg = 0.0F;
  float hue_max_deg = 0.0F;
  std::uint8_t saturation_min = 0;
  std::uint8_t value_min = 0;
  std::uint8_t value_max = 255;
};

struct ThresholdSet {
  std::array<ColourThreshold, kMaxBoards> boards{};
  std::size_t count = 0;
};

bool operator==(const ColourThreshold& a, const ColourThreshold& b);
bool operator==(const ThresholdSet& a, const ThresholdSet& b);

/// Pixel counts per board, and where in the frame each board's pixels lie.
struct AreaVector {
  std::array<std::uint32_t, kMaxBoards> pixels{};
  /// Sum of the column (0 = left) of every pixel of the board: column_sum / pixels is the
  /// board's centroid column, its bearing in the camera once the lens is known. 64-bit, so no
  /// frame size overflows it.
  std::array<std::uint64_t, kMaxBoards> column_sum{};
  /// Pixels of the board in the frame's first and last column: a blob that touches either side
  /// is cut by the frame, and its centroid is pulled inwards.
  std::array<std::uint32_t, kMaxBoards> side_pixels{};
  /// Sum of the row (0 = top) of every pixel of the board: row_sum / pixels is its centroid row,
  /// which with the lens and the camera's pitch and height tells how high the board hangs; the
  /// trainer fits the boards' geometry from it and the columns.
  std::array<std::uint64_t, kMaxBoards> row_sum{};
  /// The frame's width the columns count in; 0 when the columns were not measured (area logs
  /// written before they were, areas made by hand).
  std::uint32_t width_px = 0;
  /// The frame's height the rows count in; 0 when the rows were not measured (area logs written
  /// before they were).
  std::uint32_t height_px = 0;
  std::size_t count = 0;

  bool columns_measured() const { return width_px != 0; }
  /// Whether the frame's left or right side cuts board @p k (it has pixels in either column).
  bool cut_by_side(std::size_t k) const { return side_pixels[k] > 0U; }
  bool rows_measured() const { return height_px != 0; }
  /// Board @p k's centroid column in pixels, (width - 1) / 2 at the image centre; meaningful only
  /// when columns_measured() and pixels[k] > 0.
  double centroid_column_px(std::size_t k) const {
    return pixels[k] == 0 ? 0.0
                          : static_cast<double>(column_sum[k]) / static_cast<double>(pixels[k]);
  }
  /// Board @p k's centroid row in pixels, (height - 1) / 2 at the image centre; meaningful only
  /// when rows_measured() and pixels[k] > 0.
  double centroid_row_px(std::size_t k) const {
    return pixels[k] == 0 ? 0.0 : static_cast<double>(row_sum[k]) / static_cast<double>(pixels[k]);
  }
};

/// OpenCV's 8-bit HSV of one RGB pixel: H in 0..179 (2 degrees a step), S and V in 0..255.
/// Bit-exact with cv::cvtColor(COLOR_RGB2HSV) (the unit tests check all 2^24 colours).
struct Hsv8 {
  std::uint8_t h, s, v;
};

/// A ThresholdSet compiled at start-up into per-channel class masks. Each board's window is a
/// box in (H, S, V), so a pixel's boards are hue[H] & sat[S] & val[V]: three lookups, no
/// per-board loop, no floating point. Degrees map onto OpenCV's 2-degree steps as
/// H in [ceil(min/2), floor(max/2)] (documented in docs/segmentation.md).
class BoardClassifier {
 public:
  BoardClassifier();
  explicit BoardClassifier(const ThresholdSet& thresholds) : BoardClassifier() {
    build(thresholds);
  }
  void build(const ThresholdSet& thresholds);
  std::size_t board_count() const { return boards_; }

  Hsv8 to_hsv(std::uint8_t r, std::uint8_t g, std::uint8_t b) const {
    const int vmax = r > g ? (r > b ? r : b) : (g > b ? g : b);
    const int vmin = r < g ? (r < b ? r : b) : (g < b ? g : b);
    const int diff = vmax - vmin;
    const int vr = vmax == r ? -1 : 0;
    const int vg = vmax == g ? -1 : 0;
    const int s = (diff * sdiv_[static_cast<std::size_t>(vmax)] + (1 << (kShift - 1))) >> kShift;
    int h = (vr & (g - b)) + (~vr & ((vg & (b - r + 2 * diff)) + ((~vg) & (r - g + 4 * diff))));
    h = (h * hdiv_[static_cast<std::size_t>(diff)] + (1 << (kShift - 1))) >> kShift;
    h += h < 0 ? 180 : 0;
    return Hsv8{static_cast<std::uint8_t>(h), static_cast<std::uint8_t>(s),
                static_cast<std::uint8_t>(vmax)};
  }
  /// Bit k set: the pixel is inside board k's window.
  std::uint8_t classify(std::uint8_t r, std::uint8_t g, std::uint8_t b) const {
    const Hsv8 p = to_hsv(r, g, b);
    return static_cast<std::uint8_t>(hue_[p.h] & sat_[p.s] & val_[p.v]);
  }

 private:
  static constexpr int kShift = 12;
  std::array<std::int32_t, 256> sdiv_{};
  std::array<std::int32_t, 256> hdiv_{};
  std::array<std::uint8_t, 256> hue_{};
  std::array<std::uint8_t, 256> sat_{};
  std::array<std::uint8_t, 256> val_{};
  std::size_t boards_ = 0;
};

/// How a table segments a frame. Every path gives the same areas (the tests run each path this
/// CPU has on the same frames and compare); they differ in speed only.
enum class SegmentPath : std::uint8_t {
  kScalar = 0,  ///< portable C++: any target, bare metal included
  kAvx2 = 1,    ///< x86-64 with AVX2 (checked at run time): 8 table loads per vpgatherdd
  kNeon = 2,    ///< ARM with NEON: table loads into a row buffer, counted 16 bytes at a time
};

const char* segment_path_name(SegmentPath path);
/// Whether this build and this CPU can run @p path.
bool segment_path_supported(SegmentPath path);
/// The fastest path this build and CPU run: what a table uses unless told otherwise.
SegmentPath best_segment_path();

/// A board mask for each of 2^24 colours, built once at start-up from a BoardClassifier: one
/// load a pixel instead of the HSV arithmetic, with identical results. The storage belongs to the
/// caller (reserved at start-up, kStorageBytes); images of a few dominant colours touch only a
/// few hundred cache lines of it. ColourTable and YuyvTable differ in what indexes it.
class MaskTable {
 public:
  static constexpr std::size_t kColours = std::size_t{1} << 24;
  /// A SIMD gather reads 4 bytes around an entry, so the entries sit between zeroed guards.
  static constexpr std::size_t kGuardBytes = 64;
  static constexpr std::size_t kStorageBytes = kColours + 2 * kGuardBytes;
  /// The name callers sized the storage by before the guards existed; still the right size.
  static constexpr std::size_t kEntries = kStorageBytes;

  bool ready() const { return table_ != nullptr; }
  std::size_t board_count() const { return boards_; }
  /// The path segment_*() take with this table: best_segment_path() when built.
  SegmentPath path() const { return path_; }
  /// Picks another path (tests, benchmarks); false, and nothing changed, if it is not supported.
  bool set_path(SegmentPath path);
  /// The 2^24 entries (kGuardBytes readable on either side), indexed by index() of a subclass.
  const std::uint8_t* entries() const { return table_; }

 protected:
  /// Zeroes the guards of @p storage (kStorageBytes) and returns where the entries start.
  std::uint8_t* prepare(const BoardClassifier& classifier, std::uint8_t* storage);

  const std::uint8_t* table_ = nullptr;
  std::size_t boards_ = 0;
  SegmentPath path_ = SegmentPath::kScalar;
};

/// Indexed by an RGB24 pixel's three bytes as they lie in memory (R | G << 8 | B << 16): a
/// little-endian 4-byte load of the pixel, masked to 24 bits, is the index.
class ColourTable : public MaskTable {
 public:
  /// Fills @p storage (kStorageBytes) and uses it from now on.
  void build(const BoardClassifier& classifier, std::uint8_t* storage);
  static std::uint32_t index(std::uint8_t r, std::uint8_t g, std::uint8_t b) {
    return static_cast<std::uint32_t>(r) | (static_cast<std::uint32_t>(g) << 8U) |
           (static_cast<std::uint32_t>(b) << 16U);
  }
  std::uint8_t classify(std::uint8_t r, std::uint8_t g, std::uint8_t b) const {
    return table_[index(r, g, b)];
  }
};

/// Indexed by a YUYV pixel's (Y, U, V): each entry holds the classes of the colour OpenCV's
/// COLOR_YUV2RGB_YUYV decodes it to, so YUYV needs no decode per pixel and its areas still equal
/// the OpenCV reference. Index U | Y << 8 | V << 16: the odd pixel of a Y0 U Y1 V pair is the
/// pair's 4 bytes shifted right by 8, the even one the same with Y0 in place of Y1.
class YuyvTable : public MaskTable {
 public:
  /// Fills @p storage (kStorageBytes) and uses it from now on.
  void build(const BoardClassifier& classifier, std::uint8_t* storage);
  static std::uint32_t index(std::uint8_t y, std::uint8_t u, std::uint8_t v) {
    return static_cast<std::uint32_t>(u) | (static_cast<std::uint32_t>(y) << 8U) |
           (static_cast<std::uint32_t>(v) << 16U);
  }
  std::uint8_t classify(std::uint8_t y, std::uint8_t u, std::uint8_t v) const {
    return table_[index(y, u, v)];
  }
};

/// OpenCV's COLOR_YUV2RGB_YUYV of one pixel (BT.601 limited range, 20-bit fixed point, luma
/// below 16 clamped): what segment_yuyv classifies, exactly.
struct Rgb8 {
  std::uint8_t r, g, b;
};
Rgb8 yuv_to_rgb_opencv(std::uint8_t y, std::uint8_t u, std::uint8_t v);

/// Counts board pixels in an RGB24 image (3 bytes a pixel): one pass, no allocation.
void segment_rgb24(const std::uint8_t* data, std::uint32_t width_px, std::uint32_t height_px,
                   std::uint32_t stride_bytes, const BoardClassifier& classifier,
                   AreaVector& areas);
/// With the colour table (the cycle's): one table load a pixel, on table.path().
void segment_rgb24(const std::uint8_t* data, std::uint32_t width_px, std::uint32_t height_px,
                   std::uint32_t stride_bytes, const ColourTable& table, AreaVector& areas);

/// Counts board pixels in a YUYV image (BT.601 limited range, decoded exactly as OpenCV's
/// COLOR_YUV2RGB_YUYV, each pixel with its own luma and the chroma it shares with its
/// neighbour): one pass, no allocation. YUYV comes in pixel pairs: @p width_px must be even
/// (the metadata and the V4L2 driver ensure it), else the last pair's chroma lies past the row.
void segment_yuyv(const std::uint8_t* data, std::uint32_t width_px, std::uint32_t height_px,
                  std::uint32_t stride_bytes, const BoardClassifier& classifier, AreaVector& areas);
/// With the YUYV table (the cycle's): one table load a pixel, on table.path().
void segment_yuyv(const std::uint8_t* data, std::uint32_t width_px, std::uint32_t height_px,
                  std::uint32_t stride_bytes, const YuyvTable& table, AreaVector& areas);
/// With an RGB table: decodes each pixel first (exact but about 50 instructions a pixel), for
/// callers that hold only the RGB table (the trainer, a camera that changed format).
void segment_yuyv(const std::uint8_t* data, std::uint32_t width_px, std::uint32_t height_px,
                  std::uint32_t stride_bytes, const ColourTable& table, AreaVector& areas);

/// Convenience for host code and tests: compiles @p thresholds on the stack first.
void segment_rgb24(const std::uint8_t* data, std::uint32_t width_px, std::uint32_t height_px,
                   std::uint32_t stride_bytes, const ThresholdSet& thresholds, AreaVector& areas);
void segment_yuyv(const std::uint8_t* data, std::uint32_t width_px, std::uint32_t height_px,
                  std::uint32_t stride_bytes, const ThresholdSet& thresholds, AreaVector& areas);

}  // namespace harmoloc::algorithms
