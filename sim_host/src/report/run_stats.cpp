#include "harmoloc/sim_host/run_stats.hpp"

#include <algorithm>
#include <iterator>
#include <nlohmann/json.hpp>

#include "format.hpp"
#include "harmoloc/drivers/input_file.hpp"

namespace harmoloc::sim_host {

namespace {

using Json = firmware::stats::Json;
namespace stats = firmware::stats;
using report_text::format;

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
  Json json;
  try {
    json = Json::parse(text);
  } catch (const Json::exception& e) {
    std::string what = e.what();
    const auto bracket = what.find("] ");
    if (what.rfind("[json.exception", 0) == 0 && bracket != std::string::npos) {
      what = what.substr(bracket + 2);
    }
    throw ReportError(origin + ": not valid JSON (" + what + ")");
  }
  RunStats out;
  try {
    out.document = json.get<stats::Document>();
  } catch (const stats::FormatError& e) {
    throw ReportError(origin + ": " + e.what());
  }
  const stats::Document& d = out.document;
  out.harmoloc_version = d.harmoloc_version;
  out.board = d.board;
  out.cycles = d.cycles;
  out.frames = d.frames;
  out.overruns = d.overruns;
  out.rate_hz = d.rate_hz;
  out.budget_us = d.budget_us.value_or(out.budget_us);

  // Known stages in display order, then unknown ones in file order, the whole cycle last.
  std::vector<std::string> names(std::begin(kStageOrder), std::end(kStageOrder) - 1);
  for (const auto& stage : d.stages) {
    if (std::find(std::begin(kStageOrder), std::end(kStageOrder), stage.first) ==
        std::end(kStageOrder)) {
      names.push_back(stage.first);
    }
  }
  names.push_back("cycle");
  for (const std::string& name : names) {
    const auto it = std::find_if(d.stages.begin(), d.stages.end(),
                                 [&name](const auto& stage) { return stage.first == name; });
    if (it == d.stages.end()) continue;
    const stats::StageTiming& t = it->second;
    out.stages.push_back({name, t.median_us, t.p99_us, t.p999_us, t.max_us, t.mean_us});
  }
  if (d.cycle_histogram && !d.cycle_histogram->upper_us.empty()) {
    out.cycle_histogram = CycleHistogram{d.cycle_histogram->upper_us, d.cycle_histogram->counts};
  }
  if (d.degraded) {
    out.degraded = {{"odometry_only", d.degraded->odometry_only},
                    {"vision_only", d.degraded->vision_only},
                    {"invalid", d.degraded->invalid}};
  }
  if (d.localizer) {
    out.localizer_fixes = d.localizer->fixes;
    out.localizer_unknown_place = d.localizer->unknown_place;
  }
  // Every other section as the file has it, for the report's tables: counters a newer firmware
  // adds show up without a change here.
  for (const auto& item : json.items()) {
    if (!item.value().is_object() || item.key() == "stages" || item.key() == "cycle_histogram" ||
        item.key() == "degraded") {
      continue;
    }
    StatsSection section;
    section.name = item.key();
    flatten(item.value(), "", section.entries);
    out.sections.push_back(std::move(section));
  }
  return out;
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
