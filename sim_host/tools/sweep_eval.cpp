#include "sweep_eval.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

#include "harmoloc/firmware/pose_messages.hpp"
#include "harmoloc/sim_host/random_scene.hpp"
#include "scenario_eval.hpp"

namespace harmoloc::sim_host {

namespace {

// Seeds of a scene's runs: training, test, kidnaps, dynamic, long (distinct noise streams).
constexpr std::uint64_t kTrainSeed = 1, kTestSeed = 2, kKidnapSeed = 3, kDynamicSeed = 4,
                        kLongSeed = 5, kCoverageSeed = 6, kRoamSeed = 100, kKidnapRoam = 50;

std::string describe(const Scenario& s) {
  std::ostringstream o;
  o << s.camera.width_px << "x" << s.camera.height_px << ", " << s.boards.size() << " boards, k1 "
    << s.camera.k1 << ", " << s.route.waypoints_m.size() << " waypoints, " << s.name;
  return o.str();
}

firmware::FirmwareConfig config_for(const algorithms::ThresholdSet& thresholds,
                                    const SweepOptions& options) {
  firmware::FirmwareConfig c = options.config;
  c.thresholds = thresholds;
  c.filter.seed = options.filter_seed;
  return c;
}

// Issue 15's start-up target: under 5 cm within 2 s of the first fix; "under" means for at
// least a second, not one lucky frame.
constexpr double kSettledBound_m = 0.05, kStartupHold_s = 1.0;

// First known-place fix; from it, the time until the error comes under @p bound and stays
// there for @p hold_s (start-up), and the time until it stays under it for good; the errors
// after first fix + settle.
struct Settled {
  double first_fix_s = -1.0, startup_s = -1.0, converge_s = -1.0;
  ErrorStats after;
};

Settled settle(const RunRecord& run, double settle_s, double bound_m, double hold_s) {
  Settled s;
  for (const FrameRecord& f : run.frames) {
    if (f.fix_known) {
      s.first_fix_s = f.t_s;
      break;
    }
  }
  if (s.first_fix_s < 0.0) return s;
  double last_bad = s.first_fix_s;
  double good_since = -1.0;  // start of the current stretch under the bound
  for (const FrameRecord& f : run.frames) {
    if (f.t_s < s.first_fix_s) continue;
    if (!f.valid || f.position_error_m() >= bound_m) {
      last_bad = f.t_s;
      good_since = -1.0;
      continue;
    }
    if (good_since < 0.0) good_since = f.t_s;
    if (s.startup_s < 0.0 && f.t_s - good_since >= hold_s) s.startup_s = good_since - s.first_fix_s;
  }
  // A run that ends within hold_s of coming under the bound: it came under it.
  if (s.startup_s < 0.0 && good_since >= 0.0) s.startup_s = good_since - s.first_fix_s;
  s.converge_s = last_bad - s.first_fix_s;
  s.after = error_stats(run, s.first_fix_s + settle_s, 1e300);
  return s;
}

// From @p from_s on: the frames with a pose, those reported nominal, those of them with an
// error above 10 cm, and of those the ones published with a quality above 0 (a nominal pose's
// quality is its spread's).
struct NominalCount {
  std::size_t frames = 0, nominal = 0, bad = 0, vouched_bad = 0;
};

NominalCount count_nominal(const RunRecord& run, double from_s) {
  NominalCount c;
  for (const FrameRecord& f : run.frames) {
    if (f.t_s < from_s || !f.valid) continue;
    ++c.frames;
    if (f.health != firmware::Health::kNominal) continue;
    ++c.nominal;
    if (f.position_error_m() <= 0.10) continue;
    ++c.bad;
    if (firmware::quality_of_spread(f.sigma_m) > 0) ++c.vouched_bad;
  }
  return c;
}

std::string board_names(const TrainReport& r, const Scenario& scene) {
  std::string out;
  for (int b : r.boards) {
    if (!out.empty()) out += " ";
    out += static_cast<std::size_t>(b) < scene.boards.size()
               ? scene.boards[static_cast<std::size_t>(b)].name
               : std::to_string(b + 1);
  }
  return out;
}

// How far the boards placed from their centroid columns are from the scene's board centres.
void bearing_figures(const TrainReport& tr, const Scenario& scene, SceneResult& r) {
  r.bearings_ms = tr.bearings_ms;
  if (!tr.bearings.ok) return;
  std::vector<double> errors;
  for (std::size_t k = 0; k < tr.bearings.placements.size() && k < scene.boards.size(); ++k) {
    const algorithms::BoardPlacement& p = tr.bearings.placements[k];
    if (!p.placed) continue;
    errors.push_back(
        std::hypot(p.x_m - scene.boards[k].centre_x_m, p.y_m - scene.boards[k].centre_y_m));
  }
  if (errors.empty()) return;
  std::sort(errors.begin(), errors.end());
  r.bearing_boards_placed = errors.size();
  r.board_place_median_m = errors.size() % 2 == 1
                               ? errors[errors.size() / 2]
                               : 0.5 * (errors[errors.size() / 2 - 1] + errors[errors.size() / 2]);
  r.board_place_max_m = errors.back();
  r.bearing_residual_deg = tr.bearings.rms_residual_rad * 180.0 / algorithms::kPi;
  r.bearing_half_fov_deg = tr.bearings.half_fov_rad() * 180.0 / algorithms::kPi;
}

// The harmonic fixes' squared errors per axis, all of them and the known places', over one or
// more runs. A frame in which none of the localizer's boards showed has no fix: it is counted
// apart (HarmonicFix::board_seen).
struct FixErrors {
  double x_m2 = 0.0, y_m2 = 0.0, known_x_m2 = 0.0, known_y_m2 = 0.0;
  std::size_t all = 0, known = 0, no_board = 0;
  void add(const RunRecord& run) {
    for (const FrameRecord& f : run.frames) {
      if (!f.fix_present) continue;
      if (!f.board_seen) {
        ++no_board;
        continue;
      }
      const double ex = f.fix.x_m - f.truth.x_m, ey = f.fix.y_m - f.truth.y_m;
      x_m2 += ex * ex;
      y_m2 += ey * ey;
      ++all;
      if (f.fix_known) {
        known_x_m2 += ex * ex;
        known_y_m2 += ey * ey;
        ++known;
      }
    }
  }
  double mse_x_m2() const { return x_m2 / static_cast<double>(all); }
  double mse_y_m2() const { return y_m2 / static_cast<double>(all); }
  double known_mse_x_m2() const { return known_x_m2 / static_cast<double>(known); }
  double known_mse_y_m2() const { return known_y_m2 / static_cast<double>(known); }
};

// The boards' fits at the truth and at the estimate are only written to traces.
ReplayDetail detail(const SweepOptions& opt) {
  return opt.trace_dir.empty() ? ReplayDetail::kOutputs : ReplayDetail::kBoardFits;
}

void trace(const SweepOptions& opt, std::uint64_t seed, const char* part, const RunRecord& run) {
  if (opt.trace_dir.empty()) return;
  write_trace(run, opt.trace_dir + "/seed-" + std::to_string(seed) + "-" + part + ".csv");
}

// How far the geometry fitted to the coverage run is from the scene's: the trainer sees only
// the frames, the sweep knows the truth. Board b of the fit is the scene's board b (the areas'
// order is the scenario's).
void geometry_against_truth(const GeometryReport& g, const Scenario& scene, SceneResult& r) {
  if (!g.tried || !g.fit.ok) return;
  std::vector<double> errors;
  for (std::size_t b = 0; b < g.fit.boards.size() && b < scene.boards.size(); ++b) {
    if (!g.fit.boards[b].ok) continue;
    const BoardSpec& fit = g.fit.boards[b].board;
    const BoardSpec& truth = scene.boards[b];
    errors.push_back(
        std::hypot(std::hypot(fit.centre_x_m - truth.centre_x_m, fit.centre_y_m - truth.centre_y_m),
                   fit.centre_z_m - truth.centre_z_m));
  }
  if (!errors.empty()) {
    std::sort(errors.begin(), errors.end());
    const std::size_t n = errors.size();
    r.floor_geometry_board_error_median_m =
        n % 2 == 1 ? errors[n / 2] : 0.5 * (errors[n / 2 - 1] + errors[n / 2]);
    r.floor_geometry_board_error_max_m = errors.back();
  }
  const CameraSpec& c = g.fit.camera;
  r.floor_geometry_fov_error_deg = c.horizontal_fov_deg - scene.camera.horizontal_fov_deg;
  r.floor_geometry_pitch_error_deg = c.pitch_deg - scene.camera.pitch_deg;
  r.floor_geometry_forward_error_m = c.forward_offset_m - scene.camera.forward_offset_m;
  r.floor_heading_rounds = g.heading_rounds;
  r.floor_heading_offset_rms_deg = g.heading_offset_rms_rad * 180.0 / algorithms::kPi;
}

// Issue 20's floor runs: train on the coverage run, replay the roams, pool their frames.
void floor_part(const Scenario& scene, const algorithms::ThresholdSet& thresholds,
                std::uint64_t seed, const SweepOptions& opt, SceneResult& r,
                const std::function<void(const std::string&)>& step) {
  try {
    step("floor: coverage training");
    const Scenario coverage = coverage_variant(scene);
    const std::string& d = coverage.description;
    r.floor_summary =
        d.substr(d.find("coverage run") == std::string::npos ? 0 : d.find("coverage run"));
    TrainOptions train;
    if (opt.heading_terms) train.forward.heading_ridges = kHeadingRidges;
    train.forward.visibility = opt.visibility;
    train.forward.visibility_on_floors = !opt.no_visibility;
    if (opt.axle_bearings) train.forward.camera_forward_m = 0.0;
    train.column_gain = opt.column_gain;
    train.visibility_from_geometry = opt.visibility_from_geometry;
    train.geometry_tables.kernel_noise_ratio = opt.geometry_noise_ratio;
    train.law_from_geometry = !opt.law_from_frames;
    train.refine_headings = opt.refine_headings;
    train.projected_bearings = opt.projected_bearings;
    train.projected_areas = opt.projected_bearings && opt.projected_areas;
    train.camera_height_m = coverage.camera.height_m;  // a tape measure gives it
    const TrainedMap trained =
        train_on_scenario(coverage, kCoverageSeed, nullptr, &thresholds, &train);
    r.floor_train_frames = trained.frames;
    if (trained.report.placement.used) {
      r.floor_placement_rmse_m = trained.placement_rmse_m;
      r.floor_placement_max_m = trained.placement_max_m;
      r.floor_placement_heading_rmse_deg = trained.placement_heading_rmse_deg;
    }
    r.floor_train_ms = trained.report.train_ms + trained.report.forward_ms;
    r.floor_cv_rmse_x_m = trained.report.x.cv_rmse_m;
    r.floor_pass_heading_spread_rad = trained.report.forward.pass_heading_spread_rad;
    const ForwardMapReport& fw = trained.report.forward;
    r.floor_heading_ridge = fw.heading_ridge;
    const GeometryTablesReport& tables = trained.report.geometry.tables;
    for (std::size_t b = 0; b < tables.from_geometry.size(); ++b) {
      r.floor_geometry_boards += tables.from_geometry[b] ? 1 : 0;
      r.floor_geometry_candidates += tables.geometry_sigma[b] > 0.0 ? 1 : 0;
    }
    r.floor_projected_boards = static_cast<int>(trained.report.geometry.projected_boards);
    geometry_against_truth(trained.report.geometry, coverage, r);
    r.floor_law_from_camera = trained.report.geometry.law_from_camera;
    if (r.floor_law_from_camera)
      r.floor_law_axis_deg = trained.report.geometry.law_axis_rad * 180.0 / algorithms::kPi;
    r.floor_heading_bandwidth_m = fw.heading_bandwidth_m;
    r.floor_covered_heading_fraction = fw.covered_heading_fraction;
    r.floor_validation_rmse = fw.validation_rmse;
    r.floor_mean_validation_rmse =
        fw.heading_ridge > 0.0 ? fw.mean_validation_rmse : fw.validation_rmse;
    r.floor_cv_rmse_y_m = trained.report.y.cv_rmse_m;
    const firmware::FirmwareConfig config = config_for(thresholds, opt);
    FixErrors fixes;
    double se = 0.0, sh = 0.0, worst = 0.0;
    std::size_t frames = 0, nominal_bad = 0, vouched_bad = 0, nominal = 0;
    std::uint64_t particles = 0, particle_cycles = 0;
    for (int k = 1; k <= opt.roams; ++k) {
      step("floor: roam " + std::to_string(k));
      const Scenario roam =
          with_other_lighting(roam_variant(scene, static_cast<std::uint64_t>(k)), kRoamSeed + k);
      const RunRecord run = replay_scenario(roam, kRoamSeed + static_cast<std::uint64_t>(k),
                                            *trained.map, config, nullptr, detail(opt));
      trace(opt, seed, ("floor-roam" + std::to_string(k)).c_str(), run);
      if (!run.frames.empty()) r.floor_roam_s += run.frames.back().t_s;
      r.floor_nearby_draws += run.counters.nearby_draws;
      particles += run.counters.particles_sum;
      particle_cycles += run.counters.particle_cycles;
      fixes.add(run);
      const Settled st = settle(run, opt.settle_s, kSettledBound_m, kStartupHold_s);
      if (st.first_fix_s < 0.0) continue;
      const double from_s = st.first_fix_s + opt.settle_s;
      // The roams are pooled: their squared errors add up frame by frame.
      const ErrorStats e = error_stats(run, from_s, 1e300);
      const auto n = static_cast<double>(e.frames);
      se += e.rmse_m * e.rmse_m * n;
      sh += e.heading_rmse_deg * e.heading_rmse_deg * n;
      worst = std::max(worst, e.max_m);
      frames += e.frames;
      const NominalCount c = count_nominal(run, from_s);
      nominal += c.nominal;
      nominal_bad += c.bad;
      vouched_bad += c.vouched_bad;
    }
    if (particle_cycles > 0)
      r.floor_particles_mean =
          static_cast<double>(particles) / static_cast<double>(particle_cycles);
    if (fixes.all > 0) {
      r.floor_fix_mse_x_m2 = fixes.mse_x_m2();
      r.floor_fix_mse_y_m2 = fixes.mse_y_m2();
    }
    if (frames > 0) {
      const auto n = static_cast<double>(frames);
      r.floor_rmse_m = std::sqrt(se / n);
      r.floor_heading_rmse_deg = std::sqrt(sh / n);
      r.floor_max_m = worst;
      r.floor_nominal_over_10cm = static_cast<double>(nominal_bad) / n;
      r.floor_vouched_over_10cm = static_cast<double>(vouched_bad) / n;
      r.floor_nominal_share = static_cast<double>(nominal) / n;
    }
    if (opt.floor_kidnaps > 0) {
      try {
        step("floor: roam with kidnaps");
        const Scenario roam = with_other_lighting(
            roam_variant(scene, kKidnapRoam, 8, opt.floor_kidnaps), kRoamSeed + kKidnapRoam);
        const RunRecord run = replay_scenario(roam, kRoamSeed + kKidnapRoam, *trained.map, config,
                                              nullptr, detail(opt));
        trace(opt, seed, "floor-kidnap", run);
        const KidnapSummary ks = kidnap_summary(run, 0.10, 0.5, 2.0);
        r.floor_kidnaps = ks.outcomes.size();
        r.floor_kidnaps_recovered_2s = ks.recovered_within;
        const Settled st = settle(run, opt.settle_s, kSettledBound_m, kStartupHold_s);
        if (st.first_fix_s >= 0.0) {
          const NominalCount c = count_nominal(run, st.first_fix_s + opt.settle_s);
          if (c.frames > 0) {
            const auto n = static_cast<double>(c.frames);
            r.floor_kidnap_nominal_over_10cm = static_cast<double>(c.bad) / n;
            r.floor_kidnap_vouched_over_10cm = static_cast<double>(c.vouched_bad) / n;
          }
        }
      } catch (const std::exception& e) {
        // The roams' figures stand; the scene still counts as failed.
        r.floor_error = std::string("roam with kidnaps: ") + e.what();
      }
    }
  } catch (const std::exception& e) {
    r.floor_error = e.what();
  }
}

void route_runs(const Scenario& scene, const algorithms::ThresholdSet& thresholds,
                std::uint64_t seed, const SweepOptions& opt, SceneResult& r,
                const std::function<void(const std::string&)>& step);

}  // namespace

SceneResult evaluate_scene(const Scenario& scene, const algorithms::ThresholdSet& thresholds,
                           std::uint64_t seed, const SweepOptions& opt,
                           const SweepProgress& progress) {
  const auto t_start = std::chrono::steady_clock::now();
  SceneResult r;
  r.seed = seed;
  r.summary = describe(scene);
  const auto step = [&](const std::string& s) {
    if (progress) progress(s);
  };
  const bool route_parts = opt.nominal || opt.kidnap || opt.dynamic || opt.long_run;
  try {
    if (route_parts) route_runs(scene, thresholds, seed, opt, r, step);
  } catch (const std::exception& e) {
    r.error = e.what();
  }
  if (opt.floor) floor_part(scene, thresholds, seed, opt, r, step);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  return r;
}

namespace {

// The runs of the trained route: the nominal test run, kidnaps, the dynamic run, the long run.
void route_runs(const Scenario& scene, const algorithms::ThresholdSet& thresholds,
                std::uint64_t seed, const SweepOptions& opt, SceneResult& r,
                const std::function<void(const std::string&)>& step) {
  {
    step("training");
    TrainOptions train;
    if (opt.axle_bearings) train.forward.camera_forward_m = 0.0;
    train.column_gain = opt.column_gain;
    const TrainedMap trained = train_on_scenario(scene, kTrainSeed, nullptr, &thresholds, &train);
    const TrainReport& tr = trained.report;
    r.train_ms = tr.train_ms + tr.forward_ms;
    r.train_frames = trained.frames;
    if (tr.placement.used) {
      r.placement_rmse_m = trained.placement_rmse_m;
      r.placement_heading_rmse_deg = trained.placement_heading_rmse_deg;
    }
    r.cv_rmse_x_m = tr.x.cv_rmse_m;
    r.pass_heading_spread_rad = tr.forward.pass_heading_spread_rad;
    r.cv_rmse_y_m = tr.y.cv_rmse_m;
    r.column_weight = tr.column_weight;
    r.column_gain_c2 = tr.column_gain.gain.c2;
    r.column_gain_c4 = tr.column_gain.gain.c4;
    r.column_gain_observations = tr.column_gain.observations;
    r.boards_used = board_names(tr, scene);
    bearing_figures(tr, scene, r);
    const algorithms::MapFile& map = *trained.map;
    const firmware::FirmwareConfig config = config_for(thresholds, opt);

    if (opt.nominal) {
      step("test run");
      const RunRecord run = replay_scenario(with_other_lighting(scene, kTestSeed), kTestSeed, map,
                                            config, nullptr, detail(opt));
      trace(opt, seed, "nominal", run);
      FixErrors fixes;
      fixes.add(run);
      if (fixes.all > 0) {
        r.fix_mse_x_m2 = fixes.mse_x_m2();
        r.fix_mse_y_m2 = fixes.mse_y_m2();
        r.fix_known_fraction = static_cast<double>(fixes.known) / static_cast<double>(fixes.all);
      }
      if (fixes.all + fixes.no_board > 0)
        r.no_board_fraction =
            static_cast<double>(fixes.no_board) / static_cast<double>(fixes.all + fixes.no_board);
      if (fixes.known > 0) {
        r.fix_known_mse_x_m2 = fixes.known_mse_x_m2();
        r.fix_known_mse_y_m2 = fixes.known_mse_y_m2();
      }
      const Settled s = settle(run, opt.settle_s, kSettledBound_m, kStartupHold_s);
      r.first_fix_s = s.first_fix_s;
      r.startup_s = s.startup_s;
      r.converge_s = s.converge_s;
      if (s.after.frames > 0) {
        r.fused_rmse_m = s.after.rmse_m;
        r.fused_heading_rmse_deg = s.after.heading_rmse_deg;
        r.fused_max_m = s.after.max_m;
      }
      if (run.counters.particle_cycles > 0) r.particles_mean = run.counters.particles_mean();
    }
    if (opt.kidnap && opt.kidnaps > 0) {
      step("kidnaps");
      const Scenario k = kidnap_variant(scene, opt.kidnaps);
      const RunRecord run = replay_scenario(k, kKidnapSeed, map, config, nullptr, detail(opt));
      trace(opt, seed, "kidnap", run);
      const KidnapSummary ks = kidnap_summary(run, 0.10, 0.5, 1.0);
      r.kidnaps = ks.outcomes.size();
      r.kidnaps_detected = ks.detected;
      r.kidnaps_recovered_1s = ks.recovered_within;
      r.kidnap_mean_recovery_s = ks.recovered_ever > 0 ? ks.mean_recovery_s : -1.0;
      for (const KidnapOutcome& o : ks.outcomes) {
        if (!(o.detected && o.recovered_after_s >= 0.0 && o.recovered_after_s <= 1.0))
          r.kidnap_misses_t_s.push_back(o.t_s);
      }
    }
    if (opt.dynamic) {
      step("dynamic");
      const RunRecord run =
          replay_scenario(dynamic_variant(scene), kDynamicSeed, map, config, nullptr, detail(opt));
      trace(opt, seed, "dynamic", run);
      const Settled s = settle(run, opt.settle_s, kSettledBound_m, kStartupHold_s);
      if (s.after.frames > 0) {
        r.dynamic_max_m = s.after.max_m;
        r.dynamic_rmse_m = s.after.rmse_m;
      }
    }
    if (opt.long_run && opt.long_minutes > 0.0) {
      step("long run");
      const Scenario l = long_variant(scene, opt.long_minutes);
      const RunRecord run = replay_scenario(l, kLongSeed, map, config, nullptr, detail(opt));
      trace(opt, seed, "long", run);
      r.long_minutes = run.frames.empty() ? 0.0 : run.frames.back().t_s / 60.0;
      r.long_false_alarms = run.counters.kidnaps;
      const Settled s = settle(run, opt.settle_s, kSettledBound_m, kStartupHold_s);
      if (s.after.frames > 0) {
        r.long_max_m = s.after.max_m;
        r.long_rmse_m = s.after.rmse_m;
      }
    }
  }
}

}  // namespace

SceneResult evaluate_random_scene(std::uint64_t seed, const SweepOptions& options,
                                  const SweepProgress& progress) {
  const Scenario scene = random_scenario(seed);
  return evaluate_scene(scene, threshold_set(thresholds_for(scene)), seed, options, progress);
}

}  // namespace harmoloc::sim_host
