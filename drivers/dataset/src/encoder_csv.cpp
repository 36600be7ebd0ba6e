#include "harmoloc/dataset/encoder_csv.hpp"

#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "recording_text.hpp"

namespace harmoloc::dataset {

namespace {

// Parses [p, end) as an unsigned decimal of at most @p max_digits digits. False on anything else.
bool parse_unsigned(const char* p, const char* end, std::size_t max_digits, std::uint64_t& out) {
  const auto n = static_cast<std::size_t>(end - p);
  if (n == 0 || n > max_digits) return false;
  std::uint64_t v = 0;
  for (; p < end; ++p) {
    if (*p < '0' || *p > '9') return false;
    const auto d = static_cast<std::uint64_t>(*p - '0');
    if (v > (UINT64_MAX - d) / 10U) return false;  // would overflow 64 bits
    v = v * 10U + d;
  }
  out = v;
  return true;
}

// A count: optional '-', then digits; within -2^(bits-1) .. 2^bits - 1, returned mod 2^bits.
bool parse_count(const char* p, const char* end, std::uint8_t bits, std::uint32_t& out,
                 const char** reason) {
  const bool negative = p < end && *p == '-';
  std::uint64_t magnitude = 0;
  if (!parse_unsigned(negative ? p + 1 : p, end, 10, magnitude)) {
    *reason = "a count must be a whole number (digits, optionally after '-')";
    return false;
  }
  const std::uint64_t span = std::uint64_t{1} << bits;
  if (negative ? magnitude > span / 2U : magnitude >= span) {
    *reason = "a count does not fit the counter width (metadata encoders.counter_bits)";
    return false;
  }
  const std::uint64_t v = negative ? span - magnitude : magnitude;
  out = static_cast<std::uint32_t>(v & (span - 1U));
  return true;
}

}  // namespace

bool parse_encoder_csv_line(const char* line, std::size_t size, std::uint8_t counter_bits,
                            EncoderSample& sample, const char** reason) {
  if (counter_bits < 8 || counter_bits > 32) {
    *reason = "counter width must be 8..32 bits";
    return false;
  }
  const char* end = line + size;
  if (end > line && end[-1] == '\r') --end;
  if (end == line) {
    *reason = "empty line";
    return false;
  }
  const char* c1 =
      static_cast<const char*>(std::memchr(line, ',', static_cast<std::size_t>(end - line)));
  const char* c2 = c1 == nullptr ? nullptr
                                 : static_cast<const char*>(std::memchr(
                                       c1 + 1, ',', static_cast<std::size_t>(end - c1 - 1)));
  if (c1 == nullptr || c2 == nullptr ||
      std::memchr(c2 + 1, ',', static_cast<std::size_t>(end - c2 - 1)) != nullptr) {
    *reason = "expected three fields: timestamp_ns,left_ticks,right_ticks";
    return false;
  }
  EncoderSample s;
  if (!parse_unsigned(line, c1, 20, s.timestamp_ns)) {
    *reason = "timestamp_ns must be a whole number of nanoseconds (digits only, fits 64 bits)";
    return false;
  }
  if (!parse_count(c1 + 1, c2, counter_bits, s.left_ticks, reason)) return false;
  if (!parse_count(c2 + 1, end, counter_bits, s.right_ticks, reason)) return false;
  sample = s;
  return true;
}

std::vector<EncoderSample> read_encoder_csv(const std::string& path, std::uint8_t counter_bits) {
  const std::string text = detail::read_recording_text(path);
  const auto at = [&path](std::size_t line_no, const std::string& why) {
    return std::runtime_error(path + ":" + std::to_string(line_no) + ": " + why);
  };
  std::vector<EncoderSample> samples;
  std::size_t pos = 0, line_no = 0;
  while (pos < text.size()) {
    ++line_no;
    std::size_t eol = text.find('\n', pos);
    if (eol == std::string::npos) eol = text.size();
    const char* line = text.data() + pos;
    std::size_t size = eol - pos;
    pos = eol + 1;
    if (line_no == 1) {
      if (size > 0 && line[size - 1] == '\r') --size;
      if (std::string(line, size) != kEncoderCsvHeader)
        throw at(1, std::string("expected the header '") + kEncoderCsvHeader + "'");
      continue;
    }
    EncoderSample s;
    const char* why = nullptr;
    if (!parse_encoder_csv_line(line, size, counter_bits, s, &why)) throw at(line_no, why);
    if (!samples.empty() && s.timestamp_ns <= samples.back().timestamp_ns)
      throw at(line_no, "timestamp_ns is not after the previous line's");
    samples.push_back(s);
  }
  if (line_no == 0) throw at(1, std::string("expected the header '") + kEncoderCsvHeader + "'");
  if (samples.empty()) throw std::runtime_error(path + ": no samples after the header");
  return samples;
}

std::size_t format_encoder_csv_line(const EncoderSample& sample, char* buffer, std::size_t size) {
  const int n = std::snprintf(buffer, size, "%llu,%lu,%lu\n",
                              static_cast<unsigned long long>(sample.timestamp_ns),
                              static_cast<unsigned long>(sample.left_ticks),
                              static_cast<unsigned long>(sample.right_ticks));
  return n > 0 && static_cast<std::size_t>(n) < size ? static_cast<std::size_t>(n) : 0U;
}

bool EncoderRecorder::open(const std::string& path) {
  close();
  if (!out_.open(path)) return false;
  std::fprintf(out_.file(), "%s\n", kEncoderCsvHeader);
  any_ = false;
  written_ = 0;
  return std::ferror(out_.file()) == 0;
}

bool EncoderRecorder::close() {
  return out_.close();
}

hal::EncoderStatus EncoderRecorder::read(std::uint64_t data_time_ns, hal::EncoderCounts& counts) {
  const hal::EncoderStatus s = inner_.read(data_time_ns, counts);
  if (s != hal::EncoderStatus::kFresh || !out_.is_open()) return s;
  counter_bits_ = counts.counter_bits;
  if (any_ && counts.timestamp_ns <= last_ns_) return s;
  const std::uint32_t mask =
      counts.counter_bits >= 32 ? 0xFFFFFFFFU : (1U << counts.counter_bits) - 1U;
  char line[64];
  const std::size_t n = format_encoder_csv_line(
      EncoderSample{counts.timestamp_ns, counts.left_ticks & mask, counts.right_ticks & mask}, line,
      sizeof line);
  out_.append(line, n);
  any_ = true;
  last_ns_ = counts.timestamp_ns;
  ++written_;
  return s;
}

}  // namespace harmoloc::dataset
