// The camera and the boards fitted to the training run (TrainOptions::fit_geometry): every
// placed frame's areas and centroids, from the bearing calibration's board places and a camera
// with the law's field of view. Reported, and with TrainOptions::visibility_from_geometry the
// floor map's visibility tables come from it (forward_map_geometry.hpp).
#include <chrono>
#include <cmath>
#include <string>

#include "harmoloc/sim_host/board_geometry_fit.hpp"
#include "harmoloc/sim_host/trainer.hpp"
#include "trainer_parts.hpp"

namespace harmoloc::sim_host::trainer_detail {

double training_camera_height_m(const AreaSeries& run, const TrainOptions& opt) {
  if (opt.camera_height_m > 0.0) return opt.camera_height_m;
  return run.camera_height_m > 0.0 ? run.camera_height_m : 0.0;  // NaN: unknown
}

GeometryReport fit_training_geometry(const AreaSeries& run, const std::vector<PlacedFrame>& frames,
                                     const algorithms::BearingCalibration& bearings,
                                     const TrainOptions& opt, double camera_height_m) {
  GeometryReport report;
  if (!(camera_height_m > 0.0)) {
    report.skipped =
        "the camera's height is not known (--camera-height-m, or camera.height_m in the "
        "dataset's metadata.toml)";
    return report;
  }
  if (frames.empty()) {
    report.skipped = "the frames were not placed by odometry";
    return report;
  }
  if (!bearings.ok) {
    report.skipped = "the boards could not be placed from their centroid columns";
    return report;
  }
  std::size_t with_rows = 0;
  for (const PlacedFrame& f : frames) with_rows += run.areas[f.index].rows_measured() ? 1U : 0U;
  if (with_rows == 0) {
    report.skipped = "the areas have no row sums (an area log from before them)";
    return report;
  }
  const auto t0 = std::chrono::steady_clock::now();
  CameraSpec camera;
  camera.width_px = run.image_width_px;
  camera.height_px = run.image_height_px;
  // The law's view is the lens's; the pinhole's is a little narrower under a barrel lens, which
  // the fit finds. A generic lens, the principal point at the centre, a pitch of 10 degrees.
  camera.horizontal_fov_deg = 2.0 * bearings.half_fov_rad() * 180.0 / algorithms::kPi;
  camera.k1 = -0.15;
  camera.k2 = camera.k3 = camera.p1 = camera.p2 = 0.0;
  camera.principal_offset_x_px = camera.principal_offset_y_px = 0.0;
  camera.pitch_deg = 10.0;
  camera.height_m = camera_height_m;
  const double forward = !std::isnan(opt.forward.camera_forward_m) ? opt.forward.camera_forward_m
                                                                   : run.camera_forward_m;
  camera.forward_offset_m = std::isnan(forward) ? 0.1 : forward;
  camera.mount_yaw_deg = 0.0;
  report.camera_start = camera;

  const std::size_t boards = bearings.placements.size();
  std::vector<std::vector<BoardSighting>> sightings(boards);
  std::vector<std::size_t> frame_of;  // each sighting's frame in frames
  std::vector<double> time_s;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const PlacedFrame& f = frames[i];
    const algorithms::AreaVector& a = run.areas[f.index];
    if (!a.rows_measured() || !a.columns_measured()) continue;
    frame_of.push_back(i);
    time_s.push_back(f.t_s);
    for (std::size_t b = 0; b < boards; ++b) {
      if (b >= a.count) {  // one entry a frame for every board
        sightings[b].push_back({f.pose, 0.0, 0.0, 0.0});
        continue;
      }
      sightings[b].push_back({f.pose, static_cast<double>(a.pixels[b]), a.centroid_column_px(b),
                              a.centroid_row_px(b)});
    }
  }
  // The residual scales are a 320 x 240 frame's. A larger frame's centroids are finer in its own
  // pixels (more of them on each board's edge), and those tight scales fitted closer there: taken
  // to the frame's size on the 21 random floors at 640 x 480 and 1280 x 720, the floor roams'
  // RMSE went from 12.5 to 15.0 cm median on the 1280 x 720 ones (10.7 to 10.2 on the 640 x 480
  // ones; docs/sweep.md, 2026-12-04 (later)). So they are tried first, and the frame's scales
  // only when they leave fewer than two boards fitted (random floor 3, where two thirds of the
  // sightings fell beyond the robust threshold).
  const auto fit_with = [&](const SceneFitOptions& options) {
    const LensModel lens(camera);
    std::vector<BoardSpec> starts(boards);
    for (std::size_t b = 0; b < boards; ++b) {
      const algorithms::BoardPlacement& p = bearings.placements[b];
      BoardSpec like;
      like.name = "board" + std::to_string(b + 1);
      like.width_m = like.height_m = 0.5;
      like.centre_z_m = camera.height_m;
      if (!p.placed) {
        starts[b] = like;
        continue;
      }
      starts[b] =
          start_board_geometry(camera, lens, sightings[b], p.x_m, p.y_m, like, options.board);
    }
    return fit_scene_geometry(camera, sightings, starts, options);
  };
  for (std::size_t b = 0; b < boards; ++b) {
    if (!bearings.placements[b].placed) sightings[b].clear();  // no place to start from
  }
  report.fit = fit_with(opt.geometry_fit);
  const bool reference_frame = camera.width_px == kBoardFitReferenceWidthPx &&
                               camera.height_px == kBoardFitReferenceHeightPx;
  const auto frame_options_of = [&](SceneFitOptions o) {
    o.board = for_frame(o.board, camera.width_px, camera.height_px);
    return o;
  };
  if (!report.fit.ok && !reference_frame) {
    report.fit = fit_with(frame_options_of(opt.geometry_fit));
    report.frame_scales = true;
  }
  if (opt.refine_headings && report.fit.ok) {
    const SceneFitOptions& used =
        report.frame_scales ? frame_options_of(opt.geometry_fit) : opt.geometry_fit;
    HeadingRefinement r =
        refine_headings(report.fit, sightings, time_s, used, opt.heading_refinement);
    report.fit = std::move(r.fit);
    report.heading_rounds = r.rounds;
    report.heading_offset_rms_rad = r.rms_offset_rad;
    report.heading_offset_rad.assign(frames.size(), 0.0);
    for (std::size_t k = 0; k < frame_of.size(); ++k)
      report.heading_offset_rad[frame_of[k]] = r.offset_rad[k];
  }
  report.tried = true;
  report.ms = ms_since(t0);
  return report;
}

}  // namespace harmoloc::sim_host::trainer_detail
