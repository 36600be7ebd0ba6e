#pragma once
/// @file A fixed-capacity single-producer single-consumer ring of trivially copyable values:
/// lock-free, allocation-free, wait-free on both sides (a full ring refuses, an empty one
/// answers false). The libcamera driver hands completed requests to the cycle through it.

#include <array>
#include <atomic>
#include <cstddef>
#include <type_traits>

namespace harmoloc::drivers {

template <typename T, std::size_t Capacity>
class SpscRing {
  static_assert(Capacity >= 2 && (Capacity & (Capacity - 1)) == 0, "power of two capacity");
  static_assert(std::is_trivially_copyable<T>::value, "trivially copyable values only");

 public:
  /// Producer side. False when full (the value is not stored).
  bool push(const T& value) {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    const std::size_t tail = tail_.load(std::memory_order_acquire);
    if (head - tail == Capacity) return false;
    slots_[head & (Capacity - 1)] = value;
    head_.store(head + 1, std::memory_order_release);
    return true;
  }
  /// Consumer side. False when empty.
  bool pop(T& value) {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    const std::size_t head = head_.load(std::memory_order_acquire);
    if (head == tail) return false;
    value = slots_[tail & (Capacity - 1)];
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }
  /// Approximate from either side; exact when the other side is idle.
  std::size_t size() const {
    return head_.load(std::memory_order_acquire) - tail_.load(std::memory_order_acquire);
  }
  static constexpr std::size_t capacity() { return Capacity; }

 private:
  std::array<T, Capacity> slots_{};
  alignas(64) std::atomic<std::size_t> head_{0};
  alignas(64) std::atomic<std::size_t> tail_{0};
};

}  // namespace harmoloc::drivers
