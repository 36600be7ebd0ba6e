#include "harmoloc/sim_host/colour_windows.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <numeric>
#include <sstream>
#include <stdexcept>

#include <toml++/toml.h>

#include "harmoloc/dataset/frame_index.hpp"

namespace harmoloc::sim_host::colours {

namespace {

namespace alg = algorithms;

std::vector<std::uint8_t> read_whole_file(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw std::runtime_error(path + ": not a regular file");
  std::ifstream f(path, std::ios::binary);
  if (!f) throw std::runtime_error(path + ": cannot open");
  f.seekg(0, std::ios::end);
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(std::max<std::streamoff>(f.tellg(), 0)));
  f.seekg(0);
  f.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (!f) throw std::runtime_error(path + ": cannot read");
  return bytes;
}

// Percentile of a histogram (share 0..1 of its total), as a bin index.
template <typename Hist>
int hist_percentile(const Hist& hist, double share) {
  double total = 0.0;
  for (const auto c : hist) total += static_cast<double>(c);
  if (total <= 0.0) return 0;
  const double want = share * total;
  double sum = 0.0;
  for (std::size_t i = 0; i < hist.size(); ++i) {
    sum += static_cast<double>(hist[i]);
    if (sum >= want) return static_cast<int>(i);
  }
  return static_cast<int>(hist.size()) - 1;
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const double pos = q * static_cast<double>(v.size() - 1);
  const auto i = static_cast<std::size_t>(pos);
  const std::size_t j = std::min(i + 1, v.size() - 1);
  return v[i] + (v[j] - v[i]) * (pos - static_cast<double>(i));
}

int wrap_h8(int h8) {
  return ((h8 % kHueSteps) + kHueSteps) % kHueSteps;
}

// The firmware's HSV of a frame, three planes.
struct HsvPlanes {
  std::vector<std::uint8_t> h, s, v;
};

void to_hsv(const RgbImage& img, const alg::BoardClassifier& cls, HsvPlanes& out) {
  const std::size_t n = static_cast<std::size_t>(img.width_px) * img.height_px;
  out.h.resize(n);
  out.s.resize(n);
  out.v.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const alg::Hsv8 p = cls.to_hsv(img.rgb[3 * i], img.rgb[3 * i + 1], img.rgb[3 * i + 2]);
    out.h[i] = p.h;
    out.s[i] = p.s;
    out.v[i] = p.v;
  }
}

// Connected components (8-connected) of the pixels with the same label >= 0; each component's
// pixels get its size in @p size_of (0 for unlabelled pixels). A flood fill with one explicit
// stack: blobs of a whole frame must not recurse.
void component_sizes(const std::vector<int>& label, std::uint32_t width, std::uint32_t height,
                     std::vector<std::uint32_t>& size_of) {
  const std::size_t n = label.size();
  size_of.assign(n, 0);
  std::vector<std::uint8_t> seen(n, 0);
  std::vector<std::uint32_t> stack, members;
  for (std::size_t start = 0; start < n; ++start) {
    if (label[start] < 0 || seen[start] != 0) continue;
    const int l = label[start];
    members.clear();
    stack.assign(1, static_cast<std::uint32_t>(start));
    seen[start] = 1;
    while (!stack.empty()) {
      const std::uint32_t p = stack.back();
      stack.pop_back();
      members.push_back(p);
      const int x = static_cast<int>(p % width), y = static_cast<int>(p / width);
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const int nx = x + dx, ny = y + dy;
          if (nx < 0 || ny < 0 || nx >= static_cast<int>(width) || ny >= static_cast<int>(height))
            continue;
          const std::size_t q = static_cast<std::size_t>(ny) * width + static_cast<std::size_t>(nx);
          if (seen[q] == 0 && label[q] == l) {
            seen[q] = 1;
            stack.push_back(static_cast<std::uint32_t>(q));
          }
        }
      }
    }
    for (const std::uint32_t p : members) size_of[p] = static_cast<std::uint32_t>(members.size());
  }
}

// Marks every pixel within @p radius (Chebyshev) of a marked one: mixed pixels at a blob's edge
// carry the board's hue at a background's saturation and must not count as background.
std::vector<std::uint8_t> dilate(const std::vector<std::uint8_t>& mask, std::uint32_t width,
                                 std::uint32_t height, int radius) {
  std::vector<std::uint8_t> rows(mask.size(), 0), out(mask.size(), 0);
  for (std::uint32_t y = 0; y < height; ++y) {
    for (std::uint32_t x = 0; x < width; ++x) {
      if (mask[y * width + x] == 0) continue;
      const int x0 = std::max(0, static_cast<int>(x) - radius);
      const int x1 = std::min(static_cast<int>(width) - 1, static_cast<int>(x) + radius);
      for (int xx = x0; xx <= x1; ++xx) rows[y * width + static_cast<std::uint32_t>(xx)] = 1;
    }
  }
  for (std::uint32_t y = 0; y < height; ++y) {
    for (std::uint32_t x = 0; x < width; ++x) {
      if (rows[y * width + x] == 0) continue;
      const int y0 = std::max(0, static_cast<int>(y) - radius);
      const int y1 = std::min(static_cast<int>(height) - 1, static_cast<int>(y) + radius);
      for (int yy = y0; yy <= y1; ++yy) out[static_cast<std::uint32_t>(yy) * width + x] = 1;
    }
  }
  return out;
}

