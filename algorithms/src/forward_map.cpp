#include "harmoloc/algorithms/forward_map.hpp"

#include <algorithm>
#include <cmath>

#include "harmoloc/algorithms/column_gain.hpp"

namespace harmoloc::algorithms {

namespace {

constexpr float kPiF = 3.14159265358979F;

static_assert(ForwardMap::kHeadingSectors == 16, "the edge table below has 16 entries");
// Cosine and sine of sector edge k, at -pi + k pi / 8.
constexpr float kEdgeCos[16] = {-1.000000000F, -0.923879533F, -0.707106781F, -0.382683432F,
                                0.000000000F,  0.382683432F,  0.707106781F,  0.923879533F,
                                1.000000000F,  0.923879533F,  0.707106781F,  0.382683432F,
                                0.000000000F,  -0.382683432F, -0.707106781F, -0.923879533F};
constexpr float kEdgeSin[16] = {0.000000000F,  -0.382683432F, -0.707106781F, -0.923879533F,
                                -1.000000000F, -0.923879533F, -0.707106781F, -0.382683432F,
                                0.000000000F,  0.382683432F,  0.707106781F,  0.923879533F,
                                1.000000000F,  0.923879533F,  0.707106781F,  0.382683432F};

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

bool lay_out_grid(ForwardMap& map, std::uint32_t columns, std::uint32_t rows,
                  const std::uint8_t* stored) {
  map.columns = map.rows = map.tile_columns = map.tile_rows = map.tile_count = 0;
  if (columns == 0 || rows == 0 || columns > ForwardMap::kMaxDimension ||
      rows > ForwardMap::kMaxDimension)
    return false;
  const std::uint32_t tc = tiles_along(columns), tr = tiles_along(rows);
  const std::size_t positions = static_cast<std::size_t>(tc) * tr;
  if (positions > ForwardMap::kMaxTileGrid) return false;
  std::size_t count = 0;
  for (std::size_t t = 0; t < positions; ++t) count += stored == nullptr || stored[t] != 0 ? 1 : 0;
  if (count == 0 || count > ForwardMap::kMaxTiles) return false;
  std::uint16_t slot = 0;
  for (std::size_t t = 0; t < positions; ++t)
    map.tile_slot[t] = stored == nullptr || stored[t] != 0 ? slot++ : ForwardMap::kNoTile;
  map.columns = columns;
  map.rows = rows;
  map.tile_columns = tc;
  map.tile_rows = tr;
  map.tile_count = static_cast<std::uint32_t>(count);
  // Only what the layout uses is cleared (the arrays are large; the decoder lays out a grid on
  // every map it reads): the stored cells and the void cell.
  const std::size_t cells = map.stored_cells();
  std::fill_n(map.expected.begin(), cells * kMaxBoards, 0.0F);
  std::fill_n(map.route_distance_m.begin(), cells, 0.0F);
  std::fill_n(map.heading_rad.begin(), cells, 0.0F);
  std::fill_n(map.expected.begin() + ForwardMap::kVoidCell * kMaxBoards, kMaxBoards, 0.0F);
  map.has_heading_terms = false;
  if (ForwardMap::kHeadingTermStorage) {
    std::fill_n(map.heading_terms.begin(), cells * kMaxBoards * 2, 0.0F);
    std::fill_n(map.heading_terms.begin() + ForwardMap::kVoidCell * kMaxBoards * 2, kMaxBoards * 2,
                0.0F);
  }
  map.has_heading_coverage = false;
  if (ForwardMap::kHeadingTermStorage) {
    std::fill_n(map.heading_cover.begin(), cells, std::uint16_t{0});
    map.heading_cover[ForwardMap::kVoidCell] = 0;
  }
  map.has_bearings = false;
  map.bearing_a1_rad = map.bearing_a3_rad = 0.0F;
  map.bearing_camera_forward_m = 0.0F;
  map.bearing_sigma_rad.fill(0.0F);
  if (ForwardMap::kBearingStorage) {
    std::fill_n(map.bearing_rad.begin(), cells * kMaxBoards, ForwardMap::kNoBearing);
    std::fill_n(map.bearing_rad.begin() + ForwardMap::kVoidCell * kMaxBoards, kMaxBoards,
                ForwardMap::kNoBearing);
  } else {
    map.bearing_rad.fill(ForwardMap::kNoBearing);
  }
  map.route_distance_m[ForwardMap::kVoidCell] = ForwardMap::kVoidRouteDistance_m;
  map.heading_rad[ForwardMap::kVoidCell] = 0.0F;
  return true;
}

GridPoint locate(const ForwardMap& map, double x_m, double y_m) {
  std::uint32_t c = 0, r = 0;
  float fx = 0.0F, fy = 0.0F;
  double ox = 0.0, oy = 0.0;
  axis(x_m, map.origin_x_m, map.cell_m, map.columns, c, fx, ox);
  axis(y_m, map.origin_y_m, map.cell_m, map.rows, r, fy, oy);
  const std::uint32_t c1 = map.columns > 1U ? c + 1U : c;
  const std::uint32_t r1 = map.rows > 1U ? r + 1U : r;
  GridPoint p;
  p.index[0] = static_cast<std::uint32_t>(map.index(c, r));
  p.index[1] = static_cast<std::uint32_t>(map.index(c1, r));
  p.index[2] = static_cast<std::uint32_t>(map.index(c, r1));
  p.index[3] = static_cast<std::uint32_t>(map.index(c1, r1));
  p.weight[0] = (1.0F - fx) * (1.0F - fy);
  p.weight[1] = fx * (1.0F - fy);
  p.weight[2] = (1.0F - fx) * fy;
  p.weight[3] = fx * fy;
  p.outside_m =
      ox == 0.0 && oy == 0.0 ? 0.0F : static_cast<float>(std::min(1e6, std::hypot(ox, oy)));
  return p;
}

std::size_t nearest_stored_cell(const GridPoint& point) {
  int best = -1;
  for (int k = 0; k < 4; ++k) {
    if (point.index[k] == ForwardMap::kVoidCell) continue;
    if (best < 0 || point.weight[k] > point.weight[best]) best = k;
  }
  return best < 0 ? ForwardMap::kVoidCell : point.index[best];
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

int heading_sector(double yaw_rad) {
  return seen_heading(yaw_rad).sector;
}

SeenHeading seen_heading(double yaw_rad) {
  if (!std::isfinite(yaw_rad)) yaw_rad = 0.0;
  const double two_pi = 2.0 * static_cast<double>(kPiF);
  double u = (yaw_rad + static_cast<double>(kPiF)) / two_pi;  // turns from -pi
  u -= std::floor(u);
  const double at = u * ForwardMap::kHeadingSectors;
  SeenHeading h;
  h.sector = std::min(static_cast<int>(at), ForwardMap::kHeadingSectors - 1);
  h.within = static_cast<float>(std::min(1.0, at - h.sector));
  h.yaw_rad = static_cast<float>((u - 0.5) * two_pi);
  h.cos_yaw = static_cast<float>(std::cos(yaw_rad));
  h.sin_yaw = static_cast<float>(std::sin(yaw_rad));
  return h;
}

namespace {

// The heading at which the cell of storage index @p at reads @p h: @p h itself where the cell
// covers it (or holds no coverage), else the nearest edge of its covered sectors.
void covered_heading(const ForwardMap& map, std::size_t at, const SeenHeading& h, float& cos_yaw,
                     float& sin_yaw) {
  cos_yaw = h.cos_yaw;
  sin_yaw = h.sin_yaw;
  if (!map.has_heading_coverage || !h.keep_to_coverage) return;
  const std::uint32_t mask = map.heading_cover[at];
  if (mask == 0U || ((mask >> h.sector) & 1U) != 0U) return;
  constexpr int n = ForwardMap::kHeadingSectors;
  for (int d = 1; d <= n / 2; ++d) {
    const int up = (h.sector + d) % n, down = (h.sector - d + n) % n;
    const bool has_up = ((mask >> up) & 1U) != 0U, has_down = ((mask >> down) & 1U) != 0U;
    if (!has_up && !has_down) continue;
    // The sector above is entered at its lower edge, the one below left at its upper edge; at
    // the same count of sectors, the nearer edge.
    const int edge = has_down && (!has_up || h.within < 0.5F) ? (down + 1) % n : up;
    cos_yaw = kEdgeCos[edge];
    sin_yaw = kEdgeSin[edge];
    return;
  }
}

}  // namespace

void expected_features(const ForwardMap& map, const GridPoint& point, const SeenHeading& heading,
                       float* out) {
  expected_features(map, point, out);
  if (!ForwardMap::kHeadingTermStorage || !map.has_heading_terms) return;
  const std::size_t n = map.board_count;
  for (int k = 0; k < 4; ++k) {
    const float w = point.weight[k];
    if (w == 0.0F) continue;
    float c = 0.0F, s = 0.0F;
    covered_heading(map, point.index[k], heading, c, s);
    const float* t = map.heading_terms.data() + point.index[k] * kMaxBoards * 2;
    for (std::size_t b = 0; b < n; ++b) out[b] += w * (t[2 * b] * c + t[2 * b + 1] * s);
  }
  for (std::size_t b = 0; b < n; ++b) out[b] = std::max(out[b], 0.0F);
}

bool heading_covered(const ForwardMap& map, const GridPoint& point, const SeenHeading& heading) {
  const std::size_t cell = nearest_stored_cell(point);
  if (cell == ForwardMap::kVoidCell) return false;
  if (!ForwardMap::kHeadingTermStorage || !map.has_heading_coverage) return true;
  const std::uint32_t mask = map.heading_cover[cell];
  return mask == 0U || ((mask >> heading.sector) & 1U) != 0U;
}

bool heading_covered(const ForwardMap& map, double x_m, double y_m, double yaw_rad) {
  if (!ForwardMap::kHeadingTermStorage || !map.has_heading_coverage) return true;
  return heading_covered(map, locate(map, x_m, y_m), seen_heading(yaw_rad));
}

bool board_image_angle(const ForwardMap& map, const AreaVector& areas, std::size_t b,
                       float& angle_rad) {
  if (!map.has_bearings || !gives_bearing(areas, b)) return false;
  const double t = column_offset(areas, b);
  angle_rad = static_cast<float>(t * (static_cast<double>(map.bearing_a1_rad) +
                                      static_cast<double>(map.bearing_a3_rad) * t * t));
  return true;
}

bool projected_image_angle(const ForwardMap& map, const CameraAtPose& camera, std::size_t b,
                           float& angle_rad) {
  float column_px = 0.0F;
  if (!projected_centroid_column(map.projection, camera, b, column_px)) return false;
  angle_rad = image_angle_of_column(map, column_px);
  return true;
}

float image_angle_of_column(const ForwardMap& map, float column_px) {
  const auto w = static_cast<float>(map.projection.width_px);
  // Beyond the frame's side the law is not known, and a law with a3 < 0 turns back within
  // |t| < 0.58 at the least: a column past the side reads as just past it, which any angle
  // measured inside the frame misses by a few degrees.
  float t = (column_px - 0.5F * (w - 1.0F)) / w;
  t = t > 0.55F ? 0.55F : (t < -0.55F ? -0.55F : t);
  return t * (map.bearing_a1_rad + map.bearing_a3_rad * t * t);
}

bool expected_bearing(const ForwardMap& map, const GridPoint& point, std::size_t b,
                      float& bearing_rad) {
  if (!ForwardMap::kBearingStorage || !map.has_bearings || b >= kMaxBoards) return false;
  float reference = 0.0F, sum = 0.0F, weight = 0.0F;
  bool any = false;
  for (int k = 0; k < 4; ++k) {
    const float v = map.bearing_rad[point.index[k] * kMaxBoards + b];
    if (v == ForwardMap::kNoBearing || !(point.weight[k] > 0.0F)) continue;
    if (!any) {
      reference = v;
      any = true;
    }
    float d = v - reference;  // both in [-pi, pi]: one turn at most
    d = d > kPiF ? d - 2.0F * kPiF : (d < -kPiF ? d + 2.0F * kPiF : d);
    sum += point.weight[k] * d;
    weight += point.weight[k];
  }
  if (!any) return false;
  bearing_rad = reference + sum / weight;
  return true;
}

void expected_at_pose(const ForwardMap& map, const GridPoint& point, double x_m, double y_m,
                      const SeenHeading& heading, float* out) {
  expected_features(map, point, heading, out);
  if (map.has_visibility)
    apply_visibility(map, bearing_point(map, x_m, y_m, heading.cos_yaw, heading.sin_yaw),
                     heading.yaw_rad, out);
  if (projects_areas(map))
    apply_projected_areas(map,
                          camera_at_pose(map.projection, static_cast<float>(x_m),
                                         static_cast<float>(y_m), heading.cos_yaw, heading.sin_yaw),
                          out);
}

bool projects_areas(const ForwardMap& map) {
  for (std::size_t b = 0; b < map.board_count && b < kMaxBoards; ++b)
    if (projects_area(map, b)) return true;
  return false;
}

void apply_projected_areas(const ForwardMap& map, const CameraAtPose& camera, float* out,
                           std::uint32_t boards) {
  for (std::size_t b = 0; b < map.board_count && b < kMaxBoards; ++b) {
    if (((boards >> b) & 1U) == 0U || !projects_area(map, b)) continue;
    float area_px = 0.0F;
    if (projected_area_px(map.projection, camera, b, area_px))
      out[b] = area_px * map.projection.area_per_px[b];
  }
}

void apply_visibility(const ForwardMap& map, const GridPoint& seen_from, float yaw_rad, float* out,
                      float* bearing_rad, std::uint32_t boards) {
  if (!ForwardMap::kHeadingTermStorage || !ForwardMap::kBearingStorage || !map.has_visibility)
    return;
  const float half_fov = half_field_of_view(map);
  const std::size_t n = std::min<std::size_t>(map.board_count, kMaxBoards);
  for (std::size_t b = 0; b < n; ++b) {
    if (((boards >> b) & 1U) == 0U) continue;
    float reference = 0.0F, turn = 0.0F, weight = 0.0F, area = 0.0F, half_width = 0.0F;
    bool any = false;
    for (int k = 0; k < 4; ++k) {
      const std::size_t at = seen_from.index[k];
      const float v = map.bearing_rad[at * kMaxBoards + b];
      const float w = seen_from.weight[k];
      if (v == ForwardMap::kNoBearing || !(w > 0.0F)) continue;
      if (!any) {
        reference = v;
        any = true;
      }
      float d = v - reference;  // both in [-pi, pi]: one turn at most
      d = d > kPiF ? d - 2.0F * kPiF : (d < -kPiF ? d + 2.0F * kPiF : d);
      turn += w * d;
      weight += w;
      const float* t = map.heading_terms.data() + (at * kMaxBoards + b) * 2;
      area += w * t[0];
      half_width += w * t[1];
    }
    if (bearing_rad != nullptr)
      bearing_rad[b] = any ? reference + turn / weight : ForwardMap::kNoBearing;
    if (!any) continue;
    const float inv = 1.0F / weight;
    // yaw in [-pi, pi] (particles are kept wrapped; a pose may not be), the bearing within a
    // turn of it: two turns at most, and a value that is not finite reads as out of view.
    float a = yaw_rad - (reference + turn * inv);
    for (int k = 0; k < 2; ++k) a = a > kPiF ? a - 2.0F * kPiF : (a < -kPiF ? a + 2.0F * kPiF : a);
    out[b] = area * inv * visibility_gain(map, a) *
             visible_share(half_fov, half_width * inv, a < 0.0F ? -a : a);
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
  float heading_rad = 0.0F;
  route_heading(map, locate(map, x_m, y_m), heading_rad);
  return heading_rad;
}

bool route_heading(const ForwardMap& map, const GridPoint& point, float& heading_rad) {
  if (!map.has_heading) return false;
  const std::size_t cell = nearest_stored_cell(point);
  if (cell == ForwardMap::kVoidCell) return false;
  heading_rad = map.heading_rad[cell];
  return true;
}

}  // namespace harmoloc::algorithms
