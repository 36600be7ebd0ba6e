#pragma once
/// @file The frame index (frames.csv): `timestamp_ns,file` a line after a header line; files are
/// binary PPM (P6, 8-bit) or raw YUYV, relative to the dataset folder.

#include <cstdint>
#include <string>
#include <vector>

namespace harmoloc::dataset {

struct FrameEntry {
  std::uint64_t timestamp_ns = 0;
  std::string file;  ///< relative to the dataset folder
};

/// Throws std::runtime_error("frames.csv:LINE: reason").
std::vector<FrameEntry> read_frame_index(const std::string& path);
void write_frame_index(const std::string& path, const std::vector<FrameEntry>& frames);

/// Header of a binary PPM: size and offset of the pixel data.
struct PpmHeader {
  std::uint32_t width_px = 0;
  std::uint32_t height_px = 0;
  std::size_t data_offset = 0;
};

/// Parses a P6 header with maxval 255 from the first bytes of a file. Returns false (with a
/// reason) for anything else. No allocation.
bool parse_ppm_header(const std::uint8_t* bytes, std::size_t size, PpmHeader& header,
                      const char** reason);

void write_ppm(const std::string& path, std::uint32_t width_px, std::uint32_t height_px,
               const std::uint8_t* rgb);

}  // namespace harmoloc::dataset
