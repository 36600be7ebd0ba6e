// The cycle and its stages: frame, segmentation, harmonic fix, encoders, prediction, update
// (the board weights and the kidnap test), overrun accounting.
#include "harmoloc/firmware/localization_cycle.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "harmoloc/algorithms/odometry.hpp"
#include "harmoloc/algorithms/segmentation.hpp"

namespace harmoloc::firmware {

using algorithms::Pose2;

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

}  // namespace harmoloc::firmware
