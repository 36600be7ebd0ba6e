#include "scenario_eval.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "harmoloc/algorithms/floor_search.hpp"
#include "harmoloc/algorithms/forward_map.hpp"
#include "harmoloc/algorithms/frame_information.hpp"
#include "harmoloc/algorithms/geometry.hpp"
#include "harmoloc/algorithms/segmentation.hpp"
#include "harmoloc/host/log_encoders.hpp"
#include "harmoloc/sim_host/sim_camera.hpp"

namespace harmoloc::sim_host {

namespace {

// The link goes nowhere: the scenario table looks at the pose, not the wire.
class NullLink final : public hal::PoseLink {
 public:
  hal::LinkWrite write_frame(const std::uint8_t*, std::size_t size) override {
    ++counters_.frames_sent;
    counters_.bytes_sent += size;
    return hal::LinkWrite::kSent;
  }
  hal::LinkCounters counters() const override { return counters_; }

 private:
  hal::LinkCounters counters_{};
};

// Replays run as fast as it goes: the clock only times the stages.
class WallClock final : public hal::Clock {
 public:
  std::uint64_t now_ns() const override {
    timespec ts{};
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return static_cast<std::uint64_t>(ts.tv_sec) * 1000000000ULL +
           static_cast<std::uint64_t>(ts.tv_nsec);
  }
  void sleep_until(std::uint64_t) override {}
};

}  // namespace

double FrameRecord::position_error_m() const {
  return std::hypot(estimate.x_m - truth.x_m, estimate.y_m - truth.y_m);
}

TrainedMap train_on_scenario(const Scenario& scenario, std::uint64_t seed, const Progress& progress,
                             const algorithms::ThresholdSet* thresholds,
                             const TrainOptions* options) {
  ScenarioRun run(scenario, seed);
  const algorithms::ThresholdSet set =
      thresholds != nullptr ? *thresholds : firmware::default_config().thresholds;
  std::vector<std::uint8_t> table_storage(algorithms::ColourTable::kEntries);
  algorithms::ColourTable table;
  table.build(algorithms::BoardClassifier(set), table_storage.data());
  AreaSeries series;
  series.image_width_px = scenario.camera.width_px;
  series.image_height_px = scenario.camera.height_px;
  series.camera_forward_m = scenario.camera.forward_offset_m;
  series.camera_height_m = scenario.camera.height_m;
  std::vector<std::uint8_t> rgb;
  for (std::size_t k = 0; k < run.frame_count(); ++k) {
    run.render(k, rgb);
    algorithms::AreaVector a;
    algorithms::segment_rgb24(rgb.data(), scenario.camera.width_px, scenario.camera.height_px,
                              scenario.camera.width_px * 3U, table, a);
    series.areas.push_back(a);
    series.timestamp_ns.push_back(run.frame_timestamp_ns(k));
    if (progress && (k % 100 == 0 || k + 1 == run.frame_count()))
      progress(k + 1, run.frame_count());
  }
  series.odometry = odometry_from_can(run.encoder_frames(), scenario.can_layout, scenario.robot);
  TrainOptions opt = options != nullptr ? *options : TrainOptions{};
  opt.thresholds = set;
  TrainedMap t;
  t.map = std::make_unique<algorithms::MapFile>();
  t.report = train_on_areas(series, run.labels(), opt, *t.map);
  t.frames = run.frame_count();
  const PlacementReport& pl = t.report.placement;
  if (pl.used) {
    double se = 0.0, sh = 0.0;
    std::size_t n = 0;
    for (std::size_t k = 0; k < run.frame_count(); ++k) {
      if (!pl.placed[k]) continue;
      const algorithms::Pose2& a = pl.poses[k];
      const algorithms::Pose2& b = run.truth(k);
      const double e2 = (a.x_m - b.x_m) * (a.x_m - b.x_m) + (a.y_m - b.y_m) * (a.y_m - b.y_m);
      se += e2;
      t.placement_max_m = std::max(t.placement_max_m, std::sqrt(e2));
      const double h = algorithms::wrap_angle_rad(a.yaw_rad - b.yaw_rad);
      sh += h * h;
      ++n;
    }
    if (n > 0) {
      t.placement_rmse_m = std::sqrt(se / static_cast<double>(n));
      t.placement_heading_rmse_deg =
          std::sqrt(sh / static_cast<double>(n)) * 180.0 / algorithms::kPi;
    }
  }
  return t;
}

RunRecord replay_scenario(const Scenario& scenario, std::uint64_t seed,
                          const algorithms::MapFile& map, const firmware::FirmwareConfig& base,
                          const Progress& progress, ReplayDetail detail) {
  ScenarioRun run(scenario, seed);
  firmware::FirmwareConfig config = base;
  config.geometry = scenario.robot;  // the simulated robot, as a dataset's metadata gives it
  config.can_layout = scenario.can_layout;
  SimCamera camera(run);
  host::LogEncoders encoders(run.encoder_frames(), config.can_layout);
  NullLink link;
  WallClock clock;
  auto cycle = std::make_unique<firmware::LocalizationCycle>(config, map, camera, encoders, link,
                                                             clock, hal::PixelFormat::kRgb24);
  RunRecord record;
  record.kidnaps = run.kidnaps();
  record.frames.reserve(run.frame_count());
  const double t0 = static_cast<double>(run.frame_timestamp_ns(0)) * 1e-9;
  std::size_t k = 0;
  std::uint64_t observations = 0;
  while (cycle->run_once() == firmware::CycleResult::kRan) {
    const firmware::PoseOutput& out = cycle->pose();
    FrameRecord f;
    f.t_s = static_cast<double>(out.data_time_ns) * 1e-9 - t0;
    // The cycle ran on frame k (the simulated camera delivers every frame in order).
    f.truth = run.truth(std::min(k, run.frame_count() - 1));
    f.estimate = out.pose;
    f.valid = out.valid;
    f.health = out.health;
    f.cause = out.cause;
    const firmware::FixOutput& fix = cycle->last_fix();
    f.fix_present = fix.present;
    f.fix_known = fix.present && fix.fix.known_place;
    f.board_seen = fix.present && fix.fix.board_seen;
    f.cut_board = fix.present && fix.fix.cut_board_left_out;
    f.fix = algorithms::Pose2{fix.fix.x_m, fix.fix.y_m, 0.0};
    f.verdict = cycle->kidnap_verdict();
    f.consensus = cycle->board_assessment().consensus;
    f.boards = map.thresholds.count;
    for (std::size_t b = 0; b < map.thresholds.count; ++b) {
      if (cycle->board_static_probability(b) < 0.5)
        f.distrusted |= static_cast<std::uint8_t>(1U << b);
      f.chi2[b] = cycle->board_assessment().chi2[b];
      f.static_probability[b] = static_cast<float>(cycle->board_static_probability(b));
    }
    for (std::size_t feature = 0; feature < map.model.feature_count; ++feature)
      if (cycle->fix_check().suspect(feature))
        f.fix_suspects |= static_cast<std::uint8_t>(1U << map.model.board_index[feature]);
    f.robust_fix = algorithms::Pose2{cycle->robust_fix().x_m, cycle->robust_fix().y_m, 0.0};
    f.preference = cycle->kidnap_input().preference;
    f.evidence_known = cycle->kidnap_input().fix_known;
    f.evidence =
        algorithms::Pose2{cycle->kidnap_input().fix_x_m, cycle->kidnap_input().fix_y_m, 0.0};
    f.evidence_distance_m = cycle->kidnap_input().fix_distance_m;
    // On the cycles that did not weigh the boards (no frame, or the first frame, which seeds
    // the filter) the observation is an older frame's, so no fit is written for them.
    const bool weighed = cycle->board_observations() != observations;
    observations = cycle->board_observations();
    if (detail == ReplayDetail::kBoardFits && cycle->uses_boards() && weighed) {
      const algorithms::BoardFeatures& seen = cycle->board_observation();
      const algorithms::BoardModelParams& params = config.observation.boards;
      f.truth_nats = algorithms::floor_fit(map.forward, seen, f.truth.x_m, f.truth.y_m,
                                           f.truth.yaw_rad, params, 0U);
      f.estimate_nats = algorithms::floor_fit(map.forward, seen, out.pose.x_m, out.pose.y_m,
                                              out.pose.yaw_rad, params, 0U);
      const algorithms::FloorPose& search = cycle->floor_search_pose();
      if (search.valid) {
        f.search_x_m = search.x_m;
        f.search_y_m = search.y_m;
        f.search_nats = search.nats;
        f.search_yaw_rad = search.yaw_rad;
      }
      const auto d = static_cast<double>(map.forward.bearing_camera_forward_m);
      const algorithms::FloorPose at_truth = algorithms::floor_pose_seen_from(
          map.forward, seen, f.truth.x_m + d * std::cos(f.truth.yaw_rad),
          f.truth.y_m + d * std::sin(f.truth.yaw_rad), params, 0U);
      if (at_truth.valid) f.truth_seen_nats = at_truth.nats;
      const algorithms::BoardUpdate& model = cycle->board_update();
      if (model.map != nullptr) {
        using algorithms::ParticleFilter;
        f.truth_model_nats = std::log(ParticleFilter::board_likelihood(model, f.truth));
        f.estimate_model_nats = std::log(ParticleFilter::board_likelihood(model, out.pose));
        if (search.valid)
          f.search_model_nats = std::log(ParticleFilter::board_likelihood(
              model, algorithms::Pose2{search.x_m, search.y_m, search.yaw_rad}));
        f.boards_in_view = 0;
        for (std::size_t b = 0; b < model.boards; ++b)
          if (model.use[b] && model.observed[b] > 0.0F) ++f.boards_in_view;
        f.boards_with_bearing = __builtin_popcount(model.bearing_mask);
      }
      const algorithms::FrameInformation info =
          algorithms::frame_information(map.forward, seen, out.pose, params, f.distrusted);
      f.frame_sigma_m = info.weak_sigma_m;
      f.frame_axis_rad = info.weak_axis_rad;
    }
    if (cycle->uses_nearby_test()) {
      const algorithms::NearbyPoseTest& nearby = cycle->nearby_test();
      if (nearby.holding()) f.nearby_sum_nats = nearby.summed_nats();
      f.nearby_by_tables = nearby.by_tables() ? 1 : 0;
    }
    f.nearby_draws = cycle->counters().nearby_draws;
    if (map.forward.present())
      f.truth_lane_m = static_cast<double>(algorithms::route_distance(
          map.forward, algorithms::locate(map.forward, f.truth.x_m, f.truth.y_m)));
    f.match = cycle->kidnap_input().match;
    f.sigma_m = std::sqrt(std::max(0.0, 0.5 * (out.covariance(0, 0) + out.covariance(1, 1))));
    f.sigma_yaw_rad = std::sqrt(std::max(0.0, out.covariance(2, 2)));
    if (map.forward.has_heading_coverage && out.valid)
      f.covered =
          algorithms::heading_covered(map.forward, out.pose.x_m, out.pose.y_m, out.pose.yaw_rad)
              ? 1
              : 0;
    record.frames.push_back(f);
    ++k;
    if (progress && (k % 300 == 0 || k == run.frame_count())) progress(k, run.frame_count());
  }
  record.counters = cycle->counters();
  record.uses_boards = cycle->uses_boards();
  if (detail == ReplayDetail::kBoardFits && record.uses_boards)
    record.fit_bound_nats = 2.0 * static_cast<double>(map.thresholds.count) *
                            std::log1p(config.observation.boards.outlier_floor);
  return record;
}

void write_trace(const RunRecord& run, const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) throw std::runtime_error(path + ": cannot write the trace");
  if (run.fit_bound_nats > 0.0)
    std::fprintf(f, "# fit bound %.4f nats (a perfect fit of every board's area and bearing)\n",
                 run.fit_bound_nats);
  for (const KidnapEvent& k : run.kidnaps) {
    std::fprintf(f, "# kidnap at %.3f s: %.4f %.4f %.4f -> %.4f %.4f %.4f\n", k.t_s, k.from.x_m,
                 k.from.y_m, k.from.yaw_rad, k.to.x_m, k.to.y_m, k.to.yaw_rad);
  }
  std::fprintf(
      f,
      "t_s,truth_x_m,truth_y_m,truth_yaw_rad,x_m,y_m,yaw_rad,error_m,valid,health,"
      "fix_present,fix_known,fix_x_m,fix_y_m,verdict,distrusted,consensus,robust_fix_x_m,"
      "robust_fix_y_m,preference,sigma_m,sigma_yaw_rad,match,covered,evidence_known,"
      "evidence_x_m,evidence_y_m,evidence_distance_m,truth_nats,estimate_nats,board_seen,"
      "cut_board,fix_suspects,truth_lane_m,frame_sigma_m,frame_axis_rad,search_x_m,search_y_m,"
      "search_nats,truth_seen_nats,truth_model_nats,search_model_nats,estimate_model_nats,"
      "boards_in_view,boards_with_bearing,search_yaw_rad,nearby_sum_nats,nearby_by_tables,"
      "nearby_draws,health_cause");
  const std::size_t boards = run.frames.empty() ? 0 : run.frames.front().boards;
  for (std::size_t b = 0; b < boards; ++b) std::fprintf(f, ",chi2_%zu", b + 1);
  for (std::size_t b = 0; b < boards; ++b) std::fprintf(f, ",static_%zu", b + 1);
  std::fprintf(f, "\n");
  for (const FrameRecord& r : run.frames) {
    std::fprintf(f,
                 "%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%d,%s,%d,%d,%.4f,%.4f,%d,%u,%d,%.4f,%.4f,"
                 "%.3f,%.4f,"
                 "%.4f,%.4g,%d,%d,%.4f,%.4f,%.4f,%.3f,%.3f,%d,%d,%u,%.3f,%.4g,%.3f,%.4f,%.4f,%.3f,%"
                 ".3f,%.3f,%.3f,%.3f,%d,%d,%.4f,%.3f,%d,%llu,%d",
                 r.t_s, r.truth.x_m, r.truth.y_m, r.truth.yaw_rad, r.estimate.x_m, r.estimate.y_m,
                 r.estimate.yaw_rad, r.position_error_m(), r.valid ? 1 : 0,
                 firmware::health_name(r.health), r.fix_present ? 1 : 0, r.fix_known ? 1 : 0,
                 r.fix.x_m, r.fix.y_m, static_cast<int>(r.verdict),
                 static_cast<unsigned>(r.distrusted), r.consensus ? 1 : 0, r.robust_fix.x_m,
                 r.robust_fix.y_m, r.preference, r.sigma_m, r.sigma_yaw_rad, r.match, r.covered,
                 r.evidence_known ? 1 : 0, r.evidence.x_m, r.evidence.y_m, r.evidence_distance_m,
                 r.truth_nats, r.estimate_nats, r.board_seen ? 1 : 0, r.cut_board ? 1 : 0,
                 static_cast<unsigned>(r.fix_suspects), r.truth_lane_m, r.frame_sigma_m,
                 r.frame_axis_rad, r.search_x_m, r.search_y_m, r.search_nats, r.truth_seen_nats,
                 r.truth_model_nats, r.search_model_nats, r.estimate_model_nats, r.boards_in_view,
                 r.boards_with_bearing, r.search_yaw_rad, r.nearby_sum_nats, r.nearby_by_tables,
                 static_cast<unsigned long long>(r.nearby_draws), static_cast<int>(r.cause));
    for (std::size_t b = 0; b < boards; ++b)
      std::fprintf(f, ",%.3g", static_cast<double>(r.chi2[b]));
    for (std::size_t b = 0; b < boards; ++b)
      std::fprintf(f, ",%.3f", static_cast<double>(r.static_probability[b]));
    std::fprintf(f, "\n");
  }
  const bool failed = std::ferror(f) != 0;
  if (std::fclose(f) != 0 || failed) throw std::runtime_error(path + ": cannot write the trace");
}

