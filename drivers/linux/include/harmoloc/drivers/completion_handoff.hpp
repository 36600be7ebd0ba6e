#pragma once
/// @file The libcamera driver's hand-off between three threads, without locks and without
/// allocating in the cycle:
///
///   device thread --complete()--> [completed ring + eventfd] --take_newest()--> cycle
///   cycle --give_back()--> [released ring + eventfd] --wait_given_back()--> requeue thread
///
/// - The device's thread (libcamera's, completing requests) is the only producer of the
///   completed ring; the cycle its only consumer.
/// - The cycle is the only producer of the released ring (it gives back what it used and the
///   older items it skipped); the requeue thread its only consumer, and hands each item back to
///   the device (libcamera's queueRequest allocates: not in the cycle's thread).
/// Each ring is a SpscRing (release/acquire), so whatever the producer wrote into an item before
/// pushing it is visible to the consumer after popping it. ThreadSanitizer checks this with
/// three threads (tests/unit/drivers_test.cpp, `./run test-tsan`), and the libcamera driver is
/// built on it (libcamera_camera.cpp). T: a pointer or another trivially copyable handle.

#include <poll.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <ctime>
#include <string>

#include "harmoloc/drivers/spsc_ring.hpp"
#include "harmoloc/hal/clock.hpp"

namespace harmoloc::drivers {

template <typename T, std::size_t Capacity>
class CompletionHandoff {
 public:
  CompletionHandoff() = default;
  ~CompletionHandoff() { close(); }
  CompletionHandoff(const CompletionHandoff&) = delete;
  CompletionHandoff& operator=(const CompletionHandoff&) = delete;

  /// Creates the two eventfds. Returns an empty string, or the reason.
  std::string open() {
    completed_fd_ = ::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
    released_fd_ = ::eventfd(0, EFD_CLOEXEC);
    if (completed_fd_ < 0 || released_fd_ < 0)
      return std::string("eventfd: ") + std::strerror(errno);
    return {};
  }
  void close() {
    if (completed_fd_ >= 0) ::close(completed_fd_);
    if (released_fd_ >= 0) ::close(released_fd_);
    completed_fd_ = released_fd_ = -1;
  }

  // ---- device thread ----
  /// A completed item for the cycle. False (the item stays the caller's, counted) when the ring
  /// is full, which cannot happen while no more than Capacity items are in flight.
  bool complete(T item) {
    if (!completed_.push(item)) {
      full_.fetch_add(1, std::memory_order_relaxed);
      return false;
    }
    bump(completed_fd_);
    return true;
  }

  // ---- cycle ----
  /// Waits at most until @p deadline_ns (on @p clock) for a completed item and takes the newest
  /// one waiting; older ones are given back at once and counted in @p skipped. False on timeout.
  bool take_newest(T& item, std::uint64_t deadline_ns, const hal::Clock& clock,
                   std::uint64_t& skipped) {
    for (;;) {
      if (completed_.pop(item)) break;
      const std::uint64_t now = clock.now_ns();
      if (now >= deadline_ns) return false;
      const std::uint64_t left_ns = deadline_ns - now;
      timespec timeout{static_cast<time_t>(left_ns / 1000000000ULL),
                       static_cast<long>(left_ns % 1000000000ULL)};
      pollfd p{completed_fd_, POLLIN, 0};
      const int rc = ::ppoll(&p, 1, &timeout, nullptr);
      if (rc > 0) {
        std::uint64_t value = 0;
        if (::read(completed_fd_, &value, sizeof value) < 0) {
        }
      } else if (rc == 0) {
        if (!completed_.pop(item)) return false;
        break;
      }
    }
    T newer{};
    bool any = false;
    while (completed_.pop(newer)) {
      ++skipped;
      released_.push(item);  // room: everything in flight fits either ring
      item = newer;
      any = true;
    }
    if (any) bump(released_fd_);
    return true;
  }
  /// Hands an item back for the requeue thread.
  void give_back(T item) {
    released_.push(item);
    bump(released_fd_);
  }

  // ---- requeue thread ----
  /// Blocks until items are given back (or stop()), then calls @p requeue with each. Returns
  /// false once stop() was called.
  template <typename F>
  bool wait_given_back(F&& requeue) {
    std::uint64_t value = 0;
    while (::read(released_fd_, &value, sizeof value) < 0 && errno == EINTR) {
    }
    if (stopping_.load(std::memory_order_acquire)) return false;
    T item{};
    while (released_.pop(item)) requeue(item);
    return true;
  }

  // ---- owner ----
  /// Makes wait_given_back() return false (the requeue thread then ends).
  void stop() {
    stopping_.store(true, std::memory_order_release);
    bump(released_fd_);
  }
  /// Items complete() could not pass on because the ring was full.
  std::uint64_t full_count() const { return full_.load(std::memory_order_relaxed); }
  static constexpr std::size_t capacity() { return Capacity; }

 private:
  static void bump(int fd) {
    const std::uint64_t one = 1;
    while (::write(fd, &one, sizeof one) < 0 && errno == EINTR) {
    }
  }

  SpscRing<T, Capacity> completed_;  // device thread -> cycle
  SpscRing<T, Capacity> released_;   // cycle -> requeue thread
  int completed_fd_ = -1;            // eventfd: an item completed
  int released_fd_ = -1;             // eventfd: an item to requeue (or stop)
  std::atomic<bool> stopping_{false};
  std::atomic<std::uint64_t> full_{0};
};

}  // namespace harmoloc::drivers
