#pragma once
/// @file A sequential test between the filter's estimate and the best pose near it, for floor
/// maps. A particle cloud a few centimetres wide cannot follow boards that fit a place 10 to
/// 40 cm away better: no particle is there to be weighed, and a frame's evidence alone is too
/// flat to tell a better place from noise. So the test keeps one alternative pose, carried with
/// the estimate's motion, and sums the log-ratio of the boards' likelihood there and at the
/// estimate, frame by frame, in the filter's own model (untempered; each pose the best of a few
/// places around it, so that neither gains from being searched). When the sum passes a bound,
/// particles are drawn around the alternative and the filter's own weighing decides between
/// the two; when it falls below minus the bound, or after a number of frames, the alternative
/// is dropped and another sought. In the frames after a re-seed the alternative can instead be
/// the floor search's pose, weighed by the map's tables (NearbyPoseParams::hint_by_tables). No
/// heap; bounded work per frame.

#include <cstdint>

#include "harmoloc/algorithms/board_observation.hpp"
#include "harmoloc/algorithms/floor_search.hpp"
#include "harmoloc/algorithms/forward_map.hpp"
#include "harmoloc/algorithms/geometry.hpp"

namespace harmoloc::algorithms {

struct NearbyPoseParams {
  double bound_nats = 20.0;       ///< the summed log-ratio that draws particles (and drops at -)
  std::uint32_t max_frames = 60;  ///< frames an alternative is tested before another is sought
  double search_radius_m = 0.20;  ///< where an alternative is sought around the estimate
  /// Levels of the search (FloorSearch::refine): a 5 x 5 grid over the radius, then each further
  /// level the eight places around the best at half the step.
  int search_levels = 1;
  double min_distance_m = 0.05;  ///< an alternative nearer the estimate than this is none
  double refine_step_m = 0.02;   ///< both poses: the best of 3 x 3 places this far apart
  /// The draw: this share of the particles, around the pose (position spread refine_step_m,
  /// heading spread draw_yaw_sigma_rad: its heading comes from the bearings, a degree or two),
  /// holding this share of the weight. The following frames weigh them as any other, so a
  /// wrong draw fades and a right one takes over.
  double draw_share = 0.25;
  double draw_yaw_sigma_rad = 2.0 * kPi / 180.0;
  double draw_weight = 0.5;
  /// Within the hint frames after a re-seed: weigh the floor search's pose against the estimate
  /// by the map's tables (TablesEvidence) where the filter's own model does not veto it. After
  /// a re-seed the model can be flat over 20 cm and more where the tables are not (random floor
  /// 21: the model fitted the robot's place and the estimate 24 cm off within 0.3 nats a frame,
  /// the tables the search's pose, 2-6 cm from the robot, 5 nats a frame better than the
  /// estimate at its own heading; both refined as the test weighs them, by 0.2 on that kidnap).
  bool hint_by_tables = true;
  /// The model's log-ratio below minus this (ln 100, as the floor kidnap test's veto) vetoes a
  /// frame of the tables' evidence: the frame counts the model's log-ratio instead.
  double veto_nats = 4.6;
};

/// One frame's view of the map's tables (the floor search's fit): the search's pose, refined on
/// this frame, and the estimate refined alike (the same radius, levels and boards), so that
/// neither gains from being searched more.
struct TablesEvidence {
  FloorPose searched;
  FloorPose estimate;
};

/// The tables' evidence of one frame: @p searched (the floor search's pose) and @p estimate each
/// refined within @p radius_m (FloorSearch::refine, one level: 5 x 5 places, the heading from
/// the bearings at each), every board but those in @p leave_out.
TablesEvidence tables_evidence(const ForwardMap& map, const BoardFeatures& observed,
                               const FloorPose& searched, const Pose2& estimate, double radius_m,
                               const BoardModelParams& params, std::uint32_t leave_out);

/// The boards' log-likelihood in the filter's own model (@p update, untempered) of the best of
/// 3 x 3 places @p step_m apart around @p around, at its heading, in @p nats; returns that place.
/// The likelihood is at least the product of the boards' floors, so its log is finite.
Pose2 best_model_fit_near(const BoardUpdate& update, const Pose2& around, double step_m,
                          double& nats);

/// The filter's model's log-ratio of @p there over @p here, each the best of its 3 x 3 places
/// (best_model_fit_near, @p here first); @p there becomes its best place.
double model_log_ratio(const BoardUpdate& update, const Pose2& here, Pose2& there, double step_m);

class NearbyPoseTest {
 public:
  /// Forgets the alternative (after a re-seed).
  void reset();

  /// One frame: seeks an alternative when none is held (the floor search's refinement around
  /// @p estimate, the heading from the bearings), else carries it by the estimate's motion;
  /// refines both on @p update (the filter's board update of this frame) and adds the
  /// log-ratio. Returns true, with the pose in @p draw_at, when the sum passed the bound (the
  /// alternative is then dropped). @p hint: the floor search's pose, where there is one; when
  /// no alternative is held it is taken instead of the refinement's where it lies apart from the
  /// estimate and fits the frame better (it may lie beyond search_radius_m). @p tables: the
  /// tables' evidence of this frame (tables_evidence), where the caller has it; with
  /// hint_by_tables, while it is given and its search pose lies apart from the estimate, that pose
  /// is the alternative, taken afresh each frame, and the frame adds the tables' log-ratio unless
  /// the model vetoes it (NearbyPoseParams::veto_nats); a frame without it ends such a test.
  bool step(const ForwardMap& map, const BoardFeatures& observed, const BoardUpdate& update,
            const Pose2& estimate, const BoardModelParams& params, std::uint32_t leave_out,
            const NearbyPoseParams& test, Pose2& draw_at, const FloorPose& hint = FloorPose{},
            const TablesEvidence* tables = nullptr);

  bool holding() const { return holding_; }
  /// The alternative held is the floor search's pose, weighed by the tables.
  bool by_tables() const { return by_tables_; }
  double summed_nats() const { return sum_nats_; }

 private:
  /// Holds a new alternative (@p by_tables: the search's pose, weighed by the tables).
  void start(bool by_tables);
  /// Adds a frame's log-ratio; true, with @p alternative in @p draw_at and the test forgotten,
  /// when the sum passed the bound.
  bool add(double ratio, const Pose2& alternative, const NearbyPoseParams& test, Pose2& draw_at);
  /// The sum fell below minus the bound, or the alternative had its frames.
  bool ended(const NearbyPoseParams& test) const;

  bool holding_ = false;
  bool by_tables_ = false;  ///< the alternative is the search's pose (holding_ too)
  double dx_m_ = 0.0, dy_m_ = 0.0, dyaw_rad_ = 0.0;  ///< the alternative less the estimate
  double sum_nats_ = 0.0;
  std::uint32_t frames_ = 0;
};

}  // namespace harmoloc::algorithms