// Hue clusters of a histogram of saturated pixels: every step climbs to its local maximum
// (watershed on a circle), then neighbouring basins merge while the saddle between them is more
// than half the lower peak (one colour's hue spread, not two colours). Returns a cluster id
// per step (-1: no pixels).
std::vector<int> hue_basins(const std::array<double, kHueSteps>& hist, std::vector<int>& peaks) {
  std::array<double, kHueSteps> sm{};
  const std::array<double, 5> kernel{1.0, 2.0, 3.0, 2.0, 1.0};
  for (int h = 0; h < kHueSteps; ++h) {
    for (int d = -2; d <= 2; ++d)
      sm[static_cast<std::size_t>(h)] +=
          kernel[static_cast<std::size_t>(d + 2)] * hist[static_cast<std::size_t>(wrap_h8(h + d))];
  }
  const double top = *std::max_element(sm.begin(), sm.end());
  std::vector<int> owner(kHueSteps, -1);
  if (top <= 0.0) return owner;
  // Steps far below every peak are noise, not part of any colour.
  const double floor = top * 1e-4;
  std::vector<int> peak_of(kHueSteps, -1);
  for (int h = 0; h < kHueSteps; ++h) {
    if (sm[static_cast<std::size_t>(h)] <= floor) continue;
    // Climb to the local maximum; a plateau stops the climb where it starts, and its steps'
    // basins merge below (their saddle is their peak).
    int p = h;
    for (int guard = 0; guard < kHueSteps; ++guard) {
      const int l = wrap_h8(p - 1), r = wrap_h8(p + 1);
      const double here = sm[static_cast<std::size_t>(p)];
      if (sm[static_cast<std::size_t>(r)] > here &&
          sm[static_cast<std::size_t>(r)] >= sm[static_cast<std::size_t>(l)])
        p = r;
      else if (sm[static_cast<std::size_t>(l)] > here)
        p = l;
      else
        break;
    }
    peak_of[static_cast<std::size_t>(h)] = p;
  }
  // Basins by peak; merge across high saddles.
  std::map<int, int> id_of_peak;
  for (int h = 0; h < kHueSteps; ++h) {
    const int p = peak_of[static_cast<std::size_t>(h)];
    if (p >= 0 && id_of_peak.count(p) == 0) {
      const int id = static_cast<int>(id_of_peak.size());
      id_of_peak[p] = id;
    }
  }
  std::vector<int> parent(id_of_peak.size());
  std::iota(parent.begin(), parent.end(), 0);
  std::vector<double> height(id_of_peak.size());
  std::vector<int> peak_step(id_of_peak.size());
  for (const auto& [p, id] : id_of_peak) {
    height[static_cast<std::size_t>(id)] = sm[static_cast<std::size_t>(p)];
    peak_step[static_cast<std::size_t>(id)] = p;
  }
  const auto find = [&](int a) {
    while (parent[static_cast<std::size_t>(a)] != a) a = parent[static_cast<std::size_t>(a)];
    return a;
  };
  for (bool merged = true; merged;) {
    merged = false;
    for (int h = 0; h < kHueSteps; ++h) {
      const int pa = peak_of[static_cast<std::size_t>(h)];
      const int pb = peak_of[static_cast<std::size_t>(wrap_h8(h + 1))];
      if (pa < 0 || pb < 0) continue;
      const int a = find(id_of_peak[pa]), b = find(id_of_peak[pb]);
      if (a == b) continue;
      const double saddle =
          std::min(sm[static_cast<std::size_t>(h)], sm[static_cast<std::size_t>(wrap_h8(h + 1))]);
      const double lower =
          std::min(height[static_cast<std::size_t>(a)], height[static_cast<std::size_t>(b)]);
      if (saddle > 0.5 * lower) {
        const int keep =
            height[static_cast<std::size_t>(a)] >= height[static_cast<std::size_t>(b)] ? a : b;
        const int gone = keep == a ? b : a;
        parent[static_cast<std::size_t>(gone)] = keep;
        merged = true;
      }
    }
  }
  std::map<int, int> cluster_of_root;
  for (int h = 0; h < kHueSteps; ++h) {
    const int p = peak_of[static_cast<std::size_t>(h)];
    if (p < 0) continue;
    const int root = find(id_of_peak[p]);
    if (cluster_of_root.count(root) == 0) {
      const int id = static_cast<int>(cluster_of_root.size());
      cluster_of_root[root] = id;
      peaks.push_back(peak_step[static_cast<std::size_t>(root)]);
    }
    owner[static_cast<std::size_t>(h)] = cluster_of_root[root];
  }
  return owner;
}

// The contiguous circular range of the steps owned by @p id, around @p peak.
HueRange owned_range(const std::vector<int>& owner, int id, int peak) {
  int lo = peak, hi = peak;
  for (int k = 0; k < kHueSteps / 2 && owner[static_cast<std::size_t>(wrap_h8(lo - 1))] == id; ++k)
    lo = wrap_h8(lo - 1);
  for (int k = 0; k < kHueSteps / 2 && owner[static_cast<std::size_t>(wrap_h8(hi + 1))] == id; ++k)
    hi = wrap_h8(hi + 1);
  return HueRange{lo, hi};
}

