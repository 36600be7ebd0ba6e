// Fuzz target: simulator scenario files (sim_host::load_scenario). Each input is written to a
// file in this process's scratch directory and loaded by path. std::runtime_error is the
// documented answer to a bad file; anything else is a finding.
//
// A scenario file names a `base`, which is a built-in name or the path of another scenario
// file, loaded recursively. Inputs whose `base` names an existing file are skipped: that file
// could be the input itself (load_scenario recurses until the stack overflows, reported
// separately with tests/fuzz/regressions/scenario/self-base.toml) or any file on the machine
// (/proc/kcore, a FIFO behind a symlink...), which would make the target neither hermetic nor
// reproducible. Bases that do not exist are still fuzzed (they must be rejected cleanly).

#include <cstdint>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

#include <toml++/toml.h>

#include "fuzz_common.hpp"
#include "harmoloc/sim_host/scenario.hpp"

using namespace harmoloc;

namespace {

// True when the input's `base` would make load_scenario open another file.
bool base_names_a_file(const std::uint8_t* data, std::size_t size) {
  toml::table t;
  try {
    t = toml::parse(std::string_view(reinterpret_cast<const char*>(data), size));
  } catch (const toml::parse_error&) {
    return false;  // load_scenario rejects it before looking at base
  }
  const std::optional<std::string> base = t["base"].value_exact<std::string>();
  if (!base) return false;
  if (*base == "desk-shuttle" || *base == "tiny" || *base == "tiny-wrap16") return false;
  std::error_code ec;
  const bool exists = std::filesystem::exists(*base, ec);
  return exists || ec;  // an error (EACCES, ELOOP...) counts as "might exist"
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = fuzz::scratch_dir() + "/scenario.toml";
  if (base_names_a_file(data, size)) return -1;  // -1: not added to the corpus
  fuzz::write_file(path, data, size);
  sim_host::Scenario s;
  try {
    s = sim_host::load_scenario(path);
  } catch (const std::runtime_error& e) {
    HARMOLOC_FUZZ_CHECK(e.what() != nullptr && e.what()[0] != '\0', "empty error message");
    return 0;
  }
  HARMOLOC_FUZZ_CHECK(s.camera.width_px % 2 == 0, "odd camera width accepted");
  HARMOLOC_FUZZ_CHECK(s.camera.width_px >= 16 && s.camera.height_px >= 16,
                      "camera size out of range");
  HARMOLOC_FUZZ_CHECK(s.route.waypoints_m.size() >= 2, "route with fewer than 2 waypoints");
  HARMOLOC_FUZZ_CHECK(!s.boards.empty() && s.boards.size() <= 8, "board count out of range");
  HARMOLOC_FUZZ_CHECK(s.can_layout.counter_bits >= 8 && s.can_layout.counter_bits <= 32,
                      "counter width out of range");
  // What the simulator writes beside the dataset; exercised for memory safety.
  (void)sim_host::scenario_to_toml(s);
  return 0;
}
