// Fuzz target: simulator scenario files (sim_host::load_scenario). Each input is written to a
// file in this process's scratch directory and loaded by path. std::runtime_error is the
// documented answer to a bad file; anything else is a finding. What scenario_to_toml writes
// (the simulator's scenario.toml beside each dataset, "itself a valid scenario file" as
// docs/scenarios.md says) must load again, with the same boards, camera and route.
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
#include <vector>

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

#ifdef HARMOLOC_FUZZ_SKIP_KNOWN_FINDINGS
  // Known finding (regressions/scenario/quote-in-name.toml): scenario_to_toml writes strings
  // without TOML escaping.
  std::vector<const std::string*> texts = {&s.name, &s.description};
  for (const sim_host::BoardSpec& b : s.boards) texts.push_back(&b.name);
  for (const std::string* text : texts) {
    for (const char c : *text) {
      if (c == '"' || c == '\\' || static_cast<unsigned char>(c) < 0x20 || c == 0x7F) return 0;
    }
  }
#endif
  static const std::string written = fuzz::scratch_dir() + "/written.toml";
  const std::string toml = sim_host::scenario_to_toml(s);
  fuzz::write_file(written, reinterpret_cast<const std::uint8_t*>(toml.data()), toml.size());
  sim_host::Scenario back;
  try {
    back = sim_host::load_scenario(written);
  } catch (const std::runtime_error&) {
    fuzz::finding("the scenario.toml scenario_to_toml writes does not load");
  }
  bool same = back.name == s.name && back.description == s.description &&
              back.boards.size() == s.boards.size() && back.camera.width_px == s.camera.width_px &&
              back.camera.height_px == s.camera.height_px &&
              back.route.waypoints_m.size() == s.route.waypoints_m.size() &&
              back.route.laps == s.route.laps && back.labelled_frames == s.labelled_frames &&
              back.can_layout.counter_bits == s.can_layout.counter_bits &&
              back.encoders.initial_left == s.encoders.initial_left &&
              back.encoders.initial_right == s.encoders.initial_right;
  for (std::size_t i = 0; same && i < s.boards.size(); ++i) {
    const sim_host::BoardSpec& a = s.boards[i];
    const sim_host::BoardSpec& b = back.boards[i];
    same = a.name == b.name && a.colour.r == b.colour.r && a.colour.g == b.colour.g &&
           a.colour.b == b.colour.b;
  }
  HARMOLOC_FUZZ_CHECK(same, "the scenario.toml scenario_to_toml writes loads different");
  return 0;
}
