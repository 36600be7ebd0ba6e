#pragma once
/// @file The map file: a harmonic model with what it was trained with (camera mode, colour
/// thresholds), little-endian, versioned, with a CRC-32 over everything. Layout in
/// docs/map-format.md.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "harmoloc/algorithms/forward_map.hpp"
#include "harmoloc/algorithms/harmonic_model.hpp"
#include "harmoloc/algorithms/segmentation.hpp"

namespace harmoloc::algorithms {

/// Version 2 added the known-place dissimilarity bound, version 3 the forward map, version 4
/// the calibration measured on the training run, version 5 stores the forward map's tiles near
/// the training run instead of its whole grid, version 6 adds the board bearings, version 7 the
/// heading terms of a floor map, version 8 the headings each place was trained from, version 9
/// the camera's place the bearings are seen from, version 10 the visibility of a floor map,
/// version 11 the fix error per sample, version 12 the boards' centroid columns, version 13 the
/// area's gain by column, version 14 the visibility's optical axis, version 15 the projected
/// bearings (the fitted camera and boards' outlines), version 16 the projected bearings' spread,
/// version 17 the projected areas' feature per pixel and noise; versions 1 to 16 are still read
/// (without what they lack; a version 3 or 4 forward map as a grid of which every tile is stored, a
/// forward map before version 6 without bearings).
constexpr std::uint32_t kMapFormatVersion = 17;

/// What the trainer measured on the training run that the firmware derives its scene-dependent
/// settings from (docs/map-format.md): nothing of it is a constant tuned to one scene.
struct MapCalibration {
  bool present = false;  ///< false in maps before version 4
  /// RMS error of the harmonic fix per axis on frames predicted from other passes (metres).
  float fix_rmse_x_m = 0.0F;
  float fix_rmse_y_m = 0.0F;
  /// Median distance from a training frame to the nearest frame of another pass (metres): how
  /// far apart two runs over one place lie (wander, placement).
  float pass_spread_m = 0.0F;
  /// The wheel odometry measured against the labels (odometry_calibration.hpp): multipliers on
  /// the configured geometry, each in [0.5, 2]. Absent (false, all 1) in maps before it.
  bool odometry_present = false;
  float left_wheel_scale = 1.0F;
  float right_wheel_scale = 1.0F;
  float track_scale = 1.0F;
  /// Upper quartile of the heading difference between a training frame and the nearest frame of
  /// another pass (radians, 0..pi; absent, 0, in maps before it): how far apart in heading two
  /// passes over one place run.
  float pass_heading_spread_rad = 0.0F;
};

/// From this pass heading spread on (10 degrees), a map is a floor map (docs/filter.md): the
/// training run drove its places at several headings, so the places and headings between its
/// passes are the map's too, and the filter drops the route terms that hold a particle to the
/// passes. A route's passes run within a few degrees of each other.
constexpr float kFloorMapPassHeadingSpread_rad = 0.174533F;

/// Whether @p calibration says the map covers a floor rather than a route.
inline bool is_floor_map(const MapCalibration& calibration) {
  return calibration.pass_heading_spread_rad >= kFloorMapPassHeadingSpread_rad;
}

/// Most calibration entries a map may hold (version 4).
constexpr std::uint32_t kMaxCalibrationEntries = 64;

/// The largest map file this build reads (every count at its capacity): the loader
/// refuses a larger file before reading it.
constexpr std::size_t kMaxMapFileBytes =
    8U + 4U * 4U + kMaxBoards * 12U + 8U + HarmonicModel::kMaxFeatures + 7U * 4U +
    HarmonicModel::kMaxFeatures * 4U +
    HarmonicModel::kMaxSamples * (HarmonicModel::kMaxFeatures + 2U) * 4U + 8U + 16U +
    kMaxBoards * 4U + 4U + 4U + (ForwardMap::kMaxTileGrid + 7U) / 8U +
    ForwardMap::kMaxCells * (kMaxBoards + 2U) * 4U +
    // Version 6: the bearing law (a1, a3), each board's bearing spread, every cell's bearings;
    // version 9 the camera's offset.
    8U + 4U + kMaxBoards * 4U + ForwardMap::kMaxCells * kMaxBoards * 4U +
    // Version 7: every cell's heading terms (version 10: or the visibility, in their place, and
    // its angle gain; version 14 its optical axis).
    8U + ForwardMap::kMaxCells * kMaxBoards * 8U +
    // Version 8: every cell's heading coverage.
    ForwardMap::kMaxCells * 2U + 4U + kMaxCalibrationEntries * 8U +
    // Version 11: the per-sample fix errors.
    4U + HarmonicModel::kMaxSamples * 4U +
    // Version 15: the projection (frame size, camera, intrinsics and lens, every board's
    // outline; version 16 its bearing spread, version 17 its feature per pixel and area noise).
    8U + 12U * 4U + 9U * 4U + kMaxBoards * (4U + 12U * BearingProjection::kMaxPoints + 12U) +
    // Version 13: the column gain. Version 12: the column weight and every sample's column
    // features (when this build holds them); the CRC.
    8U + 4U +
    (HarmonicModel::kHoldsColumns ? HarmonicModel::kMaxSamples * HarmonicModel::kMaxFeatures * 4U
                                  : 0U) +
    4U;

/// How far from the map's origin a position in a map may be (metres): a training target beyond
/// it is refused (a label in millimetres or at 1e30 must not become a map the firmware trusts).
/// The same bound as the forward map's origin and the set-pose command's.
constexpr float kMaxMapCoordinate_m = 1.0e4F;

struct MapFile {
  std::uint32_t image_width_px = 0;
  std::uint32_t image_height_px = 0;
  ThresholdSet thresholds;
  HarmonicModel model;
  ForwardMap forward;  ///< absent (columns 0) in maps before version 3
  MapCalibration calibration;
};

/// Serialises @p map (host/trainer side; allocates).
std::vector<std::uint8_t> encode_map(const MapFile& map);

/// Why a map was rejected: a static message and the byte offset where it was noticed.
struct MapError {
  const char* what = nullptr;  ///< nullptr when the map is good
  std::size_t offset = 0;
  explicit operator bool() const { return what != nullptr; }
};

/// Parses and validates a map held in memory into @p map (which may be a static object: no
/// allocation). Rejects bad magic, unknown version, truncation, trailing bytes, checksum
/// mismatch, counts above capacity, non-finite or non-positive parameters, and training targets
/// that are not finite or farther than kMaxMapCoordinate_m from the origin.
MapError decode_map(const std::uint8_t* data, std::size_t size, MapFile& map);

}  // namespace harmoloc::algorithms
