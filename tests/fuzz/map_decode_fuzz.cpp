// Fuzz target: the map file decoder (algorithms::decode_map), the firmware's first contact with
// a file from outside. Each input is decoded twice: as it is (magic, version, checksum paths)
// and with its trailing CRC-32 recomputed, so the fuzzer gets past the checksum into the
// header, threshold and sample validation. A map that decodes must also be usable: its counts
// within capacity and harmonic_query on it must give a finite fix where it claims a known place.

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "fuzz_common.hpp"
#include "harmoloc/algorithms/crc32.hpp"
#include "harmoloc/algorithms/harmonic_localizer.hpp"
#include "harmoloc/algorithms/map_codec.hpp"

using namespace harmoloc::algorithms;

namespace {

MapFile g_map;  // ~164 KiB: static, as the firmware holds it

void check_decoded(const MapFile& map) {
  const HarmonicModel& m = map.model;
  HARMOLOC_FUZZ_CHECK(map.thresholds.count >= 1 && map.thresholds.count <= kMaxBoards,
                      "decoded board count out of range");
  HARMOLOC_FUZZ_CHECK(m.sample_count >= 1 && m.sample_count <= HarmonicModel::kMaxSamples,
                      "decoded sample count out of range");
  HARMOLOC_FUZZ_CHECK(m.feature_count >= 1 && m.feature_count <= HarmonicModel::kMaxFeatures,
                      "decoded feature count out of range");
  for (std::size_t k = 0; k < m.feature_count; ++k)
    HARMOLOC_FUZZ_CHECK(m.board_index[k] < map.thresholds.count, "feature board out of range");
  // Every training position is a place within 10 km of the origin (a label at 1e30 once gave a
  // map the firmware accepted and a pose of 3.7e28 m: regressions/map_decode/target-at-1e30.hmap).
  for (std::size_t i = 0; i < m.sample_count; ++i) {
    HARMOLOC_FUZZ_CHECK(std::fabs(m.target_x_m[i]) <= kMaxMapCoordinate_m &&
                            std::fabs(m.target_y_m[i]) <= kMaxMapCoordinate_m,
                        "a training position farther than 10 km");
  }

  // The cycle feeds the localizer area vectors; try an empty frame, a full frame and the first
  // training sample itself.
  std::array<float, HarmonicModel::kMaxFeatures> features{};
  AreaVector areas;
  areas.count = map.thresholds.count;
  for (std::uint32_t fill : {0U, map.image_width_px * map.image_height_px}) {
    areas.pixels.fill(fill);
    areas_to_features(m, areas, features);
    const HarmonicFix fix = harmonic_query(m, features);
#ifdef HARMOLOC_FUZZ_SKIP_KNOWN_FINDINGS
    // Known finding (regressions/map_decode/nan-fix-at-known-place.hmap): when every squared
    // distance overflows float, harmonic_query's nearest distance stays at sqrt(FLT_MAX).
    if (fix.nearest_distance >= 1.8e19) continue;
#endif
    if (fix.known_place) {
      HARMOLOC_FUZZ_CHECK(std::isfinite(fix.x_m) && std::isfinite(fix.y_m),
                          "known-place fix is not finite");
    }
  }
  features.fill(0.0F);
  std::memcpy(features.data(), m.sample(0), m.feature_count * sizeof(float));
  const HarmonicFix fix = harmonic_query(m, features);
  HARMOLOC_FUZZ_CHECK(fix.nearest_distance == 0.0, "a training sample is not at distance 0");
  if (fix.known_place) {
    HARMOLOC_FUZZ_CHECK(std::isfinite(fix.x_m) && std::isfinite(fix.y_m),
                        "known-place fix is not finite");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (!decode_map(data, size, g_map)) check_decoded(g_map);

  if (size >= 4) {
    std::vector<std::uint8_t> fixed(data, data + size);  // exact size: over-reads hit the redzone
    const std::uint32_t crc = crc32(fixed.data(), size - 4);
    for (int i = 0; i < 4; ++i) fixed[size - 4 + i] = static_cast<std::uint8_t>(crc >> (8 * i));
    const MapError error = decode_map(fixed.data(), fixed.size(), g_map);
    if (!error) {
      check_decoded(g_map);
    } else {
      HARMOLOC_FUZZ_CHECK(error.offset <= size, "error offset beyond the input");
    }
  }
  return 0;
}
