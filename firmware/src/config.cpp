#include "harmoloc/firmware/config.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#include <toml++/toml.h>

#include "harmoloc/drivers/input_file.hpp"

namespace harmoloc::firmware {

namespace {

class Checker {
 public:
  explicit Checker(std::string file) : file_(std::move(file)) {}

  [[noreturn]] void fail(const toml::node* at, const std::string& what) const {
    std::ostringstream s;
    s << file_ << ": ";
    if (at != nullptr && at->source().begin.line > 0)
      s << "line " << at->source().begin.line << ": ";
    s << what;
    throw std::runtime_error(s.str());
  }

  // Rejects keys the firmware does not know (a typo must not silently fall back to a default).
  void only(const toml::table& t, const std::string& where,
            std::initializer_list<const char*> keys) const {
    const std::set<std::string> allowed(keys.begin(), keys.end());
    for (const auto& [key, node] : t) {
      if (allowed.count(std::string(key.str())) == 0) {
        fail(&node, "unknown key '" + where + std::string(key.str()) + "'");
      }
    }
  }

  double number(const toml::table& t, const char* key, const std::string& where, double fallback,
                double lo, double hi) const {
    const toml::node* n = t.get(key);
    if (n == nullptr) return fallback;
    double v = 0.0;
    if (auto i = n->value_exact<std::int64_t>())
      v = static_cast<double>(*i);
    else if (auto d = n->value_exact<double>())
      v = *d;
    else
      fail(n, where + key + " must be a number");
    if (!(v >= lo && v <= hi)) {
      std::ostringstream s;
      s << where << key << " = " << v << " is outside " << lo << ".." << hi;
      fail(n, s.str());
    }
    return v;
  }

  // A number in [lo, hi], or the string "auto" (returned as -1: derived from the map).
  double number_or_auto(const toml::table& t, const char* key, const std::string& where,
                        double fallback, double lo, double hi) const {
    const toml::node* n = t.get(key);
    if (n == nullptr) return fallback;
    if (auto s = n->value_exact<std::string>()) {
      if (*s == "auto") return -1.0;
      fail(n, where + key + " must be a number or \"auto\"");
    }
    return number(t, key, where, fallback, lo, hi);
  }

  std::int64_t integer(const toml::table& t, const char* key, const std::string& where,
                       std::int64_t fallback, std::int64_t lo, std::int64_t hi) const {
    const toml::node* n = t.get(key);
    if (n == nullptr) return fallback;
    auto i = n->value_exact<std::int64_t>();
    if (!i) fail(n, where + key + " must be a whole number");
    if (*i < lo || *i > hi) {
      fail(n, where + key + " = " + std::to_string(*i) + " is outside " + std::to_string(lo) +
                  ".." + std::to_string(hi));
    }
    return *i;
  }

  std::string text(const toml::table& t, const char* key, const std::string& where,
                   const std::string& fallback) const {
    const toml::node* n = t.get(key);
    if (n == nullptr) return fallback;
    auto s = n->value_exact<std::string>();
    if (!s) fail(n, where + key + " must be a string");
    return *s;
  }

  const toml::table* section(const toml::table& root, const char* name) const {
    const toml::node* n = root.get(name);
    if (n == nullptr) return nullptr;
    if (!n->is_table()) fail(n, std::string("[") + name + "] must be a table");
    return n->as_table();
  }

