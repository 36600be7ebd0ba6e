#pragma once
/// @file The picture of where and from which headings a map can localize: the forward map's
/// stored region over the floor, and at each place a rose of the headings the training run
/// covered there (ForwardMap::heading_cover). harmoloc-train --coverage writes it.

#include <string>

#include "harmoloc/algorithms/forward_map.hpp"

namespace harmoloc::sim_host {

/// An SVG document of @p map's coverage: places within @p known_m of the training run, each
/// with a wedge for every covered heading sector (map frame, x right, y up, yaw from +x
/// counter-clockwise). @p title heads it. A map without headings shows the places only.
std::string coverage_svg(const algorithms::ForwardMap& map, double known_m,
                         const std::string& title);

}  // namespace harmoloc::sim_host
