#include "harmoloc/algorithms/nearby_pose_test.hpp"

#include <cmath>

#include "harmoloc/algorithms/particle_filter.hpp"

namespace harmoloc::algorithms {

Pose2 best_model_fit_near(const BoardUpdate& update, const Pose2& around, double step_m,
                          double& nats) {
  Pose2 best = around;
  nats = -HUGE_VAL;
  for (int j = -1; j <= 1; ++j) {
    for (int i = -1; i <= 1; ++i) {
      const Pose2 p{around.x_m + i * step_m, around.y_m + j * step_m, around.yaw_rad};
      const double l = std::log(ParticleFilter::board_likelihood(update, p));
      if (l > nats) {
        nats = l;
        best = p;
      }
    }
  }
  return best;
}

double model_log_ratio(const BoardUpdate& update, const Pose2& here, Pose2& there, double step_m) {
  double here_nats = 0.0, there_nats = 0.0;
  best_model_fit_near(update, here, step_m, here_nats);
  there = best_model_fit_near(update, there, step_m, there_nats);
  return there_nats - here_nats;
}

TablesEvidence tables_evidence(const ForwardMap& map, const BoardFeatures& observed,
                               const FloorPose& searched, const Pose2& estimate, double radius_m,
                               const BoardModelParams& params, std::uint32_t leave_out) {
  TablesEvidence e;
  if (!searched.valid) return e;
  e.searched = FloorSearch::refine(map, observed, searched, radius_m, params, leave_out, 1);
  const FloorPose around{estimate.x_m, estimate.y_m, estimate.yaw_rad, 0.0, true};
  e.estimate = FloorSearch::refine(map, observed, around, radius_m, params, leave_out, 1);
  return e;
}

void NearbyPoseTest::reset() {
  holding_ = false;
  by_tables_ = false;
  sum_nats_ = 0.0;
  frames_ = 0;
}

void NearbyPoseTest::start(bool by_tables) {
  holding_ = true;
  by_tables_ = by_tables;
  sum_nats_ = 0.0;
  frames_ = 0;
}

bool NearbyPoseTest::add(double ratio, const Pose2& alternative, const NearbyPoseParams& test,
                         Pose2& draw_at) {
  // A frame that cannot be weighed (no finite likelihood) tells nothing.
  if (std::isfinite(ratio)) sum_nats_ += ratio;
  ++frames_;
  if (sum_nats_ <= test.bound_nats) return false;
  draw_at = alternative;
  reset();
  return true;
}

bool NearbyPoseTest::ended(const NearbyPoseParams& test) const {
  return sum_nats_ < -test.bound_nats || frames_ >= test.max_frames;
}

bool NearbyPoseTest::step(const ForwardMap& map, const BoardFeatures& observed,
                          const BoardUpdate& update, const Pose2& estimate,
                          const BoardModelParams& params, std::uint32_t leave_out,
                          const NearbyPoseParams& test, Pose2& draw_at, const FloorPose& hint,
                          const TablesEvidence* tables) {
  if (update.map == nullptr || !floor_search_possible(map)) return false;
  const bool use_tables = test.hint_by_tables && tables != nullptr && tables->searched.valid &&
                          tables->estimate.valid &&
                          std::hypot(tables->searched.x_m - estimate.x_m,
                                     tables->searched.y_m - estimate.y_m) >= test.min_distance_m;
  if (by_tables_ && !use_tables) reset();
  if (use_tables) {
    if (!by_tables_) start(true);
    const Pose2 searched{tables->searched.x_m, tables->searched.y_m, tables->searched.yaw_rad};
    double ratio = tables->searched.nats - tables->estimate.nats;
    // The model's best of its 3 x 3 places near the search's pose serves the veto only: the
    // draw is at the tables' pose. Where the model is flat, as it is where the tables are
    // needed, any of those places is its best.
    Pose2 model_place = searched;
    const double model = model_log_ratio(update, estimate, model_place, test.refine_step_m);
    if (std::isfinite(model) && model < -test.veto_nats) ratio = model;
    if (add(ratio, searched, test, draw_at)) return true;
    if (ended(test)) reset();
    return false;
  }
  Pose2 alternative;
  if (!holding_) {
    const auto apart = [&](const FloorPose& p) {
      return p.valid &&
             std::hypot(p.x_m - estimate.x_m, p.y_m - estimate.y_m) >= test.min_distance_m;
    };
    const FloorPose around{estimate.x_m, estimate.y_m, estimate.yaw_rad, 0.0, true};
    const FloorPose found = FloorSearch::refine(map, observed, around, test.search_radius_m, params,
                                                leave_out, test.search_levels);
    const bool have_found = apart(found), have_hint = apart(hint);
    if (!have_found && !have_hint) return false;
    alternative = have_found ? Pose2{found.x_m, found.y_m, found.yaw_rad}
                             : Pose2{hint.x_m, hint.y_m, hint.yaw_rad};
    if (have_found && have_hint) {
      // The floor search's pose where it fits this frame better in the filter's model: beyond
      // the refinement's reach (a re-seed that chose the wrong start, 0.3 m or more from the
      // robot) only the search has seen the place.
      double found_nats = 0.0, hint_nats = 0.0;
      best_model_fit_near(update, alternative, test.refine_step_m, found_nats);
      best_model_fit_near(update, Pose2{hint.x_m, hint.y_m, hint.yaw_rad}, test.refine_step_m,
                          hint_nats);
      if (hint_nats > found_nats) alternative = Pose2{hint.x_m, hint.y_m, hint.yaw_rad};
    }
    start(false);
  } else {
    alternative = Pose2{estimate.x_m + dx_m_, estimate.y_m + dy_m_,
                        wrap_angle_rad(estimate.yaw_rad + dyaw_rad_)};
  }
  const double ratio = model_log_ratio(update, estimate, alternative, test.refine_step_m);
  if (add(ratio, alternative, test, draw_at)) return true;
  const double away_m = std::hypot(alternative.x_m - estimate.x_m, alternative.y_m - estimate.y_m);
  if (ended(test) || away_m < test.min_distance_m) {
    reset();
    return false;
  }
  dx_m_ = alternative.x_m - estimate.x_m;
  dy_m_ = alternative.y_m - estimate.y_m;
  dyaw_rad_ = wrap_angle_rad(alternative.yaw_rad - estimate.yaw_rad);
  return false;
}

}  // namespace harmoloc::algorithms
