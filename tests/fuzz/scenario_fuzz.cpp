// Fuzz target: simulator scenario files (sim_host::load_scenario). Each input is written to a
// file in this process's scratch directory and loaded by path. std::runtime_error is the
// documented answer to a bad file; anything else is a finding. What scenario_to_toml writes
// (the simulator's scenario.toml beside each dataset, "itself a valid scenario file" as
// docs/scenarios.md says) must load again, with the same boards, camera, route and events.
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
#include "harmoloc/drivers/input_file.hpp"
#include "harmoloc/sim_host/scenario.hpp"

using namespace harmoloc;

namespace {

// True when the input's `base` would make load_scenario open another file.
bool base_names_a_file(const std::uint8_t* data, std::size_t size) {
  // Too deep for toml++ to parse safely: load_scenario refuses it before looking at base.
  if (!drivers::check_toml_nesting(std::string_view(reinterpret_cast<const char*>(data), size))
           .empty()) {
    return false;
  }
  toml::table t;
  try {
    t = toml::parse(std::string_view(reinterpret_cast<const char*>(data), size));
  } catch (const toml::parse_error&) {
    return false;  // load_scenario rejects it before looking at base
  }
  const std::optional<std::string> base = t["base"].value_exact<std::string>();
  if (!base) return false;
  for (const char* builtin :
       {"desk-shuttle", "desk-left", "desk-right", "desk-slalom", "desk-occlusion",
        "desk-moved-board", "desk-kidnap", "desk-long", "tiny", "tiny-wrap16"}) {
    if (*base == builtin) return false;
  }
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
  // Events: keyframes in time order, positive sizes, moves of existing boards, sane kidnaps.
  for (const sim_host::OccluderSpec& o : s.occluders) {
    HARMOLOC_FUZZ_CHECK(!o.path.empty(), "occluder without keyframes");
    HARMOLOC_FUZZ_CHECK(o.radius_m > 0.0 && o.height_m > 0.0, "occluder size not positive");
    for (std::size_t k = 1; k < o.path.size(); ++k)
      HARMOLOC_FUZZ_CHECK(o.path[k][0] > o.path[k - 1][0], "occluder keyframes out of order");
  }
  for (const sim_host::BoardMoveSpec& m : s.board_moves) {
    bool found = false;
    for (const sim_host::BoardSpec& b : s.boards) found = found || b.name == m.board;
    HARMOLOC_FUZZ_CHECK(found, "board move of a board the scenario does not have");
    HARMOLOC_FUZZ_CHECK(m.at_s >= 0.0, "board move before the run");
  }
  HARMOLOC_FUZZ_CHECK(s.kidnaps.count >= 0 && s.kidnaps.interval_s > 0.0 &&
                          s.kidnaps.first_s >= 0.0 && s.kidnaps.min_distance_m >= 0.0,
                      "kidnaps out of range");

#ifdef HARMOLOC_FUZZ_SKIP_KNOWN_FINDINGS
  // Known finding (regressions/scenario/quote-in-name.toml): scenario_to_toml writes strings
  // without TOML escaping.
  std::vector<const std::string*> texts = {&s.name, &s.description};
  for (const sim_host::BoardSpec& b : s.boards) texts.push_back(&b.name);
  for (const sim_host::OccluderSpec& o : s.occluders) texts.push_back(&o.name);
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
  same = same && back.occluders.size() == s.occluders.size() &&
         back.board_moves.size() == s.board_moves.size() && back.kidnaps.count == s.kidnaps.count;
  for (std::size_t i = 0; same && i < s.occluders.size(); ++i) {
    same = back.occluders[i].name == s.occluders[i].name &&
           back.occluders[i].path.size() == s.occluders[i].path.size() &&
           back.occluders[i].colour.r == s.occluders[i].colour.r;
  }
  for (std::size_t i = 0; same && i < s.board_moves.size(); ++i)
    same = back.board_moves[i].board == s.board_moves[i].board;
  HARMOLOC_FUZZ_CHECK(same, "the scenario.toml scenario_to_toml writes loads different");
  return 0;
}
