#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>

#include "harmoloc/algorithms/kernel_selection.hpp"
#include "harmoloc/algorithms/local_fix_error.hpp"
#include "harmoloc/algorithms/route_placement.hpp"
#include "harmoloc/sim_host/lens.hpp"
#include "harmoloc/sim_host/trainer.hpp"
#include "trainer_parts.hpp"

namespace harmoloc::sim_host {

namespace trainer_detail {

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

double quantile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())))];
}

}  // namespace trainer_detail

namespace {

double rms(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x * x;
  return v.empty() ? 0.0 : std::sqrt(s / static_cast<double>(v.size()));
}

// Where in the frame the placed frames saw the boards that give a bearing: the deciles 10-90%
// of their centroid rows, as fractions of the height (0 the top row). Under the camera's pitch a
// column's direction changes with the row, and the column-to-angle law fitted at these rows is
// the one the boards are seen under (column_law_of). Empty with fewer than 20 such sightings.
std::vector<double> seen_rows(const std::vector<algorithms::AreaVector>& areas,
                              const std::vector<PlacedFrame>& frames) {
  std::vector<double> rows;
  for (const PlacedFrame& f : frames) {
    const algorithms::AreaVector& a = areas[f.index];
    if (!a.rows_measured() || a.height_px < 2) continue;
    for (std::size_t b = 0; b < a.count; ++b) {
      if (algorithms::gives_bearing(a, b))
        rows.push_back(a.centroid_row_px(b) / static_cast<double>(a.height_px - 1));
    }
  }
  if (rows.size() < 20) return {};
  std::sort(rows.begin(), rows.end());  // once, for all nine (as trainer_detail::quantile picks)
  std::vector<double> deciles;
  for (int k = 1; k <= 9; ++k)
    deciles.push_back(rows[std::min(
        rows.size() - 1, static_cast<std::size_t>(0.1 * k * static_cast<double>(rows.size())))]);
  return deciles;
}

}  // namespace

using trainer_detail::check_labels;
using trainer_detail::ms_since;
using trainer_detail::place_frames;
using trainer_detail::quantile;
using trainer_detail::report_board_steps;
using trainer_detail::train_from_labels;

