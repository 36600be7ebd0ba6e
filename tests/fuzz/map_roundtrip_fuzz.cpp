// Fuzz target: the map codec's round trip. The input gets its trailing CRC-32 recomputed (so
// the fuzzer reaches the body); when it decodes, encode_map must give back exactly the same
// bytes, and decoding those again must give the same map. A difference means the decoder
// accepts something the format does not define (an ignored field, a non-canonical encoding).
// A decoded forward map without bearings is then given some (map version 6), one without
// heading terms some (version 7), one with headings and without coverage some (version 8), and
// must round trip with them too.

#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "fuzz_common.hpp"
#include "harmoloc/algorithms/crc32.hpp"
#include "harmoloc/algorithms/map_codec.hpp"

using namespace harmoloc::algorithms;

namespace {

MapFile g_map;  // ~6 MiB each: static
MapFile g_again;

bool same_model(const MapFile& a, const MapFile& b) {
  const HarmonicModel& x = a.model;
  const HarmonicModel& y = b.model;
  if (a.image_width_px != b.image_width_px || a.image_height_px != b.image_height_px) return false;
  if (!(a.thresholds == b.thresholds)) return false;
  if (x.sample_count != y.sample_count || x.feature_count != y.feature_count) return false;
  // Bitwise, so that -0.0 and NaN payloads count (the format stores bits).
  auto same_bits = [](const void* p, const void* q, std::size_t n) {
    return std::memcmp(p, q, n) == 0;
  };
  if (!same_bits(x.board_index.data(), y.board_index.data(), x.feature_count)) return false;
  if (!same_bits(x.feature_weight.data(), y.feature_weight.data(),
                 x.feature_count * sizeof(float))) {
    return false;
  }
  const float xs[] = {x.area_scale,        x.sigma_x,
                      x.sigma_y,           x.gamma_x,
                      x.gamma_y,           x.max_nearest_distance,
                      x.max_dissimilarity, x.local_linear_ridge,
                      x.column_weight,     x.column_gain.c2,
                      x.column_gain.c4};
  const float ys[] = {y.area_scale,        y.sigma_x,
                      y.sigma_y,           y.gamma_x,
                      y.gamma_y,           y.max_nearest_distance,
                      y.max_dissimilarity, y.local_linear_ridge,
                      y.column_weight,     y.column_gain.c2,
                      y.column_gain.c4};
  const MapCalibration& ca = a.calibration;
  const MapCalibration& cb = b.calibration;
  const float cas[] = {ca.fix_rmse_x_m, ca.fix_rmse_y_m, ca.pass_spread_m};
  const float cbs[] = {cb.fix_rmse_x_m, cb.fix_rmse_y_m, cb.pass_spread_m};
  if (ca.present != cb.present || !same_bits(cas, cbs, sizeof cas)) return false;
  if (!same_bits(xs, ys, sizeof xs)) return false;
  for (std::size_t i = 0; i < x.sample_count; ++i) {
    if (!same_bits(x.sample(i), y.sample(i), x.feature_count * sizeof(float))) return false;
    if (!same_bits(&x.target_x_m[i], &y.target_x_m[i], sizeof(float))) return false;
    if (!same_bits(&x.target_y_m[i], &y.target_y_m[i], sizeof(float))) return false;
    if (!same_bits(&x.fix_error_m[i], &y.fix_error_m[i], sizeof(float))) return false;
    if (x.uses_columns() &&
        !same_bits(x.sample_columns(i), y.sample_columns(i), x.feature_count * sizeof(float)))
      return false;
  }
  const ForwardMap& f = a.forward;
  const ForwardMap& g = b.forward;
  if (f.present() != g.present()) return false;
  if (!f.present()) return true;
  if (f.columns != g.columns || f.rows != g.rows || f.board_count != g.board_count ||
      f.has_heading != g.has_heading || f.has_bearings != g.has_bearings ||
      f.tile_count != g.tile_count) {
    return false;
  }
  const std::size_t positions = static_cast<std::size_t>(f.tile_columns) * f.tile_rows;
  if (!same_bits(f.tile_slot.data(), g.tile_slot.data(), positions * sizeof(std::uint16_t)))
    return false;
  const float fs[] = {f.origin_x_m, f.origin_y_m, f.cell_m};
  const float gs[] = {g.origin_x_m, g.origin_y_m, g.cell_m};
  if (!same_bits(fs, gs, sizeof fs) || !same_bits(f.sigma.data(), g.sigma.data(), sizeof f.sigma))
    return false;
  const std::size_t cells = f.stored_cells();
  if (f.has_bearings) {
    // Version 6: the law, each board's spread and every stored cell's bearings.
    const float fb[] = {f.bearing_a1_rad, f.bearing_a3_rad, f.bearing_camera_forward_m};
    const float gb[] = {g.bearing_a1_rad, g.bearing_a3_rad, g.bearing_camera_forward_m};
    if (!same_bits(fb, gb, sizeof fb) ||
        !same_bits(f.bearing_sigma_rad.data(), g.bearing_sigma_rad.data(),
                   sizeof f.bearing_sigma_rad) ||
        !same_bits(f.bearing_rad.data(), g.bearing_rad.data(), cells * kMaxBoards * sizeof(float)))
      return false;
  }
  if (f.has_heading_terms != g.has_heading_terms) return false;
  // Version 7: every stored cell's heading terms.
  if (f.has_heading_terms && !same_bits(f.heading_terms.data(), g.heading_terms.data(),
                                        cells * kMaxBoards * 2 * sizeof(float)))
    return false;
  if (f.has_visibility != g.has_visibility) return false;
  // Version 10: the angle gain and every stored cell's visibility, in the heading terms' place.
  if (f.has_visibility &&
      (!same_bits(&f.visibility_angle_gain, &g.visibility_angle_gain, sizeof(float)) ||
       !same_bits(&f.visibility_axis_rad, &g.visibility_axis_rad, sizeof(float)) ||
       !same_bits(f.heading_terms.data(), g.heading_terms.data(),
                  cells * kMaxBoards * 2 * sizeof(float))))
    return false;
  // Version 15: the projected bearings' camera and outlines.
  const BearingProjection& fp = f.projection;
  const BearingProjection& gp = g.projection;
  if (fp.present() != gp.present()) return false;
  if (fp.present()) {
    const float fc[] = {fp.focal_px, fp.cx_px, fp.cy_px, fp.k1,         fp.k2,
                        fp.k3,       fp.p1,    fp.p2,    fp.max_radius2};
    const float gc[] = {gp.focal_px, gp.cx_px, gp.cy_px, gp.k1,         gp.k2,
                        gp.k3,       gp.p1,    gp.p2,    gp.max_radius2};
    if (fp.width_px != gp.width_px || fp.height_px != gp.height_px ||
        !same_bits(fc, gc, sizeof fc) ||
        !same_bits(fp.origin_m.data(), gp.origin_m.data(), sizeof fp.origin_m) ||
        !same_bits(fp.right.data(), gp.right.data(), sizeof fp.right) ||
        !same_bits(fp.down.data(), gp.down.data(), sizeof fp.down) ||
        !same_bits(fp.forward.data(), gp.forward.data(), sizeof fp.forward) ||
        fp.points != gp.points)
      return false;
    for (std::size_t b = 0; b < kMaxBoards; ++b) {
      for (std::size_t d = 0; d < 3; ++d) {
        for (std::size_t i = 0; i < fp.points[b]; ++i) {
          const float x = fp.point_m(b, i, d), y = gp.point_m(b, i, d);
          if (!same_bits(&x, &y, sizeof x)) return false;
        }
      }
      // Version 16: the outline's bearing spread.
      if (fp.points[b] != 0U && !same_bits(&fp.sigma_rad[b], &gp.sigma_rad[b], sizeof(float)))
        return false;
      // Version 17: its feature per projected pixel.
      if (fp.points[b] != 0U &&
          (!same_bits(&fp.area_per_px[b], &gp.area_per_px[b], sizeof(float)) ||
           !same_bits(&fp.area_sigma[b], &gp.area_sigma[b], sizeof(float))))
        return false;
    }
  }
  if (f.has_heading_coverage != g.has_heading_coverage) return false;
  // Version 8: every stored cell's heading coverage.
  if (f.has_heading_coverage &&
      !same_bits(f.heading_cover.data(), g.heading_cover.data(), cells * sizeof(std::uint16_t)))
    return false;
  return same_bits(f.expected.data(), g.expected.data(), cells * kMaxBoards * sizeof(float)) &&
         same_bits(f.route_distance_m.data(), g.route_distance_m.data(), cells * sizeof(float)) &&
         (!f.has_heading ||
          same_bits(f.heading_rad.data(), g.heading_rad.data(), cells * sizeof(float)));
}

// g_map, given a section it did not have (@p what), must decode after encoding, to the same
// model, and re-encode to the same bytes.
void check_given_round_trip(const char* what) {
  const auto fail = [what](const char* how) {
    const std::string line = std::string("a map given ") + what + " " + how;
    harmoloc::fuzz::finding(line.c_str());
  };
  const std::vector<std::uint8_t> encoded = encode_map(g_map);
  if (decode_map(encoded.data(), encoded.size(), g_again)) fail("does not decode");
  if (!same_model(g_map, g_again)) fail("decodes to another map");
  if (encode_map(g_again) != encoded) fail("re-encodes to different bytes");
}

// A decoded forward map without bearings is given some, drawn from the input's bytes (about one
// value in eight without a bearing), and must survive encode and decode with them: the bearings'
// writer and reader over whatever grid and tiles the input has.
void check_added_bearings(const std::vector<std::uint8_t>& input) {
  ForwardMap& f = g_map.forward;
  if (!f.present() || f.has_bearings) return;
  f.has_bearings = true;
  f.bearing_a1_rad = 0.5F + 0.005F * static_cast<float>(input[input.size() / 2]);
  f.bearing_a3_rad = -0.25F * f.bearing_a1_rad;
  f.bearing_camera_forward_m = 0.001F * static_cast<float>(input[0]);
  for (std::size_t b = 0; b < f.board_count; ++b)
    f.bearing_sigma_rad[b] = b == 0 ? 0.05F : 0.002F * static_cast<float>(input[b % input.size()]);
  const std::size_t cells = f.stored_cells();
  for (std::size_t i = 0; i < cells * f.board_count; ++i) {
    const std::uint8_t v = input[i % input.size()];
    f.bearing_rad[(i / f.board_count) * kMaxBoards + i % f.board_count] =
        v % 8 == 0 ? ForwardMap::kNoBearing : 0.024F * static_cast<float>(v) - 3.06F;
  }
  check_given_round_trip("bearings");
}

// A decoded forward map without heading terms is given some (map version 7), drawn from the
// input's bytes, and must survive encode and decode with them.
void check_added_heading_terms(const std::vector<std::uint8_t>& input) {
  ForwardMap& f = g_map.forward;
  if (!f.present() || f.has_heading_terms) return;
  f.has_heading_terms = true;
  const std::size_t cells = f.stored_cells();
  for (std::size_t i = 0; i < cells * f.board_count * 2; ++i) {
    const std::size_t c = i / (2 * f.board_count), k = i % (2 * f.board_count);
    f.heading_terms[c * kMaxBoards * 2 + k] =
        0.01F * static_cast<float>(input[i % input.size()]) - 1.28F;
  }
  check_given_round_trip("heading terms");
}

// A decoded forward map with headings and without coverage is given some (map version 8),
// drawn from the input's bytes, and must survive encode and decode with it.
void check_added_heading_coverage(const std::vector<std::uint8_t>& input) {
  ForwardMap& f = g_map.forward;
  if (!f.present() || !f.has_heading || f.has_heading_coverage) return;
  f.has_heading_coverage = true;
  for (std::size_t c = 0; c < f.stored_cells(); ++c) {
    f.heading_cover[c] =
        static_cast<std::uint16_t>(input[c % input.size()] | input[(c + 1) % input.size()] << 8);
  }
  check_given_round_trip("heading coverage");
}

// A decoded forward map with bearings and without visibility is given it in place of any heading
// terms (map version 10), drawn from the input's bytes, and must survive encode and decode.
void check_added_visibility(const std::vector<std::uint8_t>& input) {
  ForwardMap& f = g_map.forward;
  if (!f.present() || !f.has_bearings || f.has_visibility) return;
  f.has_heading_terms = false;
  f.has_visibility = true;
  f.visibility_angle_gain = 0.01F * static_cast<float>(input[0]) - 1.28F;
  // Within the law's half field of view, as the decoder asks (version 14).
  f.visibility_axis_rad =
      half_field_of_view(f) * (static_cast<float>(input[input.size() / 2]) / 255.0F - 0.5F);
  const std::size_t cells = f.stored_cells();
  for (std::size_t i = 0; i < cells * f.board_count * 2; ++i) {
    const std::size_t c = i / (2 * f.board_count), k = i % (2 * f.board_count);
    f.heading_terms[c * kMaxBoards * 2 + k] = 0.01F * static_cast<float>(input[i % input.size()]);
  }
  check_given_round_trip("visibility");
}

// A decoded forward map with bearings and without projected bearings is given them (map version
// 15): a camera looking ahead, and an outline for each board whose bearings the map models,
// drawn from the input's bytes, within the decoder's bounds.
void check_added_projection(const std::vector<std::uint8_t>& input) {
  ForwardMap& f = g_map.forward;
  if (!f.present() || !f.has_bearings || f.projection.present()) return;
  BearingProjection& p = f.projection;
  p.width_px = g_map.image_width_px;
  p.height_px = g_map.image_height_px;
  p.origin_m = {0.1F, 0.0F, 0.3F};
  p.right = {0.0F, -1.0F, 0.0F};
  p.down = {0.0F, 0.0F, -1.0F};
  p.forward = {1.0F, 0.0F, 0.0F};
  p.focal_px = 0.5F * static_cast<float>(p.width_px) + static_cast<float>(input[0]);
  p.cx_px = 0.5F * static_cast<float>(p.width_px);
  p.cy_px = 0.5F * static_cast<float>(p.height_px);
  p.k1 = 0.01F * static_cast<float>(input[input.size() / 2]) - 1.28F;
  p.max_radius2 = 1.0F + static_cast<float>(input[input.size() - 1]);
  for (std::size_t b = 0; b < f.board_count; ++b) {
    if (!(f.bearing_sigma_rad[b] > 0.0F)) continue;
    p.points[b] = static_cast<std::uint8_t>(3 + input[b % input.size()] % 6);
    for (std::size_t i = 0; i < 3U * p.points[b]; ++i)
      p.point_m(b, i / 3, i % 3) = 0.05F * static_cast<float>(input[(b + i) % input.size()]) - 6.0F;
    // 0 (the cells' spread) or up to about 29 degrees.
    p.sigma_rad[b] = 0.002F * static_cast<float>(input[(b + 1) % input.size()]);
    // 0 (the cells' areas) or up to about 0.26 feature a pixel.
    p.area_per_px[b] = 1e-3F * static_cast<float>(input[(b + 2) % input.size()]);
    p.area_sigma[b] = 0.01F * static_cast<float>(input[(b + 3) % input.size()]);
  }
  check_given_round_trip("projected bearings");
}

// A decoded map without per-sample fix errors is given some (version 11), drawn from the input's
// bytes (one value in 256 is 0), and must survive encode and decode.
// Any map given centroid columns (version 12): within half the root of each area feature.
void check_added_columns(const std::vector<std::uint8_t>& input) {
  HarmonicModel& m = g_map.model;
  if (m.uses_columns()) return;
  for (std::size_t i = 0; i < m.sample_count; ++i) {
    for (std::size_t k = 0; k < m.feature_count; ++k) {
      const double u = static_cast<double>(input[(i + k) % input.size()]) / 255.0;
      m.sample_columns(i)[k] =
          static_cast<float>((u - 0.5) * std::sqrt(static_cast<double>(m.sample(i)[k])));
    }
  }
  m.column_weight = 0.5F;
  check_given_round_trip("centroid columns");
}

// Any map given a column gain (version 13) within the bounds, drawn from the input's bytes: the
// gain only loosens the column features' bound, so the map still reads.
void check_added_column_gain(const std::vector<std::uint8_t>& input) {
  HarmonicModel& m = g_map.model;
  if (m.column_gain.present()) return;
  m.column_gain.c2 = 0.02F * static_cast<float>(input[0] % 101) - 1.0F;
  m.column_gain.c4 = -0.1F * static_cast<float>(input[input.size() - 1] % 41);
  if (!m.column_gain.present()) m.column_gain.c2 = 0.5F;
  check_given_round_trip("column gain");
}

void check_added_fix_errors(const std::vector<std::uint8_t>& input) {
  HarmonicModel& m = g_map.model;
  if (has_fix_errors(m)) return;
  for (std::size_t i = 0; i < m.sample_count; ++i)
    m.fix_error_m[i] = 0.001F * static_cast<float>(input[i % input.size()]);
  m.fix_error_m[0] = 0.05F;  // never all 0 (that is written as none)
  check_given_round_trip("per-sample fix errors");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 4) return 0;
  std::vector<std::uint8_t> input(data, data + size);
  const std::uint32_t crc = crc32(input.data(), size - 4);
  for (int i = 0; i < 4; ++i) input[size - 4 + i] = static_cast<std::uint8_t>(crc >> (8 * i));
  if (decode_map(input.data(), input.size(), g_map)) return 0;

#ifdef HARMOLOC_FUZZ_SKIP_KNOWN_FINDINGS
  // Known finding (regressions/map_roundtrip/nonzero-pad.hmap): decode_map ignores the pad byte
  // of each threshold, which docs/map-format.md says is 0. Compare as if it were 0.
  for (std::size_t i = 0; i < g_map.thresholds.count; ++i) input[24 + 12 * i + 11] = 0;
  const std::uint32_t crc0 = crc32(input.data(), size - 4);
  for (int i = 0; i < 4; ++i) input[size - 4 + i] = static_cast<std::uint8_t>(crc0 >> (8 * i));
#endif
  const std::vector<std::uint8_t> encoded = encode_map(g_map);
  if (input[8] >= 1 && input[8] < kMapFormatVersion) {
    // An older map (regressions/map_roundtrip/version1.hmap, corpus tiny-trained-v2.hmap,
    // forward-v3.hmap, forward-v5-sparse.hmap) is written back as the current version, without
    // what it lacked: the same model, a version 1 map's dissimilarity bound at 1, no forward map
    // before version 3, every feature weight 1 and no calibration before version 4, a forward
    // map of versions 3 and 4 with every tile of its grid stored, no bearings before version 6,
    // no heading terms before version 7, no heading coverage before version 8, no visibility
    // before version 10, no per-sample fix errors before version 11, no centroid columns before
    // version 12, no column gain before version 13, the visibility's gain centred on the centre
    // column before version 14, no projected bearings before version 15, no projected bearings'
    // spreads before version 16.
    HARMOLOC_FUZZ_CHECK(input[8] != 1 || g_map.model.max_dissimilarity == 1.0F,
                        "a version 1 map decodes with a dissimilarity bound");
    HARMOLOC_FUZZ_CHECK(input[8] >= 3 || !g_map.forward.present(),
                        "a version 1 or 2 map decodes with a forward map");
    bool unit_weights = true;
    for (std::size_t k = 0; k < g_map.model.feature_count; ++k)
      unit_weights = unit_weights && g_map.model.feature_weight[k] == 1.0F;
    HARMOLOC_FUZZ_CHECK(input[8] >= 4 || (unit_weights && !g_map.calibration.present &&
                                          g_map.model.local_linear_ridge == 0.0F),
                        "a map before version 4 decodes with weights or calibration");
    const ForwardMap& f = g_map.forward;
    HARMOLOC_FUZZ_CHECK(
        input[8] >= 5 || !f.present() || f.tile_count == f.tile_columns * f.tile_rows,
        "a version 3 or 4 forward map decodes without every tile");
    HARMOLOC_FUZZ_CHECK(input[8] >= 6 || !f.has_bearings,
                        "a map before version 6 decodes with bearings");
    HARMOLOC_FUZZ_CHECK(input[8] >= 7 || !f.has_heading_terms,
                        "a map before version 7 decodes with heading terms");
    HARMOLOC_FUZZ_CHECK(input[8] >= 8 || !f.has_heading_coverage,
                        "a map before version 8 decodes with coverage");
    HARMOLOC_FUZZ_CHECK(input[8] >= 10 || !f.has_visibility,
                        "a map before version 10 decodes with visibility");
    HARMOLOC_FUZZ_CHECK(input[8] >= 11 || !has_fix_errors(g_map.model),
                        "a map before version 11 decodes with fix errors");
    HARMOLOC_FUZZ_CHECK(input[8] >= 12 || !g_map.model.uses_columns(),
                        "a map before version 12 decodes with centroid columns");
    HARMOLOC_FUZZ_CHECK(input[8] >= 13 || !g_map.model.column_gain.present(),
                        "a map before version 13 decodes with a column gain");
    HARMOLOC_FUZZ_CHECK(input[8] >= 14 || f.visibility_axis_rad == 0.0F,
                        "a map before version 14 decodes with a visibility axis");
    HARMOLOC_FUZZ_CHECK(input[8] >= 15 || !f.projection.present(),
                        "a map before version 15 decodes with projected bearings");
    bool no_spread = true;
    for (const float v : f.projection.sigma_rad) no_spread = no_spread && v == 0.0F;
    HARMOLOC_FUZZ_CHECK(input[8] >= 16 || no_spread,
                        "a map before version 16 decodes with projected bearings' spreads");
    bool no_area = true;
    for (const float v : f.projection.area_per_px) no_area = no_area && v == 0.0F;
    for (const float v : f.projection.area_sigma) no_area = no_area && v == 0.0F;
    HARMOLOC_FUZZ_CHECK(input[8] >= 17 || no_area,
                        "a map before version 17 decodes with projected areas");
    HARMOLOC_FUZZ_CHECK(!decode_map(encoded.data(), encoded.size(), g_again),
                        "a re-encoded older map does not decode");
    HARMOLOC_FUZZ_CHECK(same_model(g_map, g_again), "decode(encode(older map)) differs");
    check_added_bearings(input);
    check_added_heading_terms(input);
    check_added_heading_coverage(input);
    check_added_visibility(input);
    check_added_fix_errors(input);
    check_added_columns(input);
    check_added_column_gain(input);
    check_added_projection(input);
    return 0;
  }
  HARMOLOC_FUZZ_CHECK(encoded.size() == input.size(),
                      "a decoded map re-encodes to a different length");
  HARMOLOC_FUZZ_CHECK(std::memcmp(encoded.data(), input.data(), input.size()) == 0,
                      "a decoded map re-encodes to different bytes");
  HARMOLOC_FUZZ_CHECK(!decode_map(encoded.data(), encoded.size(), g_again),
                      "an encoded map does not decode");
  HARMOLOC_FUZZ_CHECK(same_model(g_map, g_again), "decode(encode(map)) differs from map");
  check_added_bearings(input);
  check_added_heading_terms(input);
  check_added_heading_coverage(input);
  check_added_visibility(input);
  check_added_fix_errors(input);
  check_added_columns(input);
  check_added_column_gain(input);
  check_added_projection(input);
  return 0;
}
