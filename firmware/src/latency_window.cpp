#include "harmoloc/firmware/latency_window.hpp"

#include <algorithm>

namespace harmoloc::firmware {

void LatencyWindow::record(std::uint64_t latency_ns) {
  samples_[count_ % kCapacity] = latency_ns;
  ++count_;
  max_ns_ = std::max(max_ns_, latency_ns);
}

LatencyWindow::Summary LatencyWindow::take() {
  Summary s;
  s.count = count_;
  if (count_ > 0) {
    const std::size_t n = std::min(count_, kCapacity);
    std::array<std::uint64_t, kCapacity> sorted = samples_;
    // The lower median of an even count: a latency that was measured, not an average of two.
    const auto mid = sorted.begin() + static_cast<std::ptrdiff_t>((n - 1) / 2);
    std::nth_element(sorted.begin(), mid, sorted.begin() + static_cast<std::ptrdiff_t>(n));
    s.median_ns = *mid;
    s.max_ns = max_ns_;
  }
  count_ = 0;
  max_ns_ = 0;
  return s;
}

}  // namespace harmoloc::firmware