 private:
  std::string file_;
};

// Reads a MAVLink signing key: exactly 32 raw bytes, or 64 hex digits (surrounding whitespace
// allowed). Returns an empty string on success, else what is wrong.
std::string read_signing_key(const std::string& path, std::array<std::uint8_t, 32>& key) {
  // A regular file only, opened non-blocking: a FIFO or a terminal could block start-up.
  std::string bytes;
  if (const std::string e =
          drivers::read_regular_file(path, drivers::input_limits::kKeyBytes, bytes);
      !e.empty()) {
    return path + ": " + e;
  }
  const std::string what = path + ": must hold a 32-byte key, raw or as 64 hex digits";
  if (bytes.size() == key.size()) {
    for (std::size_t i = 0; i < key.size(); ++i) key[i] = static_cast<std::uint8_t>(bytes[i]);
  } else {
    const auto space = [](char ch) { return ch == ' ' || ch == '\t' || ch == '\n' || ch == '\r'; };
    std::size_t b = 0, e = bytes.size();
    while (b < e && space(bytes[b])) ++b;
    while (e > b && space(bytes[e - 1])) --e;
    if (e - b != 2 * key.size()) return what;
    const auto nibble = [](char ch) -> int {
      if (ch >= '0' && ch <= '9') return ch - '0';
      if (ch >= 'a' && ch <= 'f') return ch - 'a' + 10;
      if (ch >= 'A' && ch <= 'F') return ch - 'A' + 10;
      return -1;
    };
    for (std::size_t i = 0; i < key.size(); ++i) {
      const int hi = nibble(bytes[b + 2 * i]);
      const int lo = nibble(bytes[b + 2 * i + 1]);
      if (hi < 0 || lo < 0) return what;
      key[i] = static_cast<std::uint8_t>(hi * 16 + lo);
    }
  }
  bool all_zero = true;
  for (const std::uint8_t v : key) all_zero = all_zero && v == 0;
  if (all_zero) return path + ": the key is all zeros";
  return {};
}

bool flag(const Checker& check, const toml::table& t, const char* key, const std::string& where,
          bool fallback) {
  const toml::node* n = t.get(key);
  if (n == nullptr) return fallback;
  auto b = n->value_exact<bool>();
  if (!b) check.fail(n, where + key + " must be true or false");
  return *b;
}

// [observation]: the robust per-board model (docs/filter.md).
void read_observation(const Checker& check, const toml::table& root, ObservationConfig& o) {
  const toml::table* t = check.section(root, "observation");
  if (t == nullptr) return;
  const std::string w = "observation.";
  check.only(*t, w,
             {"model", "fix_term", "fix_board_check", "robust", "sigma_scale", "tempering",
              "outlier_floor", "dcs_phi", "consensus_chi2", "consensus_fraction",
              "motion_index_rate", "motion_index_min", "motion_index_max", "route_free_m",
              "route_sigma_m", "implausible_ratio"});
  const std::string model = check.text(*t, "model", w, "boards");
  if (model == "boards")
    o.model = ObservationModel::kBoards;
  else if (model == "fix")
    o.model = ObservationModel::kFix;
  else
    check.fail(t->get("model"), "observation.model must be \"boards\" or \"fix\"");
  o.fix_term = flag(check, *t, "fix_term", w, o.fix_term);
  o.fix_board_check = flag(check, *t, "fix_board_check", w, o.fix_board_check);
  auto& b = o.boards;
  b.robust = flag(check, *t, "robust", w, b.robust);
  b.sigma_scale = check.number(*t, "sigma_scale", w, b.sigma_scale, 0.1, 100.0);
  b.tempering = check.number(*t, "tempering", w, b.tempering, 1.0, 1e4);
  b.outlier_floor = check.number(*t, "outlier_floor", w, b.outlier_floor, 1e-9, 1.0);
  b.dcs_phi = check.number(*t, "dcs_phi", w, b.dcs_phi, 1e-3, 1e3);
  b.consensus_chi2 = check.number(*t, "consensus_chi2", w, b.consensus_chi2, 0.1, 1e4);
  b.consensus_fraction = check.number(*t, "consensus_fraction", w, b.consensus_fraction, 0.0, 1.0);
  b.motion_index_rate = check.number(*t, "motion_index_rate", w, b.motion_index_rate, 0.0, 1.0);
  b.motion_index_min = check.number(*t, "motion_index_min", w, b.motion_index_min, 0.0, 1.0);
  b.motion_index_max = check.number(*t, "motion_index_max", w, b.motion_index_max, 0.0, 1.0);
  if (b.motion_index_min > b.motion_index_max)
    check.fail(t, "observation.motion_index_min must not exceed motion_index_max");
  b.route_free_m = check.number(*t, "route_free_m", w, b.route_free_m, 0.0, 10.0);
  b.route_sigma_m = check.number(*t, "route_sigma_m", w, b.route_sigma_m, 0.0, 10.0);
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
              "lost_frames", "reseed", "position_sigma_m", "yaw_sigma_deg"});
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
}