// A board's pixels by hue and saturation, and by value: what its window is built from.
struct PixelStats {
  std::vector<std::array<double, 256>> board_sat_by_hue =
      std::vector<std::array<double, 256>>(kHueSteps);
  std::array<double, 256> board_value{};
};

using SatByHue = std::vector<std::array<double, 256>>;

// A window around a board's pixels: the hue steps they cover plus a margin, kept off the
// neighbouring colours' peaks (half the gap less 2 steps, as a careful user would); the
// saturation minimum 45% of the way from the background's most saturated pixels of that hue to
// the board's least saturated; the value minimum well below the board's darkest.
ProposedBoard window_from(const PixelStats& board, const SatByHue& background,
                          const std::vector<int>& neighbour_peaks_h8) {
  std::array<double, kHueSteps> hue_hist{};
  std::array<double, 256> sat_hist{};
  for (int h = 0; h < kHueSteps; ++h) {
    for (int s = 0; s < 256; ++s) {
      const double c =
          board.board_sat_by_hue[static_cast<std::size_t>(h)][static_cast<std::size_t>(s)];
      hue_hist[static_cast<std::size_t>(h)] += c;
      sat_hist[static_cast<std::size_t>(s)] += c;
    }
  }
  const int peak =
      static_cast<int>(std::max_element(hue_hist.begin(), hue_hist.end()) - hue_hist.begin());
  // Unwrap around the peak so that reds through 0 are one interval.
  std::array<double, kHueSteps> unwrapped{};
  for (int d = -kHueSteps / 2; d < kHueSteps / 2; ++d)
    unwrapped[static_cast<std::size_t>(d + kHueSteps / 2)] =
        hue_hist[static_cast<std::size_t>(wrap_h8(peak + d))];
  const int p_lo = hist_percentile(unwrapped, 0.005) - kHueSteps / 2;
  const int p_mid = hist_percentile(unwrapped, 0.5) - kHueSteps / 2;
  const int p_hi = hist_percentile(unwrapped, 0.995) - kHueSteps / 2;
  const int centre = wrap_h8(peak + p_mid);

  // 8..10 steps (16..20 degrees) each side, as far as the neighbours allow.
  constexpr int kPreferredHalf = 10, kMinHalf = 2, kMargin = 2;
  int left = std::max(p_mid - p_lo + kMargin, kPreferredHalf);
  int right = std::max(p_hi - p_mid + kMargin, kPreferredHalf);
  for (const int n : neighbour_peaks_h8) {
    const int d_right = wrap_h8(n - centre), d_left = wrap_h8(centre - n);
    if (d_right == 0) continue;
    if (d_right <= kHueSteps / 2) right = std::min(right, d_right / 2 - kMargin);
    if (d_left <= kHueSteps / 2) left = std::min(left, d_left / 2 - kMargin);
  }
  left = std::max(left, kMinHalf);
  right = std::max(right, kMinHalf);
  const HueRange hue{wrap_h8(centre - left), wrap_h8(centre + right)};

  ProposedBoard out;
  out.hue_centre_h8 = centre;
  out.board_saturation_low = static_cast<std::uint8_t>(hist_percentile(sat_hist, 0.02));
  // The background of the board's hue, and of hues a little beyond the window: light and noise
  // move a pale colour's hue more than a saturated one's.
  constexpr int kBackgroundMargin = 5;
  const HueRange near_hue{wrap_h8(hue.lo_h8 - kBackgroundMargin),
                          wrap_h8(hue.hi_h8 + kBackgroundMargin)};
  std::array<double, 256> bg_sat{};
  double bg_total = 0.0;
  for (int h = 0; h < kHueSteps; ++h) {
    const bool near = near_hue.contains(h);
    for (int s = 0; s < 256; ++s) {
      const double c = background[static_cast<std::size_t>(h)][static_cast<std::size_t>(s)];
      bg_total += c;
      if (near) bg_sat[static_cast<std::size_t>(s)] += c;
    }
  }
  // Its most saturated pixels, all but what may leak: 0.01% of the frame (scattered noise pixels
  // cannot be kept out without losing the board's own).
  int bg_high = 0;
  double above = 0.0;
  for (int s = 255; s >= 0; --s) {
    above += bg_sat[static_cast<std::size_t>(s)];
    if (above > 1e-4 * bg_total) {
      bg_high = s;
      break;
    }
  }
  out.background_saturation_high = static_cast<std::uint8_t>(bg_high);
  const int board_low = out.board_saturation_low;
  const int s_min = board_low > bg_high
                        ? bg_high + static_cast<int>(std::lround(0.45 * (board_low - bg_high)))
                        : board_low;
  out.board_value_low = static_cast<std::uint8_t>(hist_percentile(board.board_value, 0.01));
  // Well below the board's darkest in the recording: a dimmer day must not lose its pixels,
  // and dark pixels whose hue noise could reach the window are below saturation_min anyway.
  const int v_min = std::max(30, static_cast<int>(0.4 * out.board_value_low));
  out.window = to_threshold(hue, static_cast<std::uint8_t>(std::clamp(s_min, 1, 255)),
                            static_cast<std::uint8_t>(std::min(v_min, 255)));
  out.name = hue_name(centre);
  return out;
}

