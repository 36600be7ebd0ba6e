// The cycle and its stages: frame, segmentation, harmonic fix, encoders, prediction, overrun
// accounting; the update (the board weights and the kidnap test) is in
// localization_cycle_update.cpp.
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
  const bool vision = ever_fix_ && camera_fresh(last_fix_ns_);
  const bool odometry =
      have_encoder_ && data_time_ns_ - last_encoder_ns_ <=
                           static_cast<std::uint64_t>(config_.cycle.encoder_timeout_ms * 1e6);
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

bool LocalizationCycle::fix_on_map(const algorithms::HarmonicFix& fix) const {
  return !off_map(Pose2{fix.x_m, fix.y_m, 0.0});
}

bool LocalizationCycle::camera_fresh(std::uint64_t t_ns) const {
  return data_time_ns_ - t_ns <= static_cast<std::uint64_t>(config_.cycle.camera_timeout_ms * 1e6);
}

void LocalizationCycle::set_published_health() {
  Health h = assess_health();
  HealthCause cause = HealthCause::kInputs;
  if (h != Health::kNotInitialized && off_map(pose_.pose)) {
    h = Health::kInvalid;
    cause = HealthCause::kOffMap;
  } else if ((h == Health::kOdometryOnly || h == Health::kInvalid) && ever_fix_) {
    if (camera_fresh(last_view_ns_))
      cause = HealthCause::kHeadingNotCovered;
    else if (camera_fresh(last_disagree_ns_))
      cause = HealthCause::kBoardsDisagree;
  } else if (h == Health::kNominal && spread_wide_) {
    // Fresh frames and encoders, but a cloud as wide as the published quality's 0: the boards
    // do not pin the pose (one board in view, a cloud just seeded). On 30 random floors 28% of the
    // nominal cycles more than 10 cm off were so (docs/sweep.md, 2026-12-07 (7)).
    h = Health::kOdometryOnly;
    cause = HealthCause::kSpreadWide;
  }
  pose_.health = h;
  pose_.cause = cause;
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
  uncut_.fill(true);
  columns_valid_ = false;
  if (usable) {
    algorithms::areas_to_features(map_.model, areas, features);
    // The columns cost a square root a board; a map without them never reads them.
    if (map_.model.uses_columns())
      columns_valid_ = algorithms::areas_to_columns(map_.model, areas, columns_);
    // Without the boards the frame's side cuts, while two others are in view: the update's
    // fixes leave them out too (uncut_).
    fix_.fix = algorithms::harmonic_fix(map_.model, areas, features, frame_columns(), uncut_);
    if (fix_.fix.cut_board_left_out) ++counters_.cut_board_frames;
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
    } else if (const Health h = assess_health();
               h == Health::kVisionOnly ||
               (h == Health::kInvalid && ever_fix_ && camera_fresh(last_disagree_ns_))) {
      // Motion unknown: let the cloud spread as fast as the robot could move. Also while the
      // frames' boards disagree with it (the pose then goes out invalid): the robot may be
      // moving away from the cloud.
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

}  // namespace harmoloc::firmware
