#include "harmoloc/sim_host/run_stats.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <nlohmann/json.hpp>

#include "format.hpp"
#include "harmoloc/drivers/input_file.hpp"

namespace harmoloc::sim_host {

namespace {

using Json = nlohmann::ordered_json;
using report_text::format;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Typed access to the parsed JSON. Every failure names the file and the field in one line,
// which the tools print as it is.
class StatsReader {
 public:
  explicit StatsReader(std::string origin) : origin_(std::move(origin)) {}

  [[noreturn]] void fail(const std::string& reason) const {
    throw ReportError(origin_ + ": " + reason);
  }

  std::optional<double> number(const Json& object, const std::string& key,
                               const std::string& where) const {
    const auto it = object.find(key);
    if (it == object.end() || it->is_null()) return std::nullopt;
    if (!it->is_number()) fail(where + key + " is not a number");
    return it->get<double>();
  }

  std::optional<std::uint64_t> count(const Json& value, const std::string& what) const {
    if (value.is_null()) return std::nullopt;
    if (value.is_number_unsigned()) return value.get<std::uint64_t>();
    if (value.is_number_integer()) {
      const auto v = value.get<std::int64_t>();
      if (v < 0) fail(what + " is negative");
      return static_cast<std::uint64_t>(v);
    }
    if (value.is_number_float()) {
      const double v = value.get<double>();
      if (v < 0.0 || v != std::floor(v) || v > 1.8e19) fail(what + " is not a count");
      return static_cast<std::uint64_t>(v);
    }
    fail(what + " is not a count");
  }

  std::optional<std::uint64_t> count(const Json& object, const std::string& key,
                                     const std::string& where) const {
    const auto it = object.find(key);
    if (it == object.end()) return std::nullopt;
    return count(*it, where + key);
  }

  std::string string(const Json& object, const std::string& key) const {
    const auto it = object.find(key);
    if (it == object.end() || it->is_null()) return "";
    if (!it->is_string()) fail(key + " is not a string");
    return it->get<std::string>();
  }

  /// The object at @p key, nullptr when missing; fails when present but not an object.
  const Json* object(const Json& parent, const std::string& key) const {
    const auto it = parent.find(key);
    if (it == parent.end() || it->is_null()) return nullptr;
    if (!it->is_object()) fail("\"" + key + "\" is not an object");
    return &*it;
  }

