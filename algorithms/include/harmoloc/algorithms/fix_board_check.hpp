#pragma once
/// @file Which boards the harmonic fix may use while the filter tracks: Cheng et al.'s question (is
/// this landmark static?) asked of the fix. A board moved along its wall changes its area the way
/// a few centimetres of travel would; where the other boards' areas hardly change along the
/// route, its own residual at the estimate stays small, so its motion index never falls, and the
/// fix, which weighs all boards together, follows it (a random scene of the sweep: the fix 10-22
/// cm off for 90 s while the fix without that board was within 2 cm).
///
/// So every frame one board of the fix is checked by leaving it out: when the fix with it lies
/// far from the filter's estimate (beyond far_m, three times the fix's own error on the training
/// run) and the fix without it near (within near_m, one and a half times that error), the board
/// is held suspect for hold_frames and the fix does without it. A kidnap does not look like
/// this: there every board agrees on the new place, and leaving one out does not bring the fix
/// back to the old estimate. A suspect board whose fix comes back near the estimate is trusted
/// again at its next check. The fix always keeps at least two boards.
///
/// Online: fixed size, no allocation; two queries of the model a frame (one of which is the fix).

#include <array>
#include <cstddef>
#include <cstdint>

#include "harmoloc/algorithms/harmonic_localizer.hpp"
#include "harmoloc/algorithms/harmonic_model.hpp"

namespace harmoloc::algorithms {

/// Boards a fix needs for the check to run: it leaves one out and the fix keeps two. The trainer's
/// board selection keeps this many at least (KernelSelectionOptions::min_boards).
inline constexpr std::size_t kFixCheckMinBoards = 3;

struct FixCheckParams {
  double far_m = 0.0;    ///< the fix with the board at least this far from the estimate
  double near_m = 0.0;   ///< the fix without it within this (0: no check)
  int hold_frames = 30;  ///< frames a board stays suspect after a check found it so
};

/// The check's bounds from the fix's RMS error per axis on the training run (the map's
/// calibration): far 3 and near 1.5 times its radial error, at least 3 and 1.5 cm. 0 (no
/// calibration): no check.
FixCheckParams fix_check_params(double fix_rmse_x_m, double fix_rmse_y_m);

class FixBoardCheck {
 public:
  /// Trusts every board again (after a re-seed: the estimate it was checked against is gone).
  void reset();

  /// The harmonic fix from @p features with the features @p use allows, less those held
  /// suspect; checks one feature first. (@p x_m, @p y_m): the filter's predicted position.
  /// @p columns: the frame's column features (harmonic_query()), or null.
  HarmonicFix fix(const HarmonicModel& model,
                  const std::array<float, HarmonicModel::kMaxFeatures>& features,
                  const FeatureMask& use, double x_m, double y_m, const FixCheckParams& params,
                  const ColumnFeatures* columns = nullptr);

  /// Whether feature @p k is held suspect.
  bool suspect(std::size_t k) const { return hold_[k] > 0; }
  /// Checks that found a board suspect, since start-up.
  std::uint64_t suspicions() const { return suspicions_; }

 private:
  std::array<std::int32_t, HarmonicModel::kMaxFeatures> hold_{};
  std::size_t next_ = 0;
  std::uint64_t suspicions_ = 0;
};

}  // namespace harmoloc::algorithms
