#include "harmoloc/sim_host/heading_refinement.hpp"

#include <algorithm>
#include <cmath>

#include "harmoloc/sim_host/board_projection.hpp"
#include "harmoloc/sim_host/lens.hpp"

namespace harmoloc::sim_host {

namespace {

double median_of(std::vector<double>& v) {
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

}  // namespace

std::vector<double> heading_offsets_rad(const SceneGeometryFit& fit,
                                        const std::vector<std::vector<BoardSighting>>& sightings,
                                        const std::vector<double>& time_s,
                                        const BoardFitOptions& fit_options,
                                        const HeadingRefinementOptions& options) {
  const std::size_t frames = time_s.size();
  const LensModel lens(fit.camera);
  // A column's miss as an angle: the pinhole's, near enough where the rounds repeat it.
  const double focal_px = intrinsics_of(fit.camera).focal_px;
  std::vector<double> per_frame(frames, std::nan(""));
  std::vector<double> misses;
  for (std::size_t k = 0; k < frames; ++k) {
    misses.clear();
    for (std::size_t b = 0; b < sightings.size() && b < fit.boards.size(); ++b) {
      if (sightings[b].size() != frames || !fit.boards[b].ok) continue;
      const BoardSighting& s = sightings[b][k];
      if (s.area_px < fit_options.min_area_px) continue;
      const BoardImage im = project_board(fit.camera, lens, fit.boards[b].board, s.pose);
      if (!(im.area_px > 0.0) || im.cut) continue;  // a cut board's centroid is not its own
      // Seen to the right of where the fit puts it: the robot was turned further left.
      const double miss = (s.centroid_u_px - im.centroid_u_px) / focal_px;
      if (std::fabs(miss) <= options.max_miss_rad) misses.push_back(miss);
    }
    if (!misses.empty()) per_frame[k] = median_of(misses);
  }
  std::vector<double> offset(frames, std::nan("")), window, taken;
  std::size_t lo = 0, hi = 0;
  for (std::size_t k = 0; k < frames; ++k) {
    while (lo < k && time_s[lo] < time_s[k] - options.window_s) ++lo;
    while (hi < frames && time_s[hi] <= time_s[k] + options.window_s) ++hi;
    window.clear();
    for (std::size_t j = lo; j < hi; ++j) {
      if (!std::isnan(per_frame[j])) window.push_back(per_frame[j]);
    }
    if (window.size() < options.min_frames) continue;
    offset[k] = median_of(window);
    taken.push_back(offset[k]);
  }
  // A turn every frame shares is the camera's: the labels hold the run's heading.
  const double shared = taken.empty() ? 0.0 : median_of(taken);
  for (double& v : offset) v = std::isnan(v) ? 0.0 : v - shared;
  return offset;
}

HeadingRefinement refine_headings(const SceneGeometryFit& fit,
                                  std::vector<std::vector<BoardSighting>>& sightings,
                                  const std::vector<double>& time_s,
                                  const SceneFitOptions& fit_options,
                                  const HeadingRefinementOptions& options) {
  HeadingRefinement out;
  out.fit = fit;
  out.offset_rad.assign(time_s.size(), 0.0);
  SceneFitOptions again = fit_options;
  again.from_fit = true;
  const auto turn = [&](const std::vector<double>& by, double sign) {
    for (std::vector<BoardSighting>& board : sightings) {
      if (board.size() != by.size()) continue;
      for (std::size_t k = 0; k < by.size(); ++k) board[k].pose.yaw_rad += sign * by[k];
    }
  };
  for (int round = 0; round < options.rounds; ++round) {
    const std::vector<double> step =
        heading_offsets_rad(out.fit, sightings, time_s, fit_options.board, options);
    double sum2 = 0.0;
    for (double v : step) sum2 += v * v;
    const double rms = step.empty() ? 0.0 : std::sqrt(sum2 / static_cast<double>(step.size()));
    if (!(rms >= options.converged_rad)) break;
    turn(step, 1.0);
    std::vector<BoardSpec> starts;
    for (const BoardFit& b : out.fit.boards) starts.push_back(b.board);
    SceneGeometryFit refit = fit_scene_geometry(out.fit.camera, sightings, starts, again);
    if (!refit.ok) {
      turn(step, -1.0);
      break;
    }
    out.fit = std::move(refit);
    for (std::size_t k = 0; k < step.size(); ++k) out.offset_rad[k] += step[k];
    ++out.rounds;
  }
  double sum2 = 0.0;
  for (double v : out.offset_rad) sum2 += v * v;
  if (!out.offset_rad.empty())
    out.rms_offset_rad = std::sqrt(sum2 / static_cast<double>(out.offset_rad.size()));
  return out;
}

}  // namespace harmoloc::sim_host
