#include "harmoloc/algorithms/map_codec.hpp"

#include <cmath>
#include <cstring>

#include "harmoloc/algorithms/crc32.hpp"
#include "map_codec_parts.hpp"

namespace harmoloc::algorithms {

using namespace map_codec_detail;

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
    return MapError{"unsupported map format version (this firmware reads versions 1 to 17)", 8};
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
  map.forward.has_bearings = false;          // before version 6 (and without a forward map): none
  map.forward.has_heading_terms = false;     // before version 7: none
  map.forward.has_heading_coverage = false;  // before version 8: none
  map.forward.has_visibility = false;        // before version 10: none
  map.forward.visibility_angle_gain = 0.0F;
  map.forward.visibility_axis_rad = 0.0F;        // before version 14: the centre column
  map.forward.projection = BearingProjection{};  // before version 15: none
  if (version >= 3) {
    if (const MapError e = decode_forward(r, version, boards, map.forward)) return e;
    // The projection's columns are compared with the frame's under the map's law.
    const BearingProjection& p = map.forward.projection;
    if (p.present() && (p.width_px != map.image_width_px || p.height_px != map.image_height_px)) {
      map.forward.projection = BearingProjection{};
      return MapError{"forward map projection: frame size differs from the map's", r.pos()};
    }
  }
  map.calibration = MapCalibration{};
  map.model.local_linear_ridge = 0.0F;
  if (version >= 4) {
    std::uint32_t entries = 0;
    if (!r.u32(entries, "truncated: the calibration is missing")) return r.error;
    if (entries > kMaxCalibrationEntries) return MapError{"too many calibration entries", r.pos()};
    // Canonical only (what encode_map writes, so that a map reads back to the same bytes):
    // the measured entries 1, 2, 3 all or none, then the ridge (4) when it is above 0, then the
    // odometry's scales 5, 6, 7 all or none, then the pass heading spread (8) when it is above 0.
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
      else if (id == kCalibrationPassHeadingSpread)
        map.calibration.pass_heading_spread_rad = value;
      else
        return MapError{"unknown calibration entry (a newer trainer?)", r.pos()};
      if (id <= previous) return MapError{"calibration entries out of order", r.pos()};
      if (id == kCalibrationLocalLinearRidge && !(value > 0.0F))
        return MapError{"local linear ridge 0 written (absent means none)", r.pos()};
      if (id == kCalibrationPassHeadingSpread && !(value > 0.0F && value <= 3.1416F))
        return MapError{"pass heading spread not in (0, pi] (absent means 0)", r.pos()};
      const bool odometry = id >= kCalibrationLeftWheelScale && id <= kCalibrationTrackScale;
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
  m.fix_error_m.fill(0.0F);
  if (version >= 11) {
    // Version 11: the per-sample fix errors, all or none (canonical: none when every one is 0).
    std::uint32_t count = 0;
    if (!r.u32(count, "truncated: the per-sample fix errors are missing")) return r.error;
    if (count != 0 && count != m.sample_count)
      return MapError{"per-sample fix errors: count is neither 0 nor the sample count", r.pos()};
    bool any = false;
    for (std::size_t i = 0; i < count; ++i) {
      if (!r.f32(m.fix_error_m[i], "truncated per-sample fix errors")) return r.error;
      if (!std::isfinite(m.fix_error_m[i]) || m.fix_error_m[i] < 0.0F || m.fix_error_m[i] > 100.0F)
        return MapError{"per-sample fix error not finite or out of range (0..100)", r.pos()};
      any = any || m.fix_error_m[i] > 0.0F;
    }
    if (count != 0 && !any)
      return MapError{"per-sample fix errors all 0 written (absent means none)", r.pos()};
  }
  m.column_gain = ColumnGain{};
  if (version >= 13) {
    // Version 13: the area's gain by column, G(t) = exp(c2 t^2 + c4 t^4) (column_gain.hpp).
    float c2 = 0.0F, c4 = 0.0F;
    if (!r.f32(c2, "truncated: the column gain is missing") ||
        !r.f32(c4, "truncated: the column gain is missing"))
      return r.error;
    if (!column_gain_in_range(c2, c4))
      return MapError{"column gain not finite or beyond a factor of 4 in the frame", r.pos()};
    m.column_gain.c2 = c2;
    m.column_gain.c4 = c4;
  }
  // A column feature comes from the plain area: at most the gain's largest value times the
  // sample's feature, which has the gain removed.
  const double most_gain = std::exp(column_gain_log_extent(m.column_gain.c2, m.column_gain.c4));
  m.column_weight = 0.0F;
  if (version >= 12) {
    // Version 12: the centroid columns' weight (0: none follow), then n x d column features.
    if (!r.f32(m.column_weight, "truncated: the column weight is missing")) return r.error;
    if (!std::isfinite(m.column_weight) || m.column_weight < 0.0F || m.column_weight > 100.0F)
      return MapError{"column weight not finite or out of range (0..100)", r.pos()};
    if (m.column_weight > 0.0F && !HarmonicModel::kHoldsColumns) {
      m.column_weight = 0.0F;
      return MapError{
          "the map holds the boards' centroid columns, which this build leaves out "
          "(HARMOLOC_HARMONIC_COLUMNS=0): train it with --no-columns",
          r.pos()};
    }
    if (m.column_weight > 0.0F) {
      for (std::size_t i = 0; i < m.sample_count; ++i) {
        float* c = m.sample_columns(i);
        for (std::size_t k = 0; k < m.feature_count; ++k) {
          if (!r.f32(c[k], "truncated column features")) return r.error;
          // (u - 0.5) sqrt(feature) with u in [0, 1]: within half the root of the feature.
          const double bound =
              0.5 * std::sqrt(static_cast<double>(m.sample(i)[k]) * most_gain) * (1.0 + 1e-5);
          if (!std::isfinite(c[k]) || std::fabs(static_cast<double>(c[k])) > bound)
            return MapError{"column feature not finite or beyond half the root of its plain area",
                            r.pos()};
        }
      }
    }
  }
  if (r.pos() != body) {
    return MapError{version >= 12   ? "trailing bytes after the column features"
                    : version >= 11 ? "trailing bytes after the per-sample fix errors"
                    : version >= 4  ? "trailing bytes after the calibration"
                    : version >= 3  ? "trailing bytes after the forward map"
                                    : "trailing bytes after the samples",
                    r.pos()};
  }
  return MapError{};
}

}  // namespace harmoloc::algorithms
