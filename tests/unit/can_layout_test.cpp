// Where the motor controller puts the wheel counters in its CAN frame: byte order, widths,
// offsets, and frames that are not ours.
#include "harmoloc/algorithms/can_encoder_layout.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>

namespace ha = harmoloc::algorithms;

namespace {

ha::EncoderFrameLayout layout(std::uint32_t id, std::uint8_t length, std::uint8_t left,
                              std::uint8_t right, std::uint8_t bits, ha::ByteOrder order) {
  ha::EncoderFrameLayout l;
  l.id = id;
  l.length = length;
  l.left_offset = left;
  l.right_offset = right;
  l.counter_bits = bits;
  l.byte_order = order;
  return l;
}

void expect_bytes(const ha::CanFrame& f, const std::array<std::uint8_t, 8>& bytes,
                  std::uint8_t length) {
  ASSERT_EQ(f.length, length);
  for (std::uint8_t i = 0; i < length; ++i) EXPECT_EQ(f.data[i], bytes[i]) << "byte " << int{i};
}

// Decodes @p f with @p l: it is ours and carries the counters @p left and @p right.
void expect_decodes_to(const ha::EncoderFrameLayout& l, const ha::CanFrame& f, std::uint32_t left,
                       std::uint32_t right) {
  std::uint32_t got_left = 0, got_right = 0;
  ASSERT_EQ(ha::decode_encoder_frame(l, f, got_left, got_right), ha::CanDecode::kOk);
  EXPECT_EQ(got_left, left);
  EXPECT_EQ(got_right, right);
}

}  // namespace

TEST(CanLayout, DefaultIsLittleEndian32BitPairIn8Bytes) {
  const ha::EncoderFrameLayout l;  // 0x181, 8 bytes, left at 0, right at 4, 32 bits, LE
  EXPECT_TRUE(ha::layout_valid(l));
  const ha::CanFrame f = ha::encode_encoder_frame(l, 0x12345678U, 0x9ABCDEF0U, 555U);
  EXPECT_EQ(f.id, 0x181U);
  EXPECT_FALSE(f.extended);
  EXPECT_EQ(f.timestamp_ns, 555U);
  expect_bytes(f, {0x78, 0x56, 0x34, 0x12, 0xF0, 0xDE, 0xBC, 0x9A}, 8);
  expect_decodes_to(l, f, 0x12345678U, 0x9ABCDEF0U);
}

TEST(CanLayout, BigEndian32Bit) {
  const auto l = layout(0x201, 8, 4, 0, 32, ha::ByteOrder::kBigEndian);  // right first on the wire
  ASSERT_TRUE(ha::layout_valid(l));
  const ha::CanFrame f = ha::encode_encoder_frame(l, 0x01020304U, 0xA0B0C0D0U, 0);
  expect_bytes(f, {0xA0, 0xB0, 0xC0, 0xD0, 0x01, 0x02, 0x03, 0x04}, 8);
  expect_decodes_to(l, f, 0x01020304U, 0xA0B0C0D0U);
}

TEST(CanLayout, SixteenBitBothByteOrders) {
  const auto be = layout(0x181, 4, 0, 2, 16, ha::ByteOrder::kBigEndian);
  ha::CanFrame f = ha::encode_encoder_frame(be, 0x1234U, 0xABCDU, 0);
  expect_bytes(f, {0x12, 0x34, 0xAB, 0xCD, 0, 0, 0, 0}, 4);
  expect_decodes_to(be, f, 0x1234U, 0xABCDU);

  // Little endian at odd offsets inside a longer frame; the other bytes stay 0.
  const auto le = layout(0x181, 8, 1, 5, 16, ha::ByteOrder::kLittleEndian);
  f = ha::encode_encoder_frame(le, 0xBEEFU, 0x0102U, 0);
  expect_bytes(f, {0x00, 0xEF, 0xBE, 0x00, 0x00, 0x02, 0x01, 0x00}, 8);
  expect_decodes_to(le, f, 0xBEEFU, 0x0102U);

  // Values wider than the counter keep their low bits only.
  f = ha::encode_encoder_frame(le, 0x1234BEEFU, 0xFFFF0102U, 0);
  expect_decodes_to(le, f, 0xBEEFU, 0x0102U);
}

TEST(CanLayout, TwelveBitCountersAreMasked) {
  const auto l = layout(0x181, 4, 0, 2, 12, ha::ByteOrder::kLittleEndian);
  ASSERT_TRUE(ha::layout_valid(l));
  ha::CanFrame f;
  f.id = 0x181;
  f.length = 4;
  f.data = {0xFF, 0xFF, 0x34, 0x12, 0, 0, 0, 0};  // upper nibble of each pair is status bits
  expect_decodes_to(l, f, 0xFFFU, 0x234U);
}

TEST(CanLayout, RandomRoundTrips) {
  std::uint64_t s = 99;
  auto next = [&s]() {
    s = s * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<std::uint32_t>(s >> 32);
  };
  const ha::EncoderFrameLayout layouts[] = {
      layout(0x181, 8, 0, 4, 32, ha::ByteOrder::kLittleEndian),
      layout(0x181, 8, 4, 0, 32, ha::ByteOrder::kBigEndian),
      layout(0x7FF, 4, 0, 2, 16, ha::ByteOrder::kLittleEndian),
      layout(0x123, 6, 3, 0, 24, ha::ByteOrder::kBigEndian),
      layout(0x18FF0001, 2, 0, 1, 8, ha::ByteOrder::kLittleEndian)};
  for (const auto& l : layouts) {
    ASSERT_TRUE(ha::layout_valid(l));
    const std::uint32_t mask = l.counter_bits == 32 ? 0xFFFFFFFFU : (1U << l.counter_bits) - 1U;
    for (int i = 0; i < 200; ++i) {
      const std::uint32_t a = next(), b = next();
      const ha::CanFrame f = ha::encode_encoder_frame(l, a, b, 0);
      EXPECT_EQ(f.extended, l.id > 0x7FFU);
      std::uint32_t left = 0, right = 0;
      ASSERT_EQ(ha::decode_encoder_frame(l, f, left, right), ha::CanDecode::kOk);
      ASSERT_EQ(left, a & mask);
      ASSERT_EQ(right, b & mask);
    }
  }
}

