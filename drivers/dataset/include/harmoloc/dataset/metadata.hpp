#pragma once
/// @file The dataset folder's metadata.toml: what the recording is (image size, pixel format,
/// rate, robot geometry, encoder frame layout). Schema in docs/dataset-format.md.

#include <cstdint>
#include <limits>
#include <string>

#include "harmoloc/algorithms/can_encoder_layout.hpp"
#include "harmoloc/algorithms/odometry.hpp"
#include "harmoloc/hal/frame.hpp"

namespace harmoloc::dataset {

/// Where the wheel encoder counts of a recording come from (`[encoders] source`).
enum class EncoderSource : std::uint8_t {
  kCan = 0,   ///< a `candump -l` log of the CAN bus (encoders.log)
  kGpio = 1,  ///< a GPIO encoder recording, CSV (encoders.csv, encoder_csv.hpp)
};

struct DatasetMetadata {
  std::string name;
  std::uint32_t image_width_px = 0;
  std::uint32_t image_height_px = 0;
  hal::PixelFormat pixel_format = hal::PixelFormat::kRgb24;
  double frame_rate_hz = 30.0;
  std::string frames_index = "frames.csv";
  EncoderSource encoder_source = EncoderSource::kCan;
  std::string encoder_log = "encoders.log";      ///< "encoders.csv" by default for kGpio
  std::string ground_truth = "groundtruth.tum";  ///< empty when there is none (a real recording)
  std::string can_interface = "can0";
  algorithms::DiffDriveGeometry geometry;
  algorithms::EncoderFrameLayout encoder_layout;
  std::uint64_t seed = 0;
  /// camera.forward_offset_m: the camera's offset ahead of the wheel axle's centre along the
  /// heading (metres); NaN when the file does not give it (optional).
  double camera_forward_m = std::numeric_limits<double>::quiet_NaN();
  /// camera.height_m: the camera's optical centre above the floor (metres); NaN when the file
  /// does not give it (optional). The trainer fits the camera and boards with it as the scale.
  double camera_height_m = std::numeric_limits<double>::quiet_NaN();
};

/// Reads DIR/metadata.toml. Throws std::runtime_error("metadata.toml: reason") when it is
/// missing, unparsable or out of range.
DatasetMetadata read_metadata(const std::string& dataset_dir);
/// DIR/metadata.toml's text (toml_writer.hpp: numbers in their shortest exact form).
std::string metadata_toml(const DatasetMetadata& metadata);
/// Writes metadata_toml() to DIR/metadata.toml (at start-up and at the end of a recording: it
/// allocates).
void write_metadata(const std::string& dataset_dir, const DatasetMetadata& metadata);

}  // namespace harmoloc::dataset
