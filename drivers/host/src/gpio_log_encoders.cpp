#include "harmoloc/host/gpio_log_encoders.hpp"

#include <stdexcept>
#include <utility>

namespace harmoloc::host {

GpioLogEncoders::GpioLogEncoders(const std::string& path, std::uint8_t counter_bits)
    : GpioLogEncoders(dataset::read_encoder_csv(path, counter_bits), counter_bits) {}

GpioLogEncoders::GpioLogEncoders(std::vector<dataset::EncoderSample> samples,
                                 std::uint8_t counter_bits)
    : samples_(std::move(samples)),
      counter_bits_(counter_bits),
      mask_(counter_bits >= 32 ? 0xFFFFFFFFU : (1U << counter_bits) - 1U) {
  if (samples_.empty()) throw std::runtime_error("GPIO encoder recording without samples");
  if (counter_bits < 8 || counter_bits > 32)
    throw std::runtime_error("GPIO encoder recording: counter width must be 8..32 bits");
}

void GpioLogEncoders::set_loops(std::uint32_t loops, std::uint64_t span_ns) {
  loops_ = loops == 0 ? 1 : loops;
  span_ns_ = span_ns;
}

hal::EncoderStatus GpioLogEncoders::read(std::uint64_t data_time_ns, hal::EncoderCounts& counts) {
  bool fresh = false;
  const std::uint32_t left_advance = samples_.back().left_ticks - samples_.front().left_ticks;
  const std::uint32_t right_advance = samples_.back().right_ticks - samples_.front().right_ticks;
  for (;;) {
    if (next_ >= samples_.size() && loop_ + 1 < loops_) {
      ++loop_;
      next_ = 0;
    }
    if (next_ >= samples_.size() ||
        samples_[next_].timestamp_ns + loop_ * span_ns_ > data_time_ns) {
      break;
    }
    const dataset::EncoderSample& s = samples_[next_++];
    counts.left_ticks = (s.left_ticks + loop_ * left_advance) & mask_;
    counts.right_ticks = (s.right_ticks + loop_ * right_advance) & mask_;
    counts.counter_bits = counter_bits_;
    counts.timestamp_ns = s.timestamp_ns + loop_ * span_ns_;
    ++counters_.samples;
    fresh = true;
  }
  if (fresh) return hal::EncoderStatus::kFresh;
  return next_ >= samples_.size() && loop_ + 1 >= loops_ ? hal::EncoderStatus::kEnded
                                                         : hal::EncoderStatus::kNoData;
}

}  // namespace harmoloc::host
