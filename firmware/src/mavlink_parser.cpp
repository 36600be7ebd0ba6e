#include "harmoloc/firmware/mavlink_parser.hpp"

#include <algorithm>
#include <cstring>

namespace harmoloc::firmware::mavlink {

namespace {

// Sorted by id. CRC_EXTRA and the longest payload (extensions included) of each message, from
// the common message set (tests/e2e/link_commands_test.sh checks them against node-mavlink's).
constexpr MessageInfo kMessages[] = {
    {0, 50, 9},       // HEARTBEAT
    {1, 124, 43},     // SYS_STATUS
    {2, 137, 12},     // SYSTEM_TIME
    {4, 237, 14},     // PING
    {11, 89, 6},      // SET_MODE
    {20, 214, 20},    // PARAM_REQUEST_READ
    {21, 159, 2},     // PARAM_REQUEST_LIST
    {22, 220, 25},    // PARAM_VALUE
    {23, 168, 23},    // PARAM_SET
    {24, 24, 52},     // GPS_RAW_INT
    {30, 39, 28},     // ATTITUDE
    {32, 185, 28},    // LOCAL_POSITION_NED
    {33, 104, 28},    // GLOBAL_POSITION_INT
    {39, 254, 38},    // MISSION_ITEM
    {40, 230, 5},     // MISSION_REQUEST
    {41, 28, 4},      // MISSION_SET_CURRENT
    {43, 132, 3},     // MISSION_REQUEST_LIST
    {44, 221, 9},     // MISSION_COUNT
    {45, 232, 3},     // MISSION_CLEAR_ALL
    {47, 153, 8},     // MISSION_ACK
    {51, 196, 5},     // MISSION_REQUEST_INT
    {66, 148, 6},     // REQUEST_DATA_STREAM
    {69, 243, 30},    // MANUAL_CONTROL
    {70, 124, 38},    // RC_CHANNELS_OVERRIDE
    {73, 38, 38},     // MISSION_ITEM_INT
    {75, 158, 35},    // COMMAND_INT
    {76, 152, 33},    // COMMAND_LONG
    {77, 143, 10},    // COMMAND_ACK
    {102, 158, 117},  // VISION_POSITION_ESTIMATE
    {110, 84, 254},   // FILE_TRANSFER_PROTOCOL
    {111, 34, 18},    // TIMESYNC
    {126, 220, 81},   // SERIAL_CONTROL
    {251, 170, 18},   // NAMED_VALUE_FLOAT
    {253, 83, 54},    // STATUSTEXT
    {256, 71, 42},    // SETUP_SIGNING
    {331, 91, 233},   // ODOMETRY
};

}  // namespace

const MessageInfo* message_info(std::uint32_t msg_id) {
  const auto* end = std::end(kMessages);
  const auto* it =
      std::lower_bound(std::begin(kMessages), end, msg_id,
                       [](const MessageInfo& m, std::uint32_t id) { return m.id < id; });
  return it != end && it->id == msg_id ? it : nullptr;
}

std::uint8_t* FrameParser::write_area(std::size_t& room) {
  if (start_ > 0) {
    std::memmove(window_.data(), window_.data() + start_, end_ - start_);
    end_ -= start_;
    start_ = 0;
  }
  room = window_.size() - end_;
  return window_.data() + end_;
}

void FrameParser::commit(std::size_t n) {
  n = std::min(n, window_.size() - end_);
  end_ += n;
  counters_.bytes += n;
}

std::size_t FrameParser::push(const std::uint8_t* data, std::size_t n) {
  std::size_t room = 0;
  std::uint8_t* to = write_area(room);
  n = std::min(n, room);
  if (n > 0) std::memcpy(to, data, n);
  commit(n);
  return n;
}

void FrameParser::drop(std::size_t n) {
  start_ += n;
  counters_.garbage_bytes += n;
}

bool FrameParser::skip_candidate() {
  if (start_ == end_) return false;
  drop(1);
  return true;
}

bool FrameParser::next(RxFrame& out, std::size_t& work) {
  for (;;) {
    while (start_ < end_ && window_[start_] != kStx) {
      if (work == 0) return false;
      --work;
      drop(1);
    }
    const std::size_t available = end_ - start_;
    if (available < kHeaderBytes) return false;
    const std::uint8_t* f = window_.data() + start_;
    const std::uint8_t length = f[1];
    const std::uint8_t incompat = f[2];
    const std::uint32_t msg_id = static_cast<std::uint32_t>(f[7]) |
                                 static_cast<std::uint32_t>(f[8]) << 8U |
                                 static_cast<std::uint32_t>(f[9]) << 16U;
    const MessageInfo* info = message_info(msg_id);
    if (length == 0 || (incompat & ~kIncompatSigned) != 0 || info == nullptr ||
        length > info->max_payload) {
      if (work == 0) return false;
      --work;
      ++counters_.bad_headers;
      drop(1);
      continue;
    }
    const std::size_t size = kHeaderBytes + length + kChecksumBytes +
                             ((incompat & kIncompatSigned) != 0 ? kSignatureBytes : 0U);
    if (available < size || work < size) return false;
    work -= size;
    std::uint16_t crc = crc_x25(f + 1, kHeaderBytes - 1 + length);
    crc = crc_x25(&info->crc_extra, 1, crc);
    if (f[kHeaderBytes + length] != static_cast<std::uint8_t>(crc) ||
        f[kHeaderBytes + length + 1] != static_cast<std::uint8_t>(crc >> 8U)) {
      ++counters_.crc_errors;
      drop(1);
      continue;
    }
    out.bytes = f;
    out.size = size;
    out.payload_length = length;
    out.incompat_flags = incompat;
    out.sequence = f[4];
    out.system_id = f[5];
    out.component_id = f[6];
    out.msg_id = msg_id;
    std::memcpy(out.payload.data(), f + kHeaderBytes, length);
    std::memset(out.payload.data() + length, 0, out.payload.size() - length);
    start_ += size;
    ++counters_.frames;
    counters_.frame_bytes += size;
    return true;
  }
}

}  // namespace harmoloc::firmware::mavlink
