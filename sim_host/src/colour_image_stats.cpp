#include <algorithm>

#include "colour_windows_parts.hpp"

namespace harmoloc::sim_host::colours::detail {

namespace alg = algorithms;

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const double pos = q * static_cast<double>(v.size() - 1);
  const auto i = static_cast<std::size_t>(pos);
  const std::size_t j = std::min(i + 1, v.size() - 1);
  return v[i] + (v[j] - v[i]) * (pos - static_cast<double>(i));
}

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

}  // namespace harmoloc::sim_host::colours::detail
