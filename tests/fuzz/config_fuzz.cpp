// Fuzz target: the firmware's configuration file (firmware::load_config). It takes a path, so
// each input is written to a file in this process's scratch directory. A std::runtime_error is
// the documented answer to a bad file; anything else (another exception type, a crash, a
// sanitizer report) is a finding. An accepted config must hold values within its documented
// ranges (the cycle and the filter rely on them without checking again).

#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "fuzz_common.hpp"
#include "harmoloc/algorithms/can_encoder_layout.hpp"
#include "harmoloc/firmware/config.hpp"

using harmoloc::firmware::FirmwareConfig;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = harmoloc::fuzz::scratch_dir() + "/harmoloc.toml";
  harmoloc::fuzz::write_file(path, data, size);
  FirmwareConfig c;
  try {
    c = harmoloc::firmware::load_config(path);
  } catch (const std::runtime_error& e) {
    HARMOLOC_FUZZ_CHECK(e.what() != nullptr && e.what()[0] != '\0', "empty error message");
    return 0;
  }
  HARMOLOC_FUZZ_CHECK(c.cycle.rate_hz >= 1.0 && c.cycle.rate_hz <= 1000.0, "rate out of range");
  HARMOLOC_FUZZ_CHECK(c.cycle.budget_ms > 0.0 && std::isfinite(c.cycle.budget_ms),
                      "budget out of range");
  HARMOLOC_FUZZ_CHECK(c.thresholds.count >= 1 && c.thresholds.count <= 8,
                      "board count out of range");
  for (std::size_t i = 0; i < c.thresholds.count; ++i) {
    const auto& t = c.thresholds.boards[i];
    HARMOLOC_FUZZ_CHECK(t.hue_min_deg >= 0.0F && t.hue_min_deg <= 360.0F && t.hue_max_deg >= 0.0F &&
                            t.hue_max_deg <= 360.0F,
                        "hue out of range");
    HARMOLOC_FUZZ_CHECK(t.value_min <= t.value_max, "value window inverted");
  }
  HARMOLOC_FUZZ_CHECK(harmoloc::algorithms::layout_valid(c.can_layout), "invalid CAN layout");
  HARMOLOC_FUZZ_CHECK(c.geometry.wheel_radius_m > 0.0 && c.geometry.track_m > 0.0 &&
                          c.geometry.ticks_per_rev >= 1.0,
                      "geometry out of range");
  HARMOLOC_FUZZ_CHECK(c.geometry.left_direction * c.geometry.left_direction == 1 &&
                          c.geometry.right_direction * c.geometry.right_direction == 1,
                      "wheel direction not +-1");
  HARMOLOC_FUZZ_CHECK(c.filter.particles >= 16, "too few particles");
  const double ratio = c.observation.boards.implausible_ratio;
  HARMOLOC_FUZZ_CHECK(ratio == 0.0 || (ratio >= 1.0 && ratio <= 1000.0),
                      "implausible_ratio out of range");
  HARMOLOC_FUZZ_CHECK(c.filter.fix_sigma_m > 0.0 && std::isfinite(c.filter.fix_sigma_m),
                      "fix sigma out of range");
  HARMOLOC_FUZZ_CHECK(c.link.heartbeat_hz > 0.0 && std::isfinite(c.link.heartbeat_hz),
                      "heartbeat rate out of range");
  for (const std::uint8_t id : c.link.accept_system_ids)
    HARMOLOC_FUZZ_CHECK(id != 0, "accepted system id 0");
  for (const std::uint8_t id : c.link.accept_component_ids)
    HARMOLOC_FUZZ_CHECK(id != 0, "accepted component id 0");
  HARMOLOC_FUZZ_CHECK(c.link.has_signing_key == !c.link.signing_key_file.empty(),
                      "a key file named but no key, or a key without a file");
  HARMOLOC_FUZZ_CHECK(!c.link.has_signing_key || !c.link.signing_state_file.empty(),
                      "a key without a signing state file");
  HARMOLOC_FUZZ_CHECK(c.link.signing_max_ahead_s >= 1.0 && c.link.signing_max_ahead_s <= 86400.0,
                      "signing lead out of range");
  return 0;
}