TEST(CanLayout, OtherIdAndBadLength) {
  const ha::EncoderFrameLayout l;
  ha::CanFrame f = ha::encode_encoder_frame(l, 1, 2, 0);
  std::uint32_t left = 77, right = 88;
  f.id = 0x182;
  EXPECT_EQ(ha::decode_encoder_frame(l, f, left, right), ha::CanDecode::kOtherId);
  f.id = 0x181;
  f.length = 7;
  EXPECT_EQ(ha::decode_encoder_frame(l, f, left, right), ha::CanDecode::kBadLength);
  f.length = 0;
  EXPECT_EQ(ha::decode_encoder_frame(l, f, left, right), ha::CanDecode::kBadLength);
  // The outputs are left alone when the frame is not used.
  EXPECT_EQ(left, 77U);
  EXPECT_EQ(right, 88U);
  // A different ID with the wrong length is "not ours", not "bad length".
  f.id = 0x281;
  EXPECT_EQ(ha::decode_encoder_frame(l, f, left, right), ha::CanDecode::kOtherId);
}

// Standard and extended frames are different IDs on the bus even with the same number: a candump
// log's 00000181#... is not our standard 0x181 (the SocketCAN driver sees it the same way).
TEST(CanLayout, StandardAndExtendedFramesOfTheSameNumberDiffer) {
  const ha::EncoderFrameLayout standard;  // 0x181
  ha::CanFrame f = ha::encode_encoder_frame(standard, 1, 2, 0);
  std::uint32_t left = 0, right = 0;
  ASSERT_EQ(ha::decode_encoder_frame(standard, f, left, right), ha::CanDecode::kOk);
  f.extended = true;
  EXPECT_EQ(ha::decode_encoder_frame(standard, f, left, right), ha::CanDecode::kOtherId);
  ha::EncoderFrameLayout ext;
  ext.id = 0x18FF0001;
  ha::CanFrame g = ha::encode_encoder_frame(ext, 1, 2, 0);
  EXPECT_TRUE(g.extended);
  ASSERT_EQ(ha::decode_encoder_frame(ext, g, left, right), ha::CanDecode::kOk);
  ext.id = 0x181;
  g.id = 0x181;  // an extended frame numbered like a standard layout's ID
  EXPECT_EQ(ha::decode_encoder_frame(ext, g, left, right), ha::CanDecode::kOtherId);
}

TEST(CanLayout, LayoutValidity) {
  using BO = ha::ByteOrder;
  struct Case {
    ha::EncoderFrameLayout layout;
    bool valid;
    const char* what;
  };
  const Case cases[] = {
      {layout(0x181, 8, 0, 4, 32, BO::kLittleEndian), true, "two 32-bit counters in 8 bytes"},
      {layout(0x181, 8, 4, 0, 32, BO::kLittleEndian), true, "right before left"},
      {layout(0x181, 4, 0, 2, 16, BO::kLittleEndian), true, "two 16-bit counters in 4 bytes"},
      {layout(0x181, 2, 1, 0, 8, BO::kLittleEndian), true, "two 8-bit counters in 2 bytes"},
      {layout(0x181, 8, 6, 0, 16, BO::kBigEndian), true, "ends exactly at the frame end"},
      {layout(0x181, 8, 0, 2, 32, BO::kLittleEndian), false, "overlap"},
      {layout(0x181, 8, 2, 0, 32, BO::kLittleEndian), false, "overlap"},
      {layout(0x181, 8, 3, 3, 16, BO::kLittleEndian), false, "overlap"},
      {layout(0x181, 4, 0, 1, 16, BO::kLittleEndian), false, "overlap"},
      {layout(0x181, 8, 0, 6, 32, BO::kLittleEndian), false, "out of the frame"},
      {layout(0x181, 4, 0, 4, 16, BO::kLittleEndian), false, "out of the frame"},
      {layout(0x181, 3, 0, 2, 16, BO::kLittleEndian), false, "out of the frame"},
      {layout(0x181, 9, 0, 4, 32, BO::kLittleEndian), false, "no classic frame has 9 bytes"},
      {layout(0x181, 0, 0, 0, 8, BO::kLittleEndian), false, "no bytes"},
      {layout(0x181, 8, 0, 4, 7, BO::kLittleEndian), false, "counter width"},
      {layout(0x181, 8, 0, 4, 33, BO::kLittleEndian), false, "counter width"},
      {layout(0x181, 8, 0, 4, 0, BO::kLittleEndian), false, "counter width"},
      {layout(0x181, 8, 0, 4, 12, BO::kLittleEndian), true, "12-bit counters"},
      {layout(0x181, 8, 0, 4, 24, BO::kLittleEndian), true, "24-bit counters"},
  };
  for (const Case& c : cases) {
    const ha::EncoderFrameLayout& l = c.layout;
    EXPECT_EQ(ha::layout_valid(l), c.valid)
        << c.what << ": length " << int{l.length} << ", left at " << int{l.left_offset}
        << ", right at " << int{l.right_offset} << ", " << int{l.counter_bits} << " bits";
  }
}
