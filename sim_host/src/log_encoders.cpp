#include "harmoloc/sim_host/log_encoders.hpp"

#include "harmoloc/sim_host/candump_log.hpp"

namespace harmoloc::sim_host {

LogEncoders::LogEncoders(const std::string& log_path, const algorithms::EncoderFrameLayout& layout)
    : LogEncoders(read_candump_log(log_path), layout) {}

LogEncoders::LogEncoders(std::vector<algorithms::CanFrame> frames,
                         const algorithms::EncoderFrameLayout& layout)
    : frames_(std::move(frames)), layout_(layout) {}

hal::EncoderStatus LogEncoders::read(std::uint64_t data_time_ns, hal::EncoderCounts& counts) {
  bool fresh = false;
  while (next_ < frames_.size() && frames_[next_].timestamp_ns <= data_time_ns) {
    const algorithms::CanFrame& f = frames_[next_++];
    std::uint32_t left = 0, right = 0;
    switch (algorithms::decode_encoder_frame(layout_, f, left, right)) {
      case algorithms::CanDecode::kOk:
        counts.left_ticks = left;
        counts.right_ticks = right;
        counts.counter_bits = layout_.counter_bits;
        counts.timestamp_ns = f.timestamp_ns;
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
  return next_ >= frames_.size() ? hal::EncoderStatus::kEnded : hal::EncoderStatus::kNoData;
}

}  // namespace harmoloc::sim_host
