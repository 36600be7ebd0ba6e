#pragma once
/// @file A family of random scenes (docs/scenarios.md, "Random scenes"): rooms, boards, lenses,
/// resolutions, noise, lighting, robots, encoders and routes drawn from a seed, so that a sweep
/// can train and evaluate on many scenes nobody tuned on. Deterministic: the same seed gives the
/// same scene on any machine (algorithms::Pcg32 only, no std:: distributions). Each scene is
/// feasible: a careful user would have put its boards where the camera sees them (at every
/// checked point of the route at least 2 boards with a usable area, none ever more than 40% of
/// the frame); draws that are not are redrawn from the next sub-seed.

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "harmoloc/algorithms/segmentation.hpp"
#include "harmoloc/sim_host/scenario.hpp"

namespace harmoloc::sim_host {

/// The random scene of @p seed: its training run (one lap; a loop twice round), 64 labels. Its
/// description says what was drawn and how many attempts the feasibility check took.
Scenario random_scenario(std::uint64_t seed);

/// What the feasibility check found on a scene's route.
struct FeasibilityReport {
  bool feasible = false;
  std::size_t points = 0;              ///< places checked along the route (every 0.25 m)
  std::size_t min_boards_in_view = 0;  ///< fewest boards with a usable area at any of them
  double share_with_three = 0.0;       ///< share of the places with 3 or more
  double max_board_share = 0.0;        ///< largest share of the frame one board took anywhere
  std::string reason;                  ///< why not, when not feasible
};

/// Usable: at least this share of the frame's pixels (0.12%: 92 pixels at 320x240).
constexpr double kUsableBoardShare = 0.0012;
/// No board may take more than this share of the frame.
constexpr double kMaxBoardShare = 0.40;

/// Checks @p scenario's boards along its route (as driven forward, at the route's own places,
/// every 0.25 m) with SceneRenderer::visible_board_pixels on a 320-pixel-wide copy of its camera
/// (same field of view, lens and aspect). Feasible: at least 2 boards usable everywhere, none
/// above kMaxBoardShare.
FeasibilityReport check_feasibility(const Scenario& scenario);

/// The HSV windows a careful user would set for @p scenario's boards, in board order: a hue
/// window around each board's hue, narrow enough to keep off its neighbours (wrapping through 0
/// where needed: min > max), saturation_min between the room's colours and the boards', and a
/// value range wide enough for the vignetting and the lighting's range. The same for a scene and
/// its derived runs below (other lighting, kidnaps, people, moved boards, long runs).
std::vector<std::pair<std::string, algorithms::ColourThreshold>> thresholds_for(
    const Scenario& scenario);
/// The same as a ThresholdSet (names dropped), for segment_rgb24 and the trainer.
algorithms::ThresholdSet threshold_set(
    const std::vector<std::pair<std::string, algorithms::ColourThreshold>>& windows);

/// A firmware configuration (docs/config-format.md) for @p scenario: `[odometry]` with the robot's
/// nominal geometry, `[can]` with its encoder frame layout and a `[[board]]` window per board
/// (thresholds_for). What `harmoloc-sim --random` writes as harmoloc.toml.
std::string firmware_config_toml(const Scenario& scenario);

/// The same scene under other lighting (drift, steps and global gain drawn from @p seed): a test
/// run. The run's noise seed is the ScenarioRun's, not this.
Scenario with_other_lighting(const Scenario& scenario, std::uint64_t seed);

/// The scene with @p kidnaps kidnaps (at least 1 m each, less on routes too small for that: half
/// the route's span), about 15 s apart from 15 s, and laps enough for 30 s after the last.
/// Throws std::runtime_error with one line when the route allows no such schedule.
Scenario kidnap_variant(const Scenario& scenario, int kidnaps);

/// The scene, two laps or more, with a person who walks in between the route and a board and
/// hides it for a few seconds (3.5 s standing), and a board moved 30 cm along its wall (its
/// width axis) halfway through the run.
Scenario dynamic_variant(const Scenario& scenario);

/// The nominal scene driven for at least @p minutes (laps enough).
Scenario long_variant(const Scenario& scenario, double minutes);

/// The floor around a scene's route that its floor runs cover (docs/scenarios.md, "Floor
/// runs"): a rectangle along the route's principal axis (its extent plus 0.3 m, at most 3 x 2 m,
/// less where a few minutes of lanes would not cover it), clear of the walls and the desk, and the
/// headings from which at least 80% of its places (a 20 cm grid) see 2 usable boards: a
/// shuttle's mean heading and 20 degrees either side, a loop's four quarter turns from the
/// floor's axis. Shrunk towards the route's middle until at least two headings qualify.
struct FloorPlan {
  double centre_x_m = 0.0;
  double centre_y_m = 0.0;
  double axis_rad = 0.0;  ///< the long side's direction
  double half_length_m = 0.0;
  double half_width_m = 0.0;
  std::vector<double> headings_rad;  ///< the covered headings
  std::size_t places = 0;            ///< grid places checked
};
/// Throws std::runtime_error with one line when no floor qualifies.
FloorPlan floor_plan(const Scenario& scenario);

/// The training run of a floor map: lanes over floor_plan's floor along each covered heading
/// (forward along a lane, reversing diagonally to the next: the camera keeps the heading), a tour
/// of about 6 minutes at the scene's speed (at least 0.15 m/s), 64 labels over it.
Scenario coverage_variant(const Scenario& scenario);

/// A test run on the floor that no training drove: @p waypoints random poses on floor_plan's
/// floor (drawn from @p seed), headings within 12 degrees of a covered one, joined by turns on the
/// spot and straight legs along which every place sees 2 usable boards. With @p kidnaps, the
/// robot is carried every 10 s from 10 s to another such pose on the floor (at least 1 m away,
/// or 40% of the floor's diagonal on small floors) and drives on from there to the pose it was
/// heading for; more poses where the roam would end too soon.
Scenario roam_variant(const Scenario& scenario, std::uint64_t seed, int waypoints = 8,
                      int kidnaps = 0);

}  // namespace harmoloc::sim_host
