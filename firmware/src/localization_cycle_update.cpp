// The update stage: the particle filter's update from the fix or the boards' weights, and the
// kidnap test.
#include "harmoloc/firmware/localization_cycle.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace harmoloc::firmware {

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
  bool vision = false;
  if (fix_.present && !implausible) {
    if (fix_.fix.known_place) {
      ++counters_.fixes_used;
      last_known_fix_ = fix_.fix;
    } else {
      ++counters_.unknown_place;
    }
    if (!filter_.initialized()) {
      if (fix_.fix.known_place) {
        // The seed's heading on a floor comes from this frame's bearings. A frame whose boards
        // give none (all cut by the frame's side, or too small) is let pass, for a second at
        // most: seeded at the training run's mean heading there instead, random seed 25's
        // first cloud stood 100 degrees off and lost the heading in the turn that followed.
        if (seed_heading_from_boards_ || start_from_search_)
          observed_ = algorithms::board_features(map_.forward, map_.model.area_scale, areas);
        // With filter.seed_from_search (the default) the floor search looks over the whole floor
        // while the seed waits, and the first cloud starts on the search's pose and the fix. On a
        // floor map the harmonic fix is trained at the headings the coverage run drove and can be
        // 15-50 cm off at a start (random floors 1, 7 and 9): a cloud seeded around it alone
        // settled 15-20 cm from the robot for 3-10 s.
        if (start_from_search_) follow_floor(observed_);
        const SeedHeading heading = seed_heading(fix_.fix.x_m, fix_.fix.y_m);
        const bool want_heading = seed_heading_from_boards_ && !heading.from_boards;
        const bool want_search = start_from_search_ && !floor_fix_.valid;
        if ((want_heading || want_search) && start_waits_ < kStartWaitFrames) {
          ++start_waits_;
        } else if (start_from_search_ && floor_fix_.valid) {
          // The search's pose as precise as its refinement, the fix as wide as its calibrated
          // error (as the first seed around the fix alone is). With both 3 cm wide, a start
          // whose two places were both wrong (random floor 7: the search 31 cm off, the fix 17
          // cm) held no particle near the robot; on 30 random floors the worst roam went from
          // 9.3 to 7.8 cm RMSE with the wider fix (docs/sweep.md, 2026-12-08).
          const double search_sigma_m = std::max(floor_refine_m_, 0.03);
          seed_from_search(search_sigma_m, std::max(search_sigma_m, init_sigma_m_),
                           heading.sigma_rad);
          vision = true;
        } else {
          reseed_around(fix_.fix.x_m, fix_.fix.y_m, heading);
          vision = true;
        }
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
      last_view_ns_ = data_time_ns_;
      ever_fix_ = true;
    }
  }
  if (filter_.initialized()) {
    const algorithms::PoseEstimate e = filter_.estimate();
    // A view counts as vision only where the map's heading coverage holds the estimate's
    // heading at its place: facing another way, the map's view there is a guess, and a pose
    // that agrees with a guess is not known to within the map's accuracy.
    if (vision && algorithms::heading_covered(map_.forward, e.mean.x_m, e.mean.y_m, e.mean.yaw_rad))
      last_fix_ns_ = data_time_ns_;
    pose_.pose = e.mean;
    pose_.covariance = e.covariance;
    // Entered at nominal_spread_m, left under the lower resume bound: a spread hovering at the
    // bound does not flip the health (and its STATUSTEXT) every few cycles. A NaN is wide.
    const double spread_m =
        std::sqrt(std::max(0.0, 0.5 * (e.covariance(0, 0) + e.covariance(1, 1))));
    spread_wide_ = spread_wide_ ? !(spread_m < config_.filter.nominal_resume_spread_m)
                                : !(spread_m < config_.filter.nominal_spread_m);
    pose_.valid = true;
    const std::uint64_t particles = filter_.size();
    counters_.particles_min =
        counters_.particle_cycles == 0 ? particles : std::min(counters_.particles_min, particles);
    counters_.particles_max = std::max(counters_.particles_max, particles);
    counters_.particles_sum += particles;
    ++counters_.particle_cycles;
    // Where the robot was at the latest encoder sample: a gap's travel starts there.
    if (fresh_sample) {
      gap_anchor_ = e.mean;
      have_anchor_ = true;
    }
  }
  pose_.data_time_ns = data_time_ns_;
  set_published_health();
  if (pose_.cause == HealthCause::kHeadingNotCovered) ++counters_.uncovered_cycles;
  if (pose_.cause == HealthCause::kBoardsDisagree) ++counters_.disagree_cycles;
  if (pose_.cause == HealthCause::kSpreadWide) ++counters_.spread_wide_cycles;
  ++counters_.cycles_in_health[static_cast<std::size_t>(pose_.health)];
}

