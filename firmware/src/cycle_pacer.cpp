#include "harmoloc/firmware/cycle_pacer.hpp"

namespace harmoloc::firmware {

const char* pacing_name(Pacing pacing) {
  return pacing == Pacing::kTimer ? "timer" : "camera";
}

CyclePacer::CyclePacer(hal::Clock& clock, Pacing pacing, std::uint64_t period_ns)
    : clock_(clock), pacing_(pacing), period_ns_(period_ns == 0 ? 1 : period_ns) {}

std::uint64_t CyclePacer::wait_for_cycle() {
  const std::uint64_t now = clock_.now_ns();
  if (pacing_ == Pacing::kCamera) return now + period_ns_;

  if (!started_) {
    started_ = true;
    next_tick_ns_ = now;
  } else if (now > next_tick_ns_) {
    // The last cycle ran past one or more grid points: skip them (no catching up back to back)
    // and wake on the first one still ahead.
    const std::uint64_t missed = (now - next_tick_ns_ + period_ns_ - 1) / period_ns_;
    skipped_ticks_ += missed;
    next_tick_ns_ += missed * period_ns_;
  }
  clock_.sleep_until(next_tick_ns_);
  const std::uint64_t woke = clock_.now_ns();
  wakeup_latency_.record(woke > next_tick_ns_ ? woke - next_tick_ns_ : 0);
  last_tick_ns_ = next_tick_ns_;
  next_tick_ns_ += period_ns_;
  return woke;
}

}  // namespace harmoloc::firmware
