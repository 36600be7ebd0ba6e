// Fuzz target: an area log (dataset::read_area_log), as harmoloc-train --areas and
// harmoloc-report --areas read it. Each input is written to a file in this process's scratch
// directory. std::runtime_error is the documented answer to a bad file; anything else is a
// finding. What is accepted must be what the trainer relies on: increasing timestamps, areas
// within the frame, distrust masks of the boards, and column sums and side pixels that fit the
// frame and the board's pixels.

#include <cstdint>
#include <stdexcept>
#include <string>

#include "fuzz_common.hpp"
#include "harmoloc/dataset/area_log.hpp"

using namespace harmoloc;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = fuzz::scratch_dir() + "/areas.csv";
  fuzz::write_file(path, data, size);
  dataset::AreaLog log;
  try {
    log = dataset::read_area_log(path);
  } catch (const std::runtime_error& e) {
    HARMOLOC_FUZZ_CHECK(e.what() != nullptr && e.what()[0] != '\0', "empty error message");
    return 0;
  }
  HARMOLOC_FUZZ_CHECK(!log.areas.empty() && log.areas.size() == log.timestamp_ns.size(),
                      "frames and timestamps differ");
  HARMOLOC_FUZZ_CHECK(!log.has_distrust || log.distrusted_mask.size() == log.areas.size(),
                      "a distrust mask missing");
  HARMOLOC_FUZZ_CHECK(!log.has_columns || log.has_distrust, "columns without the distrust column");
  const std::uint64_t w = log.image_width_px, h = log.image_height_px;
  for (std::size_t i = 0; i < log.areas.size(); ++i) {
    const algorithms::AreaVector& a = log.areas[i];
    HARMOLOC_FUZZ_CHECK(
        a.count == log.board_names.size() && a.count >= 1 && a.count <= algorithms::kMaxBoards,
        "board count");
    if (i > 0)
      HARMOLOC_FUZZ_CHECK(log.timestamp_ns[i] > log.timestamp_ns[i - 1],
                          "timestamps not increasing");
    if (log.has_distrust)
      HARMOLOC_FUZZ_CHECK(log.distrusted_mask[i] < (1U << a.count), "mask of a board not there");
    HARMOLOC_FUZZ_CHECK(!a.columns_measured() || (log.has_columns && a.width_px == w),
                        "columns measured in another width");
    HARMOLOC_FUZZ_CHECK(
        !a.rows_measured() || (log.has_rows && a.columns_measured() && a.height_px == h),
        "rows measured in another height or without columns");
    for (std::size_t k = 0; k < algorithms::kMaxBoards; ++k) {
      HARMOLOC_FUZZ_CHECK(a.pixels[k] <= w * h, "area past the frame");
      HARMOLOC_FUZZ_CHECK(a.column_sum[k] <= std::uint64_t{a.pixels[k]} * (w - 1U),
                          "column sum past the width");
      HARMOLOC_FUZZ_CHECK(a.side_pixels[k] <= a.pixels[k] && a.side_pixels[k] <= 2U * h,
                          "side pixels past the board or the sides");
      HARMOLOC_FUZZ_CHECK(a.row_sum[k] <= std::uint64_t{a.pixels[k]} * (h - 1U),
                          "row sum past the height");
      if (!a.columns_measured())
        HARMOLOC_FUZZ_CHECK(a.column_sum[k] == 0 && a.side_pixels[k] == 0,
                            "columns of a frame not measured");
      if (!a.rows_measured())
        HARMOLOC_FUZZ_CHECK(a.row_sum[k] == 0, "rows of a frame not measured");
    }
  }
  return 0;
}
