// Fuzz target: a dataset's metadata.toml (sim_host::read_metadata). Each input is written as
// metadata.toml in this process's scratch directory. std::runtime_error is the documented answer
// to a bad file; anything else is a finding. Accepted metadata must satisfy what the fakes rely
// on (a valid CAN layout, an even YUYV width, sizes within 2..8192).

#include <cstdint>
#include <stdexcept>
#include <string>

#include "fuzz_common.hpp"
#include "harmoloc/algorithms/can_encoder_layout.hpp"
#include "harmoloc/sim_host/metadata.hpp"

using namespace harmoloc;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string dir = fuzz::scratch_dir();
  static const std::string path = dir + "/metadata.toml";
  fuzz::write_file(path, data, size);
  sim_host::DatasetMetadata m;
  try {
    m = sim_host::read_metadata(dir);
  } catch (const std::runtime_error& e) {
    HARMOLOC_FUZZ_CHECK(e.what() != nullptr && e.what()[0] != '\0', "empty error message");
    return 0;
  }
  HARMOLOC_FUZZ_CHECK(m.image_width_px >= 2 && m.image_width_px <= 8192 &&
                          m.image_height_px >= 2 && m.image_height_px <= 8192,
                      "image size out of range");
  HARMOLOC_FUZZ_CHECK(m.pixel_format != hal::PixelFormat::kYuyv || m.image_width_px % 2 == 0,
                      "odd YUYV width accepted");
  HARMOLOC_FUZZ_CHECK(m.frame_rate_hz >= 1.0 && m.frame_rate_hz <= 1000.0, "rate out of range");
  HARMOLOC_FUZZ_CHECK(algorithms::layout_valid(m.encoder_layout), "invalid CAN layout accepted");
  HARMOLOC_FUZZ_CHECK(m.geometry.wheel_radius_m > 0.0 && m.geometry.track_m > 0.0 &&
                          m.geometry.ticks_per_rev >= 1.0,
                      "geometry out of range");
  HARMOLOC_FUZZ_CHECK((m.geometry.left_direction == 1 || m.geometry.left_direction == -1) &&
                          (m.geometry.right_direction == 1 || m.geometry.right_direction == -1),
                      "wheel direction not +-1");
  return 0;
}