void name_uniquely(std::vector<ProposedBoard>& boards) {
  std::map<std::string, int> count;
  for (const auto& b : boards) ++count[b.name];
  std::map<std::string, int> seen;
  for (auto& b : boards) {
    if (count[b.name] > 1) b.name += "-" + std::to_string(++seen[b.name]);
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------------

DatasetFrames::DatasetFrames(const std::string& dataset_dir) : dir_(dataset_dir) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::is_directory(dataset_dir, ec))
    throw std::runtime_error(dataset_dir + ": no such dataset folder");
  meta_ = dataset::read_metadata(dataset_dir);
  const std::string index = (fs::path(dataset_dir) / meta_.frames_index).string();
  for (const auto& e : dataset::read_frame_index(index)) {
    files_.push_back((fs::path(dataset_dir) / e.file).string());
    stamps_.push_back(e.timestamp_ns);
  }
  if (files_.empty()) throw std::runtime_error(index + ": no frames listed");
  // Every file is checked now, not when (or whether) a pass reaches it: a frame the analysis
  // skips would still stop the firmware's replay or the trainer.
  const std::size_t n = static_cast<std::size_t>(meta_.image_width_px) * meta_.image_height_px;
  std::array<std::uint8_t, 64> head{};
  for (const std::string& path : files_) {
    const auto size = fs::is_regular_file(path, ec) ? fs::file_size(path, ec) : 0;
    if (ec || size == 0) throw std::runtime_error(path + ": missing, empty or not a file");
    std::size_t expected = 2 * n;
    if (meta_.pixel_format == hal::PixelFormat::kRgb24) {
      std::ifstream f(path, std::ios::binary);
      f.read(reinterpret_cast<char*>(head.data()), static_cast<std::streamsize>(head.size()));
      dataset::PpmHeader header;
      const char* why = nullptr;
      if (!dataset::parse_ppm_header(head.data(), static_cast<std::size_t>(f.gcount()), header,
                                     &why))
        throw std::runtime_error(path + ": " + (why ? why : "not a binary PPM"));
      if (header.width_px != meta_.image_width_px || header.height_px != meta_.image_height_px)
        throw std::runtime_error(path + ": " + std::to_string(header.width_px) + "x" +
                                 std::to_string(header.height_px) + ", the metadata says " +
                                 std::to_string(meta_.image_width_px) + "x" +
                                 std::to_string(meta_.image_height_px));
      expected = header.data_offset + 3 * n;
    }
    if (size != expected)
      throw std::runtime_error(path + ": " + std::to_string(size) + " bytes, expected " +
                               std::to_string(expected) + (size < expected ? " (truncated)" : ""));
  }
}

void DatasetFrames::read(std::size_t index, RgbImage& out) {
  const std::string& path = files_.at(index);
  bytes_ = read_whole_file(path);
  const std::uint32_t w = meta_.image_width_px, h = meta_.image_height_px;
  const std::size_t n = static_cast<std::size_t>(w) * h;
  out.width_px = w;
  out.height_px = h;
  out.rgb.resize(3 * n);
  if (meta_.pixel_format == hal::PixelFormat::kRgb24) {
    dataset::PpmHeader header;
    const char* why = nullptr;
    if (!dataset::parse_ppm_header(bytes_.data(), bytes_.size(), header, &why))
      throw std::runtime_error(path + ": " + (why ? why : "not a binary PPM"));
    if (header.width_px != w || header.height_px != h)
      throw std::runtime_error(path + ": " + std::to_string(header.width_px) + "x" +
                               std::to_string(header.height_px) + ", the metadata says " +
                               std::to_string(w) + "x" + std::to_string(h));
    if (bytes_.size() < header.data_offset + 3 * n) throw std::runtime_error(path + ": truncated");
    std::copy_n(bytes_.begin() + static_cast<std::ptrdiff_t>(header.data_offset), 3 * n,
                out.rgb.begin());
    return;
  }
  if (bytes_.size() != 2 * n)
    throw std::runtime_error(path + ": " + std::to_string(bytes_.size()) +
                             " bytes, a YUYV frame of the metadata's size has " +
                             std::to_string(2 * n));
  for (std::size_t pair = 0; pair < n / 2; ++pair) {
    const std::uint8_t* q = &bytes_[4 * pair];
    for (int k = 0; k < 2; ++k) {
      const alg::Rgb8 c = alg::yuv_to_rgb_opencv(q[2 * k], q[1], q[3]);
      std::uint8_t* o = &out.rgb[3 * (2 * pair + static_cast<std::size_t>(k))];
      o[0] = c.r;
      o[1] = c.g;
      o[2] = c.b;
    }
  }
}

void MemoryFrames::add(std::uint64_t timestamp_ns, RgbImage frame) {
  stamps_.push_back(timestamp_ns);
  frames_.push_back(std::move(frame));
}

// ---------------------------------------------------------------------------------------------

