#pragma once
/// @file hal::WheelEncoders backed by a GPIO encoder recording (encoders.csv, encoder_csv.hpp):
/// the samples are read and checked at start-up and handed out by their timestamps as the data
/// clock advances, as LogEncoders does with a candump log. The host board picks it when the
/// dataset's metadata says `[encoders] source = "gpio"`.

#include <cstdint>
#include <string>
#include <vector>

#include "harmoloc/dataset/encoder_csv.hpp"
#include "harmoloc/hal/wheel_encoders.hpp"

namespace harmoloc::host {

class GpioLogEncoders final : public hal::WheelEncoders {
 public:
  /// Reads @p path (counts of @p counter_bits bits, 8..32). Throws std::runtime_error
  /// ("FILE:LINE: reason") on a malformed recording.
  GpioLogEncoders(const std::string& path, std::uint8_t counter_bits);
  /// For tests: samples already in memory (timestamps increasing, counts within the width).
  GpioLogEncoders(std::vector<dataset::EncoderSample> samples, std::uint8_t counter_bits);

  /// Drains the samples up to @p data_time_ns and reports the latest (kFresh), kNoData when none
  /// is new, kEnded once the recording is used up.
  hal::EncoderStatus read(std::uint64_t data_time_ns, hal::EncoderCounts& counts) override;
  hal::EncoderCounters counters() const override { return counters_; }

  std::size_t sample_count() const { return samples_.size(); }
  std::uint64_t first_timestamp_ns() const { return samples_.front().timestamp_ns; }
  std::uint64_t last_timestamp_ns() const { return samples_.back().timestamp_ns; }
  /// Replays the recording @p loops times, pass k shifted by k x @p span_ns; the counters carry
  /// on from where the previous pass left them.
  void set_loops(std::uint32_t loops, std::uint64_t span_ns);

 private:
  std::vector<dataset::EncoderSample> samples_;
  std::uint8_t counter_bits_;
  std::uint32_t mask_;
  std::size_t next_ = 0;
  std::uint32_t loops_ = 1;
  std::uint32_t loop_ = 0;
  std::uint64_t span_ns_ = 0;
  hal::EncoderCounters counters_{};
};

}  // namespace harmoloc::host
