// What the cycle derives at start-up from its config and map (no allocation after it), and
// the names of its stages and health states.
#include "harmoloc/firmware/localization_cycle.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "harmoloc/algorithms/odometry.hpp"
#include "harmoloc/algorithms/segmentation.hpp"

namespace harmoloc::firmware {

using algorithms::Pose2;

const char* stage_name(Stage stage) {
  static constexpr const char* kNames[kStageCount] = {"acquire", "segment", "localize", "encoders",
                                                      "predict", "update",  "publish",  "cycle"};
  return kNames[static_cast<std::size_t>(stage)];
}

const char* health_name(Health health) {
  switch (health) {
    case Health::kNotInitialized:
      return "not_initialized";
    case Health::kNominal:
      return "nominal";
    case Health::kOdometryOnly:
      return "odometry_only";
    case Health::kVisionOnly:
      return "vision_only";
    case Health::kInvalid:
      return "invalid";
  }
  return "unknown";
}

algorithms::DiffDriveGeometry effective_geometry(const FirmwareConfig& config,
                                                 const algorithms::MapCalibration& calibration) {
  if (!config.use_map_odometry_calibration || !calibration.odometry_present) return config.geometry;
  return algorithms::calibrated(
      config.geometry, algorithms::OdometryScale{static_cast<double>(calibration.left_wheel_scale),
                                                 static_cast<double>(calibration.right_wheel_scale),
                                                 static_cast<double>(calibration.track_scale)});
}

std::string odometry_summary(const FirmwareConfig& config,
                             const algorithms::MapCalibration& calibration) {
  if (!calibration.odometry_present) return {};
  char line[200];
  std::snprintf(line, sizeof line,
                "odometry %s the map's calibration: left wheel x %.4f, right x %.4f, track x %.4f",
                config.use_map_odometry_calibration ? "with"
                                                    : "without (odometry.map_calibration "
                                                      "= false)",
                static_cast<double>(calibration.left_wheel_scale),
                static_cast<double>(calibration.right_wheel_scale),
                static_cast<double>(calibration.track_scale));
  return line;
}

bool route_terms_on(const FirmwareConfig& config, const algorithms::MapCalibration& calibration) {
  switch (config.observation.route_terms) {
    case RouteTerms::kOn:
      return true;
    case RouteTerms::kOff:
      return false;
    case RouteTerms::kAuto:
      break;
  }
  return !algorithms::is_floor_map(calibration);
}

std::string route_terms_summary(const FirmwareConfig& config,
                                const algorithms::MapCalibration& calibration) {
  if (route_terms_on(config, calibration)) return {};
  if (config.observation.route_terms == RouteTerms::kOff)
    return "no route terms (observation.route_terms = \"off\")";
  char line[200];
  std::snprintf(line, sizeof line,
                "a floor map (its training passes %.0f deg apart): particles weighed by the "
                "boards alone, no route terms",
                static_cast<double>(calibration.pass_heading_spread_rad) * 180.0 / algorithms::kPi);
  return line;
}

bool fix_term_on(const FirmwareConfig& config, const algorithms::MapFile& map) {
  switch (config.observation.fix_term) {
    case FixTerm::kOn:
      return true;
    case FixTerm::kOff:
      return false;
    case FixTerm::kAuto:
      break;
  }
  return !algorithms::is_floor_map(map.calibration);
}

std::string fix_term_summary(const FirmwareConfig& config, const algorithms::MapFile& map) {
  if (config.observation.fix_term != FixTerm::kAuto || fix_term_on(config, map)) return {};
  return "a floor map: the harmonic fix does not weigh the particles (observation.fix_term = "
         "\"auto\"; true turns it on)";
}

bool kld_on(const FirmwareConfig& config, const algorithms::MapFile& map) {
  switch (config.filter.kld_mode) {
    case KldMode::kOn:
      return true;
    case KldMode::kOff:
      return false;
    case KldMode::kAuto:
      break;
  }
  return algorithms::is_floor_map(map.calibration);
}

std::string kld_summary(const FirmwareConfig& config, const algorithms::MapFile& map) {
  if (config.filter.kld_mode != KldMode::kAuto || !kld_on(config, map)) return {};
  char line[200];
  std::snprintf(line, sizeof line,
                "a floor map: the particle count adapts between %zu and %zu (filter.kld = "
                "\"auto\"; false keeps it at %zu)",
                std::min(config.filter.kld.min_particles, config.filter.particles),
                config.filter.particles, config.filter.particles);
  return line;
}

LocalizationCycle::LocalizationCycle(const FirmwareConfig& config, const algorithms::MapFile& map,
                                     hal::Camera& camera, hal::WheelEncoders& encoders,
                                     hal::PoseLink& link, const hal::Clock& clock,
                                     hal::PixelFormat pixel_format)
    : config_(config),
      map_(map),
      camera_(camera),
      encoders_(encoders),
      link_(link),
      clock_(clock),
      classifier_(map.thresholds),
      mavlink_(config.link.system_id, config.link.component_id),
      receiver_(config.link, &signer_),
      use_boards_(config.observation.model == ObservationModel::kBoards && map.forward.present()),
      period_ns_(static_cast<std::uint64_t>(std::llround(1e9 / config.cycle.rate_hz))),
      budget_ns_(static_cast<std::uint64_t>(std::llround(config.cycle.budget_ms * 1e6))) {
  filter_.configure(config.filter.particles, config.filter.seed, config.filter.noise);
  algorithms::KldSampling kld = config.filter.kld;
  kld.enabled = kld_on(config, map);
  filter_.set_kld_sampling(kld);
  geometry_ = effective_geometry(config, map.calibration);
  board_params_ = config.observation.boards;
  // A floor map's places between its passes, at the headings it drove, are the map's too.
  route_terms_ = route_terms_on(config, map.calibration);
  if (!route_terms_) {
    board_params_.route_sigma_m = 0.0;
    board_params_.route_heading_sigma_deg = 0.0;
  }
  // A floor the boards are weighed on, with the bearings the floor's pose searches need.
  const bool searchable_floor =
      use_boards_ && !route_terms_ && algorithms::floor_search_possible(map.forward);
  nearby_on_ = searchable_floor && config.filter.nearby_test;
  seed_heading_from_boards_ = searchable_floor && config.filter.seed_heading_from_boards;
  floor_search_on_ = searchable_floor && config.kidnap.floor_search;
  start_from_search_ = floor_search_on_ && config.filter.seed_from_search;
  if (floor_search_on_) {
    // A pass tries at most kFloorPassPlaces places, kFloorPlacesPerCycle a cycle (12 cycles,
    // 0.4 s at 30 Hz): the stride is the finest that covers the grid with that many.
    const algorithms::ForwardMap& f = map.forward;
    const auto places = [&](std::uint32_t s) {
      return static_cast<std::size_t>((f.columns + s - 1U) / s) * ((f.rows + s - 1U) / s);
    };
    while (places(floor_stride_) > kFloorPassPlaces) ++floor_stride_;
    floor_refine_m_ = static_cast<double>(floor_stride_) * static_cast<double>(f.cell_m);
    // The kidnap test weighs the best of a pass (and of its refinements) against the best of
    // the estimate's own refinement (and the estimate itself). Where a fit's chance to beat a
    // level falls off exponentially, the best of n places stands ln n above one place: the
    // luck the two maxima do not share is ln of the ratio of their places. With the pass's
    // places alone (ln 3072 = 8.0 nats) a kidnap on random floor 25 went 2.7 s unconfirmed
    // while its place fitted the frame 10 nats better than the refined estimate's.
    const auto refined =
        static_cast<double>(algorithms::FloorSearch::refine_places(kFloorRefineLevels));
    const auto searched =
        static_cast<double>(std::max<std::size_t>(places(floor_stride_), 1)) + 2.0 * refined;
    floor_margin_nats_ = std::max(0.0, std::log(searched / (refined + 1.0)));
  }
  kidnap_params_ = derived_kidnap_params(
      config.kidnap.detector, map.calibration,
      floor_search_on_ ? KidnapEvidence::kFloorSearch : KidnapEvidence::kHarmonicFix);
  // The fix's own error per axis on the training run (0 without a calibration).
  const double fix_rmse = map.calibration.present
                              ? std::hypot(static_cast<double>(map.calibration.fix_rmse_x_m),
                                           static_cast<double>(map.calibration.fix_rmse_y_m)) /
                                    std::sqrt(2.0)
                              : 0.0;
  if (config.observation.fix_board_check && map.calibration.present)
    fix_check_params_ =
        algorithms::fix_check_params(static_cast<double>(map.calibration.fix_rmse_x_m),
                                     static_cast<double>(map.calibration.fix_rmse_y_m));
  if (fix_term_on(config, map) && fix_rmse > 0.0) {
    fix_term_sigma_m_ = std::max(fix_rmse, 0.005) * std::sqrt(board_params_.tempering);
    // The per-sample fix errors (map format 11) over the forward map's cells: the fix term reads
    // the error near a fix's place from one cell. Nothing else reads them.
    fix_errors_.build(map.model, map.forward);
  }
  // Where a re-seed puts the particles: around a fix, as far as the fix's own error reaches (5 cm
  // and 4 cm for maps without a calibration). Configured values win. At start-up once that error:
  // twice it reached past the end of a route where the robot started, the route term cut the
  // cloud's far side off and its mean moved 2.6 cm inwards before the robot moved (random seed
  // 15; without the route term it stayed on the fix; docs/sweep.md). A kidnap's re-seed keeps
  // twice it: it is measured on kidnaps.
  const auto spread_m = [fix_rmse](double configured_m, double fix_factor, double fallback_m) {
    if (configured_m >= 0.0) return configured_m;
    return fix_rmse > 0.0 ? std::clamp(fix_factor * fix_rmse, 0.02, 1.0) : fallback_m;
  };
  init_sigma_m_ = spread_m(config.filter.init_position_sigma_m, 1.0, 0.05);
  reseed_sigma_m_ = spread_m(config.kidnap.position_sigma_m, 2.0, 0.04);
  if (map.calibration.present && board_params_.position_spread_m == 0.0)
    board_params_.position_spread_m = static_cast<double>(map.calibration.pass_spread_m);
  reliability_.reset(board_params_);
  if (use_boards_) board_maxima_ = algorithms::board_maxima(map.forward);
  if (config.link.has_signing_key) {
    mavlink::SigningOptions options;
    options.max_ahead = static_cast<std::uint64_t>(config.link.signing_max_ahead_s *
                                                   mavlink::kSigningUnitsPerSecond);
    options.peer_clock = config.link.signing_peer_clock;
    options.persistent = !config.link.signing_state_file.empty();
    signer_.configure(config.link.signing_key, config.link.link_id, options);
  }
  mavlink_.set_signer(&signer_);
  colour_table_storage_.reset(new std::uint8_t[algorithms::MaskTable::kStorageBytes]);
  if (pixel_format == hal::PixelFormat::kYuyv)
    yuyv_table_.build(classifier_, colour_table_storage_.get());
  else
    colour_table_.build(classifier_, colour_table_storage_.get());
  // The mapped region: the box around the training positions and the forward map's cells.
  const algorithms::HarmonicModel& m = map.model;
  double x0 = 0.0, x1 = 0.0, y0 = 0.0, y1 = 0.0;
  for (std::size_t i = 0; i < m.sample_count; ++i) {
    const auto x = static_cast<double>(m.target_x_m[i]), y = static_cast<double>(m.target_y_m[i]);
    x0 = i == 0 ? x : std::min(x0, x);
    x1 = i == 0 ? x : std::max(x1, x);
    y0 = i == 0 ? y : std::min(y0, y);
    y1 = i == 0 ? y : std::max(y1, y);
  }
  if (map.forward.present()) {
    const algorithms::ForwardMap& f = map.forward;
    const auto fx0 = static_cast<double>(f.origin_x_m), fy0 = static_cast<double>(f.origin_y_m);
    const auto cell = static_cast<double>(f.cell_m);
    x0 = std::min(x0, fx0);
    y0 = std::min(y0, fy0);
    x1 = std::max(x1, fx0 + cell * (f.columns - 1U));
    y1 = std::max(y1, fy0 + cell * (f.rows - 1U));
  }
  const double margin = config.filter.map_margin_m;
  region_min_x_m_ = x0 - margin;
  region_max_x_m_ = x1 + margin;
  region_min_y_m_ = y0 - margin;
  region_max_y_m_ = y1 + margin;
}

algorithms::KidnapParams derived_kidnap_params(const algorithms::KidnapParams& configured,
                                               const algorithms::MapCalibration& calibration,
                                               KidnapEvidence evidence) {
  algorithms::KidnapParams p = configured;
  // The harmonic fix's own error on frames of other passes, measured by the trainer. Without a
  // calibration (maps before version 4) the values of those versions' defaults. The floor
  // search's pose is good to a few centimetres, not the harmonic fix's tens: distances derived
  // from the fix's error would hide kidnaps of less than a metre, so it takes those values too.
  const double fix_rmse_m = calibration.present && evidence == KidnapEvidence::kHarmonicFix
                                ? std::hypot(static_cast<double>(calibration.fix_rmse_x_m),
                                             static_cast<double>(calibration.fix_rmse_y_m))
                                : -1.0;
  // Far: well beyond what the fix's own error explains (6 sigma), at most 1 m, and at least
  // 25 cm, a step the tracking follows by itself. The cross-validated error does not see a
  // lighting drift, which biases the fix and the boards alike: on a three-board scene that bias
  // (15 cm) passed a 10 cm floor, and a false kidnap moved a right estimate 14 cm away.
  if (p.fix_distance_m < 0.0)
    p.fix_distance_m = fix_rmse_m > 0.0 ? std::clamp(6.0 * fix_rmse_m, 0.25, 1.0) : 0.25;
  // Consistent: two fixes of the same place a frame apart differ by their error (4 sigma) plus
  // what the robot drives in a frame.
  if (p.consistency_m < 0.0)
    p.consistency_m = fix_rmse_m > 0.0 ? std::clamp(4.0 * fix_rmse_m + 0.03, 0.05, 0.5) : 0.15;
  return p;
}

}  // namespace harmoloc::firmware
