#include "harmoloc/firmware/stats_document.hpp"

#include <cmath>
#include <nlohmann/json.hpp>

namespace harmoloc::firmware::stats {

namespace {

// Writing. NaN has no JSON form (nlohmann writes null, which the readers take as missing).

Json timing(const StageTiming& s) {
  return Json{{"median_us", s.median_us},
              {"p99_us", s.p99_us},
              {"p999_us", s.p999_us},
              {"max_us", s.max_us},
              {"mean_us", s.mean_us}};
}

Json latency(const LatencySummary& l) {
  return Json{{"count", l.count},         {"min_us", l.min_us}, {"mean_us", l.mean_us},
              {"median_us", l.median_us}, {"p99_us", l.p99_us}, {"p999_us", l.p999_us},
              {"max_us", l.max_us}};
}

template <typename T>
void put(Json& j, const char* key, const std::optional<T>& value) {
  if (value) j[key] = *value;
}

// Reading: each helper names the field it was asked for, so a bad file gets a one-line reason.

[[noreturn]] void fail(const std::string& reason) {
  throw FormatError(reason);
}

const Json* find(const Json& object, const std::string& key) {
  const auto it = object.find(key);
  return it == object.end() || it->is_null() ? nullptr : &*it;
}

std::optional<double> number(const Json& object, const std::string& key, const std::string& where) {
  const Json* v = find(object, key);
  if (v == nullptr) return std::nullopt;
  if (!v->is_number()) fail(where + key + " is not a number");
  return v->get<double>();
}

double number_or_missing(const Json& object, const std::string& key, const std::string& where) {
  return number(object, key, where).value_or(kMissing);
}

std::uint64_t count_value(const Json& value, const std::string& what) {
  if (value.is_number_unsigned()) return value.get<std::uint64_t>();
  if (value.is_number_integer()) {
    if (value.get<std::int64_t>() < 0) fail(what + " is negative");
    return static_cast<std::uint64_t>(value.get<std::int64_t>());
  }
  if (value.is_number_float()) {
    const double v = value.get<double>();
    if (v < 0.0 || v != std::floor(v) || v > 1.8e19) fail(what + " is not a count");
    return static_cast<std::uint64_t>(v);
  }
  fail(what + " is not a count");
}

std::optional<std::uint64_t> count(const Json& object, const std::string& key,
                                   const std::string& where) {
  const Json* v = find(object, key);
  if (v == nullptr) return std::nullopt;
  return count_value(*v, where + key);
}

void read_count(const Json& object, const std::string& key, const std::string& where,
                std::uint64_t& out) {
  if (const auto c = count(object, key, where)) out = *c;
}

std::string text(const Json& object, const std::string& key, const std::string& where) {
  const Json* v = find(object, key);
  if (v == nullptr) return "";
  if (!v->is_string()) fail(where + key + " is not a string");
  return v->get<std::string>();
}

const Json* section(const Json& parent, const std::string& key) {
  const Json* v = find(parent, key);
  if (v != nullptr && !v->is_object()) fail("\"" + key + "\" is not an object");
  return v;
}

LatencySummary read_latency(const Json& j, const std::string& where) {
  LatencySummary l;
  read_count(j, "count", where, l.count);
  l.min_us = number_or_missing(j, "min_us", where);
  l.mean_us = number_or_missing(j, "mean_us", where);
  l.median_us = number_or_missing(j, "median_us", where);
  l.p99_us = number_or_missing(j, "p99_us", where);
  l.p999_us = number_or_missing(j, "p999_us", where);
  l.max_us = number_or_missing(j, "max_us", where);
  return l;
}

CycleHistogram read_histogram(const Json& j) {
  const Json* upper = find(j, "upper_us");
  const Json* counts = find(j, "counts");
  if (upper == nullptr || !upper->is_array() || counts == nullptr || !counts->is_array())
    fail("cycle_histogram needs the arrays \"upper_us\" and \"counts\"");
  CycleHistogram h;
  for (const Json& v : *upper) {
    if (!v.is_number()) fail("cycle_histogram.upper_us holds a non-number");
    const double bound = v.get<double>();
    if (!(bound > 0.0) || (!h.upper_us.empty() && !(bound > h.upper_us.back())))
      fail("cycle_histogram.upper_us must be positive and increasing");
    h.upper_us.push_back(bound);
  }
  for (const Json& v : *counts) {
    h.counts.push_back(v.is_null() ? 0 : count_value(v, "a cycle_histogram count"));
  }
  // One count more than bounds: the last counts the cycles above the last bound.
  if (h.counts.size() != h.upper_us.size() && h.counts.size() != h.upper_us.size() + 1) {
    fail("cycle_histogram has " + std::to_string(h.counts.size()) + " counts for " +
         std::to_string(h.upper_us.size()) + " buckets");
  }
  return h;
}

// Top-level members on their own lines, the stages one a line, the rest inline: a file a person
// can read, as docs/stats-format.md shows it (nlohmann's indent would put each of the hundreds of
// histogram numbers on a line of its own).
void dump_inline(const Json& j, std::string& out) {
  if (j.is_object()) {
    out += '{';
    bool first = true;
    for (const auto& item : j.items()) {
      out += first ? "" : ", ";
      out += Json(item.key()).dump() + ": ";
      dump_inline(item.value(), out);
      first = false;
    }
    out += '}';
  } else if (j.is_array()) {
    out += '[';
    for (std::size_t i = 0; i < j.size(); ++i) {
      out += i == 0 ? "" : ", ";
      dump_inline(j[i], out);
    }
    out += ']';
  } else {
    out += j.dump();
  }
}

}  // namespace

void to_json(Json& j, const Document& d) {
  j = Json::object();
  j["harmoloc_version"] = d.harmoloc_version;
  j["board"] = d.board;
  j["ended"] = d.ended;
  j["outputs_failed"] = d.outputs_failed;
  put(j, "rate_hz", d.rate_hz);
  put(j, "budget_us", d.budget_us);
  put(j, "cycles", d.cycles);
  put(j, "frames", d.frames);
  put(j, "overruns", d.overruns);
  if (d.pacing) {
    j["pacing"] = Json{{"mode", d.pacing->mode},
                       {"skipped_ticks", d.pacing->skipped_ticks},
                       {"overrun_alarms", d.pacing->overrun_alarms}};
  }
  Json& stages = j["stages"] = Json::object();
  for (const auto& [name, s] : d.stages) stages[name] = timing(s);
  if (d.cycle_histogram) {
    j["cycle_histogram"] =
        Json{{"upper_us", d.cycle_histogram->upper_us}, {"counts", d.cycle_histogram->counts}};
  }
  if (d.health_cycles) {
    const HealthCycles& h = *d.health_cycles;
    j["health_cycles"] = Json{{"not_initialized", h.not_initialized},
                              {"nominal", h.nominal},
                              {"odometry_only", h.odometry_only},
                              {"vision_only", h.vision_only},
                              {"invalid", h.invalid}};
  }
  if (d.degraded) {
    j["degraded"] = Json{{"odometry_only", d.degraded->odometry_only},
                         {"vision_only", d.degraded->vision_only},
                         {"invalid", d.degraded->invalid}};
  }
  const Camera& c = d.camera;
  j["camera"] = Json{{"frames", c.device.frames},        {"corrupt", c.device.corrupt},
                     {"dropped", c.device.dropped},      {"errors", c.device.errors},
                     {"reopens", c.device.reopens},      {"no_frame_cycles", c.no_frame_cycles},
                     {"size_mismatch", c.size_mismatch}, {"stale", c.stale}};
  const hal::EncoderCounters& e = d.encoders.device;
  j["encoders"] = Json{{"samples", e.samples},       {"gaps_bridged", d.encoders.gaps_bridged},
                       {"ignored_id", e.ignored_id}, {"bad_length", e.bad_length},
                       {"glitches", e.glitches},     {"bus_errors", e.bus_errors},
                       {"bus_off", e.bus_off},       {"overflows", e.overflows}};
  j["link"] = Json{{"frames_sent", d.link.frames_sent},
                   {"frames_dropped", d.link.frames_dropped},
                   {"bytes_sent", d.link.bytes_sent},
                   {"errors", d.link.errors}};
  if (d.localizer) {
    const Localizer& l = *d.localizer;
    j["localizer"] = Json{{"fixes", l.fixes.value_or(0)},
                          {"unknown_place", l.unknown_place.value_or(0)},
                          {"implausible_frames", l.implausible_frames},
                          {"off_map_cycles", l.off_map_cycles},
                          {"uncovered_cycles", l.uncovered_cycles},
                          {"disagree_cycles", l.disagree_cycles},
                          {"spread_wide_cycles", l.spread_wide_cycles},
                          {"cut_board_frames", l.cut_board_frames}};
  }
  const Filter& f = d.filter;
  j["filter"] = Json{{"observation", f.observation},
                     {"resamples", f.resamples},
                     {"particles_mean", f.particles_mean},
                     {"particles_min", f.particles_min},
                     {"particles_max", f.particles_max},
                     {"no_consensus", f.no_consensus},
                     {"distrusted_board_frames", f.distrusted_board_frames},
                     {"fix_board_suspicions", f.fix_board_suspicions},
                     {"kidnap_triggers", f.kidnap_triggers},
                     {"kidnaps", f.kidnaps},
                     {"lost", f.lost},
                     {"nearby_draws", f.nearby_draws}};
  const mavlink::InboundCounters& in = d.inbound;
  j["inbound"] = Json{{"bytes_in", in.bytes_in},
                      {"frames_in", in.frames_in},
                      {"crc_errors", in.crc_errors},
                      {"bad_headers", in.bad_headers},
                      {"garbage_bytes", in.garbage_bytes},
                      {"commands_accepted", in.commands_accepted},
                      {"commands_refused", in.commands_refused},
                      {"rejected_unsigned", in.rejected_unsigned},
                      {"rejected_bad_signature", in.rejected_bad_signature},
                      {"rejected_replay", in.rejected_replay},
                      {"rejected_future", in.rejected_future},
                      {"rejected_source", in.rejected_source},
                      {"ignored_messages", in.ignored_messages},
                      {"timesync_requests", in.timesync_requests},
                      {"saturated_cycles", in.saturated_cycles}};
  if (d.wakeup_latency) j["wakeup_latency"] = latency(*d.wakeup_latency);
  if (d.capture_to_send) j["capture_to_send"] = latency(*d.capture_to_send);
  if (d.recording) {
    const Recording& r = *d.recording;
    j["recording"] = Json{{"frames", r.frames},
                          {"dropped", r.dropped},
                          {"skipped", r.skipped},
                          {"bytes", r.bytes},
                          {"stopped", r.stopped}};
  }
  if (d.resources) {
    const Resources& r = *d.resources;
    j["resources"] = Json{{"rss_kb_start", r.rss_kb_start},
                          {"rss_kb_end", r.rss_kb_end},
                          {"peak_rss_kb", r.peak_rss_kb},
                          {"open_fds_start", r.open_fds_start},
                          {"open_fds_end", r.open_fds_end}};
  }
}

void from_json(const Json& j, Document& d) {
  if (!j.is_object()) fail("not a JSON object");
  d = Document{};
  d.harmoloc_version = text(j, "harmoloc_version", "");
  d.board = text(j, "board", "");
  d.ended = text(j, "ended", "");
  read_count(j, "outputs_failed", "", d.outputs_failed);
  d.rate_hz = number(j, "rate_hz", "");
  d.budget_us = number(j, "budget_us", "");
  if (d.budget_us && !(*d.budget_us > 0.0)) fail("budget_us must be positive");
  d.cycles = count(j, "cycles", "");
  d.frames = count(j, "frames", "");
  d.overruns = count(j, "overruns", "");
  if (const Json* p = section(j, "pacing")) {
    Pacing pacing;
    pacing.mode = text(*p, "mode", "pacing.");
    read_count(*p, "skipped_ticks", "pacing.", pacing.skipped_ticks);
    read_count(*p, "overrun_alarms", "pacing.", pacing.overrun_alarms);
    d.pacing = pacing;
  }
  const Json* stages = section(j, "stages");
  if (stages == nullptr) fail("no \"stages\" section (is this a harmoloc --stats file?)");
  for (const auto& item : stages->items()) {
    const std::string where = "stages." + item.key() + ".";
    if (!item.value().is_object()) fail("stages." + item.key() + " is not an object");
    StageTiming s;
    s.median_us = number_or_missing(item.value(), "median_us", where);
    s.p99_us = number_or_missing(item.value(), "p99_us", where);
    s.p999_us = number_or_missing(item.value(), "p999_us", where);
    s.max_us = number_or_missing(item.value(), "max_us", where);
    s.mean_us = number_or_missing(item.value(), "mean_us", where);
    d.stages.emplace_back(item.key(), s);
  }
  if (const Json* h = section(j, "cycle_histogram")) d.cycle_histogram = read_histogram(*h);
  if (const Json* h = section(j, "health_cycles")) {
    HealthCycles health;
    read_count(*h, "not_initialized", "health_cycles.", health.not_initialized);
    read_count(*h, "nominal", "health_cycles.", health.nominal);
    read_count(*h, "odometry_only", "health_cycles.", health.odometry_only);
    read_count(*h, "vision_only", "health_cycles.", health.vision_only);
    read_count(*h, "invalid", "health_cycles.", health.invalid);
    d.health_cycles = health;
  }
  if (const Json* g = section(j, "degraded")) {
    Degraded degraded;
    read_count(*g, "odometry_only", "degraded.", degraded.odometry_only);
    read_count(*g, "vision_only", "degraded.", degraded.vision_only);
    read_count(*g, "invalid", "degraded.", degraded.invalid);
    d.degraded = degraded;
  }
  if (const Json* l = section(j, "localizer")) {
    Localizer localizer;
    localizer.fixes = count(*l, "fixes", "localizer.");
    localizer.unknown_place = count(*l, "unknown_place", "localizer.");
    read_count(*l, "implausible_frames", "localizer.", localizer.implausible_frames);
    read_count(*l, "off_map_cycles", "localizer.", localizer.off_map_cycles);
    read_count(*l, "uncovered_cycles", "localizer.", localizer.uncovered_cycles);
    read_count(*l, "disagree_cycles", "localizer.", localizer.disagree_cycles);
    read_count(*l, "spread_wide_cycles", "localizer.", localizer.spread_wide_cycles);
    read_count(*l, "cut_board_frames", "localizer.", localizer.cut_board_frames);
    d.localizer = localizer;
  }
  if (const Json* w = section(j, "wakeup_latency"))
    d.wakeup_latency = read_latency(*w, "wakeup_latency.");
  if (const Json* c = section(j, "capture_to_send"))
    d.capture_to_send = read_latency(*c, "capture_to_send.");
}

std::string dump(const Document& d) {
  const Json j = d;
  std::string out = "{";
  bool first = true;
  for (const auto& item : j.items()) {
    out += first ? "\n  " : ",\n  ";
    out += Json(item.key()).dump() + ": ";
    if (item.key() == "stages") {
      out += '{';
      bool first_stage = true;
      for (const auto& stage : item.value().items()) {
        out += first_stage ? "\n    " : ",\n    ";
        out += Json(stage.key()).dump() + ": ";
        dump_inline(stage.value(), out);
        first_stage = false;
      }
      out += "\n  }";
    } else {
      dump_inline(item.value(), out);
    }
    first = false;
  }
  return out + "\n}\n";
}

}  // namespace harmoloc::firmware::stats
