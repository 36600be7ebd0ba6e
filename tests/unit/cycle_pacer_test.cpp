// The cycle's pacing (firmware/cycle_pacer.hpp) against a fake monotonic clock: the timer grid
// does not drift, a cycle that runs past grid points skips them (counted) and the next wake-up is
// on the grid, and camera pacing leaves the waiting to the camera.
#include <gtest/gtest.h>

#include <vector>

#include "harmoloc/firmware/cycle_pacer.hpp"

namespace hf = harmoloc::firmware;

namespace {

// Time moves only when the test says so, or by sleeping; every wake-up is @p lateness_ns late.
class FakeClock final : public harmoloc::hal::Clock {
 public:
  std::uint64_t now_ns() const override { return now_; }
  void sleep_until(std::uint64_t wake_ns) override {
    sleeps.push_back(wake_ns);
    if (wake_ns > now_) now_ = wake_ns + lateness_ns;
  }
  void advance(std::uint64_t ns) { now_ += ns; }

  std::uint64_t lateness_ns = 0;
  std::vector<std::uint64_t> sleeps;

 private:
  std::uint64_t now_ = 1'000'000'000;
};

constexpr std::uint64_t kPeriod = 33'333'333;  // 30 Hz
constexpr std::uint64_t kStart = 1'000'000'000;

TEST(CyclePacer, TimerWakesOnAnAbsoluteGridWithoutDrift) {
  FakeClock clock;
  clock.lateness_ns = 70'000;  // every wake-up 70 us late: must not accumulate
  hf::CyclePacer pacer(clock, hf::Pacing::kTimer, kPeriod);
  for (std::uint64_t k = 0; k < 1000; ++k) {
    const std::uint64_t deadline = pacer.wait_for_cycle();
    EXPECT_EQ(pacer.last_tick_ns(), kStart + k * kPeriod) << "cycle " << k;
    // Acquire is not to wait: its deadline is the wake-up time itself.
    EXPECT_EQ(deadline, clock.now_ns());
    clock.advance(2'000'000);  // a 2 ms cycle
  }
  EXPECT_EQ(clock.sleeps.back(), kStart + 999 * kPeriod);
  EXPECT_EQ(pacer.skipped_ticks(), 0U);
  EXPECT_EQ(pacer.wakeup_latency().count(), 1000U);
  EXPECT_EQ(pacer.wakeup_latency().max_ns(), 70'000U);
}

TEST(CyclePacer, TimerSkipsTheTicksAnOverrunRanPast) {
  FakeClock clock;
  hf::CyclePacer pacer(clock, hf::Pacing::kTimer, kPeriod);
  pacer.wait_for_cycle();  // tick 0
  clock.advance(1'000'000);
  pacer.wait_for_cycle();  // tick 1
  EXPECT_EQ(pacer.last_tick_ns(), kStart + kPeriod);
  // This cycle lasts 2.5 periods: ticks 2 and 3 pass while it runs.
  clock.advance(kPeriod * 5 / 2);
  pacer.wait_for_cycle();
  EXPECT_EQ(pacer.skipped_ticks(), 2U);
  EXPECT_EQ(pacer.last_tick_ns(), kStart + 4 * kPeriod) << "the next wake-up is on the grid";
  EXPECT_EQ(clock.sleeps.back(), kStart + 4 * kPeriod);
  EXPECT_EQ(clock.now_ns(), kStart + 4 * kPeriod);
  // Back to short cycles: no catching up, one tick per period again.
  clock.advance(1'000'000);
  pacer.wait_for_cycle();
  EXPECT_EQ(pacer.last_tick_ns(), kStart + 5 * kPeriod);
  EXPECT_EQ(pacer.skipped_ticks(), 2U);
  // Ending exactly on a grid point is not late: that point is run.
  clock.advance(kPeriod);
  pacer.wait_for_cycle();
  EXPECT_EQ(pacer.last_tick_ns(), kStart + 6 * kPeriod);
  EXPECT_EQ(pacer.skipped_ticks(), 2U);
  // One nanosecond past it is.
  clock.advance(kPeriod + 1);
  pacer.wait_for_cycle();
  EXPECT_EQ(pacer.last_tick_ns(), kStart + 8 * kPeriod);
  EXPECT_EQ(pacer.skipped_ticks(), 3U);
}

TEST(CyclePacer, TimerSkipsALongStallInOneStep) {
  FakeClock clock;
  hf::CyclePacer pacer(clock, hf::Pacing::kTimer, kPeriod);
  pacer.wait_for_cycle();
  clock.advance(10'000'000'000ULL);  // a 10 s stall (300 periods)
  pacer.wait_for_cycle();
  EXPECT_EQ(pacer.skipped_ticks(), 300U);
  EXPECT_EQ(pacer.last_tick_ns(), kStart + 301 * kPeriod);
  EXPECT_EQ(clock.sleeps.size(), 2U);
}

TEST(CyclePacer, CameraPacingPassesThrough) {
  FakeClock clock;
  hf::CyclePacer pacer(clock, hf::Pacing::kCamera, kPeriod);
  for (int k = 0; k < 10; ++k) {
    const std::uint64_t now = clock.now_ns();
    // No sleeping here: acquire waits for the frame, at most one period.
    EXPECT_EQ(pacer.wait_for_cycle(), now + kPeriod);
    clock.advance(k == 5 ? 5 * kPeriod : 1'000'000);  // an overrun changes nothing here
  }
  EXPECT_TRUE(clock.sleeps.empty());
  EXPECT_EQ(pacer.skipped_ticks(), 0U);
  EXPECT_EQ(pacer.wakeup_latency().count(), 0U);
}

}  // namespace
