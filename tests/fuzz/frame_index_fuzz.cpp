// Fuzz target: a dataset's frame index (dataset::read_frame_index, frames.csv). Each input is
// written to a file in this process's scratch directory. std::runtime_error is the documented
// answer to a bad file; anything else is a finding. Accepted entries must be what FileCamera
// relies on: increasing timestamps and non-empty relative paths that do not leave the dataset.

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "fuzz_common.hpp"
#include "harmoloc/dataset/frame_index.hpp"

using namespace harmoloc;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = fuzz::scratch_dir() + "/frames.csv";
  fuzz::write_file(path, data, size);
  std::vector<dataset::FrameEntry> frames;
  try {
    frames = dataset::read_frame_index(path);
  } catch (const std::runtime_error& e) {
    HARMOLOC_FUZZ_CHECK(e.what() != nullptr && e.what()[0] != '\0', "empty error message");
    return 0;
  }
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const std::string& f = frames[i].file;
    HARMOLOC_FUZZ_CHECK(!f.empty() && f[0] != '/', "empty or absolute frame path accepted");
    HARMOLOC_FUZZ_CHECK(("/" + f + "/").find("/../") == std::string::npos,
                        "frame path leaving the dataset accepted");
    if (i > 0)
      HARMOLOC_FUZZ_CHECK(frames[i].timestamp_ns > frames[i - 1].timestamp_ns,
                          "timestamps not increasing");
  }
  return 0;
}
