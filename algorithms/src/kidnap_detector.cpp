#include "harmoloc/algorithms/kidnap_detector.hpp"

#include <algorithm>
#include <cmath>

namespace harmoloc::algorithms {

void KidnapDetector::reset() {
  previous_match_ = 0.0;
  probability_ = 0.0;
  window_left_ = 0;
  window_evidence_ = 0;
  window_lost_evidence_ = 0;
  evidence_run_ = 0;
  evidence_gap_ = 0;
  lost_run_ = 0;
  sum_x_ = sum_y_ = sum_fix_x_ = sum_fix_y_ = 0.0;
  consistent_ = 0;
}

KidnapVerdict KidnapDetector::step(const KidnapInput& in, const KidnapParams& p) {
  // Yang et al. 2021: P = min(|d_t - d_t-1| / d_t-1, 1).
  probability_ = 0.0;
  if (previous_match_ > 0.0 && std::isfinite(in.match))
    probability_ = std::min(std::fabs(in.match - previous_match_) / previous_match_, 1.0);
  previous_match_ = std::isfinite(in.match) && in.match > 0.0 ? in.match : 0.0;
  const bool triggered = probability_ > p.change_threshold;
  if (triggered) ++counters_.triggers;

  if (!p.confirm) {
    if (!triggered) return KidnapVerdict::kNone;
    ++counters_.kidnaps;
    reset();
    return KidnapVerdict::kKidnapped;
  }

  // With a fix: it is a known place far from the estimate, and the boards prefer it. Without:
  // the boards contradict the estimate and prefer the fix's place all the same. Contradiction
  // alone is not enough: a board moved towards the camera, a lighting step or a stretch the
  // forward map knows poorly (a route end) shows more area than expected while the estimate is
  // right, and the fix, although not a known place, is then near the estimate or no better.
  const bool far_and_preferred =
      in.fix_distance_m >= p.fix_distance_m && in.preference >= p.preference_min;
  bool evidence = in.fix_known && far_and_preferred;
  const bool lost_evidence =
      !in.consensus && !in.fix_known && in.contradiction && far_and_preferred;
  const bool searched = std::isfinite(in.place_x_m) && std::isfinite(in.place_y_m);
  const double place_x_m = searched ? in.place_x_m : in.fix_x_m;
  const double place_y_m = searched ? in.place_y_m : in.fix_y_m;
  if (evidence) {
    // Consistent with the previous evidence (the same place, give or take the robot's motion)?
    // If not, this frame starts a new stretch. Either the fix or the boards' place may hold
    // still: where the boards hardly change along the route their best place wanders by more
    // than a fix's error from frame to frame, and where few boards are seen the fix does.
    if (consistent_ > 0 && std::hypot(place_x_m - last_x_, place_y_m - last_y_) > p.consistency_m &&
        std::hypot(in.fix_x_m - last_fix_x_, in.fix_y_m - last_fix_y_) > p.consistency_m) {
      consistent_ = 0;
      sum_x_ = sum_y_ = sum_fix_x_ = sum_fix_y_ = 0.0;
      evidence_run_ = 0;
      evidence_gap_ = 0;
      window_evidence_ = 0;
    }
    sum_x_ += place_x_m;
    sum_y_ += place_y_m;
    sum_fix_x_ += in.fix_x_m;
    sum_fix_y_ += in.fix_y_m;
    ++consistent_;
    last_x_ = place_x_m;
    last_y_ = place_y_m;
    last_fix_x_ = in.fix_x_m;
    last_fix_y_ = in.fix_y_m;
  } else if (!evidence && evidence_run_ == 0 && window_left_ == 0) {
    consistent_ = 0;
    sum_x_ = sum_y_ = sum_fix_x_ = sum_fix_y_ = 0.0;
  }
  if (evidence) {
    ++evidence_run_;
    evidence_gap_ = 0;
  } else if (evidence_run_ > 0 && ++evidence_gap_ > p.divergence_gap_frames) {
    evidence_run_ = 0;
    evidence_gap_ = 0;
  }
  lost_run_ = lost_evidence ? lost_run_ + 1 : 0;
  if (triggered && window_left_ == 0) {
    window_left_ = p.window_frames;
    window_evidence_ = 0;
    window_lost_evidence_ = 0;
  }
  bool confirmed = false, confirmed_lost = false;
  if (window_left_ > 0) {
    if (evidence) ++window_evidence_;
    if (lost_evidence) ++window_lost_evidence_;
    --window_left_;
    confirmed = window_evidence_ >= p.evidence_frames;
    confirmed_lost = !confirmed && window_lost_evidence_ >= p.evidence_frames;
  }
  if (confirmed || evidence_run_ >= p.divergence_frames) {
    ++counters_.kidnaps;
    if (!confirmed) ++counters_.divergences;
    const double n = static_cast<double>(consistent_);
    evidence_x_m_ = consistent_ > 0 ? sum_x_ / n : place_x_m;
    evidence_y_m_ = consistent_ > 0 ? sum_y_ / n : place_y_m;
    evidence_fix_x_m_ = consistent_ > 0 ? sum_fix_x_ / n : in.fix_x_m;
    evidence_fix_y_m_ = consistent_ > 0 ? sum_fix_y_ / n : in.fix_y_m;
    reset();
    return KidnapVerdict::kKidnapped;
  }
  // A cloud spread over the map disagrees with the boards until it has converged: after a
  // re-seed over the map, only the long evidence (lost_frames in a row) calls it lost again, so
  // that the cloud is not spread again every few frames.
  if (lost_hold_ > 0) {
    --lost_hold_;
    confirmed_lost = false;
  }
  if (confirmed_lost || lost_run_ >= p.lost_frames) {
    ++counters_.kidnaps;
    ++counters_.lost;
    reset();
    lost_hold_ = p.lost_frames;
    return KidnapVerdict::kLost;
  }
  return triggered ? KidnapVerdict::kTriggered : KidnapVerdict::kNone;
}

}  // namespace harmoloc::algorithms
