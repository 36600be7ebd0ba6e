#pragma once
/// @file CRC-32 (IEEE 802.3, reflected, as zlib's crc32) for file integrity checks.

#include <cstddef>
#include <cstdint>

namespace harmoloc::algorithms {

std::uint32_t crc32(const std::uint8_t* data, std::size_t size, std::uint32_t crc = 0U);

}  // namespace harmoloc::algorithms
