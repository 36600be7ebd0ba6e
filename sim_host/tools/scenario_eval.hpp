#pragma once
/// @file Scenario evaluation for the particle filter (docs/filter.md): trains a map on a
/// simulated run and replays simulated runs (occlusions, moved boards, kidnaps) through the
/// firmware's own cycle, in memory (frames are rendered as the cycle asks for them), recording
/// the truth, the estimate, the harmonic fix and the kidnap test's verdict of every frame; then
/// the numbers of the scenario table. A host tool's library: it composes the firmware's cycle
/// with the simulator, as a board's main does.

#include <array>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "harmoloc/algorithms/kidnap_detector.hpp"
#include "harmoloc/algorithms/map_codec.hpp"
#include "harmoloc/firmware/config.hpp"
#include "harmoloc/firmware/localization_cycle.hpp"
#include "harmoloc/sim_host/scenario.hpp"
#include "harmoloc/sim_host/scenario_run.hpp"
#include "harmoloc/sim_host/trainer.hpp"

namespace harmoloc::sim_host {

using Progress = std::function<void(std::size_t done, std::size_t total)>;

/// Simulates @p scenario with @p seed in memory, segments every frame and trains a map on it
/// with its labels and its wheel odometry (the firmware's default thresholds, or @p thresholds).
struct TrainedMap {
  std::unique_ptr<algorithms::MapFile> map;
  TrainReport report;
  /// RMS distance between where the trainer placed the frames and where they were (0 when
  /// the frames were not placed by odometry).
  double placement_rmse_m = 0.0;
  double placement_heading_rmse_deg = 0.0;
  double placement_max_m = 0.0;  ///< the largest position error of a placed frame
  std::size_t frames = 0;
};
TrainedMap train_on_scenario(const Scenario& scenario, std::uint64_t seed,
                             const Progress& progress = nullptr,
                             const algorithms::ThresholdSet* thresholds = nullptr,
                             const TrainOptions* options = nullptr);

/// One frame of a replay.
struct FrameRecord {
  double t_s = 0.0;  ///< from the start of the run
  algorithms::Pose2 truth;
  algorithms::Pose2 estimate;
  bool valid = false;
  firmware::Health health = firmware::Health::kNotInitialized;
  firmware::HealthCause cause = firmware::HealthCause::kInputs;
  bool fix_present = false;  ///< the harmonic localizer computed a fix (a usable frame)
  bool fix_known = false;    ///< the harmonic localizer's own fix is a known place
  /// A board the localizer compares showed (HarmonicFix::board_seen): without, the fix is none.
  bool board_seen = false;
  /// The fix left out a board the frame's side cuts (HarmonicFix::cut_board_left_out).
  bool cut_board = false;
  algorithms::Pose2 fix;
  algorithms::KidnapVerdict verdict = algorithms::KidnapVerdict::kNone;
  std::uint8_t distrusted = 0;    ///< bit b: board b's motion index is below one half
  std::uint8_t fix_suspects = 0;  ///< bit b: the fix check holds board b suspect (fix_board_check)
  bool consensus = true;          ///< most boards agreed with the estimate
  std::size_t boards = 0;         ///< boards of the map
  /// Per board: its residual at the estimate (chi2 in the widened sigma) and motion index.
  std::array<float, algorithms::kMaxBoards> chi2{};
  std::array<float, algorithms::kMaxBoards> static_probability{};
  algorithms::Pose2 robust_fix;  ///< the fix without the distrusted boards (x, y)
  double preference = 0.0;       ///< the kidnap test's: the boards' preference for the fix's place
  /// The kidnap test's evidence pose: the harmonic fix, or on a floor the floor search's pose
  /// (KidnapInput's fix), whether it counts as a known place, and its distance to the estimate.
  bool evidence_known = false;
  algorithms::Pose2 evidence;
  double evidence_distance_m = 0.0;
  /// How well the frame's boards fit the forward map at the true pose and at the estimate
  /// (algorithms::floor_fit: nats, at most ln(1 + c) a term, in the map's trained noise). NaN
  /// where they were not computed: a replay without board fits, a map without a forward map, or
  /// a cycle that did not weigh the boards (no new frame, or the first frame, which seeds the
  /// filter). The estimate fitting better than the truth says the map is wrong there, an equal
  /// fit that the boards cannot tell the two apart.
  double truth_nats = std::numeric_limits<double>::quiet_NaN();
  double estimate_nats = std::numeric_limits<double>::quiet_NaN();
  /// The floor search's pose and its fit; the fit at the truth's place with the heading the
  /// bearings give there (what the search would find at the truth).
  double search_x_m = std::numeric_limits<double>::quiet_NaN();
  double search_y_m = std::numeric_limits<double>::quiet_NaN();
  double search_nats = std::numeric_limits<double>::quiet_NaN();
  double search_yaw_rad = std::numeric_limits<double>::quiet_NaN();
  double truth_seen_nats = std::numeric_limits<double>::quiet_NaN();
  /// The filter's own observation model (untempered log-likelihood) at the truth, the search's
  /// pose and the estimate.
  double truth_model_nats = std::numeric_limits<double>::quiet_NaN();
  double search_model_nats = std::numeric_limits<double>::quiet_NaN();
  double estimate_model_nats = std::numeric_limits<double>::quiet_NaN();
  /// Boards the filter's model weighs that show an area in this frame, and of those, the ones
  /// that give a bearing (-1 without a model): fewer than two leave a pose a line of places.
  int boards_in_view = -1;
  int boards_with_bearing = -1;
  /// The nearby pose test after this frame: its summed log-ratio (NaN when it holds no
  /// alternative), whether the alternative is the search's pose weighed by the tables (1) or
  /// not (0; -1 with no test), and the particle draws it made so far in the run.
  double nearby_sum_nats = std::numeric_limits<double>::quiet_NaN();
  int nearby_by_tables = -1;
  std::uint64_t nearby_draws = 0;
  /// How far the frame leaves the position open at the estimate (algorithms::frame_information:
  /// the weakest direction's sigma, metres, and that direction, radians). NaN where no board
  /// fits were computed.
  double frame_sigma_m = std::numeric_limits<double>::quiet_NaN();
  double frame_axis_rad = std::numeric_limits<double>::quiet_NaN();
  /// The forward map's distance from the true pose to the training run (route_distance, metres):
  /// on a floor, how far the true place lies from the coverage run's lanes. NaN without a
  /// forward map.
  double truth_lane_m = std::numeric_limits<double>::quiet_NaN();
  double sigma_m = 0.0;        ///< the published position spread (root of the mean variance)
  double sigma_yaw_rad = 0.0;  ///< the published heading spread
  double match = 0.0;          ///< the kidnap test's d_t (the particles' summed weights)
  /// The map's heading coverage at the estimate: 1 covered, 0 not, -1 the map has none.
  int covered = -1;
  double position_error_m() const;
};

struct RunRecord {
  std::vector<FrameRecord> frames;
  std::vector<KidnapEvent> kidnaps;
  firmware::CycleCounters counters;
  bool uses_boards = false;
  /// The largest fit truth_nats and estimate_nats can take (a perfect fit: ln(1 + c) for each
  /// board's area and bearing); 0 when the replay computed no fits.
  double fit_bound_nats = 0.0;
};

/// What a replay records beyond the cycle's own outputs.
enum class ReplayDetail {
  kOutputs,    ///< the cycle's outputs and inputs to its tests
  kBoardFits,  ///< also truth_nats and estimate_nats, for a trace (two fits a frame)
};

/// Replays @p scenario (seed @p seed) through the cycle with @p map and @p config.
RunRecord replay_scenario(const Scenario& scenario, std::uint64_t seed,
                          const algorithms::MapFile& map, const firmware::FirmwareConfig& config,
                          const Progress& progress = nullptr,
                          ReplayDetail detail = ReplayDetail::kOutputs);

/// Writes @p run frame by frame as CSV (truth, estimate, fix, health, the kidnap test's verdict,
/// the distrusted boards), its kidnaps as `#` lines first: for looking at one scene's run
/// (harmoloc-sweep --trace). Throws std::runtime_error naming @p path when it cannot be written.
void write_trace(const RunRecord& run, const std::string& path);

/// Errors over the frames whose time is in [@p from_s, @p to_s) and that have a pose.
struct ErrorStats {
  std::size_t frames = 0;
  double rmse_m = 0.0, max_m = 0.0, heading_rmse_deg = 0.0;
  double fix_rmse_m = 0.0;  ///< the harmonic fixes (known places) of the same frames
  std::size_t fixes = 0;
};
ErrorStats error_stats(const RunRecord& run, double from_s, double to_s);

/// What became of one kidnap.
struct KidnapOutcome {
  double t_s = 0.0;
  double distance_m = 0.0;  ///< how far the robot was carried
  bool detected = false;    ///< the filter confirmed a kidnap (re-seeded) before recovering
  double detected_after_s = -1.0;
  /// First time after the kidnap from which the error stays below the bound for hold_s, or -1.
  double recovered_after_s = -1.0;
};

struct KidnapSummary {
  std::vector<KidnapOutcome> outcomes;
  std::size_t detected = 0;
  std::size_t recovered_within = 0;  ///< detected and recovered within the deadline
  std::size_t recovered_ever = 0;    ///< recovered before the next kidnap
  double mean_recovery_s = 0.0;      ///< over those recovered at all
};

/// @p bound_m: recovered = error below this; @p hold_s: for this long; @p deadline_s: the target.
KidnapSummary kidnap_summary(const RunRecord& run, double bound_m, double hold_s,
                             double deadline_s);

}  // namespace harmoloc::sim_host