alg::ColourThreshold to_threshold(const HueRange& hue, std::uint8_t saturation_min,
                                  std::uint8_t value_min, std::uint8_t value_max) {
  alg::ColourThreshold t;
  t.hue_min_deg = static_cast<float>(2 * hue.lo_h8);
  t.hue_max_deg = static_cast<float>(2 * hue.hi_h8);
  t.saturation_min = saturation_min;
  t.value_min = value_min;
  t.value_max = value_max;
  return t;
}

HueRange hue_steps_of(const alg::ColourThreshold& t) {
  return HueRange{wrap_h8(static_cast<int>(std::ceil(t.hue_min_deg / 2.0F))),
                  wrap_h8(static_cast<int>(std::floor(t.hue_max_deg / 2.0F)))};
}

int hue_distance_h8(int a_h8, int b_h8) {
  const int d = wrap_h8(a_h8 - b_h8);
  return std::min(d, kHueSteps - d);
}

std::string hue_name(int hue_h8) {
  // The simulator's names (docs/scenarios.md), by the degrees they start at.
  static const std::array<std::pair<int, const char*>, 12> kNames{{{0, "red"},
                                                                   {15, "orange"},
                                                                   {45, "yellow"},
                                                                   {70, "lime"},
                                                                   {95, "green"},
                                                                   {155, "cyan"},
                                                                   {190, "azure"},
                                                                   {215, "blue"},
                                                                   {255, "violet"},
                                                                   {285, "magenta"},
                                                                   {320, "pink"},
                                                                   {345, "red"}}};
  const int deg = 2 * wrap_h8(hue_h8);
  const char* name = "red";
  for (const auto& [from, n] : kNames)
    if (deg >= from) name = n;
  return name;
}

