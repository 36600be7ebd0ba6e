#pragma once
/// @file The area log: one line per frame with the pixel count of every board, as the firmware
/// measured it. A robot records it while it runs (`harmoloc --record-areas`), the trainer learns
/// from it and a few labelled poses without the frames themselves. Format in
/// docs/dataset-format.md.

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "harmoloc/algorithms/segmentation.hpp"
#include "harmoloc/dataset/buffered_output.hpp"

namespace harmoloc::dataset {

/// A fingerprint of the colour thresholds, so the trainer can tell whether a log was measured
/// with the thresholds it is about to record in the map.
std::uint32_t thresholds_fingerprint(const algorithms::ThresholdSet& thresholds);

struct AreaLog {
  std::uint32_t image_width_px = 0;
  std::uint32_t image_height_px = 0;
  std::uint32_t thresholds_crc32 = 0;
  std::vector<std::string> board_names;
  std::vector<std::uint64_t> timestamp_ns;
  std::vector<algorithms::AreaVector> areas;
  /// The trailing `distrusted_mask` column (bit b: board b was distrusted by the filter in that
  /// frame). Logs written before the column existed have none: has_distrust false and the
  /// vector empty; otherwise one entry per frame.
  bool has_distrust = false;
  std::vector<std::uint32_t> distrusted_mask;
  /// The `column_sum_<board>` and `side_px_<board>` columns after it (each board's column sum and
  /// side pixels, AreaVector::column_sum and side_pixels). Without them, or in a frame whose
  /// fields are '-', the areas read with width_px 0: columns not measured.
  bool has_columns = false;
  /// The `row_sum_<board>` columns after those (AreaVector::row_sum). Without them, or in a frame
  /// whose row fields are '-', the areas read with height_px 0: rows not measured.
  bool has_rows = false;
};

/// Reads and checks an area log. Throws std::runtime_error with one line (file:line: what).
AreaLog read_area_log(const std::string& path);

/// Appends frames to an area log from inside the cycle: the file and its buffer are set up at
/// start-up, each line is formatted on the stack and appended without allocating.
class AreaLogWriter {
 public:
  /// Opens (truncates) @p path and writes the header; false if it cannot be written.
  bool open(const std::string& path, std::uint32_t width_px, std::uint32_t height_px,
            const algorithms::ThresholdSet& thresholds,
            const std::vector<std::string>& board_names);
  /// Appends one frame's areas and the boards the filter distrusted in it (bit b: board b);
  /// does nothing when no file is open.
  void write(std::uint64_t t_ns, const algorithms::AreaVector& areas,
             std::uint32_t distrusted_mask = 0);
  /// Flushes and closes; false if any write failed.
  bool close() { return out_.close(); }
  const BufferedOutput& output() const { return out_; }

 private:
  BufferedOutput out_;
  std::size_t boards_ = 0;
};

}  // namespace harmoloc::dataset
