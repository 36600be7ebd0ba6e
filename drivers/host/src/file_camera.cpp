#include "harmoloc/host/file_camera.hpp"

#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include <fcntl.h>
#include <unistd.h>

#include "harmoloc/dataset/frame_index.hpp"
#include "harmoloc/drivers/input_file.hpp"

namespace harmoloc::host {

namespace {

// Reads up to @p size bytes of a regular file; returns how many were read, or -1 on error (a
// FIFO, device or folder put in the frame's place is not read: opened non-blocking and refused,
// so the cycle never waits on it). No allocation.
long read_file(const char* path, std::uint8_t* buffer, std::size_t size) {
  const char* why = nullptr;
  const int fd = drivers::open_regular_file(path, &why);
  if (fd < 0) return -1;
  std::size_t got = 0;
  while (got < size) {
    const ssize_t n = ::read(fd, buffer + got, size - got);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    got += static_cast<std::size_t>(n);
  }
  ::close(fd);
  return static_cast<long>(got);
}

}  // namespace

FileCamera::FileCamera(const std::string& dataset_dir, const dataset::DatasetMetadata& metadata) {
  namespace fs = std::filesystem;
  const std::string index_path = (fs::path(dataset_dir) / metadata.frames_index).string();
  const std::vector<dataset::FrameEntry> entries = dataset::read_frame_index(index_path);
  if (entries.empty()) throw std::runtime_error(index_path + ": no frames listed");

  const std::size_t pixel_bytes = static_cast<std::size_t>(metadata.image_width_px) *
                                  metadata.image_height_px *
                                  hal::bytes_per_pixel_x2(metadata.pixel_format) / 2U;
  std::array<std::uint8_t, 64> head{};
  for (const dataset::FrameEntry& e : entries) {
    const std::string path = (fs::path(dataset_dir) / e.file).string();
    std::error_code ec;
    const auto status = fs::status(path, ec);
    if (!ec && !fs::is_regular_file(status))
      throw std::runtime_error("frame " + e.file + ": not a regular file");
    const auto size = fs::file_size(path, ec);
    if (ec) throw std::runtime_error("frame " + e.file + ": " + ec.message());
    if (metadata.pixel_format == hal::PixelFormat::kRgb24) {
      const long n = read_file(path.c_str(), head.data(), head.size());
      dataset::PpmHeader h;
      const char* why = nullptr;
      if (n <= 0 || !dataset::parse_ppm_header(head.data(), static_cast<std::size_t>(n), h, &why)) {
        throw std::runtime_error("frame " + e.file + ": " + (why != nullptr ? why : "unreadable"));
      }
      if (h.width_px != metadata.image_width_px || h.height_px != metadata.image_height_px) {
        throw std::runtime_error("frame " + e.file + ": " + std::to_string(h.width_px) + "x" +
                                 std::to_string(h.height_px) + ", metadata says " +
                                 std::to_string(metadata.image_width_px) + "x" +
                                 std::to_string(metadata.image_height_px));
      }
      if (data_offset_ != 0 && h.data_offset != data_offset_) {
        throw std::runtime_error("frame " + e.file +
                                 ": PPM header differs in length from the first frame's");
      }
      data_offset_ = h.data_offset;
    }
    const std::size_t expected = data_offset_ + pixel_bytes;
    if (size != expected) {
      throw std::runtime_error("frame " + e.file + ": " + std::to_string(size) +
                               " bytes, expected " + std::to_string(expected) +
                               (size < expected ? " (truncated)" : ""));
    }
    paths_.push_back(path);
    stamps_.push_back(e.timestamp_ns);
  }
  file_size_ = data_offset_ + pixel_bytes;
  period_ns_ = static_cast<std::uint64_t>(std::llround(1e9 / metadata.frame_rate_hz));
  buffer_.resize(file_size_ + 1);  // one spare byte detects a file that grew after start-up
  view_.width_px = metadata.image_width_px;
  view_.height_px = metadata.image_height_px;
  view_.format = metadata.pixel_format;
  view_.stride_bytes = static_cast<std::uint32_t>(
      metadata.image_width_px * hal::bytes_per_pixel_x2(metadata.pixel_format) / 2U);
  view_.data = buffer_.data() + data_offset_;
}

std::uint64_t FileCamera::next_timestamp_ns() const {
  if (next_ < stamps_.size()) {
    const std::uint64_t next = stamps_[next_] + loop_ * span_ns_;
    if (fill_gaps_ && have_last_ && next > last_ns_ + period_ns_ + period_ns_ / 2)
      return last_ns_ + period_ns_;
    return next;
  }
  // The next pass of a --loop replay (no ticks across the seam: it is not in the recording).
  if (loop_ + 1 < loops_ && !stamps_.empty()) return stamps_.front() + (loop_ + 1) * span_ns_;
  return 0;
}

hal::CameraStatus FileCamera::acquire(hal::FrameView& frame, std::uint64_t /*deadline_ns*/) {
  if (next_ >= paths_.size() && loop_ + 1 < loops_) {
    ++loop_;
    next_ = 0;
    have_last_ = false;
  }
  if (next_ >= paths_.size()) return hal::CameraStatus::kEnded;
  const std::uint64_t due = stamps_[next_] + loop_ * span_ns_;
  if (fill_gaps_ && have_last_ && due > last_ns_ + period_ns_ + period_ns_ / 2) {
    // A hole in the recording: this period brought no frame.
    last_ns_ += period_ns_;
    ++gap_ticks_;
    return hal::CameraStatus::kNoFrame;
  }
  last_ns_ = due;
  have_last_ = true;
  const std::size_t i = next_++;
  const long n = read_file(paths_[i].c_str(), buffer_.data(), buffer_.size());
  const char* why = nullptr;
  dataset::PpmHeader h;
  const bool header_ok =
      view_.format != hal::PixelFormat::kRgb24 ||
      (n > 0 && dataset::parse_ppm_header(buffer_.data(), static_cast<std::size_t>(n), h, &why) &&
       h.data_offset == data_offset_ && h.width_px == view_.width_px &&
       h.height_px == view_.height_px);
  if (n != static_cast<long>(file_size_) || !header_ok) {
    ++counters_.corrupt;
    return hal::CameraStatus::kCorrupt;
  }
  ++counters_.frames;
  view_.timestamp_ns = stamps_[i] + loop_ * span_ns_;
  view_.sequence = static_cast<std::uint32_t>(loop_ * paths_.size() + i);
  frame = view_;
  return hal::CameraStatus::kFrame;
}

}  // namespace harmoloc::host
