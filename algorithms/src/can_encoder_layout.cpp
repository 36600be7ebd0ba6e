#include "harmoloc/algorithms/can_encoder_layout.hpp"

namespace harmoloc::algorithms {

namespace {

std::uint8_t counter_bytes(const EncoderFrameLayout& layout) {
  return static_cast<std::uint8_t>((layout.counter_bits + 7U) / 8U);
}

std::uint32_t read_counter(const EncoderFrameLayout& layout, const std::uint8_t* p) {
  const std::uint8_t n = counter_bytes(layout);
  std::uint32_t v = 0;
  for (std::uint8_t i = 0; i < n; ++i) {
    const std::uint8_t byte = layout.byte_order == ByteOrder::kLittleEndian ? p[i] : p[n - 1U - i];
    v |= static_cast<std::uint32_t>(byte) << (8U * i);
  }
  if (layout.counter_bits < 32) v &= (1U << layout.counter_bits) - 1U;
  return v;
}

void write_counter(const EncoderFrameLayout& layout, std::uint32_t v, std::uint8_t* p) {
  const std::uint8_t n = counter_bytes(layout);
  for (std::uint8_t i = 0; i < n; ++i) {
    const auto byte = static_cast<std::uint8_t>(v >> (8U * i));
    p[layout.byte_order == ByteOrder::kLittleEndian ? i : n - 1U - i] = byte;
  }
}

}  // namespace

bool layout_valid(const EncoderFrameLayout& layout) {
  if (layout.counter_bits < 8 || layout.counter_bits > 32) return false;
  if (layout.length > 8) return false;
  const unsigned n = counter_bytes(layout);
  return layout.left_offset + n <= layout.length && layout.right_offset + n <= layout.length &&
         (layout.left_offset + n <= layout.right_offset ||
          layout.right_offset + n <= layout.left_offset);
}

CanDecode decode_encoder_frame(const EncoderFrameLayout& layout, const CanFrame& frame,
                               std::uint32_t& left_raw, std::uint32_t& right_raw) {
  // A standard and an extended frame are different IDs even with the same number (the layout's
  // ID is extended when it needs more than 11 bits), as on the bus.
  if (frame.id != layout.id || frame.extended != (layout.id > 0x7FFU)) return CanDecode::kOtherId;
  if (frame.length != layout.length) return CanDecode::kBadLength;
  left_raw = read_counter(layout, frame.data.data() + layout.left_offset);
  right_raw = read_counter(layout, frame.data.data() + layout.right_offset);
  return CanDecode::kOk;
}

CanFrame encode_encoder_frame(const EncoderFrameLayout& layout, std::uint32_t left_raw,
                              std::uint32_t right_raw, std::uint64_t timestamp_ns) {
  CanFrame frame;
  frame.id = layout.id;
  frame.extended = layout.id > 0x7FFU;
  frame.length = layout.length;
  frame.timestamp_ns = timestamp_ns;
  write_counter(layout, left_raw, frame.data.data() + layout.left_offset);
  write_counter(layout, right_raw, frame.data.data() + layout.right_offset);
  return frame;
}

}  // namespace harmoloc::algorithms
