#pragma once
/// @file When each cycle starts: camera-paced (the cycle waits in Camera::acquire for the next
/// frame, at most one period) or timer-paced (the cycle wakes on an absolute grid of the
/// monotonic clock, start + k * period, and takes whatever frame is ready without waiting).
/// Both board mains use this; the policy is documented in docs/architecture.md, "Pacing and
/// overruns". No allocation, no unbounded loop: the grid arithmetic is a division.

#include <cstdint>

#include "harmoloc/firmware/config.hpp"
#include "harmoloc/firmware/latency_histogram.hpp"
#include "harmoloc/hal/clock.hpp"

namespace harmoloc::firmware {

const char* pacing_name(Pacing pacing);

class CyclePacer {
 public:
  CyclePacer(hal::Clock& clock, Pacing pacing, std::uint64_t period_ns);

  /// Waits until the next cycle may start and returns the deadline to give Camera::acquire.
  /// Camera: does not wait; the deadline is now + one period (acquire waits for the frame).
  /// Timer: the first call starts the grid at now; later calls skip the grid points that have
  /// already passed (counted in skipped_ticks()), sleep to the next one with an absolute
  /// deadline and return the wake-up time, so acquire takes a ready frame or none at once.
  std::uint64_t wait_for_cycle();

  Pacing pacing() const { return pacing_; }
  std::uint64_t period_ns() const { return period_ns_; }
  /// Timer: grid points passed while a cycle ran (an overrun), not run to catch up.
  std::uint64_t skipped_ticks() const { return skipped_ticks_; }
  /// Timer: the grid point of the last wake-up (0 before the first).
  std::uint64_t last_tick_ns() const { return last_tick_ns_; }
  /// Timer: how late each wake-up was after its grid point.
  const LatencyHistogram& wakeup_latency() const { return wakeup_latency_; }

 private:
  hal::Clock& clock_;
  Pacing pacing_;
  std::uint64_t period_ns_;
  bool started_ = false;
  std::uint64_t next_tick_ns_ = 0;
  std::uint64_t last_tick_ns_ = 0;
  std::uint64_t skipped_ticks_ = 0;
  LatencyHistogram wakeup_latency_;
};

}  // namespace harmoloc::firmware