ErrorStats error_stats(const RunRecord& run, double from_s, double to_s) {
  ErrorStats s;
  double se = 0.0, sh = 0.0, sf = 0.0;
  for (const FrameRecord& f : run.frames) {
    if (f.t_s < from_s || f.t_s >= to_s || !f.valid) continue;
    const double e = f.position_error_m();
    se += e * e;
    s.max_m = std::max(s.max_m, e);
    const double dh = algorithms::wrap_angle_rad(f.estimate.yaw_rad - f.truth.yaw_rad);
    sh += dh * dh;
    ++s.frames;
    if (f.fix_known) {
      const double fe = std::hypot(f.fix.x_m - f.truth.x_m, f.fix.y_m - f.truth.y_m);
      sf += fe * fe;
      ++s.fixes;
    }
  }
  if (s.frames > 0) {
    s.rmse_m = std::sqrt(se / static_cast<double>(s.frames));
    s.heading_rmse_deg = std::sqrt(sh / static_cast<double>(s.frames)) * 180.0 / algorithms::kPi;
  }
  if (s.fixes > 0) s.fix_rmse_m = std::sqrt(sf / static_cast<double>(s.fixes));
  return s;
}

KidnapSummary kidnap_summary(const RunRecord& run, double bound_m, double hold_s,
                             double deadline_s) {
  KidnapSummary sum;
  double total_recovery = 0.0;
  for (std::size_t k = 0; k < run.kidnaps.size(); ++k) {
    const KidnapEvent& ev = run.kidnaps[k];
    const double end_s =
        k + 1 < run.kidnaps.size() ? run.kidnaps[k + 1].t_s : run.frames.back().t_s + 1.0;
    KidnapOutcome o;
    o.t_s = ev.t_s;
    o.distance_m = std::hypot(ev.to.x_m - ev.from.x_m, ev.to.y_m - ev.from.y_m);
    double good_since = -1.0;
    for (const FrameRecord& f : run.frames) {
      if (f.t_s < ev.t_s) continue;
      if (f.t_s >= end_s) break;
      if (!o.detected && (f.verdict == algorithms::KidnapVerdict::kKidnapped ||
                          f.verdict == algorithms::KidnapVerdict::kLost)) {
        o.detected = true;
        o.detected_after_s = f.t_s - ev.t_s;
      }
      if (o.recovered_after_s >= 0.0) continue;
      const bool good = f.valid && f.position_error_m() < bound_m;
      if (!good) {
        good_since = -1.0;
      } else {
        if (good_since < 0.0) good_since = f.t_s;
        if (f.t_s - good_since >= hold_s) o.recovered_after_s = good_since - ev.t_s;
      }
    }
    if (o.detected) ++sum.detected;
    if (o.recovered_after_s >= 0.0) {
      ++sum.recovered_ever;
      total_recovery += o.recovered_after_s;
      if (o.detected && o.recovered_after_s <= deadline_s) ++sum.recovered_within;
    }
    sum.outcomes.push_back(o);
  }
  if (sum.recovered_ever > 0)
    sum.mean_recovery_s = total_recovery / static_cast<double>(sum.recovered_ever);
  return sum;
}

}  // namespace harmoloc::sim_host
