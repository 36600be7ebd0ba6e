#include "harmoloc/drivers/monotonic_clock.hpp"

#include <cerrno>
#include <ctime>

namespace harmoloc::drivers {

std::uint64_t MonotonicClock::now_ns() const {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::uint64_t>(ts.tv_sec) * 1000000000ULL +
         static_cast<std::uint64_t>(ts.tv_nsec);
}

void MonotonicClock::sleep_until(std::uint64_t wake_ns) {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(wake_ns / 1000000000ULL);
  ts.tv_nsec = static_cast<long>(wake_ns % 1000000000ULL);
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

}  // namespace harmoloc::drivers