 private:
  std::string origin_;
};

std::string scalar_text(const Json& value) {
  if (value.is_string()) return value.get<std::string>();
  if (value.is_boolean()) return value.get<bool>() ? "true" : "false";
  if (value.is_null()) return "null";
  if (value.is_number_unsigned()) return std::to_string(value.get<std::uint64_t>());
  if (value.is_number_integer()) return std::to_string(value.get<std::int64_t>());
  if (value.is_number_float()) return format("%.6g", value.get<double>());
  return value.dump();
}

void flatten(const Json& value, const std::string& prefix,
             std::vector<std::pair<std::string, std::string>>& out) {
  if (value.is_object()) {
    for (const auto& item : value.items()) {
      flatten(item.value(), prefix.empty() ? item.key() : prefix + "." + item.key(), out);
    }
    return;
  }
  if (value.is_array()) {
    bool scalars = value.size() <= 8;
    for (const auto& v : value) scalars = scalars && !v.is_structured();
    if (!scalars) {
      out.emplace_back(prefix, format("[%zu values]", value.size()));
      return;
    }
    std::string text = "[";
    for (std::size_t i = 0; i < value.size(); ++i) {
      if (i > 0) text += ", ";
      text += scalar_text(value[i]);
    }
    out.emplace_back(prefix, text + "]");
    return;
  }
  out.emplace_back(prefix, scalar_text(value));
}

}  // namespace

const char* const kStageOrder[8] = {"acquire", "segment", "localize", "encoders",
                                    "predict", "update",  "publish",  "cycle"};

std::uint64_t CycleHistogram::overflow() const {
  return counts.size() > upper_us.size() ? counts.back() : 0;
}

std::uint64_t CycleHistogram::total() const {
  std::uint64_t sum = 0;
  for (const std::uint64_t c : counts) sum += c;
  return sum;
}

const StageTiming* RunStats::stage(const std::string& name) const {
  for (const StageTiming& s : stages) {
    if (s.name == name) return &s;
  }
  return nullptr;
}

RunStats parse_stats(const std::string& text, const std::string& origin) {
  const StatsReader reader(origin);
  Json doc;
  try {
    doc = Json::parse(text);
  } catch (const Json::exception& e) {
    std::string what = e.what();
    const auto bracket = what.find("] ");
    if (what.rfind("[json.exception", 0) == 0 && bracket != std::string::npos) {
      what = what.substr(bracket + 2);
    }
    reader.fail("not valid JSON (" + what + ")");
  }
  if (!doc.is_object()) reader.fail("not a JSON object");

  RunStats stats;
  stats.harmoloc_version = reader.string(doc, "harmoloc_version");
  stats.board = reader.string(doc, "board");
  stats.cycles = reader.count(doc, "cycles", "");
  stats.frames = reader.count(doc, "frames", "");
  stats.overruns = reader.count(doc, "overruns", "");
  stats.rate_hz = reader.number(doc, "rate_hz", "");
  if (const auto budget = reader.number(doc, "budget_us", "")) {
    if (!(*budget > 0.0)) reader.fail("budget_us must be positive");
    stats.budget_us = *budget;
  }

  const Json* stages = reader.object(doc, "stages");
  if (stages == nullptr) reader.fail("no \"stages\" section (is this a harmoloc --stats file?)");
  // Known stages in display order, then unknown ones in file order, the whole cycle last.
  std::vector<std::string> names(std::begin(kStageOrder), std::end(kStageOrder) - 1);
  for (const auto& item : stages->items()) {
    if (std::find(std::begin(kStageOrder), std::end(kStageOrder), item.key()) ==
        std::end(kStageOrder)) {
      names.push_back(item.key());
    }
  }
  names.push_back("cycle");
  for (const std::string& name : names) {
    const auto it = stages->find(name);
    if (it == stages->end()) continue;
    if (!it->is_object()) reader.fail("stages." + name + " is not an object");
    const std::string where = "stages." + name + ".";
    StageTiming s;
    s.name = name;
    s.median_us = reader.number(*it, "median_us", where).value_or(kNaN);
    s.p99_us = reader.number(*it, "p99_us", where).value_or(kNaN);
    s.p999_us = reader.number(*it, "p999_us", where).value_or(kNaN);
    s.max_us = reader.number(*it, "max_us", where).value_or(kNaN);
    s.mean_us = reader.number(*it, "mean_us", where).value_or(kNaN);
    stats.stages.push_back(s);
  }

  if (const Json* histogram = reader.object(doc, "cycle_histogram")) {
    const auto upper = histogram->find("upper_us");
    const auto counts = histogram->find("counts");
    if (upper == histogram->end() || !upper->is_array() || counts == histogram->end() ||
        !counts->is_array()) {
      reader.fail("cycle_histogram needs the arrays \"upper_us\" and \"counts\"");
    }
    CycleHistogram h;
    for (const Json& v : *upper) {
      if (!v.is_number()) reader.fail("cycle_histogram.upper_us holds a non-number");
      const double bound = v.get<double>();
      if (!(bound > 0.0) || (!h.upper_us.empty() && !(bound > h.upper_us.back()))) {
        reader.fail("cycle_histogram.upper_us must be positive and increasing");
      }
      h.upper_us.push_back(bound);
    }
    for (const Json& v : *counts) {
      h.counts.push_back(reader.count(v, "a cycle_histogram count").value_or(0));
    }
    if (h.counts.size() != h.upper_us.size() && h.counts.size() != h.upper_us.size() + 1) {
      reader.fail(format("cycle_histogram has %zu counts for %zu buckets", h.counts.size(),
                         h.upper_us.size()));
    }
    if (!h.upper_us.empty()) stats.cycle_histogram = std::move(h);
  }

  if (const Json* degraded = reader.object(doc, "degraded")) {
    for (const auto& item : degraded->items()) {
      if (const auto c = reader.count(item.value(), "degraded." + item.key())) {
        stats.degraded.emplace_back(item.key(), *c);
      }
    }
  }
  if (const Json* localizer = reader.object(doc, "localizer")) {
    stats.localizer_fixes = reader.count(*localizer, "fixes", "localizer.");
    stats.localizer_unknown_place = reader.count(*localizer, "unknown_place", "localizer.");
  }
  for (const auto& item : doc.items()) {
    if (!item.value().is_object() || item.key() == "stages" || item.key() == "cycle_histogram" ||
        item.key() == "degraded") {
      continue;
    }
    StatsSection section;
    section.name = item.key();
    flatten(item.value(), "", section.entries);
    stats.sections.push_back(std::move(section));
  }
  return stats;
}

RunStats read_stats(const std::string& path) {
  std::string text;
  if (const std::string e =
          drivers::read_regular_file(path, drivers::input_limits::kStatsBytes, text);
      !e.empty()) {
    throw ReportError(path + ": " + e);
  }
  return parse_stats(text, path);
}

}  // namespace harmoloc::sim_host
