#pragma once
// The true lower edge of each bucket of the whole-cycle histogram. The firmware lists only its
// non-empty buckets (docs/stats-format.md), so the previous listed upper edge is not a bucket's
// lower edge when empty buckets lie between: drawn that way, an isolated slow cycle becomes a
// bar milliseconds wide. On the firmware's log-linear grid (64 sub-buckets per power of two of
// nanoseconds, firmware/latency_histogram.hpp) each bucket's width follows from its upper edge;
// any other histogram is read as documented in run_stats.hpp, buckets end to end.

#include <vector>

#include "harmoloc/sim_host/run_stats.hpp"

namespace harmoloc::sim_host {

/// True when every upper edge is a bucket edge of the firmware's log-linear histogram.
bool on_firmware_grid(const CycleHistogram& histogram);

/// Lower edge of each bucket (us), same length as histogram.upper_us.
std::vector<double> bucket_lower_us(const CycleHistogram& histogram);

}  // namespace harmoloc::sim_host
