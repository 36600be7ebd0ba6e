#include "harmoloc/algorithms/map_codec.hpp"

#include <cstring>

#include "harmoloc/algorithms/crc32.hpp"
#include "map_codec_parts.hpp"

namespace harmoloc::algorithms {

using namespace map_codec_detail;

namespace {

class Writer {
 public:
  void bytes(const void* p, std::size_t n) {
    const auto* b = static_cast<const std::uint8_t*>(p);
    out.insert(out.end(), b, b + n);
  }
  void u8(std::uint8_t v) { out.push_back(v); }
  void u16(std::uint16_t v) {
    out.push_back(static_cast<std::uint8_t>(v));
    out.push_back(static_cast<std::uint8_t>(v >> 8));
  }
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
    // Bit 0: headings follow the route distances; bit 1 (version 6): the board bearings follow;
    // bit 2 (version 7): the heading terms follow; bit 3 (version 8): the heading coverage.
    // Bit 4 (version 10): the visibility follows, in the heading terms' place.
    const bool terms = ForwardMap::kHeadingTermStorage && f.has_heading_terms;
    const bool cover = ForwardMap::kHeadingTermStorage && f.has_heading && f.has_heading_coverage;
    const bool seen = ForwardMap::kHeadingTermStorage && f.has_bearings && f.has_visibility &&
                      !f.has_heading_terms;
    // Bit 5 (version 15): the projected bearings follow, last.
    const bool projected = f.has_bearings && f.projection.present();
    w.u8(static_cast<std::uint8_t>((f.has_heading ? 1U : 0U) | (f.has_bearings ? 2U : 0U) |
                                   (terms ? 4U : 0U) | (cover ? 8U : 0U) | (seen ? 16U : 0U) |
                                   (projected ? 32U : 0U)));
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
    // Version 6: the bearing law, each board's bearing spread, then every stored cell's bearings.
    if (f.has_bearings) {
      w.f32(f.bearing_a1_rad);
      w.f32(f.bearing_a3_rad);
      w.f32(f.bearing_camera_forward_m);  // version 9
      for (std::size_t b = 0; b < f.board_count; ++b) w.f32(f.bearing_sigma_rad[b]);
      for (std::size_t c = 0; c < cells; ++c) {
        for (std::size_t b = 0; b < f.board_count; ++b) w.f32(f.bearing_rad[c * kMaxBoards + b]);
      }
    }
    // Version 7: every stored cell's heading terms, per board c then s; version 10: in their
    // place, the visibility: its angle gain, then per board the feature seen whole on the axis
    // and the angular half-width; version 14: the gain's optical axis after the gain.
    if (seen) {
      w.f32(f.visibility_angle_gain);
      w.f32(f.visibility_axis_rad);
    }
    if (terms || seen) {
      for (std::size_t c = 0; c < cells; ++c) {
        for (std::size_t b = 0; b < 2 * f.board_count; ++b)
          w.f32(f.heading_terms[c * kMaxBoards * 2 + b]);
      }
    }
    // Version 8: every stored cell's covered heading sectors.
    if (cover) {
      for (std::size_t c = 0; c < cells; ++c) w.u16(f.heading_cover[c]);
    }
    // Version 15: the frame's size, the camera on the robot, its intrinsics and lens, then per
    // board its outline's point count and points (version 16: and its bearings' spread; version
    // 17: and its feature per projected pixel and area noise).
    if (projected) {
      const BearingProjection& p = f.projection;
      w.u32(p.width_px);
      w.u32(p.height_px);
      for (const auto* v : {&p.origin_m, &p.right, &p.down, &p.forward}) {
        for (const float x : *v) w.f32(x);
      }
      for (const float x :
           {p.focal_px, p.cx_px, p.cy_px, p.k1, p.k2, p.k3, p.p1, p.p2, p.max_radius2})
        w.f32(x);
      for (std::size_t b = 0; b < f.board_count; ++b) {
        w.u32(p.points[b]);
        for (std::size_t i = 0; i < 3U * p.points[b]; ++i) w.f32(p.point_m(b, i / 3, i % 3));
        if (p.points[b] == 0U) continue;
        w.f32(p.sigma_rad[b]);    // version 16
        w.f32(p.area_per_px[b]);  // version 17
        w.f32(p.area_sigma[b]);
      }
    }
  }
  // Version 4: the calibration, as (id, value) entries.
  const MapCalibration& cal = map.calibration;
  const bool local_linear = map.model.local_linear_ridge > 0.0F;
  const bool turned = cal.pass_heading_spread_rad > 0.0F;
  if (cal.present || local_linear || cal.odometry_present || turned) {
    w.u32((cal.present ? 3U : 0U) + (local_linear ? 1U : 0U) + (cal.odometry_present ? 3U : 0U) +
          (turned ? 1U : 0U));
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
    // Only above 0, as the ridge (a map trained without headings has none).
    if (turned) {
      w.u32(kCalibrationPassHeadingSpread);
      w.f32(cal.pass_heading_spread_rad);
    }
  } else {
    w.u32(0);
  }
  // Version 11: the per-sample fix errors, all or none.
  const bool fix_errors = has_fix_errors(m);
  w.u32(fix_errors ? m.sample_count : 0U);
  if (fix_errors) {
    for (std::size_t i = 0; i < m.sample_count; ++i) w.f32(m.fix_error_m[i]);
  }
  // Version 13: the area's gain by column (both 0: none), before the columns, whose check needs it.
  w.f32(m.column_gain.c2);
  w.f32(m.column_gain.c4);
  // Version 12: the centroid columns' weight, then (above 0) every sample's column features.
  const bool columns = m.uses_columns();
  w.f32(columns ? m.column_weight : 0.0F);
  if (columns) {
    for (std::size_t i = 0; i < m.sample_count; ++i) {
      for (std::size_t k = 0; k < m.feature_count; ++k) w.f32(m.sample_columns(i)[k]);
    }
  }
  w.u32(crc32(w.out.data(), w.out.size()));
  return std::move(w.out);
}

}  // namespace harmoloc::algorithms
