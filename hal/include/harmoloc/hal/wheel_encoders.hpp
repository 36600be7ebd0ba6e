#pragma once
/// @file Wheel encoder interface: the latest raw counter values of the two drive wheels.

#include <cstdint>

namespace harmoloc::hal {

/// Raw, free-running counter values as the hardware reports them. The counters wrap at
/// 2^counter_bits; the cycle computes deltas modulo that width (algorithms/odometry.hpp).
struct EncoderCounts {
  std::uint32_t left_ticks = 0;
  std::uint32_t right_ticks = 0;
  std::uint8_t counter_bits = 32;
  std::uint64_t timestamp_ns = 0;  ///< when the counts were sampled, on the data clock
};

enum class EncoderStatus : std::uint8_t {
  kFresh = 0,   ///< new counts since the last read
  kNoData = 1,  ///< nothing new (bus silent, or the controller is late)
  kEnded = 2,   ///< the source has no more data (end of a recording)
};

/// Counters an encoder source keeps about itself.
struct EncoderCounters {
  std::uint64_t samples = 0;     ///< counter pairs accepted
  std::uint64_t ignored_id = 0;  ///< CAN frames with an ID that is not ours
  std::uint64_t bad_length = 0;  ///< frames of ours with the wrong length
  std::uint64_t glitches = 0;    ///< impossible quadrature transitions
  std::uint64_t bus_errors = 0;  ///< error frames, bus-off and similar
  std::uint64_t bus_off = 0;     ///< of those, the controller went bus-off
  std::uint64_t overflows = 0;   ///< frames or edges the kernel dropped (queue full)
};

class WheelEncoders {
 public:
  /// Drains everything that arrived up to @p data_time_ns and reports the latest counts.
  /// Never blocks.
  virtual EncoderStatus read(std::uint64_t data_time_ns, EncoderCounts& counts) = 0;
  virtual EncoderCounters counters() const = 0;

 protected:
  ~WheelEncoders() = default;
};

}  // namespace harmoloc::hal
