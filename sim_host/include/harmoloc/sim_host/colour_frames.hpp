#pragma once
/// @file The frames harmoloc-colours reads (docs/colours.md): a recorded dataset's, or frames held
/// in memory, as RGB24 images in any order.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "harmoloc/dataset/metadata.hpp"

namespace harmoloc::sim_host::colours {

/// An RGB24 frame, rows packed.
struct RgbImage {
  std::uint32_t width_px = 0;
  std::uint32_t height_px = 0;
  std::vector<std::uint8_t> rgb;
};

/// Frames that can be read in any order, as often as needed (the analysis passes over a run
/// more than once).
class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual std::size_t size() const = 0;
  virtual std::uint64_t timestamp_ns(std::size_t index) const = 0;
  /// Throws std::runtime_error with one line naming the file when the frame cannot be read.
  virtual void read(std::size_t index, RgbImage& out) = 0;
};

/// A dataset folder (docs/dataset-format.md): its metadata and frame index are checked when it
/// is opened; PPM frames are read as they are, YUYV frames decoded as OpenCV (and so the
/// firmware's segmentation) decodes them.
class DatasetFrames final : public FrameSource {
 public:
  /// Throws std::runtime_error with one line: no such folder, no metadata, a bad index.
  explicit DatasetFrames(const std::string& dataset_dir);
  std::size_t size() const override { return files_.size(); }
  std::uint64_t timestamp_ns(std::size_t index) const override { return stamps_.at(index); }
  void read(std::size_t index, RgbImage& out) override;
  const dataset::DatasetMetadata& metadata() const { return meta_; }

 private:
  std::string dir_;
  dataset::DatasetMetadata meta_;
  std::vector<std::string> files_;
  std::vector<std::uint64_t> stamps_;
  std::vector<std::uint8_t> bytes_;
};

/// Frames held in memory (tests, and runs rendered by the simulator).
class MemoryFrames final : public FrameSource {
 public:
  void add(std::uint64_t timestamp_ns, RgbImage frame);
  std::size_t size() const override { return frames_.size(); }
  std::uint64_t timestamp_ns(std::size_t index) const override { return stamps_.at(index); }
  void read(std::size_t index, RgbImage& out) override { out = frames_.at(index); }

 private:
  std::vector<RgbImage> frames_;
  std::vector<std::uint64_t> stamps_;
};

}  // namespace harmoloc::sim_host::colours
