#pragma once
/// @file hal::Clock on Linux: CLOCK_MONOTONIC and absolute clock_nanosleep (the real-time wiki's
/// cyclic pattern: sleeping to an absolute time does not accumulate drift).

#include "harmoloc/hal/clock.hpp"

namespace harmoloc::drivers {

class MonotonicClock final : public hal::Clock {
 public:
  std::uint64_t now_ns() const override;
  void sleep_until(std::uint64_t wake_ns) override;
};

}  // namespace harmoloc::drivers
