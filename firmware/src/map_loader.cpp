#include "harmoloc/firmware/map_loader.hpp"

#include <sstream>

#include "harmoloc/drivers/input_file.hpp"

namespace harmoloc::firmware {

std::string load_map(const std::string& path, algorithms::MapFile& map) {
  // A regular file no larger than the format allows, checked before a byte is read.
  std::string bytes;
  if (const std::string e = drivers::read_regular_file(path, algorithms::kMaxMapFileBytes, bytes);
      !e.empty()) {
    return "map " + path + ": " + e;
  }
  const algorithms::MapError error = algorithms::decode_map(
      reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size(), map);
  if (error)
    return "map " + path + ": " + error.what + " (at byte " + std::to_string(error.offset) + ")";
  return {};
}

std::string check_map_matches(const algorithms::MapFile& map, const FirmwareConfig& config,
                              std::uint32_t width_px, std::uint32_t height_px) {
  std::ostringstream s;
  if (map.image_width_px != width_px || map.image_height_px != height_px) {
    s << "map was trained on " << map.image_width_px << "x" << map.image_height_px
      << " frames but the camera gives " << width_px << "x" << height_px;
    return s.str();
  }
  if (map.thresholds.count != config.thresholds.count) {
    s << "map was trained with " << map.thresholds.count << " boards but the config ("
      << config.source << ") has " << config.thresholds.count
      << "; retrain or use the config it was trained with";
    return s.str();
  }
  for (std::size_t i = 0; i < map.thresholds.count; ++i) {
    const auto& a = map.thresholds.boards[i];
    const auto& b = config.thresholds.boards[i];
    if (!(a == b)) {
      s << "map was trained with other colour thresholds than the config (" << config.source
        << ") for board " << i + 1 << " '" << config.board_names.names[i] << "': map hue "
        << a.hue_min_deg << ".." << a.hue_max_deg << " s>=" << int{a.saturation_min} << " v "
        << int{a.value_min} << ".." << int{a.value_max} << ", config hue " << b.hue_min_deg << ".."
        << b.hue_max_deg << " s>=" << int{b.saturation_min} << " v " << int{b.value_min} << ".."
        << int{b.value_max} << "; retrain or use the config it was trained with";
      return s.str();
    }
  }
  return {};
}

}  // namespace harmoloc::firmware