GuidedRect parse_rect(const std::string& text) {
  const auto colon = text.rfind(':');
  if (colon == std::string::npos || colon == 0)
    throw std::invalid_argument("'" + text + "' is not NAME:x,y,w,h");
  GuidedRect r;
  r.name = text.substr(0, colon);
  std::array<int, 4> v{};
  std::stringstream ss(text.substr(colon + 1));
  std::string item;
  std::size_t k = 0;
  while (std::getline(ss, item, ',')) {
    std::size_t used = 0;
    int x = 0;
    try {
      x = std::stoi(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (k >= 4 || used != item.size() || item.empty() || x < 0)
      throw std::invalid_argument("'" + text + "' is not NAME:x,y,w,h (whole pixels, >= 0)");
    v[k++] = x;
  }
  if (k != 4) throw std::invalid_argument("'" + text + "' is not NAME:x,y,w,h");
  if (v[2] == 0 || v[3] == 0) throw std::invalid_argument("'" + text + "': empty rectangle");
  r.x = v[0];
  r.y = v[1];
  r.w = v[2];
  r.h = v[3];
  return r;
}

// ---------------------------------------------------------------------------------------------

AutoResult propose_automatic(FrameSource& frames, const AutoOptions& opt) {
  AutoResult result;
  const std::size_t n = frames.size();
  if (n == 0) throw std::runtime_error("the recording has no frames");
  std::vector<std::size_t> sample;
  const std::size_t m = std::min(n, std::max<std::size_t>(opt.sample_frames, 1));
  for (std::size_t k = 0; k < m; ++k) sample.push_back(m == 1 ? 0 : k * (n - 1) / (m - 1));
  result.frames_sampled = m;
  const alg::BoardClassifier cls;
  RgbImage img;
  HsvPlanes hsv;
  const auto candidate = [&](std::size_t i) {
    return hsv.s[i] >= opt.saturation_floor && hsv.v[i] >= opt.value_floor;
  };

  // Pass 1: which saturated hues the run holds.
  std::array<double, kHueSteps> hist{};
  for (std::size_t k = 0; k < m; ++k) {
    if (opt.progress) opt.progress(k, 2 * m, "hues");
    frames.read(sample[k], img);
    to_hsv(img, cls, hsv);
    for (std::size_t i = 0; i < hsv.h.size(); ++i)
      if (candidate(i)) hist[hsv.h[i]] += 1.0;
  }
  std::vector<int> peaks;
  const std::vector<int> owner = hue_basins(hist, peaks);
  const std::size_t clusters = peaks.size();

  // Pass 2: per cluster and frame its blobs; the board candidates' pixels and the background's.
  std::vector<PixelStats> stats(clusters);
  SatByHue background(kHueSteps);
  std::vector<std::vector<double>> blob_area(clusters, std::vector<double>(m, 0.0));
  std::vector<double> all_px(clusters, 0.0), blob_px(clusters, 0.0);
  std::vector<int> label;
  std::vector<std::uint32_t> size_of;
  double frame_px = 1.0;
  for (std::size_t k = 0; k < m; ++k) {
    if (opt.progress) opt.progress(m + k, 2 * m, "blobs");
    frames.read(sample[k], img);
    to_hsv(img, cls, hsv);
    const std::size_t px = hsv.h.size();
    frame_px = static_cast<double>(px);
    const auto min_blob = static_cast<std::uint32_t>(std::ceil(opt.min_blob_share * frame_px));
    label.assign(px, -1);
    for (std::size_t i = 0; i < px; ++i)
      if (candidate(i)) label[i] = owner[hsv.h[i]];
    component_sizes(label, img.width_px, img.height_px, size_of);
    std::vector<std::uint8_t> in_blob(px, 0);
    for (std::size_t i = 0; i < px; ++i) {
      if (label[i] < 0) continue;
      const auto c = static_cast<std::size_t>(label[i]);
      all_px[c] += 1.0;
      if (size_of[i] < min_blob) continue;
      in_blob[i] = 1;
      blob_px[c] += 1.0;
      blob_area[c][k] += 1.0;
      stats[c].board_sat_by_hue[hsv.h[i]][hsv.s[i]] += 1.0;
      stats[c].board_value[hsv.v[i]] += 1.0;
    }
    const std::vector<std::uint8_t> near = dilate(in_blob, img.width_px, img.height_px, 2);
    for (std::size_t i = 0; i < px; ++i) {
      if (near[i] == 0 && hsv.v[i] >= 30) background[hsv.h[i]][hsv.s[i]] += 1.0;
    }
  }
  if (opt.progress) opt.progress(2 * m, 2 * m, "blobs");

  for (std::size_t c = 0; c < clusters; ++c) {
    HueCluster hc;
    hc.peak_h8 = peaks[c];
    hc.range = owned_range(owner, static_cast<int>(c), peaks[c]);
    hc.pixels = all_px[c];
    hc.blob_share = all_px[c] > 0.0 ? blob_px[c] / all_px[c] : 0.0;
    std::size_t seen = 0;
    for (const double a : blob_area[c]) seen += a > 0.0 ? 1 : 0;
    hc.frames_seen = static_cast<double>(seen) / static_cast<double>(m);
    const double p90 = quantile(blob_area[c], 0.9), p10 = quantile(blob_area[c], 0.1);
    hc.area_variation = p90 > 0.0 ? (p90 - p10) / p90 : 0.0;
    hc.median_area_share = quantile(blob_area[c], 0.5) / frame_px;
    char why[200];
    if (hc.blob_share < opt.min_blob_fraction) {
      std::snprintf(why, sizeof why, "scattered: %.0f%% of its pixels in blobs (< %.0f%%)",
                    100.0 * hc.blob_share, 100.0 * opt.min_blob_fraction);
    } else if (hc.frames_seen < opt.min_frames_seen) {
      std::snprintf(why, sizeof why, "rare: a blob in %.1f%% of the frames (< %.0f%%)",
                    100.0 * hc.frames_seen, 100.0 * opt.min_frames_seen);
    } else if (hc.area_variation < opt.min_area_variation) {
      std::snprintf(why, sizeof why,
                    "constant: its area changes by %.0f%% along the run (< %.0f%%): background",
                    100.0 * hc.area_variation, 100.0 * opt.min_area_variation);
    } else if (hc.median_area_share > 0.3) {
      std::snprintf(why, sizeof why, "too large: %.0f%% of the frame in half the frames",
                    100.0 * hc.median_area_share);
    } else {
      hc.is_board = true;
      std::snprintf(why, sizeof why,
                    "board: %.0f%% in blobs, in %.0f%% of the frames, area "
                    "varies %.0f%%",
                    100.0 * hc.blob_share, 100.0 * hc.frames_seen, 100.0 * hc.area_variation);
    }
    hc.verdict = why;
    result.clusters.push_back(hc);
  }

  // Rank: the boards first, then by how many blob pixels they hold over the run.
  std::vector<std::size_t> order(clusters);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    if (result.clusters[a].is_board != result.clusters[b].is_board)
      return result.clusters[a].is_board;
    return blob_px[a] > blob_px[b];
  });
  std::size_t want = 0;
  if (opt.boards > 0) {
    want = std::min(static_cast<std::size_t>(opt.boards), clusters);
  } else {
    for (const auto& hc : result.clusters) want += hc.is_board ? 1 : 0;
  }
  want = std::min(want, alg::kMaxBoards);
  std::vector<std::size_t> chosen(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(want));
  // Rejected clusters are background: their blob pixels count against a board's window.
  for (std::size_t c = 0; c < clusters; ++c) {
    if (std::find(chosen.begin(), chosen.end(), c) != chosen.end()) continue;
    result.clusters[c].is_board = false;
    for (int h = 0; h < kHueSteps; ++h)
      for (int s = 0; s < 256; ++s)
        background[static_cast<std::size_t>(h)][static_cast<std::size_t>(s)] +=
            stats[c].board_sat_by_hue[static_cast<std::size_t>(h)][static_cast<std::size_t>(s)];
  }
  for (const std::size_t c : chosen) result.clusters[c].is_board = true;
  std::sort(chosen.begin(), chosen.end(),
            [&](std::size_t a, std::size_t b) { return peaks[a] < peaks[b]; });
  for (const std::size_t c : chosen) {
    std::vector<int> others;
    for (std::size_t o = 0; o < clusters; ++o) {
      // A neighbour worth keeping off: a colour with a real share of the saturated pixels.
      if (o != c && all_px[o] >= 0.002 * all_px[c]) others.push_back(peaks[o]);
    }
    result.boards.push_back(window_from(stats[c], background, others));
  }
  name_uniquely(result.boards);
  return result;
}

