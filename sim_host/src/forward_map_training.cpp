#include "harmoloc/sim_host/forward_map_training.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "forward_map_training_parts.hpp"
#include "harmoloc/algorithms/harmonic_localizer.hpp"

namespace harmoloc::sim_host {

using namespace forward_map_training_detail;

ForwardMapReport train_forward_map(const std::vector<std::vector<float>>& features,
                                   const std::vector<std::uint64_t>& timestamps_ns,
                                   const std::vector<dataset::StampedPose>& labels,
                                   const algorithms::HarmonicModel& model, std::size_t board_count,
                                   const ForwardMapOptions& opt, algorithms::ForwardMap& out) {
  ForwardMapReport report;
  if (board_count == 0 || board_count > kMaxBoards)
    throw std::runtime_error("forward map: board count out of range");
  // Do the labels carry a heading? (A label source without orientation writes yaw 0.)
  bool labels_have_yaw = false;
  for (const dataset::StampedPose& l : labels)
    labels_have_yaw = labels_have_yaw || l.pose.yaw_rad != 0.0;

  std::vector<Positioned> frames;
  for (std::size_t i = 0; i < features.size(); ++i) {
    const std::vector<float>& f = features[i];
    bool seen = false;
    for (std::size_t b = 0; b < board_count; ++b) seen = seen || f[b] > 0.0F;
    if (!seen) continue;
    ++report.frames;
    const double t = static_cast<double>(timestamps_ns[i]) * 1e-9;
    // The labels around this frame, if close enough in time to interpolate between.
    const auto next =
        std::lower_bound(labels.begin(), labels.end(), t,
                         [](const dataset::StampedPose& l, double v) { return l.t_s < v; });
    Positioned p{0.0, 0.0, 0.0, t, false, &f, -1.0};
    bool placed = false;
    if (next != labels.end() && std::fabs(next->t_s - t) < 1e-6) {
      p.x_m = next->pose.x_m;
      p.y_m = next->pose.y_m;
      p.yaw_rad = next->pose.yaw_rad;
      placed = true;
    } else if (next != labels.end() && next != labels.begin()) {
      const dataset::StampedPose& a = *(next - 1);
      const dataset::StampedPose& b = *next;
      if (b.t_s - a.t_s <= opt.max_label_gap_s) {
        const double u = (t - a.t_s) / (b.t_s - a.t_s);
        p.x_m = a.pose.x_m + u * (b.pose.x_m - a.pose.x_m);
        p.y_m = a.pose.y_m + u * (b.pose.y_m - a.pose.y_m);
        p.yaw_rad = algorithms::wrap_angle_rad(
            a.pose.yaw_rad + u * algorithms::wrap_angle_rad(b.pose.yaw_rad - a.pose.yaw_rad));
        placed = true;
      }
    }
    if (placed) {
      p.has_yaw = labels_have_yaw;
      ++report.interpolated;
    } else {
      std::array<float, algorithms::HarmonicModel::kMaxFeatures> q{};
      for (std::size_t k = 0; k < model.feature_count; ++k) q[k] = f[model.board_index[k]];
      const algorithms::HarmonicFix fix = algorithms::harmonic_query(model, q);
      if (!fix.known_place) continue;
      p.x_m = fix.x_m;
      p.y_m = fix.y_m;
      ++report.from_harmonic;
    }
    frames.push_back(p);
  }
  report.has_heading = labels_have_yaw;
  return fit_grid(frames, board_count, opt, out, report);
}

ForwardMapReport train_forward_map_placed(const std::vector<std::vector<float>>& features,
                                          const std::vector<PlacedFrame>& placed,
                                          std::size_t board_count, const ForwardMapOptions& opt,
                                          algorithms::ForwardMap& out,
                                          const BearingObservations* bearings) {
  ForwardMapReport report;
  if (board_count == 0 || board_count > kMaxBoards)
    throw std::runtime_error("forward map: board count out of range");
  std::vector<Positioned> frames;
  frames.reserve(placed.size());
  for (const PlacedFrame& f : placed) {
    const std::vector<float>& v = features.at(f.index);
    bool seen = false;
    for (std::size_t b = 0; b < board_count; ++b) seen = seen || v[b] > 0.0F;
    if (!seen) continue;
    ++report.frames;
    ++report.by_odometry;
    const float* bearing = nullptr;
    const float* half_width = nullptr;
    if (bearings != nullptr && f.index < bearings->world_rad.size() &&
        bearings->world_rad[f.index].size() >= board_count) {
      bearing = bearings->world_rad[f.index].data();
      if (f.index < bearings->half_width_rad.size() &&
          bearings->half_width_rad[f.index].size() >= board_count)
        half_width = bearings->half_width_rad[f.index].data();
    }
    frames.push_back(Positioned{f.pose.x_m, f.pose.y_m, f.pose.yaw_rad, f.t_s, true, &v, f.travel_m,
                                bearing, half_width});
  }
  report.has_heading = true;
  const double law[3] = {bearings != nullptr ? bearings->a1_rad : 0.0,
                         bearings != nullptr ? bearings->a3_rad : 0.0,
                         bearings != nullptr ? bearings->axis_rad : 0.0};
  std::vector<double> places(2 * board_count, std::numeric_limits<double>::quiet_NaN());
  if (bearings != nullptr) {
    for (std::size_t b = 0; b < board_count && b < bearings->placements.size(); ++b) {
      if (!bearings->placements[b].placed) continue;
      places[2 * b] = bearings->placements[b].x_m;
      places[2 * b + 1] = bearings->placements[b].y_m;
    }
  }
  return fit_grid(frames, board_count, opt, out, report, bearings != nullptr ? law : nullptr,
                  places.data());
}

}  // namespace harmoloc::sim_host
