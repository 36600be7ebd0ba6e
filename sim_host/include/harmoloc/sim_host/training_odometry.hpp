#pragma once
/// @file The wheel odometry of a training run, as the trainer uses it to place every frame
/// between the labels (algorithms/route_placement.hpp): the counters of a dataset folder's
/// encoder log (candump or GPIO recording), unwrapped, with the robot's geometry.

#include <cstdint>
#include <string>
#include <vector>

#include "harmoloc/algorithms/can_encoder_layout.hpp"
#include "harmoloc/algorithms/odometry.hpp"
#include "harmoloc/algorithms/route_placement.hpp"
#include "harmoloc/dataset/encoder_csv.hpp"
#include "harmoloc/dataset/metadata.hpp"

namespace harmoloc::sim_host {

/// Wheel counters over a run: absolute times (ns, the frames' clock) and unwrapped ticks.
struct OdometryTrack {
  algorithms::DiffDriveGeometry geometry;
  std::vector<std::uint64_t> timestamp_ns;
  std::vector<std::int64_t> left_ticks, right_ticks;
  bool empty() const { return timestamp_ns.size() < 2; }
  /// The samples with times in seconds after @p t0_ns.
  std::vector<algorithms::OdometrySample> relative_to(std::uint64_t t0_ns) const;
};

/// The counter frames of a CAN log (frames of other IDs or lengths are skipped), unwrapped.
/// Samples whose time does not increase are dropped.
OdometryTrack odometry_from_can(const std::vector<algorithms::CanFrame>& frames,
                                const algorithms::EncoderFrameLayout& layout,
                                const algorithms::DiffDriveGeometry& geometry);

/// A GPIO encoder recording's samples, unwrapped at @p counter_bits.
OdometryTrack odometry_from_gpio(const std::vector<dataset::EncoderSample>& samples,
                                 std::uint8_t counter_bits,
                                 const algorithms::DiffDriveGeometry& geometry);

/// The odometry of a dataset folder (its metadata says where and how). Throws
/// std::runtime_error with one line when the log cannot be read.
OdometryTrack read_dataset_odometry(const std::string& dataset_dir,
                                    const dataset::DatasetMetadata& meta);

/// An encoder log given on its own (harmoloc-train --encoders): a GPIO recording when its first
/// line is the recording's header, else a candump log decoded with @p layout.
OdometryTrack read_odometry_file(const std::string& path,
                                 const algorithms::EncoderFrameLayout& layout,
                                 const algorithms::DiffDriveGeometry& geometry);

}  // namespace harmoloc::sim_host
