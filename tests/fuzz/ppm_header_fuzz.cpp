// Fuzz target: the binary PPM header parser (dataset::parse_ppm_header), which reads the first
// bytes of every frame file. The input is the start of a file, exactly sized, so any read past
// it hits AddressSanitizer's redzone. An accepted header must be P6/255 with a non-zero size and
// a data offset inside the bytes it was given.

#include <cstdint>
#include <cstring>

#include "fuzz_common.hpp"
#include "harmoloc/dataset/frame_index.hpp"

using namespace harmoloc;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  dataset::PpmHeader header;
  const char* reason = nullptr;
  if (!dataset::parse_ppm_header(data, size, header, &reason)) {
    HARMOLOC_FUZZ_CHECK(reason != nullptr && reason[0] != '\0', "rejected without a reason");
    // The reason may be left out.
    dataset::PpmHeader again;
    HARMOLOC_FUZZ_CHECK(!dataset::parse_ppm_header(data, size, again, nullptr),
                        "result depends on whether a reason is asked for");
    return 0;
  }
  HARMOLOC_FUZZ_CHECK(size >= 2 && data[0] == 'P' && data[1] == '6', "accepted a non-P6 file");
  HARMOLOC_FUZZ_CHECK(header.width_px > 0 && header.height_px > 0, "accepted a zero size");
  HARMOLOC_FUZZ_CHECK(header.width_px <= 1000000 && header.height_px <= 1000000,
                      "accepted a size above the parser's bound");
  HARMOLOC_FUZZ_CHECK(header.data_offset >= 8 && header.data_offset <= size,
                      "data offset outside the header bytes");
  return 0;
}
