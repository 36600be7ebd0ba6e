#pragma once
/// @file Kidnap test (Yang et al. 2021) made reliable. Yang et al. 2021 watches d_t, the sum of the
/// particles' unnormalised weights (how well the frame matches the cloud), and calls the robot
/// kidnapped when its change rate P = min(|d_t - d_t-1| / d_t-1, 1) exceeds 0.5. On its own that
/// fires on every occluded board and on ordinary frame-to-frame noise, so here a trigger only opens
/// a short window in which the kidnap must be confirmed by evidence that does not come from the
/// cloud: the harmonic localizer's global fix is a known place far from the estimate, the
/// boards fit the fix's place clearly better than the estimate's (a likelihood ratio over the
/// forward map, robust per board), and the fixes agree with each other from frame to frame. The
/// fix leaves out the boards the filter distrusts, unless it distrusts most of them: that the
/// boards all disagree at once says the estimate, not the boards, is wrong. The same evidence
/// held for a few frames at one place without a trigger also counts. Without a fix at a known place
/// (the robot put down off the trained route), the boards must show that the estimate is wrong:
/// most disagree, at least one shows more area than expected there, which no occlusion can do
/// (a person in front of the camera only hides boards), and they prefer the fix's place, known
/// or not, clearly to the estimate's (a board moved towards the camera or a lighting step also
/// shows more area, but leaves the estimate's place the better fit). The filter is then lost
/// and re-seeded over the whole map, and given lost_frames to converge before the next time.

#include <cstdint>
#include <limits>

namespace harmoloc::algorithms {

struct KidnapParams {
  double change_threshold = 0.5;  ///< Yang et al. 2021: trigger when P = min(dw, 1) exceeds this
  bool confirm = true;            ///< false: Yang et al.'s test alone (a trigger is a kidnap)
  int window_frames = 6;          ///< frames after a trigger in which to confirm it
  int evidence_frames = 3;        ///< frames of evidence needed within the window
  double fix_distance_m = 0.25;   ///< evidence: the global fix is at least this far away
  /// Evidence: the boards' log-likelihood ratio of the fix's place over the estimate's, in nats
  /// (ln 100: the frame is a hundred times likelier at the fix).
  double preference_min = 4.6;
  /// Evidence farther apart than this from one frame to the next, both the fixes and the boards'
  /// places, is not the same place: the count starts over.
  double consistency_m = 0.15;
  int divergence_frames = 8;  ///< this many frames of evidence at one place, without a trigger
  /// Frames without evidence that do not end that stretch. Where the match sinks slowly after a
  /// carry, the boards' preference can dip under preference_min for a frame or two while the
  /// fixes hold still (0: the frames must follow each other).
  int divergence_gap_frames = 2;
  int lost_frames = 90;  ///< the same for the evidence without a fix: lost
};

/// What the cycle saw this frame.
struct KidnapInput {
  double match = 0.0;                   ///< d_t: the sum of unnormalised weights after the update
  bool consensus = true;                ///< most boards agree with the estimate
  bool fix_known = false;               ///< the global fix is a known place
  double fix_distance_m = 0.0;          ///< from the global fix to the estimate
  double fix_x_m = 0.0, fix_y_m = 0.0;  ///< the global fix
  /// Where the boards place the robot near the fix (NaN: at the fix). The evidence's consistency
  /// is checked on this place.
  double place_x_m = std::numeric_limits<double>::quiet_NaN();
  double place_y_m = std::numeric_limits<double>::quiet_NaN();
  /// The boards' log-likelihood ratio of the fix's place over the estimate's (nats).
  double preference = 0.0;
  bool contradiction = false;  ///< a disagreeing board shows more area than expected
};

enum class KidnapVerdict : std::uint8_t {
  kNone = 0,
  kTriggered = 1,  ///< Yang et al.'s test fired this frame; not (yet) confirmed
  kKidnapped = 2,  ///< confirmed: re-seed around the global fix
  kLost = 3,       ///< the boards contradict the estimate and no fix is usable: re-seed widely
};

struct KidnapCounters {
  std::uint64_t triggers = 0;     ///< frames where Yang et al.'s P exceeded the threshold
  std::uint64_t kidnaps = 0;      ///< confirmed (or, without confirmation, every trigger)
  std::uint64_t divergences = 0;  ///< of those, confirmed by long evidence without a trigger
  std::uint64_t lost = 0;
};

class KidnapDetector {
 public:
  /// Forgets the previous frame (after a re-seed, so that the new cloud's first match is not
  /// compared with the old one's).
  void reset();

  /// One frame with a measurement update.
  KidnapVerdict step(const KidnapInput& input, const KidnapParams& params);

  /// Yang et al.'s P of the last frame.
  double probability() const { return probability_; }
  /// Where the evidence of the last confirmed kidnap put the robot: the mean of the boards'
  /// places over its consistent frames.
  double evidence_x_m() const { return evidence_x_m_; }
  double evidence_y_m() const { return evidence_y_m_; }
  /// The mean of the global fixes over the same frames. Where the boards tell places apart
  /// poorly (across a route, which the training never left) the fix can be the nearer of the two.
  double evidence_fix_x_m() const { return evidence_fix_x_m_; }
  double evidence_fix_y_m() const { return evidence_fix_y_m_; }
  const KidnapCounters& counters() const { return counters_; }

 private:
  double previous_match_ = 0.0;
  double probability_ = 0.0;
  int window_left_ = 0;
  int window_evidence_ = 0;
  int window_lost_evidence_ = 0;
  int evidence_run_ = 0;  // frames of evidence in the current stretch
  int evidence_gap_ = 0;  // frames without evidence since the stretch's last
  int lost_run_ = 0;
  int lost_hold_ = 0;  // frames after a lost verdict without the short (window) path; not reset()
  // The current stretch of consistent evidence: its fixes' sum and count, the last fix.
  double sum_x_ = 0.0, sum_y_ = 0.0;
  double sum_fix_x_ = 0.0, sum_fix_y_ = 0.0;
  int consistent_ = 0;
  double last_x_ = 0.0, last_y_ = 0.0;
  double last_fix_x_ = 0.0, last_fix_y_ = 0.0;
  double evidence_x_m_ = 0.0, evidence_y_m_ = 0.0;
  double evidence_fix_x_m_ = 0.0, evidence_fix_y_m_ = 0.0;
  KidnapCounters counters_{};
};

}  // namespace harmoloc::algorithms
