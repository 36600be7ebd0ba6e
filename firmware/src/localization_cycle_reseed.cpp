// Where a re-seed puts the particles: around a fix, between a place and a fix, or over the
// whole mapped region.
#include "harmoloc/firmware/localization_cycle.hpp"

#include <algorithm>
#include <cmath>

namespace harmoloc::firmware {

using algorithms::Pose2;

bool LocalizationCycle::route_heading_known() const {
  return use_boards_ && map_.forward.has_heading;
}

LocalizationCycle::SeedHeading LocalizationCycle::seed_heading(double x_m, double y_m) const {
  const double configured = config_.kidnap.yaw_sigma_deg * algorithms::kPi / 180.0;
  if (seed_heading_from_boards_) {
    // On a floor the training run drove each place at several headings: its mean there is none
    // of them (random seed 25 started 100 degrees off, on a cloud as wide as its passes, and
    // lost the heading in the turn that followed; docs/sweep.md). The frame's bearings say
    // which: each board's world bearing at the place plus its image angle.
    const algorithms::FloorPose seen = algorithms::floor_pose_seen_from(
        map_.forward, observed_, x_m, y_m, board_params_, fix_.distrusted_mask);
    if (seen.valid) return SeedHeading{seen.yaw_rad, configured, false, true};
  }
  if (!route_heading_known()) return SeedHeading{0.0, configured, true};
  // Without the route terms (a floor map) the heading at a place is one of several the training
  // run drove there: as wide as its passes over one place lie apart.
  const double sigma =
      route_terms_
          ? configured
          : std::max(configured, static_cast<double>(map_.calibration.pass_heading_spread_rad));
  return SeedHeading{static_cast<double>(algorithms::route_heading(map_.forward, x_m, y_m)), sigma,
                     false};
}

void LocalizationCycle::reseed_around(double x_m, double y_m) {
  reseed_around(x_m, y_m, seed_heading(x_m, y_m));
}

void LocalizationCycle::reseed_around(double x_m, double y_m, const SeedHeading& h) {
  const double sigma_m = filter_.initialized() ? reseed_sigma_m_ : init_sigma_m_;
  filter_.initialize(Pose2{x_m, y_m, h.yaw_rad}, sigma_m, h.sigma_rad, h.uniform);
  after_reseed();
}

void LocalizationCycle::after_reseed() {
  start_waits_ = 0;
  if (gap_ == EncoderGap::kDiffused) gap_ = EncoderGap::kReseeded;
  kidnap_.reset();
  nearby_.reset();
  nearby_hint_frames_ = config_.filter.nearby.max_frames;
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
  const SeedHeading place = seed_heading(place_x_m, place_y_m);
  const SeedHeading fix = seed_heading(fix_x_m, fix_y_m);
  filter_.initialize_between(
      Pose2{place_x_m, place_y_m, place.yaw_rad}, Pose2{fix_x_m, fix_y_m, fix.yaw_rad},
      reseed_sigma_m_, std::max(place.sigma_rad, fix.sigma_rad), place.uniform || fix.uniform);
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

}  // namespace harmoloc::firmware
