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

// The forward map section (version 3).
MapError decode_forward(Reader& r, std::uint32_t boards, ForwardMap& f) {
  if (!r.u32(f.columns, "forward map size") || !r.u32(f.rows, "forward map size")) {
    f.columns = f.rows = 0;
    return MapError{"truncated: no room for the forward map's size", r.pos()};
  }
  if (f.columns == 0 && f.rows == 0) return MapError{};
  if (f.columns == 0 || f.rows == 0 || f.columns > ForwardMap::kMaxDimension ||
      f.rows > ForwardMap::kMaxDimension || f.cell_count() > ForwardMap::kMaxCells) {
    f.columns = f.rows = 0;
    return MapError{"forward map grid out of range (at most 256 x 256 and 4096 cells)", r.pos()};
  }
  std::uint32_t board_count = 0;
  if (!r.f32(f.origin_x_m, "forward map origin") || !r.f32(f.origin_y_m, "forward map origin") ||
      !r.f32(f.cell_m, "forward map cell size") || !r.u32(board_count, "forward map boards")) {
    f.columns = f.rows = 0;
    return MapError{"truncated: the forward map's header is cut short", r.pos()};
  }
  const auto fail = [&f](const char* what, std::size_t at) {
    f.columns = f.rows = 0;
    return MapError{what, at};
  };
  if (!(std::fabs(f.origin_x_m) <= 1.0e4F) || !(std::fabs(f.origin_y_m) <= 1.0e4F) ||
      !(f.cell_m >= 1.0e-3F && f.cell_m <= 10.0F)) {
    return fail("forward map origin or cell size out of range", r.pos());
  }
  if (board_count != boards)
    return fail("forward map board count differs from the thresholds'", r.pos());
  f.board_count = board_count;
  bool any = false;
  for (std::size_t b = 0; b < board_count; ++b) {
    if (!r.f32(f.sigma[b], "forward map sigma"))
      return fail("truncated: the forward map's sigmas are cut short", r.pos());
    if (!(f.sigma[b] >= 0.0F && f.sigma[b] <= 1.0e3F))
      return fail("forward map sigma not finite and in 0..1000", r.pos());
    any = any || f.sigma[b] > 0.0F;
  }
  if (!any) return fail("forward map models no board (every sigma is 0)", r.pos());
  std::uint8_t flag = 0, pad[3] = {0, 0, 0};
  if (!r.u8(flag, "forward map flags") || !r.u8(pad[0], "forward map flags") ||
      !r.u8(pad[1], "forward map flags") || !r.u8(pad[2], "forward map flags")) {
    return fail("truncated: the forward map's flags are cut short", r.pos());
  }
  if (flag > 1U || pad[0] != 0 || pad[1] != 0 || pad[2] != 0)
    return fail("forward map flags: unknown bits set", r.pos());
  f.has_heading = flag == 1U;
  const std::size_t cells = f.cell_count();
  const std::size_t values = cells * (board_count + 1U + (f.has_heading ? 1U : 0U));
  if (!r.need(values * 4U, "forward map"))
    return fail("truncated: the forward map is shorter than its size says", r.pos());
  for (std::size_t c = 0; c < cells; ++c) {
    float* e = f.expected.data() + c * kMaxBoards;
    for (std::size_t b = 0; b < board_count; ++b) {
      r.f32(e[b], "forward map");
      if (!(e[b] >= 0.0F && e[b] <= 1.0e6F))
        return fail("forward map expected feature not finite and >= 0", r.pos());
    }
    for (std::size_t b = board_count; b < kMaxBoards; ++b) e[b] = 0.0F;
  }
  for (std::size_t c = 0; c < cells; ++c) {
    r.f32(f.route_distance_m[c], "forward map");
    if (!(f.route_distance_m[c] >= 0.0F && f.route_distance_m[c] <= 1.0e4F))
      return fail("forward map route distance not finite and >= 0", r.pos());
  }
  if (f.has_heading) {
    for (std::size_t c = 0; c < cells; ++c) {
      r.f32(f.heading_rad[c], "forward map");
      if (!(std::fabs(f.heading_rad[c]) <= 4.0F))
        return fail("forward map heading not within -pi..pi", r.pos());
    }
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
    for (std::size_t c = 0; c < f.cell_count(); ++c) {
      for (std::size_t b = 0; b < f.board_count; ++b) w.f32(f.expected[c * kMaxBoards + b]);
    }
    for (std::size_t c = 0; c < f.cell_count(); ++c) w.f32(f.route_distance_m[c]);
    if (f.has_heading) {
      for (std::size_t c = 0; c < f.cell_count(); ++c) w.f32(f.heading_rad[c]);
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
    return MapError{"unsupported map format version (this firmware reads versions 1 to 4)", 8};
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
    if (const MapError e = decode_forward(r, boards, map.forward)) return e;
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
