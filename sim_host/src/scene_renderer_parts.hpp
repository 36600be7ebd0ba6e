#pragma once
/// @file What the pieces of the scene renderer (scene_renderer*.cpp) share: the culling ids, the
/// noise table's size and the colours of the boards' backs and the stands. Private to
/// sim_host/src.

#include <cstddef>
#include <cstdint>

#include "harmoloc/sim_host/scene_renderer.hpp"

namespace harmoloc::sim_host::scene_renderer_detail {

inline constexpr int kNoBoard = -1;
// Culling objects: the desk, then the boards, then the cylinders (occluders, stands).
inline constexpr std::uint16_t kDesk = 0;
inline constexpr std::uint16_t kBoard0 = 1;
// Noise table: 4096 standard normal quantiles, three 12-bit indices a pixel from one 64-bit hash.
inline constexpr std::size_t kNoiseBits = 12;
inline constexpr std::size_t kNoiseEntries = std::size_t{1} << kNoiseBits;
inline constexpr std::uint64_t kNoiseMask = kNoiseEntries - 1;
inline constexpr Rgb kBoardBack{80, 80, 80};
inline constexpr Rgb kStandColour{70, 70, 72};
inline constexpr double kStandRadius_m = 0.015;

}  // namespace harmoloc::sim_host::scene_renderer_detail
