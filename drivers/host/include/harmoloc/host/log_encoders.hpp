#pragma once
/// @file hal::WheelEncoders backed by a `candump -l` log: frames are parsed at start-up and
/// handed out by their timestamps as the data clock advances.

#include <cstdint>
#include <string>
#include <vector>

#include "harmoloc/algorithms/can_encoder_layout.hpp"
#include "harmoloc/hal/wheel_encoders.hpp"

namespace harmoloc::host {

class LogEncoders final : public hal::WheelEncoders {
 public:
  /// Throws std::runtime_error("FILE:LINE: reason") on a malformed line.
  LogEncoders(const std::string& log_path, const algorithms::EncoderFrameLayout& layout);
  /// For tests: frames already in memory.
  LogEncoders(std::vector<algorithms::CanFrame> frames,
              const algorithms::EncoderFrameLayout& layout);

  hal::EncoderStatus read(std::uint64_t data_time_ns, hal::EncoderCounts& counts) override;
  hal::EncoderCounters counters() const override { return counters_; }
  std::size_t frame_count() const { return frames_.size(); }
  std::uint64_t first_timestamp_ns() const {
    return frames_.empty() ? 0 : frames_.front().timestamp_ns;
  }
  std::uint64_t last_timestamp_ns() const {
    return frames_.empty() ? 0 : frames_.back().timestamp_ns;
  }
  /// Replays the log @p loops times, pass k shifted by k x @p span_ns; the counters carry on from
  /// where the previous pass left them, as a real controller's would.
  void set_loops(std::uint32_t loops, std::uint64_t span_ns);

 private:
  std::vector<algorithms::CanFrame> frames_;
  algorithms::EncoderFrameLayout layout_;
  std::size_t next_ = 0;
  std::uint32_t loops_ = 1;
  std::uint32_t loop_ = 0;
  std::uint64_t span_ns_ = 0;
  std::uint32_t left_advance_ = 0;  // counter change over one pass
  std::uint32_t right_advance_ = 0;
  hal::EncoderCounters counters_{};
};

}  // namespace harmoloc::host
