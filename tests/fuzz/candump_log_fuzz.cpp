// Fuzz target: a whole candump log file (dataset::read_candump_log), as the host board's
// encoder fake reads it. Each input is written to a file in this process's scratch directory.
// std::runtime_error is the documented answer to a malformed line; anything else is a finding.

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "fuzz_common.hpp"
#include "harmoloc/dataset/candump_log.hpp"

using namespace harmoloc;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = fuzz::scratch_dir() + "/encoders.log";
  fuzz::write_file(path, data, size);
  std::vector<algorithms::CanFrame> frames;
  try {
    frames = dataset::read_candump_log(path);
  } catch (const std::runtime_error& e) {
    HARMOLOC_FUZZ_CHECK(e.what() != nullptr && e.what()[0] != '\0', "empty error message");
    return 0;
  }
  for (const algorithms::CanFrame& f : frames) {
    HARMOLOC_FUZZ_CHECK(f.length <= 8, "more than 8 data bytes");
    HARMOLOC_FUZZ_CHECK(f.extended ? f.id <= 0x1FFFFFFFU : f.id <= 0x7FFU, "CAN ID out of range");
  }
  return 0;
}
