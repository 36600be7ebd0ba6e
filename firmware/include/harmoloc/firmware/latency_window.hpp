#pragma once
/// @file The capture-to-send latencies of the last report period (about a second), for the
/// link: the cycle records one per pose sent and takes the period's median and maximum when it
/// reports them (NAMED_VALUE_FLOAT, docs/wire-protocol.md). Fixed capacity, no allocation; a
/// period with more samples than that keeps the latest kCapacity for the median and every
/// sample for the maximum.

#include <array>
#include <cstddef>
#include <cstdint>

namespace harmoloc::firmware {

class LatencyWindow {
 public:
  /// Two seconds at 30 Hz: a period of 1 s never fills it at the firmware's rates.
  static constexpr std::size_t kCapacity = 64;

  struct Summary {
    std::size_t count = 0;  ///< samples in the period (0: nothing to report)
    std::uint64_t median_ns = 0;
    std::uint64_t max_ns = 0;
  };

  void record(std::uint64_t latency_ns);
  /// The period's summary; starts the next period.
  Summary take();

 private:
  std::array<std::uint64_t, kCapacity> samples_{};
  std::size_t count_ = 0;  ///< samples recorded this period (may exceed kCapacity)
  std::uint64_t max_ns_ = 0;
};

}  // namespace harmoloc::firmware