algorithms::ColourThreshold threshold(float h0, float h1, std::uint8_t s, std::uint8_t v0) {
  return algorithms::ColourThreshold{h0, h1, s, v0, 255};
}

// ---- Devices of the Linux board: [camera], [encoders], link.device (docs/drivers.md) ----

std::string one_of(const Checker& check, const toml::table& t, const char* key,
                   const std::string& where, const std::string& fallback,
                   std::initializer_list<const char*> allowed) {
  const std::string v = check.text(t, key, where, fallback);
  std::string list;
  for (const char* a : allowed) {
    if (v == a) return v;
    list += std::string(list.empty() ? "" : ", ") + "\"" + a + "\"";
  }
  check.fail(t.get(key), where + key + " must be one of " + list);
}

std::array<unsigned, 2> line_pair(const Checker& check, const toml::table& t, const char* key,
                                  const std::array<unsigned, 2>& fallback) {
  const toml::node* n = t.get(key);
  if (n == nullptr) return fallback;
  const toml::array* a = n->as_array();
  const std::string what = std::string("encoders.") + key + " must be [A, B] line offsets 0..1023";
  if (a == nullptr || a->size() != 2) check.fail(n, what);
  std::array<unsigned, 2> out{};
  for (std::size_t k = 0; k < 2; ++k) {
    const auto v = a->get(k)->value_exact<std::int64_t>();
    if (!v || *v < 0 || *v > 1023) check.fail(a->get(k), what);
    out[k] = static_cast<unsigned>(*v);
  }
  return out;
}

void read_device_sections(const Checker& check, const toml::table& root, FirmwareConfig& c) {
  if (const toml::table* t = check.section(root, "camera")) {
    check.only(*t, "camera.",
               {"driver", "device", "width", "height", "format", "buffers", "reopen_interval_ms"});
    auto& k = c.camera;
    k.driver = one_of(check, *t, "driver", "camera.", k.driver, {"v4l2", "libcamera"});
    // libcamera names cameras by id; "" picks the first. A v4l2 device needs a path.
    k.device = check.text(*t, "device", "camera.", k.driver == "libcamera" ? "" : k.device);
    if (k.driver == "v4l2" && k.device.empty())
      check.fail(t->get("device"), "camera.device must name a V4L2 device node");
    k.width_px =
        static_cast<std::uint32_t>(check.integer(*t, "width", "camera.", k.width_px, 16, 8192));
    k.height_px =
        static_cast<std::uint32_t>(check.integer(*t, "height", "camera.", k.height_px, 16, 8192));
    k.format = one_of(check, *t, "format", "camera.", k.format, {"auto", "yuyv", "rgb24"});
    if (k.format != "rgb24" && k.width_px % 2 != 0)
      check.fail(t->get("width"), "camera.width must be even for YUYV");
    k.buffers =
        static_cast<std::uint32_t>(check.integer(*t, "buffers", "camera.", k.buffers, 2, 8));
    k.reopen_interval_ms = static_cast<std::uint32_t>(
        check.integer(*t, "reopen_interval_ms", "camera.", k.reopen_interval_ms, 10, 600000));
  }
  if (const toml::table* t = check.section(root, "encoders")) {
    check.only(*t, "encoders.",
               {"driver", "can_kernel_filter", "gpio_chip", "left_lines", "right_lines",
                "debounce_us", "gpio_reader"});
    auto& e = c.encoders;
    e.driver = one_of(check, *t, "driver", "encoders.", e.driver, {"can", "gpio"});
    if (const toml::node* n = t->get("can_kernel_filter")) {
      const auto b = n->value_exact<bool>();
      if (!b) check.fail(n, "encoders.can_kernel_filter must be true or false");
      e.can_kernel_filter = *b;
    }
    e.gpio_chip = check.text(*t, "gpio_chip", "encoders.", e.gpio_chip);
    if (e.gpio_chip.empty()) check.fail(t->get("gpio_chip"), "encoders.gpio_chip is empty");
    e.left_lines = line_pair(check, *t, "left_lines", e.left_lines);
    e.right_lines = line_pair(check, *t, "right_lines", e.right_lines);
    const unsigned all[4] = {e.left_lines[0], e.left_lines[1], e.right_lines[0], e.right_lines[1]};
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < i; ++j)
        if (all[i] == all[j])
          check.fail(t, "encoders: line " + std::to_string(all[i]) + " is used twice");
    e.debounce_us = static_cast<std::uint32_t>(
        check.integer(*t, "debounce_us", "encoders.", e.debounce_us, 0, 1000000));
    e.gpio_reader =
        one_of(check, *t, "gpio_reader", "encoders.", e.gpio_reader, {"thread", "cycle"});
  }
  if (const toml::table* t = check.section(root, "link")) {
    c.link.device = check.text(*t, "device", "link.", c.link.device);
    if (c.link.device.empty()) check.fail(t->get("device"), "link.device is empty");
  }
}

}  // namespace

