#include "harmoloc/algorithms/map_codec.hpp"

#include <cmath>
#include <cstring>

#include "harmoloc/algorithms/crc32.hpp"

namespace harmoloc::algorithms {

namespace {

// Calibration entry ids (version 4).
constexpr std::uint32_t kCalibrationFixRmseX = 1;
constexpr std::uint32_t kCalibrationFixRmseY = 2;
constexpr std::uint32_t kCalibrationPassSpread = 3;
constexpr std::uint32_t kCalibrationLocalLinearRidge = 4;
constexpr std::uint32_t kCalibrationLeftWheelScale = 5;
constexpr std::uint32_t kCalibrationRightWheelScale = 6;
constexpr std::uint32_t kCalibrationTrackScale = 7;
constexpr float kMinOdometryScale = 0.5F, kMaxOdometryScale = 2.0F;

constexpr std::uint8_t kMagic[8] = {'H', 'A', 'R', 'M', 'O', 'M', 'A', 'P'};

class Writer {
 public:
  void bytes(const void* p, std::size_t n) {
    const auto* b = static_cast<const std::uint8_t*>(p);
    out.insert(out.end(), b, b + n);
  }
  void u8(std::uint8_t v) { out.push_back(v); }
  void u32(std::uint32_t v) {
    for (int i = 0; i < 4; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  void f32(float v) {
    std::uint32_t u = 0;
    std::memcpy(&u, &v, 4);
    u32(u);
  }
  std::vector<std::uint8_t> out;
};

class Reader {
 public:
  Reader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  bool u8(std::uint8_t& v, const char* what) {
    if (!need(1, what)) return false;
    v = data_[pos_++];
    return true;
  }
  bool u32(std::uint32_t& v, const char* what) {
    if (!need(4, what)) return false;
    v = 0;
    for (int i = 0; i < 4; ++i) v |= static_cast<std::uint32_t>(data_[pos_ + i]) << (8 * i);
    pos_ += 4;
    return true;
  }
  bool f32(float& v, const char* what) {
    std::uint32_t u = 0;
    if (!u32(u, what)) return false;
    std::memcpy(&v, &u, 4);
    return true;
  }
  bool need(std::size_t n, const char* what) {
    if (size_ - pos_ < n) {
      error = MapError{what, pos_};
      return false;
    }
    return true;
  }
  std::size_t pos() const { return pos_; }
  MapError error;

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

bool finite_positive(float v) {
  return std::isfinite(v) && v > 0.0F;
}

bool finite_in(float v, float lo, float hi) {
  return v >= lo && v <= hi;  // false for NaN
}

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

// The forward map section (version 3; tiled from version 5).
MapError decode_forward(Reader& r, std::uint32_t version, std::uint32_t boards, ForwardMap& f) {
  std::uint32_t columns = 0, rows = 0;
  f.columns = f.rows = 0;
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
  if (flag > 1U || pad[0] != 0 || pad[1] != 0 || pad[2] != 0)
    return MapError{"forward map flags: unknown bits set", r.pos()};

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
  f.has_heading = flag == 1U;
  const MapError e =
      tiled ? decode_cells(r, f, f.stored_cells(), [](std::size_t c) { return c; })
            : decode_cells(r, f, static_cast<std::size_t>(columns) * rows, [&f](std::size_t c) {
                return f.index(static_cast<std::uint32_t>(c % f.columns),
                               static_cast<std::uint32_t>(c / f.columns));
              });
  if (e) {
    f.columns = f.rows = 0;
    return e;
  }
  return MapError{};
}

}  // namespace

std::vector<std::uint8_t> encode_map(const MapFile& map) {
  Writer w;
  const HarmonicModel& m = map.model;
  w.bytes(kMagic, sizeof kMagic);
  w.u32(kMapFormatVersion);
  w.u32(map.image_width_px);
  w.u32(map.image_height_px);
  w.u32(static_cast<std::uint32_t>(map.thresholds.count));
  for (std::size_t i = 0; i < map.thresholds.count; ++i) {
    const ColourThreshold& t = map.thresholds.boards[i];
    w.f32(t.hue_min_deg);
    w.f32(t.hue_max_deg);
    w.u8(t.saturation_min);
    w.u8(t.value_min);
    w.u8(t.value_max);
    w.u8(0);
  }
  w.u32(m.sample_count);
  w.u32(m.feature_count);
  for (std::size_t k = 0; k < m.feature_count; ++k) w.u8(m.board_index[k]);
  w.f32(m.area_scale);
  w.f32(m.sigma_x);
  w.f32(m.sigma_y);
  w.f32(m.gamma_x);
  w.f32(m.gamma_y);
  w.f32(m.max_nearest_distance);
  w.f32(m.max_dissimilarity);
  for (std::size_t k = 0; k < m.feature_count; ++k) w.f32(m.feature_weight[k]);
  for (std::size_t i = 0; i < m.sample_count; ++i) {
    for (std::size_t k = 0; k < m.feature_count; ++k) w.f32(m.sample(i)[k]);
    w.f32(m.target_x_m[i]);
    w.f32(m.target_y_m[i]);
  }
  const ForwardMap& f = map.forward;
  w.u32(f.present() ? f.columns : 0U);
  w.u32(f.present() ? f.rows : 0U);
  if (f.present()) {
    w.f32(f.origin_x_m);
    w.f32(f.origin_y_m);
    w.f32(f.cell_m);
    w.u32(f.board_count);
    for (std::size_t b = 0; b < f.board_count; ++b) w.f32(f.sigma[b]);
    w.u8(f.has_heading ? 1U : 0U);
    w.u8(0);
    w.u8(0);
    w.u8(0);
    // Version 5: the stored tiles as a bitmap over the tile grid (row-major, LSB first), then
    // their cells in storage order.
    w.u32(f.tile_count);
    const std::size_t positions = static_cast<std::size_t>(f.tile_columns) * f.tile_rows;
    for (std::size_t i = 0; i < (positions + 7U) / 8U; ++i) {
      std::uint8_t bits = 0;
      for (std::size_t k = 0; k < 8 && 8U * i + k < positions; ++k) {
        if (f.tile_slot[8U * i + k] != ForwardMap::kNoTile)
          bits |= static_cast<std::uint8_t>(1U << k);
      }
      w.u8(bits);
    }
    const std::size_t cells = f.stored_cells();
    for (std::size_t c = 0; c < cells; ++c) {
      for (std::size_t b = 0; b < f.board_count; ++b) w.f32(f.expected[c * kMaxBoards + b]);
    }
    for (std::size_t c = 0; c < cells; ++c) w.f32(f.route_distance_m[c]);
    if (f.has_heading) {
      for (std::size_t c = 0; c < cells; ++c) w.f32(f.heading_rad[c]);
    }
  }
  // Version 4: the calibration, as (id, value) entries.
  const MapCalibration& cal = map.calibration;
  const bool local_linear = map.model.local_linear_ridge > 0.0F;
  if (cal.present || local_linear || cal.odometry_present) {
    w.u32((cal.present ? 3U : 0U) + (local_linear ? 1U : 0U) + (cal.odometry_present ? 3U : 0U));
    if (cal.present) {
      w.u32(kCalibrationFixRmseX);
      w.f32(cal.fix_rmse_x_m);
      w.u32(kCalibrationFixRmseY);
      w.f32(cal.fix_rmse_y_m);
      w.u32(kCalibrationPassSpread);
      w.f32(cal.pass_spread_m);
    }
    // The ridge of eq. 9's local linear correction, only when cross-validation chose it (a map
    // without it reads as before, and a firmware that does not know it refuses the map).
    if (local_linear) {
      w.u32(kCalibrationLocalLinearRidge);
      w.f32(map.model.local_linear_ridge);
    }
    if (cal.odometry_present) {
      w.u32(kCalibrationLeftWheelScale);
      w.f32(cal.left_wheel_scale);
      w.u32(kCalibrationRightWheelScale);
      w.f32(cal.right_wheel_scale);
      w.u32(kCalibrationTrackScale);
      w.f32(cal.track_scale);
    }
  } else {
    w.u32(0);
  }
  w.u32(crc32(w.out.data(), w.out.size()));
  return std::move(w.out);
}

MapError decode_map(const std::uint8_t* data, std::size_t size, MapFile& map) {
  if (data == nullptr || size < sizeof kMagic + 8) return MapError{"file too short to be a map", 0};
  if (std::memcmp(data, kMagic, sizeof kMagic) != 0)
    return MapError{"not a harmoloc map (bad magic)", 0};
  const std::size_t body = size - 4;
  const std::uint32_t stored = static_cast<std::uint32_t>(data[body]) |
                               static_cast<std::uint32_t>(data[body + 1]) << 8U |
                               static_cast<std::uint32_t>(data[body + 2]) << 16U |
                               static_cast<std::uint32_t>(data[body + 3]) << 24U;

  Reader r(data, body);
  std::uint8_t skip = 0;
  for (std::size_t i = 0; i < sizeof kMagic; ++i) r.u8(skip, "magic");
  std::uint32_t version = 0;
  if (!r.u32(version, "version")) return r.error;
  if (version < 1 || version > kMapFormatVersion)
    return MapError{"unsupported map format version (this firmware reads versions 1 to 5)", 8};
  if (crc32(data, body) != stored) return MapError{"checksum mismatch: the map is corrupt", body};

  std::uint32_t boards = 0;
  if (!r.u32(map.image_width_px, "image width") || !r.u32(map.image_height_px, "image height") ||
      !r.u32(boards, "board count")) {
    return r.error;
  }
  if (map.image_width_px == 0 || map.image_height_px == 0 || map.image_width_px > 8192 ||
      map.image_height_px > 8192) {
    return MapError{"image size out of range (1..8192)", 12};
  }
  if (boards == 0 || boards > kMaxBoards) return MapError{"board count out of range (1..8)", 20};
  map.thresholds.count = boards;
  for (std::size_t i = 0; i < boards; ++i) {
    ColourThreshold& t = map.thresholds.boards[i];
    std::uint8_t pad = 0;
    if (!r.f32(t.hue_min_deg, "threshold") || !r.f32(t.hue_max_deg, "threshold") ||
        !r.u8(t.saturation_min, "threshold") || !r.u8(t.value_min, "threshold") ||
        !r.u8(t.value_max, "threshold") || !r.u8(pad, "threshold")) {
      return r.error;
    }
    if (pad != 0) return MapError{"threshold padding byte is not zero", r.pos()};
    if (!(t.hue_min_deg >= 0.0F && t.hue_min_deg <= 360.0F && t.hue_max_deg >= 0.0F &&
          t.hue_max_deg <= 360.0F)) {
      return MapError{"threshold hue outside 0..360 degrees", r.pos()};
    }
  }
  HarmonicModel& m = map.model;
  if (!r.u32(m.sample_count, "sample count") || !r.u32(m.feature_count, "feature count"))
    return r.error;
  if (m.sample_count == 0 || m.sample_count > HarmonicModel::kMaxSamples) {
    return MapError{"sample count out of range (1..4096)", r.pos()};
  }
  if (m.feature_count == 0 || m.feature_count > HarmonicModel::kMaxFeatures) {
    return MapError{"feature count out of range (1..8)", r.pos()};
  }
  for (std::size_t k = 0; k < m.feature_count; ++k) {
    if (!r.u8(m.board_index[k], "feature boards")) return r.error;
    if (m.board_index[k] >= boards)
      return MapError{"feature refers to a board that is not in the map", r.pos()};
  }
  if (!r.f32(m.area_scale, "area scale") || !r.f32(m.sigma_x, "sigma x") ||
      !r.f32(m.sigma_y, "sigma y") || !r.f32(m.gamma_x, "gamma x") ||
      !r.f32(m.gamma_y, "gamma y") || !r.f32(m.max_nearest_distance, "known-place bound")) {
    return r.error;
  }
  m.max_dissimilarity = 1.0F;  // version 1: no dissimilarity test (1 is the largest possible)
  if (version >= 2 && !r.f32(m.max_dissimilarity, "known-place dissimilarity bound"))
    return r.error;
  if (!(m.max_dissimilarity > 0.0F && m.max_dissimilarity <= 1.0F))
    return MapError{"known-place dissimilarity bound outside (0, 1]", r.pos()};
  m.feature_weight.fill(1.0F);  // before version 4: every feature in the kernel
  if (version >= 4) {
    bool any = false;
    for (std::size_t k = 0; k < m.feature_count; ++k) {
      if (!r.f32(m.feature_weight[k], "feature weights")) return r.error;
      if (!(m.feature_weight[k] >= 0.0F && m.feature_weight[k] <= 1.0F))
        return MapError{"feature weight outside 0..1", r.pos()};
      any = any || m.feature_weight[k] > 0.0F;
    }
    if (!any) return MapError{"every feature weight is 0", r.pos()};
  }
  if (!finite_positive(m.area_scale) || !finite_positive(m.sigma_x) ||
      !finite_positive(m.sigma_y) || !finite_positive(m.max_nearest_distance) ||
      !std::isfinite(m.gamma_x) || !std::isfinite(m.gamma_y)) {
    return MapError{"model parameter not a finite positive number", r.pos()};
  }
  // Features are percent of the frame; anything far beyond cannot come from a real camera and
  // would overflow the distances in float.
  if (m.area_scale > 1.0e3F || m.max_nearest_distance > 1.0e4F || m.sigma_x > 1.0e9F ||
      m.sigma_y > 1.0e9F) {
    return MapError{"model parameter out of range", r.pos()};
  }
  const std::size_t record = (m.feature_count + 2U) * 4U;
  if (!r.need(static_cast<std::size_t>(m.sample_count) * record, "samples")) {
    return MapError{"truncated: fewer samples than the header says", r.pos()};
  }
  for (std::size_t i = 0; i < m.sample_count; ++i) {
    float* s = m.sample(i);
    for (std::size_t k = 0; k < m.feature_count; ++k) r.f32(s[k], "samples");
    r.f32(m.target_x_m[i], "samples");
    r.f32(m.target_y_m[i], "samples");
    for (std::size_t k = 0; k < m.feature_count; ++k) {
      if (!std::isfinite(s[k]) || s[k] < 0.0F)
        return MapError{"sample feature not finite and >= 0", r.pos()};
    }
    if (!std::isfinite(m.target_x_m[i]) || !std::isfinite(m.target_y_m[i])) {
      return MapError{"sample coordinate not finite", r.pos()};
    }
    if (!(std::fabs(m.target_x_m[i]) <= kMaxMapCoordinate_m &&
          std::fabs(m.target_y_m[i]) <= kMaxMapCoordinate_m)) {
      return MapError{"sample coordinate farther than 10 km from the origin", r.pos()};
    }
  }
  map.forward.columns = map.forward.rows = 0;
  if (version >= 3) {
    if (const MapError e = decode_forward(r, version, boards, map.forward)) return e;
  }
  map.calibration = MapCalibration{};
  map.model.local_linear_ridge = 0.0F;
  if (version >= 4) {
    std::uint32_t entries = 0;
    if (!r.u32(entries, "truncated: the calibration is missing")) return r.error;
    if (entries > kMaxCalibrationEntries) return MapError{"too many calibration entries", r.pos()};
    // Canonical only (what encode_map writes, so that a map reads back to the same bytes):
    // the measured entries 1, 2, 3 all or none, then the ridge (4) when it is above 0, then the
    // odometry's scales 5, 6, 7 all or none.
    std::uint32_t measured = 0, previous = 0, odometry_entries = 0;
    for (std::uint32_t i = 0; i < entries; ++i) {
      std::uint32_t id = 0;
      float value = 0.0F;
      if (!r.u32(id, "truncated calibration") || !r.f32(value, "truncated calibration"))
        return r.error;
      if (!std::isfinite(value) || value < 0.0F || value > 100.0F)
        return MapError{"calibration value not finite or out of range (0..100)", r.pos()};
      if (id == kCalibrationFixRmseX)
        map.calibration.fix_rmse_x_m = value;
      else if (id == kCalibrationFixRmseY)
        map.calibration.fix_rmse_y_m = value;
      else if (id == kCalibrationPassSpread)
        map.calibration.pass_spread_m = value;
      else if (id == kCalibrationLocalLinearRidge)
        map.model.local_linear_ridge = value;
      else if (id == kCalibrationLeftWheelScale)
        map.calibration.left_wheel_scale = value;
      else if (id == kCalibrationRightWheelScale)
        map.calibration.right_wheel_scale = value;
      else if (id == kCalibrationTrackScale)
        map.calibration.track_scale = value;
      else
        return MapError{"unknown calibration entry (a newer trainer?)", r.pos()};
      if (id <= previous) return MapError{"calibration entries out of order", r.pos()};
      if (id == kCalibrationLocalLinearRidge && !(value > 0.0F))
        return MapError{"local linear ridge 0 written (absent means none)", r.pos()};
      const bool odometry = id >= kCalibrationLeftWheelScale;
      if (odometry && !(value >= kMinOdometryScale && value <= kMaxOdometryScale))
        return MapError{"odometry scale out of range (0.5..2)", r.pos()};
      measured += id < kCalibrationLocalLinearRidge ? 1U : 0U;
      odometry_entries += odometry ? 1U : 0U;
      previous = id;
    }
    if (measured != 0 && measured != 3)
      return MapError{"calibration incomplete (entries 1 to 3 are written together)", r.pos()};
    if (odometry_entries != 0 && odometry_entries != 3)
      return MapError{"odometry calibration incomplete (entries 5 to 7 are written together)",
                      r.pos()};
    map.calibration.present = measured > 0;
    map.calibration.odometry_present = odometry_entries > 0;
  }
  if (r.pos() != body) {
    return MapError{version >= 4   ? "trailing bytes after the calibration"
                    : version >= 3 ? "trailing bytes after the forward map"
                                   : "trailing bytes after the samples",
                    r.pos()};
  }
  return MapError{};
}

}  // namespace harmoloc::algorithms
