#include "harmoloc/sim_host/forward_map_training.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "harmoloc/algorithms/harmonic_localizer.hpp"

namespace harmoloc::sim_host {

namespace {

using algorithms::ForwardMap;
using algorithms::kMaxBoards;

struct Positioned {
  double x_m, y_m, yaw_rad, t_s;
  bool has_yaw;
  const std::vector<float>* features;
  double travel_m;  // < 0: unknown (then passes are told apart by time)
};

// Whether @p p is of the same pass as a frame at (@p t_s, @p travel_m), for validation.
bool same_pass(const Positioned& p, double t_s, double travel_m, double exclude_s,
               double exclude_m) {
  if (travel_m >= 0.0 && p.travel_m >= 0.0) return std::fabs(p.travel_m - travel_m) < exclude_m;
  return std::fabs(p.t_s - t_s) < exclude_s;
}

// Kernel-weighted mean of the frames' features at (x, y); weights relative to the nearest
// frame, so that a place far from every frame takes its nearest frames' values. Frames within
// @p exclude_s of @p t_s are left out (validation against other passes). Returns false when
// no frame is left.
bool kernel_mean(const std::vector<Positioned>& frames, double x, double y, double bandwidth_m,
                 std::size_t boards, double t_s, double travel_m, double exclude_s,
                 double exclude_m, double* out) {
  const bool exclude = exclude_s > 0.0 || exclude_m > 0.0;
  double d2_min = std::numeric_limits<double>::infinity();
  for (const Positioned& p : frames) {
    if (exclude && same_pass(p, t_s, travel_m, exclude_s, exclude_m)) continue;
    d2_min = std::min(d2_min, (p.x_m - x) * (p.x_m - x) + (p.y_m - y) * (p.y_m - y));
  }
  if (!std::isfinite(d2_min)) return false;
  const double inv = 0.5 / (bandwidth_m * bandwidth_m);
  double sum_w = 0.0;
  for (std::size_t b = 0; b < boards; ++b) out[b] = 0.0;
  for (const Positioned& p : frames) {
    if (exclude && same_pass(p, t_s, travel_m, exclude_s, exclude_m)) continue;
    const double e = ((p.x_m - x) * (p.x_m - x) + (p.y_m - y) * (p.y_m - y) - d2_min) * inv;
    if (e > 30.0) continue;
    const double w = std::exp(-e);
    sum_w += w;
    for (std::size_t b = 0; b < boards; ++b) out[b] += w * static_cast<double>((*p.features)[b]);
  }
  for (std::size_t b = 0; b < boards; ++b) out[b] /= sum_w;
  return true;
}

}  // namespace

namespace {

// Fits the grid to frames that already have a position (shared by both ways of placing them).
ForwardMapReport fit_grid(std::vector<Positioned>& frames, std::size_t board_count,
                          const ForwardMapOptions& opt, algorithms::ForwardMap& out,
                          ForwardMapReport report);

}  // namespace

ForwardMapReport train_forward_map(const std::vector<std::vector<float>>& features,
                                   const std::vector<std::uint64_t>& timestamps_ns,
                                   const std::vector<StampedPose>& labels,
                                   const algorithms::HarmonicModel& model, std::size_t board_count,
                                   const ForwardMapOptions& opt, algorithms::ForwardMap& out) {
  ForwardMapReport report;
  if (board_count == 0 || board_count > kMaxBoards)
    throw std::runtime_error("forward map: board count out of range");
  // Do the labels carry a heading? (A label source without orientation writes yaw 0.)
  bool labels_have_yaw = false;
  for (const StampedPose& l : labels) labels_have_yaw = labels_have_yaw || l.pose.yaw_rad != 0.0;

  std::vector<Positioned> frames;
  for (std::size_t i = 0; i < features.size(); ++i) {
    const std::vector<float>& f = features[i];
    bool seen = false;
    for (std::size_t b = 0; b < board_count; ++b) seen = seen || f[b] > 0.0F;
    if (!seen) continue;
    ++report.frames;
    const double t = static_cast<double>(timestamps_ns[i]) * 1e-9;
    // The labels around this frame, if close enough in time to interpolate between.
    const auto next = std::lower_bound(labels.begin(), labels.end(), t,
                                       [](const StampedPose& l, double v) { return l.t_s < v; });
    Positioned p{0.0, 0.0, 0.0, t, false, &f, -1.0};
    bool placed = false;
    if (next != labels.end() && std::fabs(next->t_s - t) < 1e-6) {
      p.x_m = next->pose.x_m;
      p.y_m = next->pose.y_m;
      p.yaw_rad = next->pose.yaw_rad;
      placed = true;
    } else if (next != labels.end() && next != labels.begin()) {
      const StampedPose& a = *(next - 1);
      const StampedPose& b = *next;
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
                                          algorithms::ForwardMap& out) {
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
    frames.push_back(
        Positioned{f.pose.x_m, f.pose.y_m, f.pose.yaw_rad, f.t_s, true, &v, f.travel_m});
  }
  report.has_heading = true;
  return fit_grid(frames, board_count, opt, out, report);
}

namespace {

ForwardMapReport fit_grid(std::vector<Positioned>& frames, std::size_t board_count,
                          const ForwardMapOptions& opt, algorithms::ForwardMap& out,
                          ForwardMapReport report) {
  if (frames.size() < 8) {
    throw std::runtime_error("forward map: only " + std::to_string(frames.size()) +
                             " frames could be positioned (at least 8 needed)");
  }

  // Which boards change at all: a board never seen (or always the same) is not modelled.
  std::vector<bool> modelled(board_count, false);
  for (std::size_t b = 0; b < board_count; ++b) {
    float lo = std::numeric_limits<float>::infinity(), hi = -lo;
    for (const Positioned& p : frames) {
      lo = std::min(lo, (*p.features)[b]);
      hi = std::max(hi, (*p.features)[b]);
    }
    modelled[b] = hi > lo;
  }

  // Kernel width: the candidate whose prediction of each frame from other passes fits best.
  std::vector<double> mean(board_count);
  double best = std::numeric_limits<double>::infinity();
  std::vector<double> best_sq;
  // Frames with another pass close by in position: within twice the median distance from a
  // frame to the nearest frame of another pass. Elsewhere (the turn at the end of a route driven
  // once each way) leaving the own pass out leaves nothing near, and the residual would measure
  // extrapolation, not the noise a new run over the same place shows.
  std::vector<char> comparable(frames.size(), 0);
  {
    std::vector<double> nearest(frames.size(), std::numeric_limits<double>::infinity());
    for (std::size_t i = 0; i < frames.size(); ++i) {
      const Positioned& p = frames[i];
      double closest = std::numeric_limits<double>::infinity();
      for (const Positioned& q : frames) {
        if (same_pass(q, p.t_s, p.travel_m, opt.exclude_same_pass_s, opt.exclude_same_pass_m))
          continue;
        closest =
            std::min(closest, (q.x_m - p.x_m) * (q.x_m - p.x_m) + (q.y_m - p.y_m) * (q.y_m - p.y_m));
      }
      nearest[i] = std::sqrt(closest);
    }
    std::vector<double> finite;
    for (double d : nearest) {
      if (std::isfinite(d)) finite.push_back(d);
    }
    if (!finite.empty()) {
      auto mid = finite.begin() + static_cast<std::ptrdiff_t>(finite.size() / 2);
      std::nth_element(finite.begin(), mid, finite.end());
      report.pass_spread_m = *mid;
      const double bound = std::max(2.0 * *mid, 0.01);
      for (std::size_t i = 0; i < frames.size(); ++i) comparable[i] = nearest[i] <= bound ? 1 : 0;
    }
  }
  for (double h : opt.bandwidths_m) {
    std::vector<double> sq(board_count, 0.0);
    std::size_t n = 0;
    for (std::size_t i = 0; i < frames.size(); ++i) {
      const Positioned& p = frames[i];
      if (!comparable[i]) continue;
      if (!kernel_mean(frames, p.x_m, p.y_m, h, board_count, p.t_s, p.travel_m,
                       opt.exclude_same_pass_s, opt.exclude_same_pass_m, mean.data())) {
        continue;
      }
      ++n;
      for (std::size_t b = 0; b < board_count; ++b) {
        const double r = static_cast<double>((*p.features)[b]) - mean[b];
        sq[b] += r * r;
      }
    }
    if (n == 0) continue;
    double total = 0.0;
    std::size_t used = 0;
    for (std::size_t b = 0; b < board_count; ++b) {
      sq[b] /= static_cast<double>(n);
      if (modelled[b]) {
        total += sq[b];
        ++used;
      }
    }
    total = used > 0 ? total / static_cast<double>(used) : 0.0;
    if (total < best) {
      best = total;
      report.bandwidth_m = h;
      best_sq = sq;
    }
  }
  if (best_sq.empty()) {
    // A single pass: no other pass to validate against; the smallest width, noise from itself.
    report.bandwidth_m = opt.bandwidths_m.front();
    best_sq.assign(board_count, 0.0);
    for (const Positioned& p : frames) {
      kernel_mean(frames, p.x_m, p.y_m, report.bandwidth_m, board_count, p.t_s, -1.0, 0.0, 0.0,
                  mean.data());
      for (std::size_t b = 0; b < board_count; ++b) {
        const double r = static_cast<double>((*p.features)[b]) - mean[b];
        best_sq[b] += r * r / static_cast<double>(frames.size());
      }
    }
    best = 0.0;
    for (std::size_t b = 0; b < board_count; ++b) best += best_sq[b];
    best /= static_cast<double>(board_count);
  }
  report.validation_rmse = std::sqrt(best);

  // The grid over the training positions.
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  for (const Positioned& p : frames) {
    x0 = std::min(x0, p.x_m);
    y0 = std::min(y0, p.y_m);
    x1 = std::max(x1, p.x_m);
    y1 = std::max(y1, p.y_m);
  }
  x0 -= opt.margin_m;
  y0 -= opt.margin_m;
  x1 += opt.margin_m;
  y1 += opt.margin_m;
  double cell = opt.min_cell_m;
  const auto cells_along = [&](double extent) {
    return static_cast<std::size_t>(std::ceil(extent / cell)) + 1U;
  };
  while (cells_along(x1 - x0) * cells_along(y1 - y0) > ForwardMap::kMaxCells ||
         cells_along(x1 - x0) > ForwardMap::kMaxDimension ||
         cells_along(y1 - y0) > ForwardMap::kMaxDimension) {
    cell *= 1.05;
  }
  out = ForwardMap{};
  out.columns = static_cast<std::uint32_t>(cells_along(x1 - x0));
  out.rows = static_cast<std::uint32_t>(cells_along(y1 - y0));
  out.origin_x_m = static_cast<float>(x0);
  out.origin_y_m = static_cast<float>(y0);
  out.cell_m = static_cast<float>(cell);
  out.board_count = static_cast<std::uint32_t>(board_count);
  report.sigma.assign(board_count, 0.0);
  for (std::size_t b = 0; b < board_count; ++b) {
    if (!modelled[b]) continue;
    // A floor: a board whose frames agree perfectly must still not make the filter certain.
    double peak = 0.0;
    for (const Positioned& p : frames) peak = std::max(peak, static_cast<double>((*p.features)[b]));
    report.sigma[b] = std::max(std::sqrt(best_sq[b]), std::max(1e-3 * peak, 1e-4));
    out.sigma[b] = static_cast<float>(report.sigma[b]);
  }
  out.has_heading = report.has_heading;
  for (std::uint32_t r = 0; r < out.rows; ++r) {
    for (std::uint32_t c = 0; c < out.columns; ++c) {
      const double x = x0 + c * cell, y = y0 + r * cell;
      kernel_mean(frames, x, y, report.bandwidth_m, board_count, 0.0, -1.0, 0.0, 0.0, mean.data());
      float* e = out.cell(c, r);
      for (std::size_t b = 0; b < board_count; ++b)
        e[b] = modelled[b] ? static_cast<float>(mean[b]) : 0.0F;
      double d2 = 1e300, yaw_d2 = 1e300;
      float yaw = 0.0F;
      for (const Positioned& p : frames) {
        const double d = (p.x_m - x) * (p.x_m - x) + (p.y_m - y) * (p.y_m - y);
        d2 = std::min(d2, d);
        if (p.has_yaw && d < yaw_d2) {
          yaw_d2 = d;
          yaw = static_cast<float>(p.yaw_rad);
        }
      }
      const std::size_t index = static_cast<std::size_t>(r) * out.columns + c;
      out.route_distance_m[index] = static_cast<float>(std::sqrt(d2));
      out.heading_rad[index] = yaw;
    }
  }
  return report;
}

}  // namespace

}  // namespace harmoloc::sim_host
