#include "histogram_edges.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace harmoloc::sim_host {

namespace {

constexpr int kSubBits = 6;  // firmware/latency_histogram.hpp: 64 sub-buckets an octave

/// The width (ns) of the firmware bucket whose upper edge is @p upper_ns, or 0 when no bucket
/// ends there. Octave 0 is 1 ns wide buckets up to 64 ns; above, an upper edge is
/// (65 + sub) << shift with sub in 0..63, and the bucket is 1 << shift wide.
std::uint64_t firmware_width_ns(std::uint64_t upper_ns) {
  if (upper_ns == 0) return 0;
  if (upper_ns <= (1U << kSubBits)) return 1;
  for (int shift = 0; shift < 42; ++shift) {
    const std::uint64_t unit = std::uint64_t{1} << shift;
    if (upper_ns % unit != 0) break;
    const std::uint64_t mantissa = upper_ns / unit;
    if (mantissa >= 65 && mantissa <= 128) return unit;
  }
  return 0;
}

std::uint64_t to_ns(double us) {
  return static_cast<std::uint64_t>(std::llround(us * 1000.0));
}

}  // namespace

bool on_firmware_grid(const CycleHistogram& histogram) {
  if (histogram.upper_us.empty()) return false;
  for (const double us : histogram.upper_us) {
    const std::uint64_t ns = to_ns(us);
    if (std::fabs(static_cast<double>(ns) - us * 1000.0) > 1e-3 || firmware_width_ns(ns) == 0) {
      return false;
    }
  }
  return true;
}

std::vector<double> bucket_lower_us(const CycleHistogram& histogram) {
  const std::vector<double>& upper = histogram.upper_us;
  std::vector<double> lower(upper.size(), 0.0);
  const bool grid = on_firmware_grid(histogram);
  for (std::size_t b = 0; b < upper.size(); ++b) {
    const double previous = b == 0 ? 0.0 : upper[b - 1];
    if (grid) {
      const double width_us = static_cast<double>(firmware_width_ns(to_ns(upper[b]))) / 1000.0;
      lower[b] = std::max(previous, upper[b] - width_us);
    } else {
      lower[b] = previous;
    }
  }
  return lower;
}

}  // namespace harmoloc::sim_host