std::vector<ProposedBoard> propose_guided(const RgbImage& frame,
                                          const std::vector<GuidedRect>& rects,
                                          const AutoOptions& opt) {
  const alg::BoardClassifier cls;
  HsvPlanes hsv;
  to_hsv(frame, cls, hsv);
  const std::size_t px = hsv.h.size();
  std::vector<int> inside(px, -1);
  for (std::size_t r = 0; r < rects.size(); ++r) {
    const GuidedRect& g = rects[r];
    if (g.x + g.w > static_cast<int>(frame.width_px) ||
        g.y + g.h > static_cast<int>(frame.height_px))
      throw std::runtime_error("rectangle '" + g.name + "' leaves the " +
                               std::to_string(frame.width_px) + "x" +
                               std::to_string(frame.height_px) + " frame");
    for (int y = g.y; y < g.y + g.h; ++y)
      for (int x = g.x; x < g.x + g.w; ++x)
        inside[static_cast<std::size_t>(y) * frame.width_px + static_cast<std::size_t>(x)] =
            static_cast<int>(r);
  }
  // Each rectangle's dominant saturated hue is its board; the rest of the rectangle (the wall
  // around a board) is neither board nor background.
  std::vector<PixelStats> stats(rects.size());
  std::vector<int> peaks;
  for (std::size_t r = 0; r < rects.size(); ++r) {
    std::array<double, kHueSteps> hist{};
    for (std::size_t i = 0; i < px; ++i)
      if (inside[i] == static_cast<int>(r) && hsv.s[i] >= opt.saturation_floor &&
          hsv.v[i] >= opt.value_floor)
        hist[hsv.h[i]] += 1.0;
    std::vector<int> basin_peaks;
    const std::vector<int> owner = hue_basins(hist, basin_peaks);
    if (basin_peaks.empty())
      throw std::runtime_error("rectangle '" + rects[r].name +
                               "' holds no saturated colour (saturation >= " +
                               std::to_string(opt.saturation_floor) + ")");
    int best = 0;
    double best_px = -1.0;
    for (std::size_t b = 0; b < basin_peaks.size(); ++b) {
      double sum = 0.0;
      for (int h = 0; h < kHueSteps; ++h)
        sum += owner[static_cast<std::size_t>(h)] == static_cast<int>(b)
                   ? hist[static_cast<std::size_t>(h)]
                   : 0.0;
      if (sum > best_px) {
        best_px = sum;
        best = static_cast<int>(b);
      }
    }
    peaks.push_back(basin_peaks[static_cast<std::size_t>(best)]);
    for (std::size_t i = 0; i < px; ++i) {
      if (inside[i] != static_cast<int>(r) || hsv.s[i] < opt.saturation_floor ||
          hsv.v[i] < opt.value_floor || owner[hsv.h[i]] != best)
        continue;
      stats[r].board_sat_by_hue[hsv.h[i]][hsv.s[i]] += 1.0;
      stats[r].board_value[hsv.v[i]] += 1.0;
    }
  }
  SatByHue background(kHueSteps);
  for (std::size_t i = 0; i < px; ++i)
    if (inside[i] < 0 && hsv.v[i] >= 30) background[hsv.h[i]][hsv.s[i]] += 1.0;
  std::vector<ProposedBoard> out;
  for (std::size_t r = 0; r < rects.size(); ++r) {
    std::vector<int> others;
    for (std::size_t o = 0; o < rects.size(); ++o)
      if (o != r) others.push_back(peaks[o]);
    ProposedBoard b = window_from(stats[r], background, others);
    b.name = rects[r].name;
    out.push_back(b);
  }
  return out;
}

// ---------------------------------------------------------------------------------------------

RunAreas measure_run(FrameSource& frames, const alg::ThresholdSet& windows, std::size_t step,
                     const Progress& progress) {
  RunAreas out;
  out.boards = windows.count;
  out.area_px.assign(windows.count, {});
  out.overlap_px.assign(windows.count, std::vector<std::uint64_t>(windows.count, 0));
  out.total_px.assign(windows.count, 0);
  std::vector<std::uint8_t> storage(alg::ColourTable::kStorageBytes);
  alg::ColourTable table;
  table.build(alg::BoardClassifier(windows), storage.data());
  RgbImage img;
  step = std::max<std::size_t>(step, 1);
  const std::size_t n = frames.size();
  for (std::size_t f = 0; f < n; f += step) {
    if (progress) progress(f, n, "areas");
    frames.read(f, img);
    const std::size_t px = static_cast<std::size_t>(img.width_px) * img.height_px;
    out.frame_px = px;
    std::array<std::uint32_t, 256> by_mask{};
    for (std::size_t i = 0; i < px; ++i)
      ++by_mask[table.classify(img.rgb[3 * i], img.rgb[3 * i + 1], img.rgb[3 * i + 2])];
    out.timestamp_ns.push_back(frames.timestamp_ns(f));
    for (std::size_t b = 0; b < windows.count; ++b) out.area_px[b].push_back(0);
    for (unsigned mask = 1; mask < 256; ++mask) {
      const std::uint32_t count = by_mask[mask];
      if (count == 0) continue;
      for (std::size_t a = 0; a < windows.count; ++a) {
        if ((mask & (1U << a)) == 0) continue;
        out.area_px[a].back() += count;
        out.total_px[a] += count;
        for (std::size_t b = a + 1; b < windows.count; ++b) {
          if ((mask & (1U << b)) == 0) continue;
          out.overlap_px[a][b] += count;
          out.overlap_px[b][a] += count;
        }
      }
    }
  }
  if (progress) progress(n, n, "areas");
  return out;
}