FirmwareConfig default_config() {
  FirmwareConfig c;
  const std::array<std::pair<const char*, algorithms::ColourThreshold>, 6> boards = {{
      {"red", threshold(345.0F, 10.0F, 110, 60)},
      {"green", threshold(100.0F, 145.0F, 110, 60)},
      {"blue", threshold(215.0F, 250.0F, 110, 60)},
      {"yellow", threshold(45.0F, 70.0F, 110, 60)},
      {"magenta", threshold(285.0F, 320.0F, 110, 60)},
      {"cyan", threshold(170.0F, 200.0F, 110, 60)},
  }};
  c.thresholds.count = boards.size();
  for (std::size_t i = 0; i < boards.size(); ++i) {
    c.board_names.names[i] = boards[i].first;
    c.thresholds.boards[i] = boards[i].second;
  }
  // Derived from the map's calibration at start-up (docs/filter.md): they depend on the scene.
  c.kidnap.detector.fix_distance_m = -1.0;
  c.kidnap.detector.consistency_m = -1.0;
  c.kidnap.position_sigma_m = -1.0;
  c.filter.init_position_sigma_m = -1.0;
  return c;
}

FirmwareConfig load_config(const std::string& path) {
  const Checker check(path);
  toml::table root;
  // Whatever cannot be read as a config stops start-up (a directory or /dev/zero must not run
  // on the built-in defaults); its size and nesting are checked before toml++ sees it.
  std::string text;
  if (const std::string e =
          drivers::read_regular_file(path, drivers::input_limits::kTomlBytes, text);
      !e.empty()) {
    throw std::runtime_error(path + ": " + e);
  }
  if (const std::string e = drivers::check_toml_nesting(text); !e.empty())
    throw std::runtime_error(path + ": " + e);
  try {
    root = toml::parse(text, path);
  } catch (const toml::parse_error& e) {
    std::ostringstream s;
    s << path << ": line " << e.source().begin.line << ": " << e.description();
    throw std::runtime_error(s.str());
  }
  FirmwareConfig c = default_config();
  c.source = path;
  check.only(root, "",
             {"cycle", "board", "odometry", "can", "filter", "observation", "kidnap", "link",
              "realtime", "camera", "encoders"});

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

  if (const toml::table* t = check.section(root, "filter")) {
    check.only(
        *t, "filter.",
        {"particles", "seed", "alpha", "fix_sigma_m", "outlier_probability", "resample_threshold",
         "init_position_sigma_m", "vision_only_speed_mps", "map_margin_m"});
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
  }

  read_observation(check, root, c.observation);
  read_kidnap(check, root, c.kidnap);

  if (const toml::table* t = check.section(root, "link")) {
    check.only(*t, "link.",
               {"system_id", "component_id", "baud", "heartbeat_hz", "accept_system_ids",
                "accept_component_ids", "signing_key_file", "signing_state_file",
                "signing_max_ahead_s", "signing_clock", "link_id", "device"});
    c.link.system_id = static_cast<std::uint8_t>(
        check.integer(*t, "system_id", "link.", c.link.system_id, 1, 255));
    c.link.component_id = static_cast<std::uint8_t>(
        check.integer(*t, "component_id", "link.", c.link.component_id, 1, 255));
    c.link.baud =
        static_cast<unsigned>(check.integer(*t, "baud", "link.", c.link.baud, 9600, 921600));
    c.link.heartbeat_hz = check.number(*t, "heartbeat_hz", "link.", c.link.heartbeat_hz, 0.1, 50.0);
    const auto id_list = [&](const char* key, std::vector<std::uint8_t>& ids) {
      const toml::node* n = t->get(key);
      if (n == nullptr) return;
      const toml::array* a = n->as_array();
      if (a == nullptr) check.fail(n, std::string("link.") + key + " must be a list of ids 1..255");
      ids.clear();
      for (const toml::node& e : *a) {
        const auto v = e.value_exact<std::int64_t>();
        if (!v || *v < 1 || *v > 255)
          check.fail(&e, std::string("link.") + key + " must be a list of ids 1..255");
        ids.push_back(static_cast<std::uint8_t>(*v));
      }
    };
    id_list("accept_system_ids", c.link.accept_system_ids);
    id_list("accept_component_ids", c.link.accept_component_ids);
    c.link.link_id =
        static_cast<std::uint8_t>(check.integer(*t, "link_id", "link.", c.link.link_id, 0, 255));
    c.link.signing_key_file = check.text(*t, "signing_key_file", "link.", "");
    if (!c.link.signing_key_file.empty()) {
      // A relative path is taken from the config file's folder, wherever harmoloc is started.
      std::filesystem::path key_path(c.link.signing_key_file);
      if (key_path.is_relative()) key_path = std::filesystem::path(path).parent_path() / key_path;
      const std::string e = read_signing_key(key_path.string(), c.link.signing_key);
      if (!e.empty()) check.fail(t->get("signing_key_file"), "link.signing_key_file: " + e);
      c.link.has_signing_key = true;
    }
    const std::string state = check.text(*t, "signing_state_file", "link.", "");
    if (!state.empty()) {
      std::filesystem::path state_path(state);
      if (state_path.is_relative())
        state_path = std::filesystem::path(path).parent_path() / state_path;
      c.link.signing_state_file = state_path.string();
    }
    // Without it, a signed command captured on the line could be replayed after a restart.
    if (c.link.has_signing_key && c.link.signing_state_file.empty()) {
      check.fail(t->get("signing_key_file"),
                 "link.signing_key_file needs link.signing_state_file (where the replay "
                 "protection survives a restart, e.g. /var/lib/harmoloc/signing.state)");
    }
    c.link.signing_max_ahead_s =
        check.number(*t, "signing_max_ahead_s", "link.", c.link.signing_max_ahead_s, 1.0, 86400.0);
    const std::string clock = check.text(*t, "signing_clock", "link.", "wall");
    if (clock == "wall")
      c.link.signing_peer_clock = false;
    else if (clock == "peer")
      c.link.signing_peer_clock = true;
    else
      check.fail(t->get("signing_clock"), "link.signing_clock must be \"wall\" or \"peer\"");
  }
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
  read_device_sections(check, root, c);
  return c;
}

std::string read_signing_key_file(const std::string& path, std::array<std::uint8_t, 32>& key) {
  return read_signing_key(path, key);
}

}  // namespace harmoloc::firmware
