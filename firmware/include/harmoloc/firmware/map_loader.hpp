#pragma once
/// @file Start-up loading of the map file, checked against the firmware's configuration and
/// camera mode.

#include <cstdint>
#include <string>

#include "harmoloc/algorithms/map_codec.hpp"
#include "harmoloc/firmware/config.hpp"

namespace harmoloc::firmware {

/// Reads and decodes @p path into @p map. Returns an empty string, or one line saying what is
/// wrong ("map FILE: reason (at byte N)").
std::string load_map(const std::string& path, algorithms::MapFile& map);

/// Checks that the map was trained with the configured colour thresholds and for this camera
/// mode. Returns an empty string, or one line naming the first difference.
std::string check_map_matches(const algorithms::MapFile& map, const FirmwareConfig& config,
                              std::uint32_t width_px, std::uint32_t height_px);

}  // namespace harmoloc::firmware
