#include "harmoloc/firmware/localization_cycle.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "harmoloc/algorithms/odometry.hpp"
#include "harmoloc/algorithms/segmentation.hpp"

namespace harmoloc::firmware {

using algorithms::Pose2;

const char* stage_name(Stage stage) {
  static constexpr const char* kNames[kStageCount] = {"acquire", "segment", "localize", "encoders",
                                                      "predict", "update",  "publish",  "cycle"};
  return kNames[static_cast<std::size_t>(stage)];
}

const char* health_name(Health health) {
  switch (health) {
    case Health::kNotInitialized:
      return "not_initialized";
    case Health::kNominal:
      return "nominal";
    case Health::kOdometryOnly:
      return "odometry_only";
    case Health::kVisionOnly:
      return "vision_only";
    case Health::kInvalid:
      return "invalid";
  }
  return "unknown";
}

algorithms::DiffDriveGeometry effective_geometry(const FirmwareConfig& config,
                                                 const algorithms::MapCalibration& calibration) {
  if (!config.use_map_odometry_calibration || !calibration.odometry_present) return config.geometry;
  return algorithms::calibrated(
      config.geometry, algorithms::OdometryScale{static_cast<double>(calibration.left_wheel_scale),
                                                 static_cast<double>(calibration.right_wheel_scale),
                                                 static_cast<double>(calibration.track_scale)});
}

std::string odometry_summary(const FirmwareConfig& config,
                             const algorithms::MapCalibration& calibration) {
  if (!calibration.odometry_present) return {};
  char line[200];
  std::snprintf(line, sizeof line,
                "odometry %s the map's calibration: left wheel x %.4f, right x %.4f, track x %.4f",
                config.use_map_odometry_calibration ? "with"
                                                    : "without (odometry.map_calibration "
                                                      "= false)",
                static_cast<double>(calibration.left_wheel_scale),
                static_cast<double>(calibration.right_wheel_scale),
                static_cast<double>(calibration.track_scale));
  return line;
}

LocalizationCycle::LocalizationCycle(const FirmwareConfig& config, const algorithms::MapFile& map,
                                     hal::Camera& camera, hal::WheelEncoders& encoders,
                                     hal::PoseLink& link, const hal::Clock& clock,
                                     hal::PixelFormat pixel_format)
    : config_(config),
      map_(map),
      camera_(camera),
      encoders_(encoders),
      link_(link),
      clock_(clock),
      classifier_(map.thresholds),
      mavlink_(config.link.system_id, config.link.component_id),
      receiver_(config.link, &signer_),
      use_boards_(config.observation.model == ObservationModel::kBoards && map.forward.present()),
      period_ns_(static_cast<std::uint64_t>(std::llround(1e9 / config.cycle.rate_hz))),
      budget_ns_(static_cast<std::uint64_t>(std::llround(config.cycle.budget_ms * 1e6))) {
  filter_.configure(config.filter.particles, config.filter.seed, config.filter.noise);
  kidnap_params_ = derived_kidnap_params(config.kidnap.detector, map.calibration);
  geometry_ = effective_geometry(config, map.calibration);
  board_params_ = config.observation.boards;
  // The fix's own error per axis on the training run (0 without a calibration).
  const double fix_rmse = map.calibration.present
                              ? std::hypot(static_cast<double>(map.calibration.fix_rmse_x_m),
                                           static_cast<double>(map.calibration.fix_rmse_y_m)) /
                                    std::sqrt(2.0)
                              : 0.0;
  if (config.observation.fix_board_check && map.calibration.present)
    fix_check_params_ =
        algorithms::fix_check_params(static_cast<double>(map.calibration.fix_rmse_x_m),
                                     static_cast<double>(map.calibration.fix_rmse_y_m));
  if (config.observation.fix_term && fix_rmse > 0.0)
    fix_term_sigma_m_ = std::max(fix_rmse, 0.005) * std::sqrt(board_params_.tempering);
  // Where a re-seed puts the particles: around a fix, as far as the fix's own error reaches
  // (twice it; 5 cm and 4 cm for maps without a calibration). Configured values win.
  init_sigma_m_ = config.filter.init_position_sigma_m >= 0.0 ? config.filter.init_position_sigma_m
                  : fix_rmse > 0.0                           ? std::clamp(2.0 * fix_rmse, 0.02, 1.0)
                                                             : 0.05;
  reseed_sigma_m_ = config.kidnap.position_sigma_m >= 0.0 ? config.kidnap.position_sigma_m
                    : fix_rmse > 0.0                      ? std::clamp(2.0 * fix_rmse, 0.02, 1.0)
                                                          : 0.04;
  if (map.calibration.present && board_params_.position_spread_m == 0.0)
    board_params_.position_spread_m = static_cast<double>(map.calibration.pass_spread_m);
  reliability_.reset(board_params_);
  if (use_boards_) board_maxima_ = algorithms::board_maxima(map.forward);
  if (config.link.has_signing_key) {
    mavlink::SigningOptions options;
    options.max_ahead = static_cast<std::uint64_t>(config.link.signing_max_ahead_s *
                                                   mavlink::kSigningUnitsPerSecond);
    options.peer_clock = config.link.signing_peer_clock;
    options.persistent = !config.link.signing_state_file.empty();
    signer_.configure(config.link.signing_key, config.link.link_id, options);
  }
  mavlink_.set_signer(&signer_);
  colour_table_storage_.reset(new std::uint8_t[algorithms::MaskTable::kStorageBytes]);
  if (pixel_format == hal::PixelFormat::kYuyv)
    yuyv_table_.build(classifier_, colour_table_storage_.get());
  else
    colour_table_.build(classifier_, colour_table_storage_.get());
  // The mapped region: the box around the training positions and the forward map's cells.
  const algorithms::HarmonicModel& m = map.model;
  double x0 = 0.0, x1 = 0.0, y0 = 0.0, y1 = 0.0;
  for (std::size_t i = 0; i < m.sample_count; ++i) {
    const auto x = static_cast<double>(m.target_x_m[i]), y = static_cast<double>(m.target_y_m[i]);
    x0 = i == 0 ? x : std::min(x0, x);
    x1 = i == 0 ? x : std::max(x1, x);
    y0 = i == 0 ? y : std::min(y0, y);
    y1 = i == 0 ? y : std::max(y1, y);
  }
  if (map.forward.present()) {
    const algorithms::ForwardMap& f = map.forward;
    const auto fx0 = static_cast<double>(f.origin_x_m), fy0 = static_cast<double>(f.origin_y_m);
    const auto cell = static_cast<double>(f.cell_m);
    x0 = std::min(x0, fx0);
    y0 = std::min(y0, fy0);
    x1 = std::max(x1, fx0 + cell * (f.columns - 1U));
    y1 = std::max(y1, fy0 + cell * (f.rows - 1U));
  }
  const double margin = config.filter.map_margin_m;
  region_min_x_m_ = x0 - margin;
  region_max_x_m_ = x1 + margin;
  region_min_y_m_ = y0 - margin;
  region_max_y_m_ = y1 + margin;
}

algorithms::KidnapParams derived_kidnap_params(const algorithms::KidnapParams& configured,
                                               const algorithms::MapCalibration& calibration) {
  algorithms::KidnapParams p = configured;
  // The harmonic fix's own error on frames of other passes, measured by the trainer. Without a
  // calibration (maps before version 4) the values of those versions' defaults.
  const double fix_rmse_m = calibration.present
                                ? std::hypot(static_cast<double>(calibration.fix_rmse_x_m),
                                             static_cast<double>(calibration.fix_rmse_y_m))
                                : -1.0;
  // Far: well beyond what the fix's own error explains (6 sigma), at most 1 m, and at least
  // 25 cm, a step the tracking follows by itself. The cross-validated error does not see a
  // lighting drift, which biases the fix and the boards alike: on a three-board scene that bias
  // (15 cm) passed a 10 cm floor, and a false kidnap moved a right estimate 14 cm away.
  if (p.fix_distance_m < 0.0)
    p.fix_distance_m = fix_rmse_m > 0.0 ? std::clamp(6.0 * fix_rmse_m, 0.25, 1.0) : 0.25;
  // Consistent: two fixes of the same place a frame apart differ by their error (4 sigma) plus
  // what the robot drives in a frame.
  if (p.consistency_m < 0.0)
    p.consistency_m = fix_rmse_m > 0.0 ? std::clamp(4.0 * fix_rmse_m + 0.03, 0.05, 0.5) : 0.15;
  return p;
}

namespace {

// Times one stage into its histogram.
class StageTimer {
 public:
  StageTimer(const hal::Clock& clock, LatencyHistogram& histogram)
      : clock_(clock), histogram_(histogram), start_(clock.now_ns()) {}
  ~StageTimer() { histogram_.record(clock_.now_ns() - start_); }
  StageTimer(const StageTimer&) = delete;
  StageTimer& operator=(const StageTimer&) = delete;

