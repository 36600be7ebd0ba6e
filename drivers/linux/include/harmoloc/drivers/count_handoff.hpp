#pragma once
/// @file The GPIO encoder reader thread's hand-off to the cycle: a sequence lock made of atomics.
/// One writer (the reader thread) publishes the decoded positions and counters without ever
/// waiting; readers (the cycle) take a consistent snapshot, retrying a bounded number of times
/// while a write is under way. Every shared field is an atomic, so there is no data race in the
/// C++ sense (ThreadSanitizer checks it: tests/unit/drivers_test.cpp, `./run test-tsan`); the
/// sequence number makes the snapshot consistent (never the left count of one write with the
/// right count of another). Nothing allocates.
///
/// The pattern is Boehm's ("Can seqlocks get along with programming language memory models?",
/// 2012): the writer makes the sequence odd, fences, stores the fields relaxed and makes the
/// sequence even with release; the reader loads the sequence with acquire, the fields relaxed,
/// fences with acquire and checks that the sequence did not move.

#include <atomic>
#include <cstdint>

namespace harmoloc::drivers {

struct CountSnapshot {
  std::int64_t left = 0;
  std::int64_t right = 0;
  std::uint64_t glitches = 0;
  std::uint64_t overflows = 0;
  bool failed = false;
};

class CountHandoff {
 public:
  static constexpr int kMaxReadAttempts = 8;

  /// Writer side (one thread only). Never waits.
  void publish(const CountSnapshot& s) {
    begin_write();
    store(s);
    end_write();
  }

  /// Reader side: a consistent snapshot, or false if a write was under way on every attempt
  /// (the caller reports no data for this cycle and tries again next time).
  bool read(CountSnapshot& out) const {
    for (int attempt = 0; attempt < kMaxReadAttempts; ++attempt) {
      const std::uint32_t s1 = seq_.load(std::memory_order_acquire);
      if ((s1 & 1U) != 0) continue;
      CountSnapshot s;
      s.left = left_.load(std::memory_order_relaxed);
      s.right = right_.load(std::memory_order_relaxed);
      s.glitches = glitches_.load(std::memory_order_relaxed);
      s.overflows = overflows_.load(std::memory_order_relaxed);
      s.failed = failed_.load(std::memory_order_relaxed);
      std::atomic_thread_fence(std::memory_order_acquire);
      if (seq_.load(std::memory_order_relaxed) != s1) continue;
      out = s;
      return true;
    }
    return false;
  }

  /// Single fields for diagnostics (each atomic on its own; not a consistent snapshot).
  std::int64_t left() const { return left_.load(std::memory_order_relaxed); }
  std::int64_t right() const { return right_.load(std::memory_order_relaxed); }
  std::uint64_t glitches() const { return glitches_.load(std::memory_order_relaxed); }
  std::uint64_t overflows() const { return overflows_.load(std::memory_order_relaxed); }
  bool failed() const { return failed_.load(std::memory_order_relaxed); }

  // The writer's steps, public so that a test can hold a write open and check that readers
  // neither block nor see it half done. publish() is these three in order.
  void begin_write() {
    const std::uint32_t s = seq_.load(std::memory_order_relaxed);
    seq_.store(s + 1, std::memory_order_relaxed);
    std::atomic_thread_fence(std::memory_order_release);
  }
  void store(const CountSnapshot& s) {
    left_.store(s.left, std::memory_order_relaxed);
    right_.store(s.right, std::memory_order_relaxed);
    glitches_.store(s.glitches, std::memory_order_relaxed);
    overflows_.store(s.overflows, std::memory_order_relaxed);
    failed_.store(s.failed, std::memory_order_relaxed);
  }
  void end_write() {
    seq_.store(seq_.load(std::memory_order_relaxed) + 1, std::memory_order_release);
  }

 private:
  std::atomic<std::uint32_t> seq_{0};
  std::atomic<std::int64_t> left_{0};
  std::atomic<std::int64_t> right_{0};
  std::atomic<std::uint64_t> glitches_{0};
  std::atomic<std::uint64_t> overflows_{0};
  std::atomic<bool> failed_{false};
};

}  // namespace harmoloc::drivers