std::vector<std::string> window_warnings(const RunAreas& r, const std::vector<std::string>& names) {
  std::vector<std::string> out;
  const double frame_px = static_cast<double>(std::max<std::size_t>(r.frame_px, 1));
  std::vector<double> median(r.boards), p10(r.boards), p90(r.boards);
  for (std::size_t b = 0; b < r.boards; ++b) {
    const std::vector<double> a(r.area_px[b].begin(), r.area_px[b].end());
    median[b] = quantile(a, 0.5);
    p10[b] = quantile(a, 0.1);
    p90[b] = quantile(a, 0.9);
  }
  char line[400];
  for (std::size_t b = 0; b < r.boards; ++b) {
    const char* name = names[b].c_str();
    if (r.total_px[b] == 0) {
      std::snprintf(
          line, sizeof line,
          "board '%s': no pixel in its window in any frame (wrong colour, or not in view)", name);
      out.emplace_back(line);
      continue;
    }
    // What a board looks like here: the other boards' typical area when in view.
    std::vector<double> others;
    for (std::size_t o = 0; o < r.boards; ++o)
      if (o != b && p90[o] > 0.0) others.push_back(p90[o]);
    const double typical = others.empty() ? 0.0 : quantile(others, 0.5);
    const double share = median[b] / frame_px;
    if (share > 0.25 || (typical > 0.0 && median[b] > 3.0 * typical && share > 0.02)) {
      std::snprintf(line, sizeof line,
                    "board '%s' catches background: %.1f%% of the frame in half the frames "
                    "(%.0f px; the other boards at most %.0f px in most frames)",
                    name, 100.0 * share, median[b], typical);
      out.emplace_back(line);
    }
    if (p10[b] > 0.0 && p90[b] > 0.0 && (p90[b] - p10[b]) / p90[b] < 0.15) {
      std::snprintf(line, sizeof line,
                    "board '%s' has a nearly constant area (%.0f..%.0f px in 80%% of the frames): "
                    "it tells no places apart (background, or part of the robot in view)",
                    name, p10[b], p90[b]);
      out.emplace_back(line);
    }
  }
  for (std::size_t a = 0; a < r.boards; ++a) {
    for (std::size_t b = a + 1; b < r.boards; ++b) {
      const double smaller =
          static_cast<double>(std::max<std::uint64_t>(std::min(r.total_px[a], r.total_px[b]), 1));
      const double shared = static_cast<double>(r.overlap_px[a][b]);
      if (shared > 0.02 * smaller) {
        std::snprintf(line, sizeof line,
                      "boards '%s' and '%s' overlap: %.1f%% of the smaller one's pixels are in "
                      "both windows",
                      names[a].c_str(), names[b].c_str(), 100.0 * shared / smaller);
        out.emplace_back(line);
      }
    }
  }
  return out;
}

// ---------------------------------------------------------------------------------------------

alg::ThresholdSet threshold_set_of(const std::vector<ProposedBoard>& boards) {
  if (boards.size() > alg::kMaxBoards)
    throw std::runtime_error("more than " + std::to_string(alg::kMaxBoards) + " boards");
  alg::ThresholdSet set;
  for (const auto& b : boards) set.boards[set.count++] = b.window;
  return set;
}

std::string boards_toml(const std::vector<ProposedBoard>& boards, const std::string& base) {
  toml::table root;
  if (!base.empty()) {
    try {
      root = toml::parse(base);
    } catch (const toml::parse_error& e) {
      std::ostringstream where;
      where << "line " << e.source().begin.line << ": " << e.description();
      throw std::runtime_error(where.str());
    }
    root.erase("board");
  }
  toml::array list;
  for (const auto& b : boards) {
    const auto& w = b.window;
    toml::table t;
    t.insert("name", b.name);
    t.insert("hue_deg", toml::array{static_cast<std::int64_t>(std::lround(w.hue_min_deg)),
                                    static_cast<std::int64_t>(std::lround(w.hue_max_deg))});
    t.insert("saturation_min", static_cast<std::int64_t>(w.saturation_min));
    t.insert("value_min", static_cast<std::int64_t>(w.value_min));
    t.insert("value_max", static_cast<std::int64_t>(w.value_max));
    list.push_back(std::move(t));
  }
  root.insert("board", std::move(list));
  std::ostringstream o;
  o << "# Colour windows proposed by harmoloc-colours (docs/colours.md). Hue in degrees (min > "
       "max\n"
       "# wraps through 0), saturation and value 8-bit HSV, as the firmware segments them.\n";
  o << root << "\n";
  return o.str();
}

}  // namespace harmoloc::sim_host::colours
