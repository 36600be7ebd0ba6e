#include "harmoloc/host/log_encoders.hpp"

#include <cstdio>
#include <stdexcept>

#include "harmoloc/dataset/candump_log.hpp"

namespace harmoloc::host {

LogEncoders::LogEncoders(const std::string& log_path, const algorithms::EncoderFrameLayout& layout)
    : LogEncoders(dataset::read_candump_log(log_path), layout) {
  // A log without one encoder frame would run the whole replay vision-only, looking fine.
  std::size_t usable = 0;
  for (const algorithms::CanFrame& f : frames_) {
    std::uint32_t l = 0, r = 0;
    if (algorithms::decode_encoder_frame(layout_, f, l, r) == algorithms::CanDecode::kOk) ++usable;
  }
  if (frames_.empty()) throw std::runtime_error(log_path + ": no CAN frames in the log");
  if (usable == 0) {
    char id[16];
    std::snprintf(id, sizeof id, "0x%X", layout_.id);
    throw std::runtime_error(log_path + ": none of its " + std::to_string(frames_.size()) +
                             " frames is an encoder frame (ID " + id + ", " +
                             std::to_string(layout_.length) +
                             " bytes; the [can] layout of the config or metadata)");
  }
}

LogEncoders::LogEncoders(std::vector<algorithms::CanFrame> frames,
                         const algorithms::EncoderFrameLayout& layout)
    : frames_(std::move(frames)), layout_(layout) {}

void LogEncoders::set_loops(std::uint32_t loops, std::uint64_t span_ns) {
  loops_ = loops == 0 ? 1 : loops;
  span_ns_ = span_ns;
  bool first = true;
  std::uint32_t l0 = 0, r0 = 0, l1 = 0, r1 = 0;
  for (const algorithms::CanFrame& f : frames_) {
    std::uint32_t l = 0, r = 0;
    if (algorithms::decode_encoder_frame(layout_, f, l, r) != algorithms::CanDecode::kOk) continue;
    if (first) {
      l0 = l;
      r0 = r;
      first = false;
    }
    l1 = l;
    r1 = r;
  }
  left_advance_ = l1 - l0;
  right_advance_ = r1 - r0;
}

hal::EncoderStatus LogEncoders::read(std::uint64_t data_time_ns, hal::EncoderCounts& counts) {
  bool fresh = false;
  const std::uint32_t mask =
      layout_.counter_bits >= 32 ? 0xFFFFFFFFU : (1U << layout_.counter_bits) - 1U;
  for (;;) {
    if (next_ >= frames_.size() && loop_ + 1 < loops_) {
      ++loop_;
      next_ = 0;
    }
    if (next_ >= frames_.size() || frames_[next_].timestamp_ns + loop_ * span_ns_ > data_time_ns)
      break;
    const algorithms::CanFrame& f = frames_[next_++];
    std::uint32_t left = 0, right = 0;
    switch (algorithms::decode_encoder_frame(layout_, f, left, right)) {
      case algorithms::CanDecode::kOk:
        counts.left_ticks = (left + loop_ * left_advance_) & mask;
        counts.right_ticks = (right + loop_ * right_advance_) & mask;
        counts.counter_bits = layout_.counter_bits;
        counts.timestamp_ns = f.timestamp_ns + loop_ * span_ns_;
        ++counters_.samples;
        fresh = true;
        break;
      case algorithms::CanDecode::kOtherId:
        ++counters_.ignored_id;
        break;
      case algorithms::CanDecode::kBadLength:
        ++counters_.bad_length;
        break;
    }
  }
  if (fresh) return hal::EncoderStatus::kFresh;
  return next_ >= frames_.size() && loop_ + 1 >= loops_ ? hal::EncoderStatus::kEnded
                                                        : hal::EncoderStatus::kNoData;
}

}  // namespace harmoloc::host