bool LocalizationCycle::update_with_boards(
    const algorithms::AreaVector& areas,
    const std::array<float, algorithms::HarmonicModel::kMaxFeatures>& features) {
  const algorithms::BoardModelParams& params = board_params_;
  double yaw_variance_rad2 = 0.0, position_variance_m2 = 0.0;
  // The cloud's spread in position only where the map projects areas (BoardReliability::assess).
  const bool projected_areas = algorithms::projects_areas(map_.forward);
  const algorithms::Pose2 estimate =
      filter_.mean_pose(&yaw_variance_rad2, projected_areas ? &position_variance_m2 : nullptr);
  observed_ = algorithms::board_features(map_.forward, map_.model.area_scale, areas);
  ++observations_;
  const algorithms::BoardFeatures& observed = observed_;
  assessment_ =
      reliability_.assess(map_.forward, observed, estimate, params, board_update_,
                          yaw_variance_rad2, std::sqrt(position_variance_m2), filter_.size());
  if (!assessment_.consensus) ++counters_.no_consensus;

  // The global fix without the boards that are not to be trusted now: those the motion index
  // has written off, and, while the others agree with the estimate, those that do not; nor
  // those the frame's side cuts (localize()).
  algorithms::FeatureMask use{};
  for (std::size_t k = 0; k < map_.model.feature_count; ++k) {
    const std::size_t b = map_.model.board_index[k];
    const bool outlier =
        assessment_.consensus && static_cast<double>(assessment_.chi2[b]) >= params.consensus_chi2;
    use[k] = !reliability_.distrusted(b) && !outlier && uncut_[k];
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
  robust_fix_ = fix_check_.fix(map_.model, features, use, estimate.x_m, estimate.y_m,
                               fix_check_params_, frame_columns());
  counters_.fix_board_suspicions = fix_check_.suspicions();

  const double match = filter_.update_boards(board_update_);
  // The fix (without the distrusted boards) as a second view of the same frame: where the
  // forward map is coarse or its boards noisy, the boards' terms are flat along the route, and
  // the fix still knows where the robot is. Its width is the fix's own error on the training run
  // (the map's calibration), widened as the boards' terms are tempered; an outlier floor keeps a
  // wrong fix from dragging the cloud. Where the training run's fixes that named this place were
  // wrong by more (the map's per-sample fix errors), it is that much wider: there a fix 10-20 cm
  // off outweighed the boards and held a re-seeded cloud off the robot (docs/sweep.md).
  if (fix_term_sigma_m_ > 0.0 && robust_fix_.known_place) {
    const double sigma_m = algorithms::fix_term_sigma_m(
        fix_term_sigma_m_, board_params_.tempering,
        fix_errors_.at(map_.forward, robust_fix_.x_m, robust_fix_.y_m));
    filter_.update_position(robust_fix_.x_m, robust_fix_.y_m, sigma_m,
                            config_.filter.outlier_probability);
  }
  if (filter_.resample_if_needed(config_.filter.resample_threshold)) ++counters_.resamples;
  // The kidnap test takes the fix of every board: leaving out the boards that disagree with the
  // estimate would pull the fix towards the estimate exactly when the estimate is wrong. A
  // moved or hidden board cannot fake a kidnap with it: the boards must also prefer the fix's
  // place (board_preference, where a board showing less than expected does not count).
  const algorithms::HarmonicFix& evidence_fix = fix_.fix;
  // Without the boards the filter has written off (moved, or hidden by someone walking away),
  // unless it has written off most of them: then the estimate is the suspect.
  const std::uint32_t leave_out = 2 * distrusted <= modelled ? distrusted_mask : 0U;
  // The floor search runs in every cycle: after a kidnap on a floor most boards can still agree
  // with the old estimate within their widened noise (on a random floor the consensus held for
  // 1.5 s and more after four of five kidnaps), so the consensus cannot tell it when to look.
  // It weighs every board, as the kidnap test's harmonic fix does: after a kidnap the boards the
  // robot now sees disagree with the old estimate, the motion index writes them off within half
  // a second, and without them the search had no bearing left. On random floor 6 its pose stood
  // 2 cm from the robot, 20 nats better than the estimate, 0.4 s after a kidnap, and was gone
  // the next frame for 30 s. A moved board costs it at most ln(1 / c) at every place.
  if (floor_search_on_) follow_floor(observed);
  // On a floor the cloud cannot follow boards that keep preferring a place 10 cm or more away
  // (no particle is there to be weighed); the nearby pose test draws some there when they do.
  // For the first frames after a re-seed the floor search's pose is an alternative too, beyond
  // the refinement's reach: where the re-seed's two starts were a search pose and a harmonic fix
  // and the cloud chose the wrong one (random floor 7: 0.3 m off, the search's pose 2 cm from
  // the robot and 7-12 nats better a frame for 3 s). Not in steady tracking: where the map errs
  // the search's pose errs further than the cloud, which the odometry holds (random floor 1:
  // roam RMSE 14.9 -> 24.8 cm with the hint always on; weighed by the tables always, floors 1,
  // 2, 3, 15 and 21 went from 4.2-8.8 to 9.9-21.5 cm).
  const bool hint = floor_search_on_ && nearby_hint_frames_ > 0;
  if (nearby_hint_frames_ > 0) --nearby_hint_frames_;
  algorithms::Pose2 draw_at;
  // In those frames the map's tables weigh the search's pose against the estimate, each the
  // best of 5 x 5 places 2 cm apart around it (the same luck for both), with every board as the
  // search weighs them.
  const algorithms::NearbyPoseParams& nearby = config_.filter.nearby;
  algorithms::TablesEvidence tables;
  if (nearby_on_ && hint && nearby.hint_by_tables && floor_fix_.valid) {
    tables = algorithms::tables_evidence(map_.forward, observed, floor_fix_, estimate,
                                         2.0 * nearby.refine_step_m, board_params_,
                                         kFloorSearchLeaveOut);
  }
  if (nearby_on_ &&
      nearby_.step(map_.forward, observed, board_update_, estimate, params, leave_out, nearby,
                   draw_at, hint ? floor_fix_ : algorithms::FloorPose{}, &tables)) {
    const auto count =
        static_cast<std::size_t>(static_cast<double>(filter_.size()) * nearby.draw_share);
    filter_.replace_some(draw_at, nearby.refine_step_m, nearby.draw_yaw_sigma_rad,
                         std::max<std::size_t>(count, 1), nearby.draw_weight);
    ++counters_.nearby_draws;
  }

  if (config_.kidnap.enabled && floor_search_on_) {
    floor_kidnap_test(observed, estimate, match);
  } else if (config_.kidnap.enabled) {
    algorithms::KidnapInput in;
    in.match = match;
    in.consensus = assessment_.consensus;
    in.fix_known = evidence_fix.known_place;
    in.fix_x_m = evidence_fix.x_m;
    in.fix_y_m = evidence_fix.y_m;
    // Also for a fix that is not a known place: without a known fix, "lost" needs the boards to
    // prefer the fix's place as well (algorithms/kidnap_detector.hpp). A fix beyond the mapped
    // region (a local linear correction extrapolates) is no evidence either way: a re-seed there
    // would be published as off the map.
    const bool fix_usable = fix_on_map(evidence_fix);
    if (!fix_usable) in.fix_known = false;
    in.fix_distance_m =
        fix_usable ? std::hypot(evidence_fix.x_m - estimate.x_m, evidence_fix.y_m - estimate.y_m)
                   : 0.0;
    if (fix_usable && in.fix_distance_m >= kidnap_params_.fix_distance_m) {
      // The boards' best place near the fix (as far from it as the kidnap distance, and as
      // far from the estimate), not the fix's own place alone: where few boards are in view the
      // fix can be off by more than its training error while the boards tell the place apart.
      // That place is the evidence: its consistency is checked and the cloud re-seeded there.
      const double reach = kidnap_params_.fix_distance_m;
      const algorithms::PlacePreference best = algorithms::board_preference_near(
          map_.forward, observed, evidence_fix.x_m, evidence_fix.y_m, reach, estimate.x_m,
          estimate.y_m, reach, params, leave_out, estimate.yaw_rad);
      in.preference = best.nats;
      in.place_x_m = best.x_m;
      in.place_y_m = best.y_m;
    }
    in.contradiction = assessment_.exceeding > 0;
    if (step_kidnap_test(in) == algorithms::KidnapVerdict::kKidnapped) {
      if (config_.kidnap.reseed == ReseedStrategy::kAroundFix && evidence_fix.known_place)
        reseed_between(kidnap_.evidence_x_m(), kidnap_.evidence_y_m(), kidnap_.evidence_fix_x_m(),
                       kidnap_.evidence_fix_y_m());
      else
        reseed_globally();
    }
  }
  // A known-place fix vouches for the estimate only where the filter weighs it. On a floor map
  // (the fix term off) the fix, trained at the headings the coverage run drove, can be a metre
  // off: on random floor 23 it kept a kidnapped robot's pose nominal for 3.5 s, 1.1 m from the
  // robot, while every board disagreed with the estimate (chi2 in the thousands) and the frames
  // gave no bearing for the floor search to confirm the kidnap with.
  const bool fix_vouches = fix_term_sigma_m_ > 0.0 && robust_fix_.known_place;
  if (assessment_.consensus || fix_vouches) return true;
  last_disagree_ns_ = data_time_ns_;
  return false;
}

void LocalizationCycle::follow_floor(const algorithms::BoardFeatures& observed) {
  constexpr std::uint32_t leave_out = kFloorSearchLeaveOut;
  using algorithms::FloorSearch;
  const algorithms::BoardModelParams& params = board_params_;
  // The pose followed so far, refined on this frame (the robot moved), against the best of a
  // pass that completed this cycle, refined too (the pass saw several frames).
  algorithms::FloorPose followed = FloorSearch::refine(
      map_.forward, observed, floor_fix_, floor_refine_m_, params, leave_out, kFloorRefineLevels);
  if (floor_search_.step(map_.forward, observed, params, leave_out, kFloorPlacesPerCycle,
                         floor_stride_)) {
    followed = algorithms::better_of(
        followed, FloorSearch::refine(map_.forward, observed, floor_search_.last_pass(),
                                      floor_refine_m_, params, leave_out, kFloorRefineLevels));
  }
  floor_fix_ = followed;
}

void LocalizationCycle::floor_kidnap_test(const algorithms::BoardFeatures& observed,
                                          const algorithms::Pose2& estimate, double match) {
  constexpr std::uint32_t leave_out = kFloorSearchLeaveOut;
  // The floor search's pose stands for the harmonic fix: a known place where it is valid, far
  // when it is, and the boards (areas and bearings) prefer it to the estimate by the difference
  // of their fits.
  algorithms::KidnapInput in;
  in.match = match;
  in.consensus = assessment_.consensus;
  in.contradiction = assessment_.exceeding > 0;
  in.fix_known = floor_fix_.valid;
  if (floor_fix_.valid) {
    in.fix_x_m = floor_fix_.x_m;
    in.fix_y_m = floor_fix_.y_m;
    in.fix_distance_m = std::hypot(floor_fix_.x_m - estimate.x_m, floor_fix_.y_m - estimate.y_m);
    if (in.fix_distance_m >= kidnap_params_.fix_distance_m) {
      // The estimate searched as the search's pose was: its own heading may be a few degrees
      // off, which the bearings' narrow noise would count as many nats against it.
      algorithms::FloorPose near{estimate.x_m, estimate.y_m, estimate.yaw_rad, 0.0, true};
      near.nats = algorithms::floor_fit(map_.forward, observed, estimate.x_m, estimate.y_m,
                                        estimate.yaw_rad, board_params_, leave_out);
      near = algorithms::better_of(
          near, algorithms::FloorSearch::refine(map_.forward, observed, near, floor_refine_m_,
                                                board_params_, leave_out, kFloorRefineLevels));
      // The best of a pass is the luckiest of its places: it must beat the estimate by the luck
      // the two maxima do not share more (floor_margin_nats_, set at start-up).
      in.preference = floor_fix_.nats - near.nats - floor_margin_nats_;
      // The search weighs the map's tables; the filter weighs the boards projected from the
      // fitted camera where the map has them, and a place the tables predict poorly can fit the
      // tables worse than a wrong place does. Where the filter's own model finds the search's
      // place as unlikely against the estimate as the test asks the other way (ln 100), that
      // is no evidence: on random floor 27's roam the tables fitted the robot's place at -9.4
      // nats and a place 0.8 m away at -0.8, the filter's model the robot's place at -0.5 and
      // that one at -17, and the test re-seeded a right estimate there (RMSE 2.2 -> 38.3 cm).
      // Where the model is flat (the boards it sees written off after a kidnap) it does not
      // contradict the search.
      if (in.preference >= kidnap_params_.preference_min && board_update_.map != nullptr) {
        algorithms::Pose2 searched{floor_fix_.x_m, floor_fix_.y_m, floor_fix_.yaw_rad};
        const double model_nats = algorithms::model_log_ratio(board_update_, estimate, searched,
                                                              config_.filter.nearby.refine_step_m);
        if (std::isfinite(model_nats) && model_nats < -kidnap_params_.preference_min)
          in.preference = model_nats;
      }
      in.place_x_m = floor_fix_.x_m;
      in.place_y_m = floor_fix_.y_m;
    }
  }
  if (step_kidnap_test(in) != algorithms::KidnapVerdict::kKidnapped) return;
  // At the search's pose of this frame, not the evidence's mean over the frames that confirmed
  // it: the robot moved on meanwhile, and the pose carries the heading.
  if (config_.kidnap.reseed == ReseedStrategy::kAroundFix && floor_fix_.valid) {
    const double sigma_m = config_.kidnap.position_sigma_m >= 0.0 ? config_.kidnap.position_sigma_m
                                                                  : std::max(floor_refine_m_, 0.03);
    seed_from_search(sigma_m, sigma_m, config_.kidnap.yaw_sigma_deg * algorithms::kPi / 180.0);
  } else {
    reseed_globally();
  }
}

void LocalizationCycle::seed_from_search(double sigma_m, double fix_sigma_m, double yaw_sigma_rad) {
  const algorithms::Pose2 searched{floor_fix_.x_m, floor_fix_.y_m, floor_fix_.yaw_rad};
  // The harmonic fix as a second start, where it is a known place apart from the search's pose
  // and the boards give a heading there: the search weighs the boards alone, and where the map
  // predicts the robot's own place poorly a wrong place can fit the frame better (random floor
  // 2: the truth at -8 to -20 nats, a place 0.2-0.6 m off at -0.7, the fix 4-10 cm from the
  // robot). The filter weighs the fix as well, and the next frames choose between the two.
  const algorithms::HarmonicFix& fix = fix_.fix;
  const bool fix_apart = fix.known_place && fix_on_map(fix) &&
                         std::hypot(fix.x_m - searched.x_m, fix.y_m - searched.y_m) > sigma_m;
  const SeedHeading at_fix = fix_apart ? seed_heading(fix.x_m, fix.y_m) : SeedHeading{};
  if (at_fix.from_boards) {
    filter_.initialize_between(searched, sigma_m,
                               algorithms::Pose2{fix.x_m, fix.y_m, at_fix.yaw_rad}, fix_sigma_m,
                               std::max(yaw_sigma_rad, at_fix.sigma_rad), false);
  } else {
    filter_.initialize(searched, sigma_m, yaw_sigma_rad, false);
  }
  after_reseed();
}

algorithms::KidnapVerdict LocalizationCycle::step_kidnap_test(const algorithms::KidnapInput& in) {
  kidnap_input_ = in;
  kidnap_verdict_ = kidnap_.step(in, kidnap_params_);
  const algorithms::KidnapCounters& k = kidnap_.counters();
  counters_.kidnap_triggers = k.triggers;
  counters_.kidnaps = k.kidnaps;
  counters_.lost = k.lost;
  if (kidnap_verdict_ == algorithms::KidnapVerdict::kKidnapped) {
    pending_text_ = "harmoloc: kidnap detected, relocalized";
  } else if (kidnap_verdict_ == algorithms::KidnapVerdict::kLost) {
    reseed_globally();
    pending_text_ = "harmoloc: lost (boards disagree, no fix), relocalizing over the map";
  }
  return kidnap_verdict_;
}

}  // namespace harmoloc::firmware
