#include "harmoloc/sim_host/colour_frames.hpp"

#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "harmoloc/algorithms/segmentation.hpp"
#include "harmoloc/dataset/frame_index.hpp"

namespace harmoloc::sim_host::colours {

namespace {

namespace alg = algorithms;

std::vector<std::uint8_t> read_whole_file(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw std::runtime_error(path + ": not a regular file");
  std::ifstream f(path, std::ios::binary);
  if (!f) throw std::runtime_error(path + ": cannot open");
  f.seekg(0, std::ios::end);
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(std::max<std::streamoff>(f.tellg(), 0)));
  f.seekg(0);
  f.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (!f) throw std::runtime_error(path + ": cannot read");
  return bytes;
}

}  // namespace

DatasetFrames::DatasetFrames(const std::string& dataset_dir) : dir_(dataset_dir) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::is_directory(dataset_dir, ec))
    throw std::runtime_error(dataset_dir + ": no such dataset folder");
  meta_ = dataset::read_metadata(dataset_dir);
  const std::string index = (fs::path(dataset_dir) / meta_.frames_index).string();
  for (const auto& e : dataset::read_frame_index(index)) {
    files_.push_back((fs::path(dataset_dir) / e.file).string());
    stamps_.push_back(e.timestamp_ns);
  }
  if (files_.empty()) throw std::runtime_error(index + ": no frames listed");
  // Every file is checked now, not when (or whether) a pass reaches it: a frame the analysis
  // skips would still stop the firmware's replay or the trainer.
  const std::size_t n = static_cast<std::size_t>(meta_.image_width_px) * meta_.image_height_px;
  std::array<std::uint8_t, 64> head{};
  for (const std::string& path : files_) {
    const auto size = fs::is_regular_file(path, ec) ? fs::file_size(path, ec) : 0;
    if (ec || size == 0) throw std::runtime_error(path + ": missing, empty or not a file");
    std::size_t expected = 2 * n;
    if (meta_.pixel_format == hal::PixelFormat::kRgb24) {
      std::ifstream f(path, std::ios::binary);
      f.read(reinterpret_cast<char*>(head.data()), static_cast<std::streamsize>(head.size()));
      dataset::PpmHeader header;
      const char* why = nullptr;
      if (!dataset::parse_ppm_header(head.data(), static_cast<std::size_t>(f.gcount()), header,
                                     &why))
        throw std::runtime_error(path + ": " + (why ? why : "not a binary PPM"));
      if (header.width_px != meta_.image_width_px || header.height_px != meta_.image_height_px)
        throw std::runtime_error(path + ": " + std::to_string(header.width_px) + "x" +
                                 std::to_string(header.height_px) + ", the metadata says " +
                                 std::to_string(meta_.image_width_px) + "x" +
                                 std::to_string(meta_.image_height_px));
      expected = header.data_offset + 3 * n;
    }
    if (size != expected)
      throw std::runtime_error(path + ": " + std::to_string(size) + " bytes, expected " +
                               std::to_string(expected) + (size < expected ? " (truncated)" : ""));
  }
}

void DatasetFrames::read(std::size_t index, RgbImage& out) {
  const std::string& path = files_.at(index);
  bytes_ = read_whole_file(path);
  const std::uint32_t w = meta_.image_width_px, h = meta_.image_height_px;
  const std::size_t n = static_cast<std::size_t>(w) * h;
  out.width_px = w;
  out.height_px = h;
  out.rgb.resize(3 * n);
  if (meta_.pixel_format == hal::PixelFormat::kRgb24) {
    dataset::PpmHeader header;
    const char* why = nullptr;
    if (!dataset::parse_ppm_header(bytes_.data(), bytes_.size(), header, &why))
      throw std::runtime_error(path + ": " + (why ? why : "not a binary PPM"));
    if (header.width_px != w || header.height_px != h)
      throw std::runtime_error(path + ": " + std::to_string(header.width_px) + "x" +
                               std::to_string(header.height_px) + ", the metadata says " +
                               std::to_string(w) + "x" + std::to_string(h));
    if (bytes_.size() < header.data_offset + 3 * n) throw std::runtime_error(path + ": truncated");
    std::copy_n(bytes_.begin() + static_cast<std::ptrdiff_t>(header.data_offset), 3 * n,
                out.rgb.begin());
    return;
  }
  if (bytes_.size() != 2 * n)
    throw std::runtime_error(path + ": " + std::to_string(bytes_.size()) +
                             " bytes, a YUYV frame of the metadata's size has " +
                             std::to_string(2 * n));
  for (std::size_t pair = 0; pair < n / 2; ++pair) {
    const std::uint8_t* q = &bytes_[4 * pair];
    for (int k = 0; k < 2; ++k) {
      const alg::Rgb8 c = alg::yuv_to_rgb_opencv(q[2 * k], q[1], q[3]);
      std::uint8_t* o = &out.rgb[3 * (2 * pair + static_cast<std::size_t>(k))];
      o[0] = c.r;
      o[1] = c.g;
      o[2] = c.b;
    }
  }
}

void MemoryFrames::add(std::uint64_t timestamp_ns, RgbImage frame) {
  stamps_.push_back(timestamp_ns);
  frames_.push_back(std::move(frame));
}

}  // namespace harmoloc::sim_host::colours
