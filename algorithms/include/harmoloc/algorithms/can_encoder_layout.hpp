#pragma once
/// @file Where a motor controller puts the two wheel counters in its CAN frames. Pure decoding;
/// the SocketCAN driver and the candump-log fake both use it.

#include <array>
#include <cstdint>

#include "harmoloc/algorithms/odometry.hpp"

namespace harmoloc::algorithms {

/// One classic CAN frame (up to 8 data bytes).
struct CanFrame {
  std::uint32_t id = 0;  ///< 11-bit or 29-bit identifier, without flags
  bool extended = false;
  std::uint8_t length = 0;  ///< data length (DLC), 0..8
  std::array<std::uint8_t, 8> data{};
  std::uint64_t timestamp_ns = 0;
};

enum class ByteOrder : std::uint8_t { kLittleEndian = 0, kBigEndian = 1 };

struct EncoderFrameLayout {
  std::uint32_t id = 0x181;        ///< frame carrying both counters
  std::uint8_t length = 8;         ///< required data length
  std::uint8_t left_offset = 0;    ///< byte offset of the left counter
  std::uint8_t right_offset = 4;   ///< byte offset of the right counter
  std::uint8_t counter_bits = 32;  ///< 16 or 32 (counter width on the wire)
  ByteOrder byte_order = ByteOrder::kLittleEndian;
};

enum class CanDecode : std::uint8_t { kOk = 0, kOtherId = 1, kBadLength = 2 };

/// True when the layout itself is consistent (counters inside the frame, width 8..32 in bytes).
bool layout_valid(const EncoderFrameLayout& layout);

/// Extracts the raw counters of a frame with our ID and the expected length. Our ID is extended
/// when it needs more than 11 bits; a frame of the other kind with the same number is another ID.
CanDecode decode_encoder_frame(const EncoderFrameLayout& layout, const CanFrame& frame,
                               std::uint32_t& left_raw, std::uint32_t& right_raw);

/// Builds the frame a controller would send (the simulator and tests use it).
CanFrame encode_encoder_frame(const EncoderFrameLayout& layout, std::uint32_t left_raw,
                              std::uint32_t right_raw, std::uint64_t timestamp_ns);

}  // namespace harmoloc::algorithms
