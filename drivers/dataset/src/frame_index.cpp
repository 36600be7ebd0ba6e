#include "harmoloc/dataset/frame_index.hpp"

#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "recording_text.hpp"

namespace harmoloc::dataset {

std::vector<FrameEntry> read_frame_index(const std::string& path) {
  const std::string content = detail::read_recording_text(path);
  std::istringstream in(content);
  std::vector<FrameEntry> frames;
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    if (line_no == 1 && line.rfind("timestamp_ns", 0) == 0) continue;
    const auto comma = line.find(',');
    const std::string where = path + ":" + std::to_string(line_no) + ": ";
    if (comma == std::string::npos)
      throw std::runtime_error(where + "expected 'timestamp_ns,file'");
    const std::string stamp = line.substr(0, comma);
    if (stamp.empty() || stamp.find_first_not_of("0123456789") != std::string::npos ||
        stamp.size() > 19) {
      throw std::runtime_error(where + "timestamp '" + stamp +
                               "' is not a whole number of nanoseconds");
    }
    FrameEntry e;
    e.timestamp_ns = std::stoull(stamp);
    e.file = line.substr(comma + 1);
    if (e.file.empty()) throw std::runtime_error(where + "empty file name");
    const std::string wrapped = "/" + e.file + "/";
    if (wrapped.find("/../") != std::string::npos || e.file[0] == '/') {
      throw std::runtime_error(where + "file must be a relative path inside the dataset");
    }
    if (!frames.empty() && e.timestamp_ns <= frames.back().timestamp_ns) {
      throw std::runtime_error(where + "timestamps must increase");
    }
    frames.push_back(std::move(e));
  }
  return frames;
}

void write_frame_index(const std::string& path, const std::vector<FrameEntry>& frames) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path + ": cannot write");
  out << "timestamp_ns,file\n";
  for (const FrameEntry& f : frames) out << f.timestamp_ns << ',' << f.file << '\n';
  if (!out) throw std::runtime_error(path + ": write failed");
}

namespace {

// Reads the next header token of a PPM (skipping whitespace and # comments).
bool next_number(const std::uint8_t* b, std::size_t size, std::size_t& pos, std::uint32_t& value) {
  for (;;) {
    while (pos < size && (b[pos] == ' ' || b[pos] == '\t' || b[pos] == '\n' || b[pos] == '\r'))
      ++pos;
    if (pos < size && b[pos] == '#') {
      while (pos < size && b[pos] != '\n') ++pos;
      continue;
    }
    break;
  }
  if (pos >= size || b[pos] < '0' || b[pos] > '9') return false;
  std::uint64_t v = 0;
  while (pos < size && b[pos] >= '0' && b[pos] <= '9') {
    v = v * 10U + static_cast<std::uint64_t>(b[pos] - '0');
    if (v > 1000000U) return false;
    ++pos;
  }
  value = static_cast<std::uint32_t>(v);
  return true;
}

}  // namespace

bool parse_ppm_header(const std::uint8_t* bytes, std::size_t size, PpmHeader& header,
                      const char** reason) {
  const char* why = nullptr;
  std::size_t pos = 2;
  std::uint32_t maxval = 0;
  if (size < 2 || bytes[0] != 'P' || bytes[1] != '6') {
    why = "not a binary PPM (P6)";
  } else if (!next_number(bytes, size, pos, header.width_px) ||
             !next_number(bytes, size, pos, header.height_px) ||
             !next_number(bytes, size, pos, maxval)) {
    why = "truncated or malformed PPM header";
  } else if (maxval != 255) {
    why = "PPM maxval must be 255 (8-bit)";
  } else if (header.width_px == 0 || header.height_px == 0) {
    why = "PPM size is zero";
  } else if (pos >= size || !(bytes[pos] == ' ' || bytes[pos] == '\n' || bytes[pos] == '\r' ||
                              bytes[pos] == '\t')) {
    why = "PPM header not followed by a single whitespace byte";
  }
  if (why != nullptr) {
    if (reason != nullptr) *reason = why;
    return false;
  }
  header.data_offset = pos + 1;
  return true;
}

void write_ppm(const std::string& path, std::uint32_t width_px, std::uint32_t height_px,
               const std::uint8_t* rgb) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) throw std::runtime_error(path + ": cannot write");
  std::fprintf(f, "P6\n%u %u\n255\n", width_px, height_px);
  const std::size_t n = static_cast<std::size_t>(width_px) * height_px * 3U;
  const bool ok = std::fwrite(rgb, 1, n, f) == n;
  if (std::fclose(f) != 0 || !ok) throw std::runtime_error(path + ": write failed");
}

}  // namespace harmoloc::dataset
