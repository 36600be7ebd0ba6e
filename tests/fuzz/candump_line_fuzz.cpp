// Fuzz target: one candump log line (dataset::parse_candump_line). An accepted line must give a
// frame within CAN's limits, and formatting that frame and parsing the result must give the same
// frame back (the simulator writes logs with format_candump_line and the fake bus reads them).

#include <cstdint>
#include <string>

#include "fuzz_common.hpp"
#include "harmoloc/dataset/candump_log.hpp"

using namespace harmoloc;

namespace {

bool same_frame(const algorithms::CanFrame& a, const algorithms::CanFrame& b) {
  return a.id == b.id && a.extended == b.extended && a.length == b.length && a.data == b.data &&
         a.timestamp_ns == b.timestamp_ns;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string line(reinterpret_cast<const char*>(data), size);
  algorithms::CanFrame frame;
  std::string reason;
  if (!dataset::parse_candump_line(line, frame, reason)) {
    HARMOLOC_FUZZ_CHECK(!reason.empty(), "rejected without a reason");
    return 0;
  }
#ifdef HARMOLOC_FUZZ_SKIP_KNOWN_FINDINGS
  // Known finding (regressions/candump_line/seconds-overflow.txt): timestamps from 2^64 ns
  // (18446744073.709551616 s) on wrap around silently. Skip lines with that many seconds.
  // The line parsed, so it starts with '(' and 1..12 second digits up to the dot.
  const std::string seconds = line.substr(1, line.find('.') - 1);
  if (seconds.size() > 11 || (seconds.size() == 11 && seconds >= "18446744073")) return 0;
#endif
  HARMOLOC_FUZZ_CHECK(frame.length <= 8, "more than 8 data bytes");
  HARMOLOC_FUZZ_CHECK(frame.extended ? frame.id <= 0x1FFFFFFFU : frame.id <= 0x7FFU,
                      "CAN ID out of range");
  const std::string formatted = dataset::format_candump_line(frame, "can0");
  algorithms::CanFrame again;
  std::string why;
  HARMOLOC_FUZZ_CHECK(dataset::parse_candump_line(formatted, again, why),
                      "a formatted frame does not parse");
  HARMOLOC_FUZZ_CHECK(same_frame(frame, again), "parse(format(frame)) differs from frame");
  return 0;
}
