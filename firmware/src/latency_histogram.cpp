#include "harmoloc/firmware/latency_histogram.hpp"

#include <algorithm>
#include <cmath>

namespace harmoloc::firmware {

std::size_t LatencyHistogram::bucket_of(std::uint64_t ns) {
  // Octave 0 holds 0..63 ns linearly; octave k >= 1 holds [2^(k+5), 2^(k+6)) in 64 steps.
  if (ns < kSub) return static_cast<std::size_t>(ns);
  const int msb = 63 - __builtin_clzll(ns);
  const int octave = msb - kSubBits + 1;
  if (octave >= kOctaves) return kBuckets - 1;
  const auto sub = static_cast<std::size_t>((ns >> (msb - kSubBits)) & (kSub - 1U));
  return static_cast<std::size_t>(octave) * kSub + sub;
}

std::uint64_t LatencyHistogram::bucket_upper_ns(std::size_t i) {
  const std::size_t octave = i / kSub;
  const std::uint64_t sub = i % kSub;
  if (octave == 0) return sub + 1;
  const int shift = static_cast<int>(octave) - 1;
  return ((kSub + sub + 1) << shift);
}

void LatencyHistogram::record(std::uint64_t duration_ns) {
  ++counts_[bucket_of(duration_ns)];
  ++count_;
  sum_ns_ += duration_ns;
  max_ns_ = std::max(max_ns_, duration_ns);
  min_ns_ = std::min(min_ns_, duration_ns);
}

std::uint64_t LatencyHistogram::quantile_ns(double q) const {
  if (count_ == 0) return 0;
  if (q >= 1.0) return max_ns_;
  const auto rank = static_cast<std::uint64_t>(std::ceil(q * static_cast<double>(count_)));
  std::uint64_t seen = 0;
  for (std::size_t i = 0; i < kBuckets; ++i) {
    seen += counts_[i];
    if (seen >= std::max<std::uint64_t>(rank, 1)) return std::min(bucket_upper_ns(i), max_ns_);
  }
  return max_ns_;
}

}  // namespace harmoloc::firmware
