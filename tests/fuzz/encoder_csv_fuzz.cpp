// Fuzz target: a GPIO encoder recording (encoders.csv, dataset::read_encoder_csv) and its replay
// (host::GpioLogEncoders), as the host board reads it when the metadata says
// [encoders] source = "gpio". Input: 1 byte choosing the counter width (8 + b % 25 bits), then
// the file's bytes, written to a file in this process's scratch directory.
// std::runtime_error is the documented answer to a bad recording; anything else is a finding.
//
// Also checked: an accepted recording has strictly increasing timestamps and counts within the
// width; every sample formats and parses back to itself; the replay hands out every sample at its
// own timestamp (and, looped twice, counts within the width); and the line parser, given each
// line of the input in a buffer of exactly its size (so AddressSanitizer sees any read past the
// line), accepts exactly the lines the whole-file reader accepted.

#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "fuzz_common.hpp"
#include "harmoloc/dataset/encoder_csv.hpp"
#include "harmoloc/host/gpio_log_encoders.hpp"

using namespace harmoloc;

namespace {

// An independent reading of an accepted line (strtoull / strtoll on copies of the fields), to
// check the parser's values and ranges against.
struct Reference {
  unsigned long long t = 0;
  long long left = 0, right = 0;
};
bool reference_parse(const char* line, std::size_t n, Reference& r) {
  std::string text(line, n);
  if (!text.empty() && text.back() == '\r') text.pop_back();
  const std::size_t c1 = text.find(','), c2 = text.find(',', c1 + 1);
  if (c1 == std::string::npos || c2 == std::string::npos) return false;
  const std::string f[3] = {text.substr(0, c1), text.substr(c1 + 1, c2 - c1 - 1),
                            text.substr(c2 + 1)};
  errno = 0;
  r.t = std::strtoull(f[0].c_str(), nullptr, 10);
  r.left = std::strtoll(f[1].c_str(), nullptr, 10);
  r.right = std::strtoll(f[2].c_str(), nullptr, 10);
  return errno == 0;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const auto bits = static_cast<std::uint8_t>(8U + data[0] % 25U);
  const std::uint64_t span = std::uint64_t{1} << bits;
  ++data;
  --size;
  static const std::string path = fuzz::scratch_dir() + "/encoders.csv";
  fuzz::write_file(path, data, size);

  // The line parser on every line after the first, each in a buffer of its exact size.
  std::vector<bool> line_ok;
  {
    std::size_t pos = 0;
    bool first = true;
    while (pos < size) {
      const auto* nl = static_cast<const std::uint8_t*>(std::memchr(data + pos, '\n', size - pos));
      const std::size_t end = nl != nullptr ? static_cast<std::size_t>(nl - data) : size;
      if (!first) {
        const std::size_t n = end - pos;
        std::unique_ptr<char[]> line(new char[n == 0 ? 1 : n]);
        if (n > 0) std::memcpy(line.get(), data + pos, n);
        dataset::EncoderSample s;
        const char* why = nullptr;
        const bool ok = dataset::parse_encoder_csv_line(line.get(), n, bits, s, &why);
        HARMOLOC_FUZZ_CHECK(ok || (why != nullptr && why[0] != '\0'), "rejected without a reason");
        if (ok) {
          HARMOLOC_FUZZ_CHECK(s.left_ticks < span && s.right_ticks < span, "count beyond width");
          Reference r;
          HARMOLOC_FUZZ_CHECK(reference_parse(line.get(), n, r), "strtoll disagrees: not numbers");
          const auto lo = -static_cast<long long>(span / 2U);
          const auto hi = static_cast<long long>(span - 1U);
          HARMOLOC_FUZZ_CHECK(r.left >= lo && r.left <= hi && r.right >= lo && r.right <= hi,
                              "accepted a count outside -2^(bits-1)..2^bits-1");
          HARMOLOC_FUZZ_CHECK(r.t == s.timestamp_ns, "timestamp differs from strtoull's");
          HARMOLOC_FUZZ_CHECK(static_cast<std::uint64_t>(r.left) % span == s.left_ticks &&
                                  static_cast<std::uint64_t>(r.right) % span == s.right_ticks,
                              "count differs from strtoll's modulo 2^bits");
        }
        line_ok.push_back(ok);
      }
      first = false;
      pos = end + 1;
    }
  }

  std::vector<dataset::EncoderSample> samples;
  try {
    samples = dataset::read_encoder_csv(path, bits);
  } catch (const std::runtime_error& e) {
    HARMOLOC_FUZZ_CHECK(e.what() != nullptr && e.what()[0] != '\0', "empty error message");
    HARMOLOC_FUZZ_CHECK(std::strncmp(e.what(), path.c_str(), path.size()) == 0,
                        "error does not start with the file name");
    return 0;
  }
  HARMOLOC_FUZZ_CHECK(!samples.empty(), "a recording without samples was accepted");
  HARMOLOC_FUZZ_CHECK(samples.size() == line_ok.size(), "a line the reader took is not counted");
  for (bool ok : line_ok) HARMOLOC_FUZZ_CHECK(ok, "the reader accepted a line the parser refuses");
  char buf[64];
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const dataset::EncoderSample& s = samples[i];
    HARMOLOC_FUZZ_CHECK(s.left_ticks < span && s.right_ticks < span, "count beyond the width");
    if (i > 0)
      HARMOLOC_FUZZ_CHECK(s.timestamp_ns > samples[i - 1].timestamp_ns,
                          "timestamps not increasing");
    const std::size_t n = dataset::format_encoder_csv_line(s, buf, sizeof buf);
    HARMOLOC_FUZZ_CHECK(n > 0 && buf[n - 1] == '\n', "format failed");
    dataset::EncoderSample back;
    const char* why = nullptr;
    HARMOLOC_FUZZ_CHECK(dataset::parse_encoder_csv_line(buf, n - 1, bits, back, &why),
                        "a formatted sample does not parse");
    HARMOLOC_FUZZ_CHECK(back == s, "format/parse round trip changed the sample");
  }

  // The replay: each sample at its own time, then the end.
  host::GpioLogEncoders replay(samples, bits);
  hal::EncoderCounts c;
  for (const dataset::EncoderSample& s : samples) {
    HARMOLOC_FUZZ_CHECK(replay.read(s.timestamp_ns, c) == hal::EncoderStatus::kFresh,
                        "a sample was not handed out at its time");
    HARMOLOC_FUZZ_CHECK(c.left_ticks == s.left_ticks && c.right_ticks == s.right_ticks &&
                            c.timestamp_ns == s.timestamp_ns && c.counter_bits == bits,
                        "the replay changed a sample");
  }
  HARMOLOC_FUZZ_CHECK(replay.read(UINT64_MAX, c) == hal::EncoderStatus::kEnded, "no end");
  // Looped (for memory safety and the width; the shift may wrap 64 bits on huge timestamps).
  host::GpioLogEncoders looped(samples, bits);
  looped.set_loops(2, samples.back().timestamp_ns - samples.front().timestamp_ns + 1);
  for (int k = 0; k < 4 && looped.read(UINT64_MAX, c) == hal::EncoderStatus::kFresh; ++k)
    HARMOLOC_FUZZ_CHECK(c.left_ticks < span && c.right_ticks < span, "looped count beyond width");
  return 0;
}
