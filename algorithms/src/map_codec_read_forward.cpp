#include "harmoloc/algorithms/map_codec.hpp"

#include <array>
#include <cmath>

#include "map_codec_parts.hpp"

namespace harmoloc::algorithms::map_codec_detail {

namespace {

// The values of one stored cell: every board's expected feature, then (in a second pass) the
// route distance and the heading. Versions 3 and 4 store them for the cells row by row, version
// 5 for the stored tiles' cells in storage order; both read through @p cell_at.
template <typename CellAt>
MapError decode_cells(Reader& r, ForwardMap& f, std::size_t cells, CellAt cell_at) {
  const std::size_t boards = f.board_count;
  const std::size_t values = cells * (boards + 1U + (f.has_heading ? 1U : 0U));
  if (!r.need(values * 4U, "forward map"))
    return MapError{"truncated: the forward map is shorter than its size says", r.pos()};
  for (std::size_t c = 0; c < cells; ++c) {
    float* e = f.expected.data() + cell_at(c) * kMaxBoards;
    for (std::size_t b = 0; b < boards; ++b) {
      r.f32(e[b], "forward map");
      if (!finite_in(e[b], 0.0F, 1.0e6F))
        return MapError{"forward map expected feature not finite and >= 0", r.pos()};
    }
  }
  for (std::size_t c = 0; c < cells; ++c) {
    float& d = f.route_distance_m[cell_at(c)];
    r.f32(d, "forward map");
    if (!finite_in(d, 0.0F, 1.0e4F))
      return MapError{"forward map route distance not finite and >= 0", r.pos()};
  }
  if (f.has_heading) {
    for (std::size_t c = 0; c < cells; ++c) {
      float& h = f.heading_rad[cell_at(c)];
      r.f32(h, "forward map");
      if (!finite_in(h, -4.0F, 4.0F))
        return MapError{"forward map heading not within -pi..pi", r.pos()};
    }
  }
  return MapError{};
}

// The board bearings (version 6), after the cells' other values: the lens's column-to-angle law
// angle(t) = a1 t + a3 t^3, each board's bearing spread, then every stored cell's bearing of
// every board, in storage order (version 6 is tiled). From version 9 the camera's offset ahead of
// the axle follows the law: where the cells' bearings are seen from.
MapError decode_bearings(Reader& r, std::uint32_t version, ForwardMap& f) {
  const std::size_t boards = f.board_count;
  const std::size_t offset_bytes = version >= 9 ? 4U : 0U;
  if (!r.need(8U + offset_bytes + boards * 4U, "forward map bearings"))
    return MapError{"truncated: the forward map's bearing law is cut short", r.pos()};
  float a1 = 0.0F, a3 = 0.0F;
  r.f32(a1, "forward map bearings");
  if (!(a1 > 0.0F && a1 <= 4.0F))  // false for NaN (the trainer's grid reaches 3.2)
    return MapError{"forward map bearing law: a1 not finite and in (0, 4] rad", r.pos()};
  // a3 >= -a1 also keeps the law increasing over the frame (|t| <= 0.5): its slope
  // a1 + 3 a3 t^2 is at least a1 / 4 there.
  r.f32(a3, "forward map bearings");
  if (!finite_in(a3, -a1, 3.0F * a1))
    return MapError{"forward map bearing law: a3 not finite and in [-a1, 3 a1]", r.pos()};
  float camera_forward = 0.0F;
  if (version >= 9) {
    r.f32(camera_forward, "forward map bearings");
    if (!finite_in(camera_forward, -1.0F, 1.0F))
      return MapError{"forward map bearings: camera offset not finite and within 1 m", r.pos()};
  }
  std::array<float, kMaxBoards> sigma{};
  bool any = false;
  for (std::size_t b = 0; b < boards; ++b) {
    r.f32(sigma[b], "forward map bearings");
    if (!finite_in(sigma[b], 0.0F, 1.0F))
      return MapError{"forward map bearing sigma not finite and in 0..1 rad", r.pos()};
    any = any || sigma[b] > 0.0F;
  }
  if (!any)
    return MapError{"forward map bearings model no board (every bearing sigma is 0)", r.pos()};
  const std::size_t cells = f.stored_cells();
  if (!r.need(cells * boards * 4U, "forward map bearings"))
    return MapError{"truncated: the forward map's bearings are shorter than its size says",
                    r.pos()};
  for (std::size_t c = 0; c < cells; ++c) {
    float* bearing = f.bearing_rad.data() + c * kMaxBoards;
    for (std::size_t b = 0; b < boards; ++b) {
      r.f32(bearing[b], "forward map bearings");
      if (bearing[b] != ForwardMap::kNoBearing && !finite_in(bearing[b], -3.1416F, 3.1416F))
        return MapError{"forward map bearing neither within -pi..pi nor 8 (none)", r.pos()};
    }
  }
  f.bearing_a1_rad = a1;
  f.bearing_a3_rad = a3;
  f.bearing_camera_forward_m = camera_forward;
  f.bearing_sigma_rad = sigma;
  return MapError{};
}

// The heading terms (version 7), after the bearings: every stored cell's c and s of every board,
// in storage order.
MapError decode_heading_terms(Reader& r, ForwardMap& f) {
  const std::size_t boards = f.board_count, cells = f.stored_cells();
  if (!r.need(cells * boards * 8U, "forward map heading terms"))
    return MapError{"truncated: the forward map's heading terms are shorter than its size says",
                    r.pos()};
  for (std::size_t c = 0; c < cells; ++c) {
    float* t = f.heading_terms.data() + c * kMaxBoards * 2;
    for (std::size_t b = 0; b < 2 * boards; ++b) {
      r.f32(t[b], "forward map heading terms");
      if (!finite_in(t[b], -1.0e6F, 1.0e6F))
        return MapError{"forward map heading term not finite and within 1e6", r.pos()};
    }
  }
  return MapError{};
}

// The visibility (version 10), in the heading terms' place: the angle gain (version 14: and its
// optical axis), then every stored cell's feature seen whole on the axis and angular half-width
// of every board, in storage order.
MapError decode_visibility(Reader& r, std::uint32_t version, ForwardMap& f) {
  const std::size_t boards = f.board_count, cells = f.stored_cells();
  float gain = 0.0F, axis = 0.0F;
  if (!r.f32(gain, "forward map visibility"))
    return MapError{"truncated: the forward map's visibility is cut short", r.pos()};
  if (!finite_in(gain, -2.0F, 2.0F))
    return MapError{"forward map visibility: angle gain not finite and in -2..2", r.pos()};
  if (version >= 14) {
    if (!r.f32(axis, "forward map visibility"))
      return MapError{"truncated: the forward map's visibility is cut short", r.pos()};
    // Within the lens's half field of view (the law's half_field_of_view; the map format's
    // bound on a1 + a3 / 4 keeps it under pi / 2).
    if (!finite_in(axis, -half_field_of_view(f), half_field_of_view(f)))
      return MapError{
          "forward map visibility: optical axis not finite and within the field of "
          "view",
          r.pos()};
  }
  f.visibility_angle_gain = gain;
  f.visibility_axis_rad = axis;
  if (!r.need(cells * boards * 8U, "forward map visibility"))
    return MapError{"truncated: the forward map's visibility is shorter than its size says",
                    r.pos()};
  for (std::size_t c = 0; c < cells; ++c) {
    float* t = f.heading_terms.data() + c * kMaxBoards * 2;
    for (std::size_t b = 0; b < boards; ++b) {
      r.f32(t[2 * b], "forward map visibility");
      if (!finite_in(t[2 * b], 0.0F, 1.0e6F))
        return MapError{"forward map visibility: a feature not finite and in 0..1e6", r.pos()};
      r.f32(t[2 * b + 1], "forward map visibility");
      if (!finite_in(t[2 * b + 1], 0.0F, 3.2F))
        return MapError{"forward map visibility: a half-width not finite and in 0..3.2 rad",
                        r.pos()};
    }
  }
  return MapError{};
}

// The heading coverage (version 8), after the heading terms: every stored cell's sectors, kept
// only where this build holds heading terms (without them nothing reads it).
MapError decode_heading_coverage(Reader& r, ForwardMap& f) {
  const std::size_t cells = f.stored_cells();
  if (!r.need(cells * 2U, "forward map heading coverage"))
    return MapError{"truncated: the forward map's heading coverage is shorter than its size says",
                    r.pos()};
  for (std::size_t c = 0; c < cells; ++c) {
    std::uint16_t mask = 0;
    r.u16(mask, "forward map heading coverage");
    if (ForwardMap::kHeadingTermStorage) f.heading_cover[c] = mask;
  }
  return MapError{};
}

// The projected bearings (version 15), last in the section: the frame's size, the camera on the
// robot (origin, then its right, down and forward axes), its intrinsics and lens, then per board
// its outline's point count (0, or 3 to BearingProjection::kMaxPoints) and points, from version
// 16 after an outline its bearings' spread (0: the cells'), from version 17 its feature per
// projected pixel (0: the cells' areas) and its projected areas' noise (0: the map's sigma).
MapError decode_projection(Reader& r, std::uint32_t version, ForwardMap& f) {
  BearingProjection p;
  if (!r.need(8U + 12U * 4U + 9U * 4U, "forward map projection"))
    return MapError{"truncated: the forward map's projection is cut short", r.pos()};
  r.u32(p.width_px, "forward map projection");
  r.u32(p.height_px, "forward map projection");
  if (p.width_px == 0 || p.height_px == 0 || p.width_px > 8192 || p.height_px > 8192)
    return MapError{"forward map projection: frame size out of range", r.pos()};
  for (auto* v : {&p.origin_m, &p.right, &p.down, &p.forward}) {
    for (float& x : *v) r.f32(x, "forward map projection");
  }
  for (const float x : p.origin_m) {
    if (!finite_in(x, -10.0F, 10.0F))
      return MapError{"forward map projection: camera place not finite and within 10 m", r.pos()};
  }
  // The axes: unit vectors at right angles (within float rounding of the trainer's doubles).
  const auto dot = [](const std::array<float, 3>& a, const std::array<float, 3>& b) {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  };
  for (const auto* a : {&p.right, &p.down, &p.forward}) {
    if (!finite_in(dot(*a, *a), 0.999F, 1.001F))
      return MapError{"forward map projection: a camera axis is not a unit vector", r.pos()};
  }
  if (!finite_in(dot(p.right, p.down), -1e-3F, 1e-3F) ||
      !finite_in(dot(p.right, p.forward), -1e-3F, 1e-3F) ||
      !finite_in(dot(p.down, p.forward), -1e-3F, 1e-3F))
    return MapError{"forward map projection: the camera's axes are not at right angles", r.pos()};
  for (float* x :
       {&p.focal_px, &p.cx_px, &p.cy_px, &p.k1, &p.k2, &p.k3, &p.p1, &p.p2, &p.max_radius2})
    r.f32(*x, "forward map projection");
  const auto w = static_cast<float>(p.width_px), h = static_cast<float>(p.height_px);
  if (!finite_in(p.focal_px, 1.0F, 100.0F * w) || !finite_in(p.cx_px, 0.0F, w) ||
      !finite_in(p.cy_px, 0.0F, h))
    return MapError{
        "forward map projection: intrinsics out of range (focal length, principal "
        "point in the frame)",
        r.pos()};
  for (const float k : {p.k1, p.k2, p.k3, p.p1, p.p2}) {
    if (!finite_in(k, -100.0F, 100.0F))
      return MapError{"forward map projection: a lens coefficient not finite and within 100",
                      r.pos()};
  }
  if (!finite_in(p.max_radius2, 1e-4F, 1e18F))
    return MapError{"forward map projection: lens radius not finite and positive", r.pos()};
  bool any = false;
  for (std::size_t b = 0; b < f.board_count; ++b) {
    std::uint32_t n = 0;
    if (!r.u32(n, "forward map projection"))
      return MapError{"truncated: the forward map's projection is cut short", r.pos()};
    if (n != 0 && (n < 3 || n > BearingProjection::kMaxPoints))
      return MapError{"forward map projection: an outline has neither 0 nor 3 to 8 points",
                      r.pos()};
    if (n != 0 && !(f.bearing_sigma_rad[b] > 0.0F))
      return MapError{"forward map projection: an outline for a board without bearings", r.pos()};
    if (!r.need(12U * n, "forward map projection"))
      return MapError{"truncated: the forward map's projection is cut short", r.pos()};
    p.points[b] = static_cast<std::uint8_t>(n);
    for (std::size_t i = 0; i < 3U * n; ++i) {
      float& x = p.point_m(b, i / 3, i % 3);
      r.f32(x, "forward map projection");
      if (!finite_in(x, -1.0e4F, 1.0e4F))
        return MapError{"forward map projection: an outline point not finite and within 10 km",
                        r.pos()};
    }
    if (n != 0 && version >= 16) {
      if (!r.f32(p.sigma_rad[b], "forward map projection"))
        return MapError{"truncated: the forward map's projection is cut short", r.pos()};
      // 0: the cells' spread (a version 15 map written again); beyond 45 degrees it is no
      // bearing.
      if (!finite_in(p.sigma_rad[b], 0.0F, 0.785F))
        return MapError{
            "forward map projection: an outline's bearing spread not finite and within 0 to 45 "
            "degrees",
            r.pos()};
    }
    if (n != 0 && version >= 17) {
      if (!r.f32(p.area_per_px[b], "forward map projection") ||
          !r.f32(p.area_sigma[b], "forward map projection"))
        return MapError{"truncated: the forward map's projection is cut short", r.pos()};
      // 0: the cells' areas; a feature per pixel beyond the largest area scale is no area.
      if (!finite_in(p.area_per_px[b], 0.0F, 1.0e3F))
        return MapError{
            "forward map projection: an outline's feature per pixel not finite and within 0 to "
            "1000",
            r.pos()};
      // 0: the map's sigma; within the bound on the map's sigmas.
      if (!finite_in(p.area_sigma[b], 0.0F, 1.0e3F))
        return MapError{
            "forward map projection: an outline's area noise not finite and within 0 to 1000",
            r.pos()};
    }
    any = any || n != 0;
  }
  if (!any) return MapError{"forward map projection holds no outline", r.pos()};
  f.projection = p;
  return MapError{};
}

}  // namespace

// The forward map section (version 3; tiled from version 5, bearings from version 6).
MapError decode_forward(Reader& r, std::uint32_t version, std::uint32_t boards, ForwardMap& f) {
  std::uint32_t columns = 0, rows = 0;
  f.columns = f.rows = 0;
  f.has_bearings = false;
  f.has_heading_terms = false;
  f.has_heading_coverage = false;
  f.has_visibility = false;
  f.visibility_angle_gain = 0.0F;
  f.visibility_axis_rad = 0.0F;
  f.projection = BearingProjection{};
  if (!r.u32(columns, "forward map size") || !r.u32(rows, "forward map size"))
    return MapError{"truncated: no room for the forward map's size", r.pos()};
  if (columns == 0 && rows == 0) return MapError{};
  // Versions 3 and 4 store every cell of a grid of at most 4096; version 5 the tiles near the
  // training run of a grid of at most this build's tile grid.
  const bool tiled = version >= 5;
  if (tiled ? (columns == 0 || rows == 0 || columns > ForwardMap::kMaxDimension ||
               rows > ForwardMap::kMaxDimension ||
               static_cast<std::size_t>(tiles_along(columns)) * tiles_along(rows) >
                   ForwardMap::kMaxTileGrid)
            : (columns == 0 || rows == 0 || columns > 256 || rows > 256 ||
               static_cast<std::size_t>(columns) * rows > 4096)) {
    return MapError{tiled ? "forward map grid out of range (its tile grid exceeds this firmware's)"
                          : "forward map grid out of range (at most 256 x 256 and 4096 cells)",
                    r.pos()};
  }
  std::uint32_t board_count = 0;
  float origin_x = 0.0F, origin_y = 0.0F, cell = 0.0F;
  if (!r.f32(origin_x, "forward map origin") || !r.f32(origin_y, "forward map origin") ||
      !r.f32(cell, "forward map cell size") || !r.u32(board_count, "forward map boards")) {
    return MapError{"truncated: the forward map's header is cut short", r.pos()};
  }
  if (!(std::fabs(origin_x) <= 1.0e4F) || !(std::fabs(origin_y) <= 1.0e4F) ||
      !finite_in(cell, 1.0e-3F, 10.0F)) {
    return MapError{"forward map origin or cell size out of range", r.pos()};
  }
  if (board_count != boards)
    return MapError{"forward map board count differs from the thresholds'", r.pos()};
  std::array<float, kMaxBoards> sigma{};
  bool any = false;
  for (std::size_t b = 0; b < board_count; ++b) {
    if (!r.f32(sigma[b], "forward map sigma"))
      return MapError{"truncated: the forward map's sigmas are cut short", r.pos()};
    if (!finite_in(sigma[b], 0.0F, 1.0e3F))
      return MapError{"forward map sigma not finite and in 0..1000", r.pos()};
    any = any || sigma[b] > 0.0F;
  }
  if (!any) return MapError{"forward map models no board (every sigma is 0)", r.pos()};
  std::uint8_t flag = 0, pad[3] = {0, 0, 0};
  if (!r.u8(flag, "forward map flags") || !r.u8(pad[0], "forward map flags") ||
      !r.u8(pad[1], "forward map flags") || !r.u8(pad[2], "forward map flags")) {
    return MapError{"truncated: the forward map's flags are cut short", r.pos()};
  }
  // Bit 0: headings; bit 1 (version 6 on): bearings; bit 2 (version 7 on): heading terms; bit 3
  // (version 8 on): heading coverage; bit 4 (version 10 on): visibility.
  const unsigned known = version >= 15   ? 63U
                         : version >= 10 ? 31U
                         : version >= 8  ? 15U
                         : version >= 7  ? 7U
                         : version >= 6  ? 3U
                                         : 1U;
  if ((flag & ~known) != 0U || pad[0] != 0 || pad[1] != 0 || pad[2] != 0)
    return MapError{"forward map flags: unknown bits set", r.pos()};
  if ((flag & 8U) != 0U && (flag & 1U) == 0U)
    return MapError{"forward map holds heading coverage but no headings", r.pos()};
  if ((flag & 16U) != 0U && ((flag & 2U) == 0U || (flag & 4U) != 0U))
    return MapError{"forward map holds visibility without bearings or with heading terms", r.pos()};
  if ((flag & 32U) != 0U && (flag & 2U) == 0U)
    return MapError{"forward map holds projected bearings but no bearings", r.pos()};
  if ((flag & 2U) != 0U && !ForwardMap::kBearingStorage)
    return MapError{
        "forward map holds bearings this build has no room for (train it with "
        "--no-bearings)",
        r.pos()};
  if ((flag & 4U) != 0U && !ForwardMap::kHeadingTermStorage)
    return MapError{
        "forward map holds heading terms (a floor map) this build has no room for (train it "
        "without --heading-terms)",
        r.pos()};
  if ((flag & 16U) != 0U && !ForwardMap::kHeadingTermStorage)
    return MapError{
        "forward map holds visibility (a floor map) this build has no room for (train it "
        "with --no-visibility)",
        r.pos()};

  // The layout: every tile (versions 3 and 4), or the stored tiles' bitmap (version 5).
  const std::size_t positions = static_cast<std::size_t>(tiles_along(columns)) * tiles_along(rows);
  std::array<std::uint8_t, ForwardMap::kMaxTileGrid> stored{};
  if (tiled) {
    std::uint32_t tile_count = 0;
    if (!r.u32(tile_count, "forward map tile count"))
      return MapError{"truncated: the forward map's tile count is missing", r.pos()};
    if (tile_count == 0 || tile_count > ForwardMap::kMaxTiles)
      return MapError{"forward map tile count out of range (more than this firmware holds)",
                      r.pos()};
    const std::size_t mask_bytes = (positions + 7U) / 8U;
    if (!r.need(mask_bytes, "forward map tiles"))
      return MapError{"truncated: the forward map's tile bitmap is cut short", r.pos()};
    std::size_t count = 0;
    for (std::size_t i = 0; i < mask_bytes; ++i) {
      std::uint8_t bits = 0;
      r.u8(bits, "forward map tiles");
      for (std::size_t k = 0; k < 8; ++k) {
        const bool set = ((bits >> k) & 1U) != 0U;
        if (!set) continue;
        if (8U * i + k >= positions)
          return MapError{"forward map tile bitmap: bits set beyond the tile grid", r.pos()};
        stored[8U * i + k] = 1;
        ++count;
      }
    }
    if (count != tile_count)
      return MapError{"forward map tile bitmap does not hold the tile count", r.pos()};
  } else {
    stored.fill(1);
  }
  if (!lay_out_grid(f, columns, rows, stored.data()))
    return MapError{"forward map needs more tiles than this firmware holds", r.pos()};
  f.origin_x_m = origin_x;
  f.origin_y_m = origin_y;
  f.cell_m = cell;
  f.board_count = board_count;
  f.sigma = sigma;
  f.has_heading = (flag & 1U) != 0U;
  MapError e =
      tiled ? decode_cells(r, f, f.stored_cells(), [](std::size_t c) { return c; })
            : decode_cells(r, f, static_cast<std::size_t>(columns) * rows, [&f](std::size_t c) {
                return f.index(static_cast<std::uint32_t>(c % f.columns),
                               static_cast<std::uint32_t>(c / f.columns));
              });
  if (!e && (flag & 2U) != 0U) {
    e = decode_bearings(r, version, f);
    f.has_bearings = !e;
  }
  if (!e && (flag & 4U) != 0U) {
    e = decode_heading_terms(r, f);
    f.has_heading_terms = !e;
  }
  if (!e && (flag & 16U) != 0U) {
    e = decode_visibility(r, version, f);
    f.has_visibility = !e;
  }
  if (!e && (flag & 8U) != 0U) {
    e = decode_heading_coverage(r, f);
    f.has_heading_coverage = !e && ForwardMap::kHeadingTermStorage;
  }
  if (!e && (flag & 32U) != 0U) e = decode_projection(r, version, f);
  if (e) {
    f.columns = f.rows = 0;
    f.projection = BearingProjection{};
    return e;
  }
  return MapError{};
}

}  // namespace harmoloc::algorithms::map_codec_detail
