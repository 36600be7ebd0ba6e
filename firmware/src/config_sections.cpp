// The config's sections of the cycle, boards, odometry, CAN layout, filter, observation model,
// kidnap test and real-time settings (docs/config-format.md).
#include "config_checker.hpp"

#include <cmath>
#include <cstdint>

namespace harmoloc::firmware::config_detail {

// [cycle]: rate, budget, time-outs, pacing.
void read_cycle(const Checker& check, const toml::table& root, FirmwareConfig& c) {
  if (const toml::table* t = check.section(root, "cycle")) {
    check.only(*t, "cycle.",
               {"rate_hz", "budget_ms", "camera_timeout_ms", "encoder_timeout_ms", "pacing",
                "overrun_alarm_cycles"});
    c.cycle.rate_hz = check.number(*t, "rate_hz", "cycle.", c.cycle.rate_hz, 1.0, 1000.0);
    c.cycle.budget_ms = check.number(*t, "budget_ms", "cycle.", c.cycle.budget_ms, 0.01, 1000.0);
    c.cycle.camera_timeout_ms =
        check.number(*t, "camera_timeout_ms", "cycle.", c.cycle.camera_timeout_ms, 1.0, 60000.0);
    c.cycle.encoder_timeout_ms =
        check.number(*t, "encoder_timeout_ms", "cycle.", c.cycle.encoder_timeout_ms, 1.0, 60000.0);
    const std::string pacing = check.text(*t, "pacing", "cycle.", "camera");
    if (pacing == "camera")
      c.cycle.pacing = Pacing::kCamera;
    else if (pacing == "timer")
      c.cycle.pacing = Pacing::kTimer;
    else
      check.fail(t->get("pacing"), "cycle.pacing must be \"camera\" or \"timer\"");
    c.cycle.overrun_alarm_cycles = static_cast<std::uint32_t>(
        check.integer(*t, "overrun_alarm_cycles", "cycle.", c.cycle.overrun_alarm_cycles, 1, 1000));
  }
}

// [[board]]: the colour windows, one per landmark board.
void read_boards(const Checker& check, const toml::table& root, FirmwareConfig& c) {
  if (const toml::node* boards_node = root.get("board")) {
    const toml::array* boards = boards_node->as_array();
    if (boards == nullptr || !boards->is_array_of_tables())
      check.fail(boards_node, "[[board]] entries must be tables");
    if (boards->empty() || boards->size() > algorithms::kMaxBoards)
      check.fail(boards_node, "1 to 8 [[board]] entries");
    c.thresholds.count = boards->size();
    for (std::size_t i = 0; i < boards->size(); ++i) {
      const toml::table& b = *(*boards)[i].as_table();
      const std::string where = "board[" + std::to_string(i) + "].";
      check.only(b, where, {"name", "hue_deg", "saturation_min", "value_min", "value_max"});
      c.board_names.names[i] = check.text(b, "name", where, "board" + std::to_string(i + 1));
      const toml::node* hue = b.get("hue_deg");
      const toml::array* h = hue != nullptr ? hue->as_array() : nullptr;
      if (h == nullptr || h->size() != 2)
        check.fail(hue != nullptr ? hue : &b, where + "hue_deg must be [min, max] in degrees");
      algorithms::ColourThreshold& t = c.thresholds.boards[i];
      for (int k = 0; k < 2; ++k) {
        const toml::node& e = *h->get(static_cast<std::size_t>(k));
        double v = 0.0;
        if (auto iv = e.value_exact<std::int64_t>())
          v = static_cast<double>(*iv);
        else if (auto dv = e.value_exact<double>())
          v = *dv;
        else
          check.fail(&e, where + "hue_deg values must be numbers");
        if (!(v >= 0.0 && v <= 360.0))
          check.fail(&e, where + "hue_deg values must be within 0..360");
        (k == 0 ? t.hue_min_deg : t.hue_max_deg) = static_cast<float>(v);
      }
      t.saturation_min =
          static_cast<std::uint8_t>(check.integer(b, "saturation_min", where, 100, 0, 255));
      t.value_min = static_cast<std::uint8_t>(check.integer(b, "value_min", where, 50, 0, 255));
      t.value_max = static_cast<std::uint8_t>(check.integer(b, "value_max", where, 255, 0, 255));
      if (t.value_min > t.value_max) check.fail(&b, where + "value_min is above value_max");
    }
  }
}

// [odometry]: wheel geometry and whether the map's odometry calibration applies.
void read_odometry(const Checker& check, const toml::table& root, FirmwareConfig& c) {
  if (const toml::table* t = check.section(root, "odometry")) {
    c.has_odometry_section = true;
    check.only(*t, "odometry.",
               {"wheel_radius_m", "track_m", "ticks_per_rev", "left_direction", "right_direction",
                "map_calibration"});
    auto& g = c.geometry;
    g.wheel_radius_m =
        check.number(*t, "wheel_radius_m", "odometry.", g.wheel_radius_m, 0.001, 10.0);
    g.track_m = check.number(*t, "track_m", "odometry.", g.track_m, 0.01, 100.0);
    g.ticks_per_rev = check.number(*t, "ticks_per_rev", "odometry.", g.ticks_per_rev, 1.0, 1e9);
    g.left_direction =
        static_cast<int>(check.integer(*t, "left_direction", "odometry.", g.left_direction, -1, 1));
    g.right_direction = static_cast<int>(
        check.integer(*t, "right_direction", "odometry.", g.right_direction, -1, 1));
    if (g.left_direction == 0 || g.right_direction == 0)
      check.fail(t, "odometry.*_direction must be 1 or -1");
    c.use_map_odometry_calibration =
        flag(check, *t, "map_calibration", "odometry.", c.use_map_odometry_calibration);
  }
}

// [can]: where the motor controller puts the wheel counters in its frame.
void read_can(const Checker& check, const toml::table& root, FirmwareConfig& c) {
  if (const toml::table* t = check.section(root, "can")) {
    c.has_can_section = true;
    check.only(*t, "can.",
               {"interface", "encoder_id", "length", "left_offset", "right_offset", "counter_bits",
                "byte_order"});
    auto& l = c.can_layout;
    c.can_interface = check.text(*t, "interface", "can.", c.can_interface);
    l.id = static_cast<std::uint32_t>(check.integer(*t, "encoder_id", "can.", l.id, 0, 0x1FFFFFFF));
    l.length = static_cast<std::uint8_t>(check.integer(*t, "length", "can.", l.length, 1, 8));
    l.left_offset =
        static_cast<std::uint8_t>(check.integer(*t, "left_offset", "can.", l.left_offset, 0, 7));
    l.right_offset =
        static_cast<std::uint8_t>(check.integer(*t, "right_offset", "can.", l.right_offset, 0, 7));
    l.counter_bits =
        static_cast<std::uint8_t>(check.integer(*t, "counter_bits", "can.", l.counter_bits, 8, 32));
    const std::string order = check.text(*t, "byte_order", "can.", "little");
    if (order == "little")
      l.byte_order = algorithms::ByteOrder::kLittleEndian;
    else if (order == "big")
      l.byte_order = algorithms::ByteOrder::kBigEndian;
    else
      check.fail(t->get("byte_order"), "can.byte_order must be \"little\" or \"big\"");
    if (!algorithms::layout_valid(l))
      check.fail(t, "can: the two counters must fit, without overlapping, in 'length' bytes");
  }
}

// [filter]: the particle filter.
void read_filter(const Checker& check, const toml::table& root, FirmwareConfig& c) {
  if (const toml::table* t = check.section(root, "filter")) {
    check.only(*t, "filter.",
               {"particles",
                "seed",
                "alpha",
                "fix_sigma_m",
                "outlier_probability",
                "resample_threshold",
                "init_position_sigma_m",
                "vision_only_speed_mps",
                "map_margin_m",
                "nominal_spread_m",
                "nominal_resume_spread_m",
                "kld",
                "kld_min_particles",
                "kld_epsilon",
                "kld_bin_m",
                "kld_bin_deg",
                "nearby_test",
                "nearby_bound_nats",
                "nearby_frames",
                "nearby_radius_m",
                "nearby_levels",
                "nearby_hint_by_tables",
                "seed_heading_from_boards",
                "seed_from_search"});
    auto& f = c.filter;
    f.particles = static_cast<std::size_t>(
        check.integer(*t, "particles", "filter.", static_cast<std::int64_t>(f.particles), 16,
                      static_cast<std::int64_t>(algorithms::ParticleFilter::kMaxParticles)));
    f.seed = static_cast<std::uint64_t>(
        check.integer(*t, "seed", "filter.", static_cast<std::int64_t>(f.seed), 0, INT64_MAX));
    if (const toml::node* a = t->get("alpha")) {
      const toml::array* arr = a->as_array();
      if (arr == nullptr || arr->size() != 4)
        check.fail(a, "filter.alpha must be [alpha1, alpha2, alpha3, alpha4]");
      double* out[4] = {&f.noise.alpha1, &f.noise.alpha2, &f.noise.alpha3, &f.noise.alpha4};
      for (std::size_t k = 0; k < 4; ++k) {
        const toml::node& e = *arr->get(k);
        double v = -1.0;
        if (auto iv = e.value_exact<std::int64_t>())
          v = static_cast<double>(*iv);
        else if (auto dv = e.value_exact<double>())
          v = *dv;
        if (!(v >= 0.0 && v <= 10.0))
          check.fail(&e, "filter.alpha values must be numbers within 0..10");
        *out[k] = v;
      }
    }
    f.fix_sigma_m = check.number(*t, "fix_sigma_m", "filter.", f.fix_sigma_m, 0.001, 10.0);
    f.outlier_probability =
        check.number(*t, "outlier_probability", "filter.", f.outlier_probability, 0.0, 0.9);
    f.resample_threshold =
        check.number(*t, "resample_threshold", "filter.", f.resample_threshold, 0.0, 1.0);
    f.init_position_sigma_m = check.number_or_auto(*t, "init_position_sigma_m", "filter.",
                                                   f.init_position_sigma_m, 0.001, 10.0);
    f.vision_only_speed_mps =
        check.number(*t, "vision_only_speed_mps", "filter.", f.vision_only_speed_mps, 0.0, 10.0);
    f.map_margin_m = check.number(*t, "map_margin_m", "filter.", f.map_margin_m, 0.0, 100.0);
    f.nominal_spread_m =
        check.number(*t, "nominal_spread_m", "filter.", f.nominal_spread_m, 0.001, 100.0);
    // Without its own value the resume bound keeps the defaults' ratio to the spread bound.
    const toml::node* resume = t->get("nominal_resume_spread_m");
    f.nominal_resume_spread_m = resume != nullptr
                                    ? check.number(*t, "nominal_resume_spread_m", "filter.",
                                                   f.nominal_resume_spread_m, 0.001, 100.0)
                                    : 0.7 * f.nominal_spread_m;
    if (f.nominal_resume_spread_m > f.nominal_spread_m) {
      check.fail(resume, "filter.nominal_resume_spread_m must not exceed filter.nominal_spread_m");
    }
    algorithms::KldSampling& k = f.kld;
    f.kld_mode = on_off_auto(check, *t, "kld", "filter.", f.kld_mode, KldMode::kOn, KldMode::kOff,
                             KldMode::kAuto);
    k.min_particles = static_cast<std::size_t>(check.integer(
        *t, "kld_min_particles", "filter.", static_cast<std::int64_t>(k.min_particles), 16,
        static_cast<std::int64_t>(algorithms::ParticleFilter::kMaxParticles)));
    k.epsilon = check.number(*t, "kld_epsilon", "filter.", k.epsilon, 0.001, 1.0);
    k.bin_xy_m = check.number(*t, "kld_bin_m", "filter.", k.bin_xy_m, 0.005, 1.0);
    const double bin_deg = check.number(*t, "kld_bin_deg", "filter.",
                                        k.bin_yaw_rad * 180.0 / algorithms::kPi, 1.0, 90.0);
    k.bin_yaw_rad = bin_deg * algorithms::kPi / 180.0;
    f.nearby_test = flag(check, *t, "nearby_test", "filter.", f.nearby_test);
    f.seed_heading_from_boards =
        flag(check, *t, "seed_heading_from_boards", "filter.", f.seed_heading_from_boards);
    f.seed_from_search = flag(check, *t, "seed_from_search", "filter.", f.seed_from_search);
    f.nearby.bound_nats =
        check.number(*t, "nearby_bound_nats", "filter.", f.nearby.bound_nats, 1.0, 1000.0);
    f.nearby.max_frames = static_cast<std::uint32_t>(check.integer(
        *t, "nearby_frames", "filter.", static_cast<std::int64_t>(f.nearby.max_frames), 1, 3000));
    f.nearby.search_radius_m =
        check.number(*t, "nearby_radius_m", "filter.", f.nearby.search_radius_m, 0.05, 2.0);
    f.nearby.search_levels = static_cast<int>(check.integer(
        *t, "nearby_levels", "filter.", static_cast<std::int64_t>(f.nearby.search_levels), 1, 4));
    f.nearby.hint_by_tables =
        flag(check, *t, "nearby_hint_by_tables", "filter.", f.nearby.hint_by_tables);
  }
}

// [observation]: the robust per-board model (docs/filter.md).
void read_observation(const Checker& check, const toml::table& root, ObservationConfig& o) {
  const toml::table* t = check.section(root, "observation");
  if (t == nullptr) return;
  const std::string w = "observation.";
  check.only(*t, w,
             {"model",
              "fix_term",
              "fix_board_check",
              "robust",
              "sigma_scale",
              "tempering",
              "outlier_floor",
              "dcs_phi",
              "consensus_chi2",
              "consensus_fraction",
              "motion_index_rate",
              "motion_index_rise_rate",
              "motion_index_min",
              "motion_index_max",
              "route_free_m",
              "route_sigma_m",
              "route_heading_free_deg",
              "route_heading_sigma_deg",
              "implausible_ratio",
              "bearings",
              "cut_board_width",
              "route_terms"});
  const std::string model = check.text(*t, "model", w, "boards");
  if (model == "boards")
    o.model = ObservationModel::kBoards;
  else if (model == "fix")
    o.model = ObservationModel::kFix;
  else
    check.fail(t->get("model"), "observation.model must be \"boards\" or \"fix\"");
  const std::string route_terms = check.text(*t, "route_terms", w, "auto");
  if (route_terms == "auto")
    o.route_terms = RouteTerms::kAuto;
  else if (route_terms == "on")
    o.route_terms = RouteTerms::kOn;
  else if (route_terms == "off")
    o.route_terms = RouteTerms::kOff;
  else
    check.fail(t->get("route_terms"),
               "observation.route_terms must be \"auto\", \"on\" or \"off\"");
  // true and false as before "auto" was the default: on and off whatever the map.
  o.fix_term = on_off_auto(check, *t, "fix_term", w, o.fix_term, FixTerm::kOn, FixTerm::kOff,
                           FixTerm::kAuto);
  o.fix_board_check = flag(check, *t, "fix_board_check", w, o.fix_board_check);
  auto& b = o.boards;
  b.robust = flag(check, *t, "robust", w, b.robust);
  b.bearings = flag(check, *t, "bearings", w, b.bearings);
  b.cut_board_width = check.number(*t, "cut_board_width", w, b.cut_board_width, 0.0, 100.0);
  b.sigma_scale = check.number(*t, "sigma_scale", w, b.sigma_scale, 0.1, 100.0);
  b.tempering = check.number(*t, "tempering", w, b.tempering, 1.0, 1e4);
  b.outlier_floor = check.number(*t, "outlier_floor", w, b.outlier_floor, 1e-9, 1.0);
  b.dcs_phi = check.number(*t, "dcs_phi", w, b.dcs_phi, 1e-3, 1e3);
  b.consensus_chi2 = check.number(*t, "consensus_chi2", w, b.consensus_chi2, 0.1, 1e4);
  b.consensus_fraction = check.number(*t, "consensus_fraction", w, b.consensus_fraction, 0.0, 0.99);
  b.motion_index_rate = check.number(*t, "motion_index_rate", w, b.motion_index_rate, 0.0, 1.0);
  b.motion_index_rise_rate =
      check.number(*t, "motion_index_rise_rate", w, b.motion_index_rise_rate, 0.0, 1.0);
  b.motion_index_min = check.number(*t, "motion_index_min", w, b.motion_index_min, 0.0, 1.0);
  b.motion_index_max = check.number(*t, "motion_index_max", w, b.motion_index_max, 0.0, 1.0);
  if (b.motion_index_min > b.motion_index_max)
    check.fail(t, "observation.motion_index_min must not exceed motion_index_max");
  b.route_free_m = check.number(*t, "route_free_m", w, b.route_free_m, 0.0, 10.0);
  b.route_sigma_m = check.number(*t, "route_sigma_m", w, b.route_sigma_m, 0.0, 10.0);
  b.route_heading_free_deg =
      check.number(*t, "route_heading_free_deg", w, b.route_heading_free_deg, 0.0, 180.0);
  b.route_heading_sigma_deg =
      check.number(*t, "route_heading_sigma_deg", w, b.route_heading_sigma_deg, 0.0, 180.0);
  b.implausible_ratio = check.number(*t, "implausible_ratio", w, b.implausible_ratio, 0.0, 1000.0);
  if (b.implausible_ratio > 0.0 && b.implausible_ratio < 1.0)
    check.fail(t->get("implausible_ratio"),
               "observation.implausible_ratio must be 0 (off) or >= 1");
}

// [kidnap]: Yang et al.'s test, its confirmation and the re-seed (docs/filter.md).
void read_kidnap(const Checker& check, const toml::table& root, KidnapConfig& k) {
  const toml::table* t = check.section(root, "kidnap");
  if (t == nullptr) return;
  const std::string w = "kidnap.";
  check.only(*t, w,
             {"enabled", "change_threshold", "confirm", "window_frames", "evidence_frames",
              "fix_distance_m", "preference_min", "consistency_m", "divergence_frames",
              "divergence_gap_frames", "lost_frames", "reseed", "position_sigma_m", "yaw_sigma_deg",
              "floor_search"});
  k.enabled = flag(check, *t, "enabled", w, k.enabled);
  auto& d = k.detector;
  d.change_threshold = check.number(*t, "change_threshold", w, d.change_threshold, 0.0, 1.0);
  d.confirm = flag(check, *t, "confirm", w, d.confirm);
  d.window_frames =
      static_cast<int>(check.integer(*t, "window_frames", w, d.window_frames, 1, 1000));
  d.evidence_frames =
      static_cast<int>(check.integer(*t, "evidence_frames", w, d.evidence_frames, 1, 1000));
  if (d.evidence_frames > d.window_frames)
    check.fail(t, "kidnap.evidence_frames must not exceed window_frames");
  d.fix_distance_m = check.number_or_auto(*t, "fix_distance_m", w, d.fix_distance_m, 0.0, 100.0);
  d.preference_min = check.number(*t, "preference_min", w, d.preference_min, 0.0, 1000.0);
  d.consistency_m = check.number_or_auto(*t, "consistency_m", w, d.consistency_m, 0.0, 100.0);
  d.divergence_frames =
      static_cast<int>(check.integer(*t, "divergence_frames", w, d.divergence_frames, 1, 100000));
  d.divergence_gap_frames = static_cast<int>(
      check.integer(*t, "divergence_gap_frames", w, d.divergence_gap_frames, 0, 100000));
  d.lost_frames = static_cast<int>(check.integer(*t, "lost_frames", w, d.lost_frames, 1, 100000));
  const std::string reseed = check.text(*t, "reseed", w, "fix");
  if (reseed == "fix")
    k.reseed = ReseedStrategy::kAroundFix;
  else if (reseed == "uniform")
    k.reseed = ReseedStrategy::kUniform;
  else
    check.fail(t->get("reseed"), "kidnap.reseed must be \"fix\" or \"uniform\"");
  k.position_sigma_m =
      check.number_or_auto(*t, "position_sigma_m", w, k.position_sigma_m, 0.001, 10.0);
  k.yaw_sigma_deg = check.number(*t, "yaw_sigma_deg", w, k.yaw_sigma_deg, 0.0, 360.0);
  k.floor_search = flag(check, *t, "floor_search", w, k.floor_search);
}

// [realtime]: scheduling, CPU and memory locking.
void read_realtime(const Checker& check, const toml::table& root, FirmwareConfig& c) {
  if (const toml::table* t = check.section(root, "realtime")) {
    check.only(*t, "realtime.", {"enabled", "priority", "cpu", "lock_memory", "prefault_stack_kb"});
    auto flag = [&](const char* key, bool fallback) {
      const toml::node* n = t->get(key);
      if (n == nullptr) return fallback;
      auto b = n->value_exact<bool>();
      if (!b) check.fail(n, std::string("realtime.") + key + " must be true or false");
      return *b;
    };
    c.realtime.enabled = flag("enabled", c.realtime.enabled);
    c.realtime.lock_memory = flag("lock_memory", c.realtime.lock_memory);
    c.realtime.priority =
        static_cast<int>(check.integer(*t, "priority", "realtime.", c.realtime.priority, 1, 99));
    c.realtime.cpu =
        static_cast<int>(check.integer(*t, "cpu", "realtime.", c.realtime.cpu, -1, 1023));
    c.realtime.prefault_stack_kb = static_cast<std::size_t>(
        check.integer(*t, "prefault_stack_kb", "realtime.",
                      static_cast<std::int64_t>(c.realtime.prefault_stack_kb), 0, 65536));
  }
}

}  // namespace harmoloc::firmware::config_detail
