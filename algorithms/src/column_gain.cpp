#include "harmoloc/algorithms/column_gain.hpp"

#include <algorithm>
#include <cmath>

#include "harmoloc/algorithms/forward_map.hpp"

namespace harmoloc::algorithms {

double ColumnGain::at(double t) const {
  return std::exp(static_cast<double>(c2) * t * t + static_cast<double>(c4) * t * t * t * t);
}

double column_offset(double u_px, std::uint32_t width_px) {
  if (width_px == 0) return 0.0;
  return (u_px - 0.5 * (static_cast<double>(width_px) - 1.0)) / width_px;
}

double column_offset(const AreaVector& areas, std::size_t board) {
  return column_offset(areas.centroid_column_px(board), areas.width_px);
}

float remove_column_gain(const ColumnGain& gain, const AreaVector& areas, std::size_t board,
                         float feature) {
  if (!gain.present() || !areas.columns_measured() || board >= areas.count ||
      areas.pixels[board] == 0)
    return feature;
  return static_cast<float>(static_cast<double>(feature) / gain.at(column_offset(areas, board)));
}

double column_gain_log_extent(double c2, double c4) {
  // log G = c2 s + c4 s^2 over s = t^2 in [0, 0.25]: largest at an end or at the vertex.
  const auto log_gain = [&](double s) { return c2 * s + c4 * s * s; };
  double extent = std::max(std::fabs(log_gain(0.0)), std::fabs(log_gain(0.25)));
  if (c4 != 0.0) {
    const double vertex = -c2 / (2.0 * c4);
    if (vertex > 0.0 && vertex < 0.25) extent = std::max(extent, std::fabs(log_gain(vertex)));
  }
  return extent;
}

bool column_gain_in_range(double c2, double c4) {
  if (!std::isfinite(c2) || !std::isfinite(c4)) return false;
  // A hair over the bound, so that a float-rounded fit at the bound still reads back.
  return column_gain_log_extent(c2, c4) <= std::log(kMaxColumnGain) * (1.0 + 1e-6);
}

void ColumnGainFit::add_pair(const AreaVector& first, const AreaVector& second,
                             std::size_t boards) {
  ++pairs_;
  for (std::size_t b = 0; b < boards; ++b) {
    if (!gives_bearing(first, b) || !gives_bearing(second, b)) continue;
    const double t1 = column_offset(first, b), t2 = column_offset(second, b);
    const double x2 = t1 * t1 - t2 * t2, x4 = t1 * t1 * t1 * t1 - t2 * t2 * t2 * t2;
    const double y = std::log(static_cast<double>(first.pixels[b]) / second.pixels[b]);
    s22_ += x2 * x2;
    s24_ += x2 * x4;
    s44_ += x4 * x4;
    r2_ += x2 * y;
    r4_ += x4 * y;
    ++observations_;
  }
}

bool ColumnGainFit::solve(std::size_t min_observations, ColumnGain& out) const {
  out = ColumnGain{};
  const double det = s22_ * s44_ - s24_ * s24_;
  if (observations_ < min_observations || !(det > 0.0)) return false;
  const double c2 = (s44_ * r2_ - s24_ * r4_) / det;
  const double c4 = (s22_ * r4_ - s24_ * r2_) / det;
  if (!column_gain_in_range(c2, c4)) return false;
  out.c2 = static_cast<float>(c2);
  out.c4 = static_cast<float>(c4);
  return true;
}

}  // namespace harmoloc::algorithms