TrainReport train_on_areas(const AreaSeries& run, const std::vector<dataset::StampedPose>& labels,
                           const TrainOptions& opt, algorithms::MapFile& map) {
  check_labels(labels);
  TrainReport report;
  report.segment_ms = run.segment_ms;
  report.frames = run.areas.size();
  if (labels.empty()) throw std::runtime_error("no labels");
  if (run.areas.empty()) throw std::runtime_error("the run has no frames");
  const double camera_height_m = trainer_detail::training_camera_height_m(run, opt);
  if (opt.visibility_from_geometry && opt.geometry_tables_required && !(camera_height_m > 0.0)) {
    throw std::runtime_error(
        "--visibility-from-geometry: the camera's height is not known (give --camera-height-m "
        "H, or camera.height_m in the dataset's metadata.toml)");
  }
  const std::size_t boards = opt.thresholds.count;
  const float area_scale = 100.0F / static_cast<float>(run.image_width_px * run.image_height_px);
  std::vector<std::vector<float>> all(run.areas.size(), std::vector<float>(boards, 0.0F));
  for (std::size_t i = 0; i < run.areas.size(); ++i) {
    for (std::size_t b = 0; b < boards; ++b)
      all[i][b] = static_cast<float>(run.areas[i].pixels[b]) * area_scale;
  }
  const bool with_odometry =
      opt.use_odometry && !run.odometry.empty() && opt.method == TrainMethod::kNeighbourGraph;
  // Each board's centroid-column feature (HarmonicModel::columns), where the run measured them;
  // only the placed path with column features asked for uses them.
  bool columns_measured = true;
  for (const algorithms::AreaVector& a : run.areas)
    columns_measured = columns_measured && a.columns_measured();
  const bool want_columns = with_odometry && opt.column_features && columns_measured &&
                            algorithms::HarmonicModel::kHoldsColumns;
  std::vector<std::vector<float>> all_columns(want_columns ? run.areas.size() : 0,
                                              std::vector<float>(boards, 0.0F));
  for (std::size_t i = 0; i < all_columns.size(); ++i) {
    const algorithms::AreaVector& a = run.areas[i];
    for (std::size_t b = 0; b < boards; ++b) {
      if (a.pixels[b] > 0)
        all_columns[i][b] =
            algorithms::column_feature(a.centroid_column_px(b), a.width_px, all[i][b]);
    }
  }
  if (!with_odometry) {
    train_from_labels(run, labels, opt, map, report);
    if (opt.forward_map) {
      const auto t_forward = std::chrono::steady_clock::now();
      report.forward = train_forward_map(all, run.timestamp_ns, labels, map.model, boards,
                                         opt.forward, map.forward);
      report.has_forward_map = true;
      report.forward_ms = ms_since(t_forward);
    }
    return report;
  }

  const auto t_train = std::chrono::steady_clock::now();
  PlacementReport& pr = report.placement;
  const algorithms::PlacementResult placed = place_frames(run, labels, opt, pr);
  // The stretch the labels cover, and how far beyond it the odometry may carry a frame.
  std::vector<PlacedFrame> frames;
  pr.poses = placed.poses;
  for (std::uint64_t t : run.timestamp_ns)
    pr.times_s.push_back(static_cast<double>(t / 1000000000ULL) +
                         static_cast<double>(t % 1000000000ULL) * 1e-9);
  pr.placed.assign(run.areas.size(), false);
  for (std::size_t i = 0; i < run.areas.size(); ++i) {
    bool seen = false;
    for (std::size_t b = 0; b < boards; ++b) seen = seen || run.areas[i].pixels[b] > 0;
    if (!seen) {
      ++report.empty_frames;
      continue;
    }
    if (placed.support_m[i] > opt.max_extrapolation_m) {
      ++pr.beyond_labels;
      continue;
    }
    pr.placed[i] = true;
    frames.push_back(
        PlacedFrame{i, static_cast<double>(run.timestamp_ns[i] - run.timestamp_ns[0]) * 1e-9,
                    placed.travel_m[i], placed.poses[i]});
  }
  pr.frames = frames.size();
  if (frames.size() < 16)
    throw std::runtime_error("only " + std::to_string(frames.size()) +
                             " frames with a board in view lie within the labelled stretch");

  // The area's gain by column, from the run's own passes: the harmonic samples have it removed,
  // as every query will (areas_to_features()). The forward map and the column features keep
  // the plain areas.
  algorithms::ColumnGain column_gain;
  if (opt.column_gain && columns_measured)
    column_gain = trainer_detail::fit_column_gain(run, frames, boards, report.column_gain);
  std::vector<std::vector<float>> gain_removed;
  if (column_gain.present()) {
    gain_removed = all;
    for (std::size_t i = 0; i < all.size(); ++i) {
      for (std::size_t b = 0; b < boards; ++b)
        gain_removed[i][b] =
            algorithms::remove_column_gain(column_gain, run.areas[i], b, all[i][b]);
    }
  }
  const std::vector<std::vector<float>>& harmonic = column_gain.present() ? gain_removed : all;

  // The harmonic map over every placed frame: samples and held-out queries evenly spread.
  const std::vector<int> candidates = trainer_detail::candidate_boards(opt.boards, boards);
  const auto pick = [](std::size_t total, std::size_t want) {
    std::vector<std::size_t> out;
    want = std::min(want, total);
    for (std::size_t k = 0; k < want; ++k) out.push_back((k * total + total / 2) / want);
    return out;
  };
  const auto fill = [&](const std::vector<std::size_t>& which) {
    algorithms::PlacedSamples s;
    s.features.resize(static_cast<Eigen::Index>(which.size()),
                      static_cast<Eigen::Index>(candidates.size()));
    s.xy.resize(static_cast<Eigen::Index>(which.size()), 2);
    // Without columns the matrix stays empty: the kernel then compares areas only.
    if (want_columns) s.columns.resize(s.features.rows(), s.features.cols());
    for (std::size_t r = 0; r < which.size(); ++r) {
      const PlacedFrame& f = frames[which[r]];
      for (std::size_t c = 0; c < candidates.size(); ++c) {
        const auto board = static_cast<std::size_t>(candidates[c]);
        s.features(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) =
            static_cast<double>(harmonic[f.index][board]);
        if (want_columns)
          s.columns(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) =
              static_cast<double>(all_columns[f.index][board]);
      }
      s.xy(static_cast<Eigen::Index>(r), 0) = f.pose.x_m;
      s.xy(static_cast<Eigen::Index>(r), 1) = f.pose.y_m;
      s.travel_m.push_back(f.travel_m);
    }
    return s;
  };
  const std::vector<std::size_t> sample_rows = pick(
      frames.size(),
      static_cast<std::size_t>(std::clamp(
          opt.max_placed_samples, 16, static_cast<int>(algorithms::HarmonicModel::kMaxSamples))));
  const algorithms::PlacedSamples samples = fill(sample_rows);
  const algorithms::PlacedSamples queries =
      fill(pick(frames.size(), static_cast<std::size_t>(std::max(opt.max_cv_queries, 16))));
  algorithms::KernelSelectionOptions ko;
  ko.same_pass_m = opt.same_pass_m;
  ko.select_features = opt.select_boards && opt.boards.empty();
  if (!opt.local_linear) ko.local_linear_ridges.clear();
  algorithms::KernelSelection sel = algorithms::select_kernel_model(samples, queries, ko);

  // The same with each board's feature in units of its noise (the forward map measures it
  // against other passes): a large board's few percent of noise then no longer drowns a small
  // board's informative change. Kept where cross-validation prefers it.
  std::vector<double> scale(candidates.size(), 1.0);
  const auto forward = std::make_unique<algorithms::ForwardMap>();
  bool have_forward = false;
  ForwardMapReport forward_report;
  double forward_ms = 0.0;
  // Where the boards stand and the lens's column-to-angle law, from the placed frames' centroid
  // columns; with the law, every frame's world bearing of each board for the forward map.
  const auto t_bearings = std::chrono::steady_clock::now();
  // The boards placed from the frames' poses as they stand (the placement's, or the refined).
  const auto bearings_from_frames = [&] {
    std::vector<algorithms::BearingFrame> bearing_frames;
    for (const PlacedFrame& f : frames) {
      if (run.areas[f.index].columns_measured())
        bearing_frames.push_back({f.pose, run.areas[f.index]});
    }
    return bearing_frames.empty() ? algorithms::BearingCalibration{}
                                  : algorithms::calibrate_bearings(bearing_frames);
  };
  report.bearings = bearings_from_frames();
  report.bearings_ms = ms_since(t_bearings);
  // TrainOptions::refine_headings: the frames take the headings the geometry fit refined, for
  // all that is trained after it, and the boards are placed again from them.
  const auto take_headings = [&](const GeometryReport& g) {
    if (g.heading_rounds == 0 || g.heading_offset_rad.size() != frames.size()) return false;
    for (std::size_t i = 0; i < frames.size(); ++i) {
      PlacedFrame& f = frames[i];
      f.pose.yaw_rad = algorithms::wrap_angle_rad(f.pose.yaw_rad + g.heading_offset_rad[i]);
      pr.poses[f.index].yaw_rad = f.pose.yaw_rad;
    }
    algorithms::BearingCalibration again = bearings_from_frames();
    if (again.ok) report.bearings = std::move(again);
    return true;
  };
  if (opt.fit_geometry) {
    report.geometry =
        trainer_detail::fit_training_geometry(run, frames, report.bearings, opt, camera_height_m);
    take_headings(report.geometry);
  }
  const bool with_bearings = opt.bearings && report.bearings.ok;
  // Every placed frame's world bearing of each board under the law (a1, a3), for the forward map.
  const auto observations_under = [&](double a1_rad, double a3_rad, double axis_rad) {
    BearingObservations o;
    o.a1_rad = a1_rad;
    o.a3_rad = a3_rad;
    o.axis_rad = axis_rad;
    o.placements = report.bearings.placements;
    o.world_rad.resize(run.areas.size());
    o.half_width_rad.resize(run.areas.size());
    algorithms::BearingCalibration under;
    under.a1_rad = a1_rad;
    under.a3_rad = a3_rad;
    for (const PlacedFrame& f : frames) {
      const algorithms::AreaVector& a = run.areas[f.index];
      std::vector<float>& out = o.world_rad[f.index];
      std::vector<float>& half = o.half_width_rad[f.index];
      out.assign(boards, std::numeric_limits<float>::quiet_NaN());
      half.assign(boards, 0.0F);
      for (std::size_t b = 0; b < boards; ++b) {
        if (!algorithms::gives_bearing(a, b)) continue;
        out[b] = static_cast<float>(algorithms::wrap_angle_rad(
            f.pose.yaw_rad - under.angle_rad(a.centroid_column_px(b), a.width_px)));
        // A board about as wide as high spans the square root of its pixels in columns.
        half[b] = static_cast<float>(0.5 * std::fabs(a1_rad) *
                                     std::sqrt(static_cast<double>(a.pixels[b])) /
                                     static_cast<double>(a.width_px));
      }
    }
    return o;
  };
  BearingObservations observations;
  if (with_bearings)
    observations = observations_under(report.bearings.a1_rad, report.bearings.a3_rad, 0.0);
  if (opt.forward_map) {
    const auto t_forward = std::chrono::steady_clock::now();
    ForwardMapOptions forward_opt = opt.forward;
    if (std::isnan(forward_opt.camera_forward_m))
      forward_opt.camera_forward_m = run.camera_forward_m;
    forward_report = train_forward_map_placed(all, frames, boards, forward_opt, *forward,
                                              with_bearings ? &observations : nullptr);
    // The fit takes seconds: only for a map whose tables it fills (a floor's), unless asked.
    if (opt.visibility_from_geometry && (opt.fit_geometry || forward->has_visibility)) {
      GeometryReport& g = report.geometry;
      bool turned = false;
      if (!opt.fit_geometry) {
        g = trainer_detail::fit_training_geometry(run, frames, report.bearings, opt,
                                                  camera_height_m);
        turned = take_headings(g);
      }
      g.tables_asked = true;
      // The law triangulated from the frames leaves out the optical axis's offset and the
      // camera's place ahead of the axle (calibrate_bearings), and bends a1 and a3 to make up for
      // them: on random floor 1 (the principal point 25 px left of the centre) a board's bearing
      // at the truth was off by +1.2 degrees at the frame's left edge and by 0 at its right. The
      // fitted camera's law has neither error, and the forward map is trained again with it:
      // its bearings, and its visibility tables from the kernel or the geometry, their angle
      // gain centred on the camera's optical axis (the law's angles start at the centre column).
      const bool fitted = g.tried && g.fit.ok;
      const std::vector<double> rows =
          fitted ? seen_rows(run.areas, frames) : std::vector<double>{};
      const ColumnLaw law = fitted ? column_law_of(g.fit.camera, rows) : ColumnLaw{};
      const bool law_taken =
          opt.law_from_geometry && with_bearings && forward->has_visibility && law.ok;
      if (law_taken || turned) {
        auto first = std::make_unique<algorithms::ForwardMap>(*forward);
        const ForwardMapReport first_report = forward_report;
        if (with_bearings)
          observations =
              law_taken ? observations_under(law.a1_rad, law.a3_rad, law.optical_axis_rad)
                        : observations_under(report.bearings.a1_rad, report.bearings.a3_rad, 0.0);
        forward_report = train_forward_map_placed(all, frames, boards, forward_opt, *forward,
                                                  with_bearings ? &observations : nullptr);
        if (!forward->has_visibility) {  // the same frames under another law lost the visibility
          *forward = *first;
          forward_report = first_report;
        } else if (law_taken) {
          g.law_from_camera = true;
          g.law_a1_rad = law.a1_rad;
          g.law_a3_rad = law.a3_rad;
          g.law_axis_rad = static_cast<double>(forward->visibility_axis_rad);
          g.law_rows = rows;
        }
      }
      if (g.tried) {
        g.tables = visibility_from_geometry(g.fit, run.areas, frames, area_scale, *forward,
                                            opt.geometry_tables);
        // With projected areas, every board the fit holds is offered an outline, not only those
        // whose tables the geometry serves: a board the frame's side often cuts loses the
        // tables' contest (the cells' view of a cut board is coarse) while its projection, which
        // clips the outline to the frame, may predict its areas many times closer than either
        // table (random floor 27, board 5: 0.006 against 0.17). It keeps the outline only where
        // its areas are taken (below).
        std::vector<char> outlined = g.tables.from_geometry;
        if (opt.projected_areas) {
          for (std::size_t b = 0; b < outlined.size() && b < g.fit.boards.size(); ++b)
            outlined[b] = outlined[b] != 0 || g.fit.boards[b].ok ? 1 : 0;
        }
        if (opt.projected_bearings && g.tables.applied)
          g.projected_boards = project_bearings_from_geometry(g.fit, outlined, *forward);
        if (g.projected_boards > 0) {
          // The projection is weighed by its own miss, not the cells' (a board's projection may
          // hold to a fifth of the cells' spread, or miss by twice it). A board with too few
          // frames (0) keeps the cells' spread.
          g.projected_spread_rad = projected_bearing_spread(*forward, run.areas, frames);
          for (std::size_t b = 0; b < g.projected_spread_rad.size(); ++b)
            forward->projection.sigma_rad[b] = static_cast<float>(g.projected_spread_rad[b]);
          if (opt.projected_areas) {
            g.projected_area_sigma =
                project_areas_from_geometry(run.areas, frames, area_scale, *forward);
            g.projected_boards -= drop_untaken_outlines(g.tables.from_geometry, *forward);
            for (std::size_t b = 0; b < g.projected_spread_rad.size(); ++b)
              if (forward->projection.points[b] == 0U) g.projected_spread_rad[b] = 0.0;
            g.projected_area_taken.assign(g.projected_area_sigma.size(), 0);
            for (std::size_t b = 0; b < g.projected_area_sigma.size(); ++b) {
              g.projected_area_taken[b] = algorithms::projects_area(*forward, b) ? 1 : 0;
              g.projected_area_boards += g.projected_area_taken[b] != 0 ? 1U : 0U;
            }
          }
        }
      } else
        g.tables.skipped = "the geometry was not fitted: " + g.skipped;
    }
    forward_ms = ms_since(t_forward);
    have_forward = true;
  }
  if (have_forward && opt.noise_weighted_kernel) {
    const ForwardMapReport& noise = forward_report;
    double largest = 0.0;
    for (std::size_t c = 0; c < candidates.size(); ++c) {
      // The harmonic map sees no heading: its noise is the areas' spread over every heading
      // (the forward map's without heading terms).
      const double sigma = noise.heading_blind_sigma[static_cast<std::size_t>(candidates[c])];
      scale[c] = sigma > 0.0 ? 1.0 / sigma : 0.0;
      largest = std::max(largest, scale[c]);
    }
    if (largest > 0.0) {
      for (double& v : scale) v = v > 0.0 ? v / largest : 1.0;  // kernel weights scale^2 <= 1
      const auto scaled = [&](algorithms::PlacedSamples s) {
        for (std::size_t c = 0; c < candidates.size(); ++c)
          s.features.col(static_cast<Eigen::Index>(c)) *= scale[c];
        return s;
      };
      algorithms::KernelSelection weighted =
          algorithms::select_kernel_model(scaled(samples), scaled(queries), ko);
      if (weighted.x.cv_mse + weighted.y.cv_mse < sel.x.cv_mse + sel.y.cv_mse) {
        sel = std::move(weighted);
        report.noise_weighted = true;
      }
    }
  }
  if (!report.noise_weighted) std::fill(scale.begin(), scale.end(), 1.0);

  // The boards' centroid columns in the kernel, over the chosen boards: at a turn, two places
  // can show the same amounts of each board with the boards at other columns. Each column is
  // weighed by the square root of its board's kernel weight (HarmonicModel::column_weight); the
  // weight CV prefers is kept where it improves x + y by options.min_improvement.
  if (want_columns) {
    report.areas_only_cv_rmse_x_m = std::sqrt(sel.x.cv_mse);
    report.areas_only_cv_rmse_y_m = std::sqrt(sel.y.cv_mse);
    const auto restricted = [&](const algorithms::PlacedSamples& s) {
      algorithms::PlacedSamples r;
      r.features.resize(s.features.rows(), static_cast<Eigen::Index>(sel.columns.size()));
      r.columns.resizeLike(r.features);
      for (std::size_t i = 0; i < sel.columns.size(); ++i) {
        const auto c = static_cast<std::size_t>(sel.columns[i]);
        r.features.col(static_cast<Eigen::Index>(i)) =
            s.features.col(static_cast<Eigen::Index>(c)) * scale[c];
        r.columns.col(static_cast<Eigen::Index>(i)) =
            s.columns.col(static_cast<Eigen::Index>(c)) * std::sqrt(scale[c]);
      }
      r.xy = s.xy;
      r.travel_m = s.travel_m;
      return r;
    };
    const algorithms::PlacedSamples rs = restricted(samples), rq = restricted(queries);
    algorithms::KernelSelectionOptions co = ko;
    co.select_features = false;
    double best = (sel.x.cv_mse + sel.y.cv_mse) * (1.0 - co.min_improvement);
    double previous = std::numeric_limits<double>::infinity();
    for (const double w : {0.5, 1.0, 2.0, 4.0}) {
      co.column_weight = w;
      algorithms::KernelSelection with = algorithms::select_kernel_model(rs, rq, co);
      if (with.columns.size() != sel.columns.size()) break;  // a chosen board never changed
      const double score = with.x.cv_mse + with.y.cv_mse;
      if (!(score < previous)) break;  // past the best weight (CV over w has one dip)
      previous = score;
      if (!(score < best)) continue;
      best = score;
      with.columns = sel.columns;
      with.steps = sel.steps;
      sel = std::move(with);
      report.column_weight = w;
    }
  }

  // Every board whose area changes is a feature; the ones the selection dropped stay in the
  // map with weight 0 in the kernel, so that the known-place test still compares them.
  std::vector<int> features_in_map;
  for (Eigen::Index k = 0; k < samples.features.cols(); ++k) {
    if (samples.features.col(k).maxCoeff() <= samples.features.col(k).minCoeff())
      report.constant_boards.push_back(candidates[static_cast<std::size_t>(k)]);
    else
      features_in_map.push_back(static_cast<int>(k));
  }
  report_board_steps(sel.steps, candidates, report.board_steps);
  for (int c : sel.columns) report.boards.push_back(candidates[static_cast<std::size_t>(c)]);
  report.x = AxisReport{sel.x.sigma, 0.0, std::sqrt(sel.x.cv_mse), 0};
  report.y = AxisReport{sel.y.sigma, 0.0, std::sqrt(sel.y.cv_mse), 0};
  report.local_linear_ridge = sel.local_linear_ridge;
  report.kernel_average_cv_rmse_x_m = std::sqrt(sel.kernel_average_cv_mse_x);
  report.kernel_average_cv_rmse_y_m = std::sqrt(sel.kernel_average_cv_mse_y);
  pr.cv_rmse_placed_x_m = rms(sel.error_x_m);
  pr.cv_rmse_placed_y_m = rms(sel.error_y_m);
  pr.harmonic_from_placed = true;
  report.labelled = labels.size();
  report.unlabelled = sample_rows.size();

  // Known-place bounds from how far each held-out frame lies from the nearest sample of
  // another pass, over every feature: what a frame of a new run over the same place looks like.
  std::vector<double> nearest_distance, nearest_dissimilarity;
  algorithms::other_pass_nearest(samples, queries, features_in_map, opt.same_pass_m,
                                 nearest_distance, nearest_dissimilarity);
  if (nearest_distance.empty())
    throw std::runtime_error(
        "no frame of the run has another pass over the same place to compare "
        "with: drive the route at least forth and back (or twice round)");
  report.known_place_bound = std::max(4.0 * quantile(nearest_distance, 0.99), 1e-3);
  report.dissimilarity_bound =
      std::min(1.0, std::max(opt.known_place_margin * quantile(nearest_dissimilarity, 0.99), 0.01));
  report.train_ms = ms_since(t_train);

  algorithms::reset_in_place(map);
  map.image_width_px = run.image_width_px;
  map.image_height_px = run.image_height_px;
  map.thresholds = opt.thresholds;
  auto& model = map.model;
  model.sample_count = static_cast<std::uint32_t>(sample_rows.size());
  model.feature_count = static_cast<std::uint32_t>(features_in_map.size());
  for (std::size_t k = 0; k < features_in_map.size(); ++k) {
    const int c = features_in_map[k];
    model.board_index[k] = static_cast<std::uint8_t>(candidates[static_cast<std::size_t>(c)]);
    const bool chosen = std::find(sel.columns.begin(), sel.columns.end(), c) != sel.columns.end();
    model.feature_weight[k] = chosen ? static_cast<float>(scale[static_cast<std::size_t>(c)] *
                                                          scale[static_cast<std::size_t>(c)])
                                     : 0.0F;
  }
  model.area_scale = area_scale;
  model.column_gain = column_gain;
  model.sigma_x = static_cast<float>(report.x.sigma);
  model.sigma_y = static_cast<float>(report.y.sigma);
  model.gamma_x = 0.0F;
  model.gamma_y = 0.0F;
  model.local_linear_ridge = static_cast<float>(sel.local_linear_ridge);
  model.column_weight = static_cast<float>(report.column_weight);
  model.max_nearest_distance = static_cast<float>(report.known_place_bound);
  model.max_dissimilarity = static_cast<float>(report.dissimilarity_bound);
  for (std::size_t i = 0; i < sample_rows.size(); ++i) {
    for (std::size_t k = 0; k < features_in_map.size(); ++k) {
      model.sample(i)[k] =
          static_cast<float>(samples.features(static_cast<Eigen::Index>(i), features_in_map[k]));
      if (model.uses_columns())
        model.sample_columns(i)[k] =
            static_cast<float>(samples.columns(static_cast<Eigen::Index>(i), features_in_map[k]));
    }
    model.target_x_m[i] = static_cast<float>(samples.xy(static_cast<Eigen::Index>(i), 0));
    model.target_y_m[i] = static_cast<float>(samples.xy(static_cast<Eigen::Index>(i), 1));
  }

  // Where the fixes that named a place were wrong (docs/filter.md, "The fix error here"): within
  // twice the fix's own RMS error of each sample (never under 5 cm), at least three fixes, else
  // the global error.
  {
    const double fix_rmse_m =
        std::hypot(pr.cv_rmse_placed_x_m, pr.cv_rmse_placed_y_m) / std::sqrt(2.0);
    algorithms::LocalFixErrorOptions lo;
    lo.radius_m = std::max(2.0 * fix_rmse_m, 0.05);
    lo.fallback_m = fix_rmse_m;
    const std::vector<double> local =
        algorithms::local_fix_errors(samples.xy, algorithms::cross_validated_fixes(sel, queries),
                                     sel.error_x_m, sel.error_y_m, lo);
    for (std::size_t i = 0; i < local.size(); ++i)
      model.fix_error_m[i] = static_cast<float>(std::min(local[i], 100.0));
    report.local_fix_error_median_m = quantile(local, 0.5);
    report.local_fix_error_max_m =
        local.empty() ? 0.0 : *std::max_element(local.begin(), local.end());
  }
  map.calibration.present = true;
  map.calibration.fix_rmse_x_m = static_cast<float>(pr.cv_rmse_placed_x_m);
  map.calibration.fix_rmse_y_m = static_cast<float>(pr.cv_rmse_placed_y_m);
  if (report.placement.odometry.used) {
    const algorithms::OdometryScale& s = report.placement.odometry.scale;
    map.calibration.odometry_present = true;
    map.calibration.left_wheel_scale = static_cast<float>(s.left);
    map.calibration.right_wheel_scale = static_cast<float>(s.right);
    map.calibration.track_scale = static_cast<float>(s.track);
  }

  if (have_forward) {
    map.forward = *forward;
    report.forward = forward_report;
    map.calibration.pass_spread_m = static_cast<float>(report.forward.pass_spread_m);
    map.calibration.pass_heading_spread_rad =
        static_cast<float>(report.forward.pass_heading_spread_rad);
    report.has_forward_map = true;
    report.forward_ms = forward_ms;
  }
  return report;
}

}  // namespace harmoloc::sim_host
