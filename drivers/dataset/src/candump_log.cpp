#include "harmoloc/dataset/candump_log.hpp"

#include <cctype>
#include <cstdio>
#include <sstream>
#include <stdexcept>

#include "recording_text.hpp"

namespace harmoloc::dataset {

using algorithms::CanFrame;

namespace {

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

}  // namespace

bool parse_candump_line(const std::string& line, CanFrame& frame, std::string& reason) {
  // (1700000000.123456) can0 181#0011223344556677
  std::size_t pos = 0;
  if (line.empty() || line[0] != '(') {
    reason = "expected '(seconds.microseconds)' at the start";
    return false;
  }
  const auto close = line.find(')');
  if (close == std::string::npos) {
    reason = "missing ')' after the timestamp";
    return false;
  }
  const std::string stamp = line.substr(1, close - 1);
  const auto dot = stamp.find('.');
  if (dot == std::string::npos || dot == 0 || stamp.size() - dot - 1 != 6 || dot > 12) {
    reason = "timestamp must be seconds.microseconds (6 digits)";
    return false;
  }
  std::uint64_t sec = 0, usec = 0;
  for (std::size_t i = 0; i < stamp.size(); ++i) {
    if (i == dot) continue;
    if (!std::isdigit(static_cast<unsigned char>(stamp[i]))) {
      reason = "timestamp has a non-digit";
      return false;
    }
    if (i < dot)
      sec = sec * 10U + static_cast<std::uint64_t>(stamp[i] - '0');
    else
      usec = usec * 10U + static_cast<std::uint64_t>(stamp[i] - '0');
  }
  if (sec > 18446744072ULL) {  // sec * 1e9 must fit in 64 bits of nanoseconds
    reason = "timestamp out of range";
    return false;
  }
  pos = close + 1;
  while (pos < line.size() && line[pos] == ' ') ++pos;
  const auto iface_end = line.find(' ', pos);
  if (iface_end == std::string::npos || iface_end == pos) {
    reason = "missing interface name";
    return false;
  }
  pos = iface_end;
  while (pos < line.size() && line[pos] == ' ') ++pos;
  const auto hash = line.find('#', pos);
  if (hash == std::string::npos) {
    reason = "missing ID#DATA";
    return false;
  }
  const std::size_t id_len = hash - pos;
  if (id_len != 3 && id_len != 8) {
    reason = "CAN ID must have 3 (standard) or 8 (extended) hex digits";
    return false;
  }
  std::uint32_t id = 0;
  for (std::size_t i = pos; i < hash; ++i) {
    const int h = hex_value(line[i]);
    if (h < 0) {
      reason = "CAN ID is not hexadecimal";
      return false;
    }
    id = (id << 4U) | static_cast<std::uint32_t>(h);
  }
  if ((id_len == 3 && id > 0x7FFU) || (id_len == 8 && id > 0x1FFFFFFFU)) {
    reason = "CAN ID out of range";
    return false;
  }
  std::size_t d = hash + 1;
  if (d < line.size() && line[d] == '#') {
    reason = "CAN FD frames are not supported";
    return false;
  }
  if (d < line.size() && (line[d] == 'R' || line[d] == 'r')) {
    reason = "remote frames carry no data";
    return false;
  }
  std::size_t end = line.size();
  while (end > d && (line[end - 1] == '\r' || line[end - 1] == ' ')) --end;
  const std::size_t hex_len = end - d;
  if (hex_len % 2 != 0 || hex_len > 16) {
    reason = "data must be 0 to 8 bytes of hex pairs";
    return false;
  }
  frame = CanFrame{};
  for (std::size_t i = 0; i < hex_len / 2; ++i) {
    const int hi = hex_value(line[d + 2 * i]);
    const int lo = hex_value(line[d + 2 * i + 1]);
    if (hi < 0 || lo < 0) {
      reason = "data is not hexadecimal";
      return false;
    }
    frame.data[i] = static_cast<std::uint8_t>((hi << 4) | lo);
  }
  frame.id = id;
  frame.extended = id_len == 8;
  frame.length = static_cast<std::uint8_t>(hex_len / 2);
  frame.timestamp_ns = sec * 1000000000ULL + usec * 1000ULL;
  return true;
}

std::vector<CanFrame> read_candump_log(const std::string& path) {
  const std::string content = detail::read_recording_text(path);
  std::istringstream in(content);
  std::vector<CanFrame> frames;
  std::string line, reason;
  int line_no = 0, previous_line = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty() || line == "\r") continue;
    CanFrame frame;
    if (!parse_candump_line(line, frame, reason)) {
      throw std::runtime_error(path + ":" + std::to_string(line_no) + ": " + reason);
    }
    // candump writes a bus's frames in the order the kernel stamped them. A line dated before
    // the one above it would be handed out at once and move the pose by whatever its counts say
    // (a 57 cm jump), and one dated far ahead holds back every line after it: odometry off for
    // the rest of the run. Either is a damaged log.
    if (!frames.empty() && frame.timestamp_ns < frames.back().timestamp_ns) {
      const auto seconds = [](std::uint64_t ns) {
        char text[32];
        std::snprintf(text, sizeof text, "%llu.%06llu",
                      static_cast<unsigned long long>(ns / 1000000000ULL),
                      static_cast<unsigned long long>(ns / 1000ULL % 1000000ULL));
        return std::string(text);
      };
      throw std::runtime_error(
          path + ":" + std::to_string(line_no) + ": timestamp " + seconds(frame.timestamp_ns) +
          " is before line " + std::to_string(previous_line) + "'s " +
          seconds(frames.back().timestamp_ns) + " (lines must be in time order)");
    }
    frames.push_back(frame);
    previous_line = line_no;
  }
  return frames;
}

std::string format_candump_line(const CanFrame& frame, const std::string& iface) {
  char buf[96];
  int n = std::snprintf(
      buf, sizeof buf, "(%llu.%06llu) %s ",
      static_cast<unsigned long long>(frame.timestamp_ns / 1000000000ULL),
      static_cast<unsigned long long>((frame.timestamp_ns / 1000ULL) % 1000000ULL), iface.c_str());
  n += std::snprintf(buf + n, sizeof buf - static_cast<std::size_t>(n),
                     frame.extended ? "%08X#" : "%03X#", frame.id);
  for (std::uint8_t i = 0; i < frame.length && i < 8; ++i) {
    n += std::snprintf(buf + n, sizeof buf - static_cast<std::size_t>(n), "%02X", frame.data[i]);
  }
  return std::string(buf, static_cast<std::size_t>(n));
}

}  // namespace harmoloc::dataset
