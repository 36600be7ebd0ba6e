// The area's gain by column (algorithms/column_gain.hpp), measured on the training run: pairs of
// placed frames from different passes over one place at nearly one heading.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "harmoloc/algorithms/geometry.hpp"
#include "trainer_parts.hpp"

namespace harmoloc::sim_host::trainer_detail {

namespace {

// Two frames form a pair when the odometry placed them this close, at most this far apart in
// heading, and at least this far apart in time (another pass, not the next frame of the same
// one, whose columns hardly differ). The distance is the placement's own accuracy: the area
// changes by more than the gain's effect over a few centimetres.
constexpr double kPairDistance_m = 0.02;
constexpr double kPairHeading_rad = 0.436;  // 25 degrees
constexpr double kPairSeparation_s = 2.0;
// Fewer observations than this: no gain (plain areas).
constexpr std::size_t kMinObservations = 50;
// More pairs than this (a robot standing still for minutes): the first ones in time order.
constexpr std::size_t kMaxPairs = 1000000;

}  // namespace

algorithms::ColumnGain fit_column_gain(const AreaSeries& run,
                                       const std::vector<PlacedFrame>& frames, std::size_t boards,
                                       ColumnGainReport& report) {
  report = ColumnGainReport{};
  // The candidate pairs by a sweep over x, then in (first, second) order, so that the sums add
  // up in the same order however the frames lie.
  std::vector<std::size_t> by_x;
  for (std::size_t i = 0; i < frames.size(); ++i)
    if (run.areas[frames[i].index].columns_measured()) by_x.push_back(i);
  std::sort(by_x.begin(), by_x.end(), [&](std::size_t a, std::size_t b) {
    return frames[a].pose.x_m < frames[b].pose.x_m ||
           (frames[a].pose.x_m == frames[b].pose.x_m && a < b);
  });
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  for (std::size_t p = 0; p < by_x.size(); ++p) {
    const PlacedFrame& a = frames[by_x[p]];
    for (std::size_t q = p + 1; q < by_x.size(); ++q) {
      const PlacedFrame& b = frames[by_x[q]];
      if (b.pose.x_m - a.pose.x_m > kPairDistance_m) break;
      const std::size_t first = std::min(by_x[p], by_x[q]), second = std::max(by_x[p], by_x[q]);
      const PlacedFrame& f = frames[first];
      const PlacedFrame& s = frames[second];
      if (s.t_s - f.t_s < kPairSeparation_s) continue;
      const double dx = f.pose.x_m - s.pose.x_m, dy = f.pose.y_m - s.pose.y_m;
      if (dx * dx + dy * dy > kPairDistance_m * kPairDistance_m) continue;
      if (std::fabs(algorithms::wrap_angle_rad(f.pose.yaw_rad - s.pose.yaw_rad)) > kPairHeading_rad)
        continue;
      pairs.emplace_back(static_cast<std::uint32_t>(first), static_cast<std::uint32_t>(second));
    }
  }
  std::sort(pairs.begin(), pairs.end());
  if (pairs.size() > kMaxPairs) pairs.resize(kMaxPairs);
  algorithms::ColumnGainFit fit;
  for (const auto& [first, second] : pairs)
    fit.add_pair(run.areas[frames[first].index], run.areas[frames[second].index], boards);
  algorithms::ColumnGain gain;
  report.fitted = fit.solve(kMinObservations, gain);
  report.pairs = fit.pairs();
  report.observations = fit.observations();
  report.gain = gain;
  return gain;
}

}  // namespace harmoloc::sim_host::trainer_detail
