#include "harmoloc/algorithms/forward_map.hpp"

#include <algorithm>
#include <cmath>

namespace harmoloc::algorithms {

namespace {

// Cell coordinate along one axis: the lower corner index and the fraction towards the next,
// clamped to the grid; @p outside_m gets how far beyond the border the position lies.
void axis(double position_m, float origin_m, float cell_m, std::uint32_t cells,
          std::uint32_t& lower, float& fraction, double& outside_m) {
  const double u = (position_m - static_cast<double>(origin_m)) / static_cast<double>(cell_m);
  const double last = static_cast<double>(cells - 1U);
  if (!(u > 0.0)) {  // also NaN
    lower = 0;
    fraction = 0.0F;
    outside_m = std::isfinite(u) ? -u * static_cast<double>(cell_m) : 1e6;
    return;
  }
  if (u >= last) {
    lower = cells > 1U ? cells - 2U : 0U;
    fraction = cells > 1U ? 1.0F : 0.0F;
    outside_m = std::isfinite(u) ? (u - last) * static_cast<double>(cell_m) : 1e6;
    return;
  }
  const double f = std::floor(u);
  lower = static_cast<std::uint32_t>(f);
  fraction = static_cast<float>(u - f);
  outside_m = 0.0;
}

}  // namespace

GridPoint locate(const ForwardMap& map, double x_m, double y_m) {
  std::uint32_t c = 0, r = 0;
  float fx = 0.0F, fy = 0.0F;
  double ox = 0.0, oy = 0.0;
  axis(x_m, map.origin_x_m, map.cell_m, map.columns, c, fx, ox);
  axis(y_m, map.origin_y_m, map.cell_m, map.rows, r, fy, oy);
  const std::uint32_t c1 = map.columns > 1U ? c + 1U : c;
  const std::uint32_t r1 = map.rows > 1U ? r + 1U : r;
  GridPoint p;
  p.index[0] = r * map.columns + c;
  p.index[1] = r * map.columns + c1;
  p.index[2] = r1 * map.columns + c;
  p.index[3] = r1 * map.columns + c1;
  p.weight[0] = (1.0F - fx) * (1.0F - fy);
  p.weight[1] = fx * (1.0F - fy);
  p.weight[2] = (1.0F - fx) * fy;
  p.weight[3] = fx * fy;
  p.outside_m =
      ox == 0.0 && oy == 0.0 ? 0.0F : static_cast<float>(std::min(1e6, std::hypot(ox, oy)));
  return p;
}

void expected_features(const ForwardMap& map, const GridPoint& point, float* out) {
  const std::size_t n = map.board_count;
  const float* corner[4];
  for (int k = 0; k < 4; ++k) corner[k] = map.expected.data() + point.index[k] * kMaxBoards;
  for (std::size_t b = 0; b < n; ++b) {
    out[b] = point.weight[0] * corner[0][b] + point.weight[1] * corner[1][b] +
             point.weight[2] * corner[2][b] + point.weight[3] * corner[3][b];
  }
}

float route_distance(const ForwardMap& map, const GridPoint& point) {
  const auto& d = map.route_distance_m;
  return point.weight[0] * d[point.index[0]] + point.weight[1] * d[point.index[1]] +
         point.weight[2] * d[point.index[2]] + point.weight[3] * d[point.index[3]] +
         point.outside_m;
}

float route_heading(const ForwardMap& map, double x_m, double y_m) {
  if (!map.has_heading || !map.present()) return 0.0F;
  const GridPoint p = locate(map, x_m, y_m);
  int best = 0;
  for (int k = 1; k < 4; ++k) {
    if (p.weight[k] > p.weight[best]) best = k;
  }
  return map.heading_rad[p.index[best]];
}

}  // namespace harmoloc::algorithms
