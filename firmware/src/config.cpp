#include "harmoloc/firmware/config.hpp"

#include <sstream>
#include <stdexcept>

#include <toml++/toml.h>

#include "config_checker.hpp"
#include "harmoloc/drivers/input_file.hpp"

namespace harmoloc::firmware {

using namespace config_detail;

namespace {

algorithms::ColourThreshold threshold(float h0, float h1, std::uint8_t s, std::uint8_t v0) {
  return algorithms::ColourThreshold{h0, h1, s, v0, 255};
}

}  // namespace

FirmwareConfig default_config() {
  FirmwareConfig c;
  const std::array<std::pair<const char*, algorithms::ColourThreshold>, 6> boards = {{
      {"red", threshold(345.0F, 10.0F, 110, 60)},
      {"green", threshold(100.0F, 145.0F, 110, 60)},
      {"blue", threshold(215.0F, 250.0F, 110, 60)},
      {"yellow", threshold(45.0F, 70.0F, 110, 60)},
      {"magenta", threshold(285.0F, 320.0F, 110, 60)},
      {"cyan", threshold(170.0F, 200.0F, 110, 60)},
  }};
  c.thresholds.count = boards.size();
  for (std::size_t i = 0; i < boards.size(); ++i) {
    c.board_names.names[i] = boards[i].first;
    c.thresholds.boards[i] = boards[i].second;
  }
  // Derived from the map's calibration at start-up (docs/filter.md): they depend on the scene.
  c.kidnap.detector.fix_distance_m = -1.0;
  c.kidnap.detector.consistency_m = -1.0;
  c.kidnap.position_sigma_m = -1.0;
  c.filter.init_position_sigma_m = -1.0;
  return c;
}

FirmwareConfig load_config(const std::string& path) {
  const Checker check(path);
  toml::table root;
  // Whatever cannot be read as a config stops start-up (a directory or /dev/zero must not run
  // on the built-in defaults); its size and nesting are checked before toml++ sees it.
  std::string text;
  if (const std::string e =
          drivers::read_regular_file(path, drivers::input_limits::kTomlBytes, text);
      !e.empty()) {
    throw std::runtime_error(path + ": " + e);
  }
  if (const std::string e = drivers::check_toml_nesting(text); !e.empty())
    throw std::runtime_error(path + ": " + e);
  try {
    root = toml::parse(text, path);
  } catch (const toml::parse_error& e) {
    std::ostringstream s;
    s << path << ": line " << e.source().begin.line << ": " << e.description();
    throw std::runtime_error(s.str());
  }
  FirmwareConfig c = default_config();
  c.source = path;
  check.only(root, "",
             {"cycle", "board", "odometry", "can", "filter", "observation", "kidnap", "link",
              "realtime", "camera", "encoders"});

  read_cycle(check, root, c);
  read_boards(check, root, c);
  read_odometry(check, root, c);
  read_can(check, root, c);
  read_filter(check, root, c);
  read_observation(check, root, c.observation);
  read_kidnap(check, root, c.kidnap);
  read_link(check, root, path, c);
  read_realtime(check, root, c);
  read_device_sections(check, root, c);
  return c;
}

std::string read_signing_key_file(const std::string& path, std::array<std::uint8_t, 32>& key) {
  return read_signing_key(path, key);
}

}  // namespace harmoloc::firmware
