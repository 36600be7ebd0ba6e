#pragma once
/// @file Monotonic clock for pacing the cycle and timing its stages.

#include <cstdint>

namespace harmoloc::hal {

class Clock {
 public:
  /// Nanoseconds on a monotonic clock (CLOCK_MONOTONIC on Linux).
  virtual std::uint64_t now_ns() const = 0;
  /// Sleeps until the absolute monotonic time @p wake_ns (returns at once if it has passed).
  virtual void sleep_until(std::uint64_t wake_ns) = 0;

 protected:
  ~Clock() = default;
};

}  // namespace harmoloc::hal