 private:
  const hal::Clock& clock_;
  LatencyHistogram& histogram_;
  std::uint64_t start_;
};

}  // namespace

Health LocalizationCycle::assess_health() const {
  if (!filter_.initialized()) return Health::kNotInitialized;
  const auto ms = [](double v) { return static_cast<std::uint64_t>(v * 1e6); };
  const bool vision =
      ever_fix_ && data_time_ns_ - last_fix_ns_ <= ms(config_.cycle.camera_timeout_ms);
  const bool odometry =
      have_encoder_ && data_time_ns_ - last_encoder_ns_ <= ms(config_.cycle.encoder_timeout_ms);
  if (vision && odometry) return Health::kNominal;
  if (odometry) return Health::kOdometryOnly;
  if (vision) return Health::kVisionOnly;
  return Health::kInvalid;
}

bool LocalizationCycle::off_map(const Pose2& p) const {
  // Written so that a NaN is off the map too.
  return !(p.x_m >= region_min_x_m_ && p.x_m <= region_max_x_m_ && p.y_m >= region_min_y_m_ &&
           p.y_m <= region_max_y_m_);
}

Health LocalizationCycle::published_health() const {
  const Health h = assess_health();
  if (h == Health::kNotInitialized || !off_map(pose_.pose)) return h;
  return Health::kInvalid;
}

CycleResult LocalizationCycle::run_once() {
  return run(0, false);
}

CycleResult LocalizationCycle::run_once(std::uint64_t acquire_deadline_ns) {
  return run(acquire_deadline_ns, true);
}

CycleResult LocalizationCycle::run(std::uint64_t acquire_deadline_ns, bool have_deadline) {
  const std::uint64_t cycle_start = clock_.now_ns();
  FrameIn in;
  {
    StageTimer t(clock_, histogram(Stage::kAcquire));
    in.status =
        camera_.acquire(in.frame, have_deadline ? acquire_deadline_ns : cycle_start + period_ns_);
  }
  if (in.status == hal::CameraStatus::kEnded) return CycleResult::kEnded;
  // On a live board acquire() is where the cycle waits for the camera (its pacing): the compute
  // budget starts when it returns. A replay's acquire does not wait and counts in full.
  const std::uint64_t compute_start = live_clock_ ? clock_.now_ns() : cycle_start;
  ++counters_.cycles;
  take_frame(in, cycle_start);

  algorithms::AreaVector areas;
  {
    StageTimer t(clock_, histogram(Stage::kSegment));
    segment(in, areas);
  }
  if (in.have_frame) camera_.release();
  Features features{};
  {
    StageTimer t(clock_, histogram(Stage::kLocalize));
    localize(in.usable, areas, features);
  }
  EncoderIn encoders;
  {
    StageTimer t(clock_, histogram(Stage::kEncoders));
    encoders = read_encoders();
  }
  {
    StageTimer t(clock_, histogram(Stage::kPredict));
    predict(encoders);
  }
  {
    StageTimer t(clock_, histogram(Stage::kUpdate));
    update(areas, features, encoders.fresh_sample);
  }
  {
    StageTimer t(clock_, histogram(Stage::kPublish));
    service_link();
    publish();
  }

  const std::uint64_t elapsed = clock_.now_ns() - compute_start;
  histogram(Stage::kCycle).record(elapsed);
  if (elapsed > budget_ns_) ++counters_.overruns;
  account_overrun(elapsed > budget_ns_);
  return CycleResult::kRan;
}

void LocalizationCycle::take_frame(FrameIn& in, std::uint64_t cycle_start) {
  // A frame stamped no later than the last one used (a repeated or reordered timestamp) is no
  // new view of the scene: released unused and counted; the cycle goes on as without a frame.
  const bool stale = in.status == hal::CameraStatus::kFrame && have_frame_time_ &&
                     in.frame.timestamp_ns <= last_frame_ns_;
  if (stale) {
    camera_.release();
    ++counters_.stale_frames;
  }
  in.have_frame = in.status == hal::CameraStatus::kFrame && !stale;
  frame_this_cycle_ = in.have_frame;
  if (in.have_frame) frame_time_ns_ = in.frame.timestamp_ns;
  if (in.have_frame) {
    // The data clock never goes back: a frame stamped before it (late) is used at its time.
    data_time_ns_ =
        have_data_time_ ? std::max(in.frame.timestamp_ns, data_time_ns_) : in.frame.timestamp_ns;
    have_data_time_ = true;
    last_frame_ns_ = in.frame.timestamp_ns;
    have_frame_time_ = true;
    ++counters_.frames;
  } else {
    if (in.status == hal::CameraStatus::kCorrupt)
      ++counters_.corrupt_frames;
    else if (!stale)
      ++counters_.no_frame;
    if (live_clock_) {
      data_time_ns_ = std::max(data_time_ns_, cycle_start);
      have_data_time_ = true;
    } else {
      data_time_ns_ += period_ns_;
    }
  }
  in.usable = in.have_frame && in.frame.width_px == map_.image_width_px &&
              in.frame.height_px == map_.image_height_px;
  if (in.have_frame && !in.usable) ++counters_.frame_size_mismatch;
}

void LocalizationCycle::segment(const FrameIn& in, algorithms::AreaVector& areas) {
  if (in.usable) {
    // A frame of the format the table was not built for (the camera changed format) is
    // segmented exactly without it: by the HSV arithmetic, or decoding YUYV to RGB per pixel.
    const hal::FrameView& f = in.frame;
    if (f.format == hal::PixelFormat::kRgb24) {
      if (colour_table_.ready()) {
        algorithms::segment_rgb24(f.data, f.width_px, f.height_px, f.stride_bytes, colour_table_,
                                  areas);
      } else {
        algorithms::segment_rgb24(f.data, f.width_px, f.height_px, f.stride_bytes, classifier_,
                                  areas);
      }
    } else if (yuyv_table_.ready()) {
      algorithms::segment_yuyv(f.data, f.width_px, f.height_px, f.stride_bytes, yuyv_table_, areas);
    } else {
      algorithms::segment_yuyv(f.data, f.width_px, f.height_px, f.stride_bytes, colour_table_,
                               areas);
    }
  }
}

void LocalizationCycle::localize(bool usable, const algorithms::AreaVector& areas,
                                 Features& features) {
  fix_.present = false;
  fix_.distrusted_mask = 0;
  if (usable) {
    algorithms::areas_to_features(map_.model, areas, features);
    fix_.fix = algorithms::harmonic_query(map_.model, features);
    fix_.areas = areas;
    fix_.present = true;
  }
}

LocalizationCycle::EncoderIn LocalizationCycle::read_encoders() {
  EncoderIn e;
  hal::EncoderCounts counts{};
  if (encoders_.read(data_time_ns_, counts) == hal::EncoderStatus::kFresh) {
    ++counters_.encoder_samples;
    if (have_encoder_ && gap_ != EncoderGap::kNone) {
      // The first sample after a gap the cloud spent diffusing (vision only). Its counts are
      // absolute, so they hold the travel over the whole gap: the cloud, which has meanwhile
      // spread and followed the fixes, is moved so that its centre is where that travel
      // takes the pose of the last sample (predict), keeping its spread. Applying the
      // travel on top of what the cloud did would count the motion the fixes saw twice.
      // If the filter was re-seeded in the gap, the counts only become the new reference.
      if (gap_ == EncoderGap::kDiffused) {
        const std::int64_t dl = algorithms::wrapped_delta(last_counts_.left_ticks,
                                                          counts.left_ticks, counts.counter_bits);
        const std::int64_t dr = algorithms::wrapped_delta(last_counts_.right_ticks,
                                                          counts.right_ticks, counts.counter_bits);
        gap_travel_ = algorithms::odometry_from_ticks(geometry_, dl, dr);
        e.bridge_now = true;
      }
      ++counters_.encoder_gaps_bridged;
      gap_ = EncoderGap::kNone;
    } else if (have_encoder_) {
      const std::int64_t dl = algorithms::wrapped_delta(last_counts_.left_ticks, counts.left_ticks,
                                                        counts.counter_bits);
      const std::int64_t dr = algorithms::wrapped_delta(last_counts_.right_ticks,
                                                        counts.right_ticks, counts.counter_bits);
      e.delta = algorithms::odometry_from_ticks(geometry_, dl, dr);
      e.dt_s = static_cast<double>(counts.timestamp_ns - last_counts_.timestamp_ns) * 1e-9;
      e.have_delta = true;
    }
    last_counts_ = counts;
    last_encoder_ns_ = counts.timestamp_ns;
    have_encoder_ = true;
    e.fresh_sample = true;
  }
  return e;
}

void LocalizationCycle::predict(const EncoderIn& e) {
  if (filter_.initialized()) {
    if (e.bridge_now) {
      const algorithms::Pose2 target = algorithms::apply_arc(gap_anchor_, gap_travel_);
      const algorithms::Pose2 mean = filter_.estimate().mean;
      filter_.shift(target.x_m - mean.x_m, target.y_m - mean.y_m,
                    algorithms::wrap_angle_rad(target.yaw_rad - mean.yaw_rad));
    } else if (e.have_delta) {
      filter_.predict(e.delta);
    } else if (assess_health() == Health::kVisionOnly) {
      // Motion unknown: let the cloud spread as fast as the robot could move.
      const double step_m = config_.filter.vision_only_speed_mps / config_.cycle.rate_hz;
      filter_.predict(algorithms::OdometryDelta{0.0, 0.0});
      filter_.diffuse(step_m, 0.5 * step_m / (0.5 * geometry_.track_m));
      if (gap_ == EncoderGap::kNone && have_anchor_) gap_ = EncoderGap::kDiffused;
    }
  }
  if (e.have_delta && e.dt_s > 0.0) {
    pose_.speed_mps = e.delta.distance_m / e.dt_s;
    pose_.yaw_rate_rps = e.delta.yaw_rad / e.dt_s;
  }
}

void LocalizationCycle::update(const algorithms::AreaVector& areas, const Features& features,
                               bool fresh_sample) {
  kidnap_verdict_ = algorithms::KidnapVerdict::kNone;
  // A frame no place on the map can look like (noise, a blinded sensor) is not a view.
  const bool implausible =
      fix_.present && use_boards_ &&
      algorithms::frame_implausible(map_.forward, board_maxima_,
                                    algorithms::board_features(map_.model.area_scale, areas),
                                    config_.observation.boards.implausible_ratio);
  if (implausible) ++counters_.implausible_frames;
  if (fix_.present && !implausible) {
    if (fix_.fix.known_place) {
      ++counters_.fixes_used;
      last_known_fix_ = fix_.fix;
    } else {
      ++counters_.unknown_place;
    }
    bool vision = false;
    if (!filter_.initialized()) {
      if (fix_.fix.known_place) {
        reseed_around(fix_.fix.x_m, fix_.fix.y_m);
        vision = true;
      }
    } else if (use_boards_) {
      vision = update_with_boards(areas, features);
    } else if (fix_.fix.known_place) {
      filter_.update_position(fix_.fix.x_m, fix_.fix.y_m, config_.filter.fix_sigma_m,
                              config_.filter.outlier_probability);
      if (filter_.resample_if_needed(config_.filter.resample_threshold)) ++counters_.resamples;
      vision = true;
    }
    if (vision) {
      last_fix_ns_ = data_time_ns_;
      ever_fix_ = true;
    }
  }
  if (filter_.initialized()) {
    const algorithms::PoseEstimate e = filter_.estimate();
    pose_.pose = e.mean;
    pose_.covariance = e.covariance;
    pose_.valid = true;
    // Where the robot was at the latest encoder sample: a gap's travel starts there.
    if (fresh_sample) {
      gap_anchor_ = e.mean;
      have_anchor_ = true;
    }
  }
  pose_.data_time_ns = data_time_ns_;
  pose_.health = published_health();
  ++counters_.cycles_in_health[static_cast<std::size_t>(pose_.health)];
}

void LocalizationCycle::account_overrun(bool overrun) {
  if (!overrun_alarm_enabled_) return;
  // The streak counts towards the change of state: overruns while the alarm is off, cycles
  // within the budget while it is on.
  if (overrun == overrun_alarm_) {
    overrun_streak_ = 0;
    return;
  }
  if (++overrun_streak_ < config_.cycle.overrun_alarm_cycles) return;
  overrun_streak_ = 0;
  overrun_alarm_ = !overrun_alarm_;
  if (overrun_alarm_) {
    ++counters_.overrun_alarms;
    pending_overrun_text_ = "harmoloc: cycle overrun";
  } else {
    pending_overrun_text_ = "harmoloc: cycle overrun cleared";
  }
}

bool LocalizationCycle::update_with_boards(
    const algorithms::AreaVector& areas,
    const std::array<float, algorithms::HarmonicModel::kMaxFeatures>& features) {
  const algorithms::BoardModelParams& params = board_params_;
  const algorithms::Pose2 estimate = filter_.mean_position();
  const algorithms::BoardFeatures observed =
      algorithms::board_features(map_.model.area_scale, areas);
  assessment_ = reliability_.assess(map_.forward, observed, estimate, params, board_update_);
  if (!assessment_.consensus) ++counters_.no_consensus;

  // The global fix without the boards that are not to be trusted now: those the motion index
  // has written off, and, while the others agree with the estimate, those that do not.
  algorithms::FeatureMask use{};
  for (std::size_t k = 0; k < map_.model.feature_count; ++k) {
    const std::size_t b = map_.model.board_index[k];
    const bool outlier =
        assessment_.consensus && static_cast<double>(assessment_.chi2[b]) >= params.consensus_chi2;
    use[k] = !reliability_.distrusted(b) && !outlier;
  }
  std::size_t modelled = 0, distrusted = 0;
  std::uint32_t distrusted_mask = 0;  // bit b: board b written off
  for (std::size_t b = 0; b < board_update_.boards; ++b) {
    if (!board_update_.use[b]) continue;
    ++modelled;
    if (!reliability_.distrusted(b)) continue;
    ++distrusted;
    distrusted_mask |= 1U << b;
  }
  counters_.distrusted_boards += distrusted;
  fix_.distrusted_mask = distrusted_mask;
  robust_fix_ =
      fix_check_.fix(map_.model, features, use, estimate.x_m, estimate.y_m, fix_check_params_);
  counters_.fix_board_suspicions = fix_check_.suspicions();

  const double match = filter_.update_boards(board_update_);
  // The fix (without the distrusted boards) as a second view of the same frame: where the
  // forward map is coarse or its boards noisy, the boards' terms are flat along the route, and
  // the fix still knows where the robot is. Its width is the fix's own error on the training run
  // (the map's calibration), widened as the boards' terms are tempered; an outlier floor keeps a
  // wrong fix from dragging the cloud.
  if (fix_term_sigma_m_ > 0.0 && robust_fix_.known_place) {
    filter_.update_position(robust_fix_.x_m, robust_fix_.y_m, fix_term_sigma_m_,
                            config_.filter.outlier_probability);
  }
  if (filter_.resample_if_needed(config_.filter.resample_threshold)) ++counters_.resamples;
  // The kidnap test takes the fix of every board: leaving out the boards that disagree with the
  // estimate would pull the fix towards the estimate exactly when the estimate is wrong. A
  // moved or hidden board cannot fake a kidnap with it: the boards must also prefer the fix's
  // place (board_preference, where a board showing less than expected does not count).
  const algorithms::HarmonicFix& evidence_fix = fix_.fix;

  if (config_.kidnap.enabled) {
    algorithms::KidnapInput in;
    in.match = match;
    in.consensus = assessment_.consensus;
    in.fix_known = evidence_fix.known_place;
    in.fix_x_m = evidence_fix.x_m;
    in.fix_y_m = evidence_fix.y_m;
    // Also for a fix that is not a known place: without a known fix, "lost" needs the boards to
    // prefer the fix's place as well (algorithms/kidnap_detector.hpp).
    const bool fix_finite = std::isfinite(evidence_fix.x_m) && std::isfinite(evidence_fix.y_m);
    in.fix_distance_m =
        fix_finite ? std::hypot(evidence_fix.x_m - estimate.x_m, evidence_fix.y_m - estimate.y_m)
                   : 0.0;
    if (fix_finite && in.fix_distance_m >= kidnap_params_.fix_distance_m) {
      // Without the boards the filter has written off (moved, or hidden by someone walking
      // away), unless it has written off most of them: then the estimate is the suspect.
      const std::uint32_t leave_out = 2 * distrusted <= modelled ? distrusted_mask : 0U;
      // The boards' best place near the fix (as far from it as the kidnap distance, and as
      // far from the estimate), not the fix's own place alone: where few boards are in view the
      // fix can be off by more than its training error while the boards tell the place apart.
      // That place is the evidence: its consistency is checked and the cloud re-seeded there.
      const double reach = kidnap_params_.fix_distance_m;
      const algorithms::PlacePreference best = algorithms::board_preference_near(
          map_.forward, observed, evidence_fix.x_m, evidence_fix.y_m, reach, estimate.x_m,
          estimate.y_m, reach, params, leave_out);
      in.preference = best.nats;
      in.place_x_m = best.x_m;
      in.place_y_m = best.y_m;
    }
    in.contradiction = assessment_.exceeding > 0;
    kidnap_input_ = in;
    kidnap_verdict_ = kidnap_.step(in, kidnap_params_);
    const algorithms::KidnapCounters& k = kidnap_.counters();
    counters_.kidnap_triggers = k.triggers;
    counters_.kidnaps = k.kidnaps;
    counters_.lost = k.lost;
    if (kidnap_verdict_ == algorithms::KidnapVerdict::kKidnapped) {
      if (config_.kidnap.reseed == ReseedStrategy::kAroundFix && evidence_fix.known_place)
        reseed_between(kidnap_.evidence_x_m(), kidnap_.evidence_y_m(), kidnap_.evidence_fix_x_m(),
                       kidnap_.evidence_fix_y_m());
      else
        reseed_globally();
      pending_text_ = "harmoloc: kidnap detected, relocalized";
    } else if (kidnap_verdict_ == algorithms::KidnapVerdict::kLost) {
      reseed_globally();
      pending_text_ = "harmoloc: lost (boards disagree, no fix), relocalizing over the map";
    }
  }
  return assessment_.consensus || robust_fix_.known_place;
}

bool LocalizationCycle::route_heading_known() const {
  return use_boards_ && map_.forward.has_heading;
}

algorithms::Pose2 LocalizationCycle::route_pose(double x_m, double y_m) const {
  const double yaw = route_heading_known()
                         ? static_cast<double>(algorithms::route_heading(map_.forward, x_m, y_m))
                         : 0.0;
  return Pose2{x_m, y_m, yaw};
}

double LocalizationCycle::reseed_yaw_sigma_rad() const {
  return config_.kidnap.yaw_sigma_deg * algorithms::kPi / 180.0;
}

void LocalizationCycle::reseed_around(double x_m, double y_m) {
  const double sigma_m = filter_.initialized() ? reseed_sigma_m_ : init_sigma_m_;
  filter_.initialize(route_pose(x_m, y_m), sigma_m, reseed_yaw_sigma_rad(), !route_heading_known());
  after_reseed();
}

void LocalizationCycle::after_reseed() {
  if (gap_ == EncoderGap::kDiffused) gap_ = EncoderGap::kReseeded;
  kidnap_.reset();
  // What the boards' motion indices learnt was learnt against the old, wrong estimate.
  reliability_.reset(board_params_);
  fix_check_.reset();
  ++reset_counter_;
}

void LocalizationCycle::reseed_between(double place_x_m, double place_y_m, double fix_x_m,
                                       double fix_y_m) {
  // The boards' place and the fix's place: where the boards hardly change (across a route the
  // training never left) the boards' best place can be centimetres off while the fix is not, and
  // elsewhere the other way round. The cloud starts on both and the next frames choose. A cloud
  // started on the wrong one alone converges all the same, but by selecting the particles whose
  // heading carried them towards the truth: a heading bias that the odometry then turns into
  // position error for seconds.
  if (std::hypot(place_x_m - fix_x_m, place_y_m - fix_y_m) <= reseed_sigma_m_) {
    reseed_around(place_x_m, place_y_m);
    return;
  }
  filter_.initialize_between(route_pose(place_x_m, place_y_m), route_pose(fix_x_m, fix_y_m),
                             reseed_sigma_m_, reseed_yaw_sigma_rad(), !route_heading_known());
  after_reseed();
}

void LocalizationCycle::reseed_globally() {
  const algorithms::ForwardMap& f = map_.forward;
  if (config_.kidnap.reseed == ReseedStrategy::kUniform && f.present()) {
    const auto x0 = static_cast<double>(f.origin_x_m), y0 = static_cast<double>(f.origin_y_m);
    const auto cell = static_cast<double>(f.cell_m);
    filter_.initialize_uniform(x0, y0, x0 + cell * (f.columns - 1U), y0 + cell * (f.rows - 1U));
  } else {
    const algorithms::HarmonicModel& m = map_.model;
    filter_.initialize_around_points(m.target_x_m.data(), m.target_y_m.data(), m.sample_count,
                                     reseed_sigma_m_);
  }
  after_reseed();
}

void LocalizationCycle::send(std::size_t size) {
  if (link_.write_frame(frame_buffer_.data(), size) != hal::LinkWrite::kSent)
    ++counters_.link_dropped;
}

void LocalizationCycle::report_capture_to_send() {
  const LatencyWindow::Summary s = capture_to_send_window_.take();
  if (s.count == 0) return;  // a replay, or no pose sent since the last heartbeat
  // time_boot_ms: the data clock, which on a live board is the monotonic clock (time since boot).
  const auto boot_ms = static_cast<std::uint32_t>(data_time_ns_ / 1'000'000U);
  send(mavlink_.named_value_float(boot_ms, "c2s_p50_ms",
                                  static_cast<float>(static_cast<double>(s.median_ns) * 1e-6),
                                  frame_buffer_));
  send(mavlink_.named_value_float(boot_ms, "c2s_max_ms",
                                  static_cast<float>(static_cast<double>(s.max_ns) * 1e-6),
                                  frame_buffer_));
}

void LocalizationCycle::publish() {
  const Health health = pose_.health;
  const bool heartbeat_due = data_time_ns_ >= next_heartbeat_ns_;
  if (heartbeat_due || heartbeat_requested_) {
    heartbeat_requested_ = false;
    mavlink::Heartbeat hb;
    hb.system_status = heartbeat_status(health, overrun_alarm_);
    send(mavlink_.heartbeat(hb, frame_buffer_));
  }
  if (heartbeat_due) {  // a requested one leaves the schedule alone
    report_capture_to_send();
    const auto step = static_cast<std::uint64_t>(std::llround(1e9 / config_.link.heartbeat_hz));
    next_heartbeat_ns_ = (next_heartbeat_ns_ == 0 ? data_time_ns_ : next_heartbeat_ns_) + step;
    if (next_heartbeat_ns_ <= data_time_ns_) next_heartbeat_ns_ = data_time_ns_ + step;
  }
  // Invalid because the pose is off the map says so in its own words.
  const bool off = pose_.valid && health == Health::kInvalid && off_map(pose_.pose);
  if (off) ++counters_.off_map_cycles;
  if (health != last_reported_health_ || off != last_reported_off_map_) {
    const HealthText t = health_text(health, off);
    send(mavlink_.statustext(t.severity, t.text, frame_buffer_));
    last_reported_health_ = health;
    last_reported_off_map_ = off;
  }
  if (pending_overrun_text_ != nullptr) {
    send(mavlink_.statustext(overrun_alarm_ ? mavlink::kSeverityWarning : mavlink::kSeverityInfo,
                             pending_overrun_text_, frame_buffer_));
    pending_overrun_text_ = nullptr;
  }
  if (pending_text_ != nullptr) {
    send(mavlink_.statustext(mavlink::kSeverityWarning, pending_text_, frame_buffer_));
    pending_text_ = nullptr;
  }
  if (!pose_.valid) return;

  // Map frame -> MAV_FRAME_LOCAL_FRD (pose_messages.hpp).
  send(mavlink_.odometry(odometry_message(pose_, data_time_ns_, reset_counter_), frame_buffer_));
  if (live_clock_ && frame_this_cycle_) {
    const std::uint64_t sent_ns = clock_.now_ns();
    const std::uint64_t latency_ns = sent_ns > frame_time_ns_ ? sent_ns - frame_time_ns_ : 0;
    capture_to_send_.record(latency_ns);
    capture_to_send_window_.record(latency_ns);
  }
}

}  // namespace harmoloc::firmware
