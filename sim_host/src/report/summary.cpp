// The report's text summary (the terminal) and its JSON twin (summary.json, for scripts).
#include "harmoloc/sim_host/report.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>

#include "format.hpp"

namespace harmoloc::sim_host {

using report_text::budget;
using report_text::cm;
using report_text::duration;
using report_text::format;
using report_text::seconds;

namespace {

// Ordered: summary.json keeps the order a person reads it in.
using Json = nlohmann::ordered_json;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string position_line(const TrajectoryErrors& e) {
  return format("x %s  y %s  xy %s  (max %s, p95 %s)", cm(e.rmse_x_m).c_str(),
                cm(e.rmse_y_m).c_str(), cm(e.rmse_position_m).c_str(), cm(e.max_position_m).c_str(),
                cm(e.p95_position_m).c_str());
}

std::string fixes_line(const TrajectoryErrors& e) {
  return format("RMSE %s (x %.2f, y %.2f; MSE x %.1f, y %.1f cm2) over %zu fixes",
                cm(e.rmse_position_m).c_str(), e.rmse_x_m * 100.0, e.rmse_y_m * 100.0, e.mse_x_cm2,
                e.mse_y_cm2, e.count);
}

Json errors_json(const TrajectoryErrors& e, bool heading) {
  Json j;
  j["count"] = e.count;
  j["outside_truth"] = e.outside_truth;
  j["skipped"] = e.skipped;
  j["skip_initial_s"] = e.skip_initial_s;
  j["rmse_x_cm"] = e.rmse_x_m * 100.0;
  j["rmse_y_cm"] = e.rmse_y_m * 100.0;
  j["rmse_position_cm"] = e.rmse_position_m * 100.0;
  j["mse_x_cm2"] = e.mse_x_cm2;
  j["mse_y_cm2"] = e.mse_y_cm2;
  j["mean_position_cm"] = e.mean_position_m * 100.0;
  j["p95_position_cm"] = e.p95_position_m * 100.0;
  j["max_position_cm"] = e.max_position_m * 100.0;
  if (heading) {
    j["rmse_heading_deg"] = e.rmse_heading_deg;
    j["max_heading_deg"] = e.max_heading_deg;
  }
  return j;
}

Json rpe_json(const RelativeErrors& r) {
  Json j;
  j["delta"] = r.delta;
  j["delta_unit"] = r.unit == DeltaUnit::kMetres ? "m" : "s";
  j["pairs"] = r.pairs;
  const auto value = [&](double m) { return r.pairs == 0 ? Json(nullptr) : Json(m * 100.0); };
  j["rmse_cm"] = value(r.rmse_m);
  j["mean_cm"] = value(r.mean_m);
  j["median_cm"] = value(r.median_m);
  j["max_cm"] = value(r.max_m);
  return j;
}

std::string rpe_line(const RelativeErrors& r) {
  if (r.pairs == 0) return "n/a (too short for one pair)";
  return format("RMSE %s  median %s  max %s over %zu pairs", cm(r.rmse_m).c_str(),
                cm(r.median_m).c_str(), cm(r.max_m).c_str(), r.pairs);
}

/// Seconds spent in each health on the link, in the order health_label's callers show them.
std::vector<std::pair<firmware::Health, double>> health_time(const LinkLog& link) {
  std::vector<std::pair<firmware::Health, double>> out;
  for (const HealthSpan& span : link.health) {
    auto it =
        std::find_if(out.begin(), out.end(), [&](const auto& e) { return e.first == span.health; });
    if (it == out.end()) {
      out.emplace_back(span.health, 0.0);
      it = out.end() - 1;
    }
    it->second += span.end_s - span.start_s;
  }
  return out;
}

Json number_or_null(double v) {
  return std::isfinite(v) ? Json(v) : Json(nullptr);
}

/// The budget share of the cycle's p99, NaN when unknown.
double p99_budget_percent(const RunStats& stats) {
  const StageTiming* cycle = stats.stage("cycle");
  if (cycle == nullptr) return kNaN;
  return cycle->p99_us / stats.budget_us * 100.0;
}

}  // namespace

std::string summary_text(const Report& report, const std::string& index_path) {
  std::string out;
  if (!report.inputs.title.empty()) out += "harmoloc run report: " + report.inputs.title + "\n";
  const TrajectoryErrors& all = report.estimate_all;
  const TrajectoryErrors* late = report.estimate_converged ? &*report.estimate_converged : nullptr;
  const std::string after = format("  after %-7s", seconds(report.inputs.skip_initial_s).c_str());
  out += format("position RMSE  %s over %zu poses", position_line(all).c_str(), all.count);
  if (all.outside_truth > 0) {
    out += format(" (%zu more outside the truth's time span)", all.outside_truth);
  }
  out += "\n";
  if (late != nullptr) {
    out +=
        format("%s%s over %zu poses\n", after.c_str(), position_line(*late).c_str(), late->count);
  }
  out += format("position MSE   x %.2f cm2  y %.2f cm2\n", all.mse_x_cm2, all.mse_y_cm2);
  if (late != nullptr) {
    out += format("%sx %.2f cm2  y %.2f cm2\n", after.c_str(), late->mse_x_cm2, late->mse_y_cm2);
  }
  out += format("heading RMSE   %.2f deg  (max %.1f deg)\n", all.rmse_heading_deg,
                all.max_heading_deg);
  if (late != nullptr) {
    out += format("%s%.2f deg  (max %.1f deg)\n", after.c_str(), late->rmse_heading_deg,
                  late->max_heading_deg);
  }
  out += "RPE 1 m        " + rpe_line(report.rpe_1m) + "\n";
  if (report.rpe_1m_converged) out += after + rpe_line(*report.rpe_1m_converged) + "\n";
  out += "RPE 1 s        " + rpe_line(report.rpe_1s) + "\n";
  if (report.rpe_1s_converged) out += after + rpe_line(*report.rpe_1s_converged) + "\n";
  if (report.fixes_all) {
    out += "harmonic fixes " + fixes_line(*report.fixes_all) + "\n";
  }
  if (report.fixes_converged) {
    out += after + fixes_line(*report.fixes_converged) + "\n";
  }
  if (report.stats) {
    const RunStats& stats = *report.stats;
    const std::string overruns =
        stats.overruns ? std::to_string(*stats.overruns) : std::string("n/a");
    if (const StageTiming* cycle = stats.stage("cycle")) {
      out += format(
          "cycle time     median %s  p99 %s  max %s  (budget %s, %.1f%% used at p99), "
          "overruns %s\n",
          duration(cycle->median_us).c_str(), duration(cycle->p99_us).c_str(),
          duration(cycle->max_us).c_str(), budget(stats.budget_us).c_str(),
          p99_budget_percent(stats), overruns.c_str());
    } else {
      out += format("cycle time     n/a (no \"cycle\" stage)  budget %s, overruns %s\n",
                    budget(stats.budget_us).c_str(), overruns.c_str());
    }
    const StageTiming* slowest = nullptr;
    for (const StageTiming& s : stats.stages) {
      if (s.name == "cycle" || !std::isfinite(s.p99_us)) continue;
      if (slowest == nullptr || s.p99_us > slowest->p99_us) slowest = &s;
    }
    if (!stats.stages.empty()) {
      out +=
          format("per stage      %-10s %10s %10s %10s %10s\n", "", "median", "p99", "p99.9", "max");
      for (const StageTiming& s : stats.stages) {
        out += format("               %-10s %10s %10s %10s %10s\n", s.name.c_str(),
                      duration(s.median_us).c_str(), duration(s.p99_us).c_str(),
                      duration(s.p999_us).c_str(), duration(s.max_us).c_str());
      }
    }
    if (slowest != nullptr) {
      out += format("slowest stage  %s (median %s, p99 %s)\n", slowest->name.c_str(),
                    duration(slowest->median_us).c_str(), duration(slowest->p99_us).c_str());
    }
    if (!stats.degraded.empty()) {
      std::string list;
      for (const auto& [name, count] : stats.degraded) {
        if (!list.empty()) list += ", ";
        list += name + " " + std::to_string(count);
      }
      if (stats.cycles)
        list += format(" (of %llu cycles)", static_cast<unsigned long long>(*stats.cycles));
      out += "degraded       " + list + "\n";
    }
  }
  if (report.link) {
    const std::vector<std::pair<firmware::Health, double>> spent = health_time(*report.link);
    double total_s = 0.0;
    for (const auto& e : spent) total_s += e.second;
    std::string list;
    for (const auto& [health, time_s] : spent) {
      if (!list.empty()) list += ", ";
      list +=
          format("%s %.1f%%", health_label(health), total_s > 0.0 ? 100.0 * time_s / total_s : 0.0);
    }
    out += "health (link)  " + (list.empty() ? std::string("n/a") : list) +
           format(" (%zu changes)\n",
                  report.link->health.empty() ? 0 : report.link->health.size() - 1);
    const SigmaConsistency c = sigma_consistency(report);
    if (c.poses > 0) {
      out +=
          format("2 sigma (link) x %.1f%%  y %.1f%% of %zu poses within +-2 sigma\n",
                 100.0 * static_cast<double>(c.inside_x) / static_cast<double>(c.poses),
                 100.0 * static_cast<double>(c.inside_y) / static_cast<double>(c.poses), c.poses);
    }
  }
  if (report.areas && report.areas->has_distrust) {
    std::string list;
    for (const BoardAreaSummary& b : board_area_summary(report)) {
      if (!list.empty()) list += ", ";
      list += format("%s %.1f s", b.name.c_str(), b.distrusted_s);
    }
    out += "distrusted     " + list + "\n";
  }
  if (!index_path.empty()) out += "report         " + index_path + "\n";
  return out;
}

std::string summary_json(const Report& report) {
  Json j;
  j["title"] = report.inputs.title;
  j["inputs"] = {
      {"truth", report.inputs.truth_path},
      {"estimate", report.inputs.estimate_path},
      {"fixes", report.inputs.fixes_path.empty() ? Json(nullptr) : Json(report.inputs.fixes_path)},
      {"stats", report.inputs.stats_path.empty() ? Json(nullptr) : Json(report.inputs.stats_path)},
      {"link", report.inputs.link_path.empty() ? Json(nullptr) : Json(report.inputs.link_path)},
      {"areas", report.inputs.areas_path.empty() ? Json(nullptr) : Json(report.inputs.areas_path)}};
  j["skip_initial_s"] = report.inputs.skip_initial_s;
  j["units"] = "lengths in cm, MSE in cm2, angles in degrees, times in microseconds";
  Json estimate;
  estimate["all"] = errors_json(report.estimate_all, true);
  estimate["all"]["rpe_1m"] = rpe_json(report.rpe_1m);
  estimate["all"]["rpe_1s"] = rpe_json(report.rpe_1s);
  if (report.estimate_converged) {
    estimate["after_convergence"] = errors_json(*report.estimate_converged, true);
    if (report.rpe_1m_converged) {
      estimate["after_convergence"]["rpe_1m"] = rpe_json(*report.rpe_1m_converged);
    }
    if (report.rpe_1s_converged) {
      estimate["after_convergence"]["rpe_1s"] = rpe_json(*report.rpe_1s_converged);
    }
  }
  j["estimate"] = estimate;
  if (report.fixes_all) {
    Json fixes;
    fixes["all"] = errors_json(*report.fixes_all, false);
    if (report.fixes_converged) {
      fixes["after_convergence"] = errors_json(*report.fixes_converged, false);
    }
    j["fixes"] = fixes;
  }
  if (report.link) {
    Json link;
    link["poses"] = report.link->poses.size();
    link["frames"] = report.link->frames;
    link["crc_errors"] = report.link->crc_errors;
    link["health_changes"] = report.link->health.empty() ? 0 : report.link->health.size() - 1;
    Json spent = Json::object();
    for (const auto& [health, time_s] : health_time(*report.link)) {
      spent[health_label(health)] = time_s;
    }
    link["health_time_s"] = spent;
    const SigmaConsistency c = sigma_consistency(report);
    const auto share = [&](std::size_t inside) {
      return c.poses == 0
                 ? Json(nullptr)
                 : Json(100.0 * static_cast<double>(inside) / static_cast<double>(c.poses));
    };
    link["within_2sigma_x_percent"] = share(c.inside_x);
    link["within_2sigma_y_percent"] = share(c.inside_y);
    j["link"] = link;
  }
  if (report.areas) {
    Json areas;
    areas["frames"] = report.areas->areas.size();
    areas["has_distrust"] = report.areas->has_distrust;
    Json boards = Json::array();
    for (const BoardAreaSummary& b : board_area_summary(report)) {
      boards.push_back(
          {{"name", b.name},
           {"frames", b.frames},
           {"mean_percent", b.mean_percent},
           {"min_percent", b.min_percent},
           {"max_percent", b.max_percent},
           {"distrusted_s", report.areas->has_distrust ? Json(b.distrusted_s) : Json(nullptr)}});
    }
    areas["boards"] = boards;
    j["areas"] = areas;
  }
  if (report.stats) {
    const RunStats& s = *report.stats;
    Json timing;
    timing["harmoloc_version"] = s.harmoloc_version;
    timing["board"] = s.board;
    timing["budget_us"] = s.budget_us;
    timing["cycles"] = s.cycles ? Json(*s.cycles) : Json(nullptr);
    timing["frames"] = s.frames ? Json(*s.frames) : Json(nullptr);
    timing["overruns"] = s.overruns ? Json(*s.overruns) : Json(nullptr);
    timing["rate_hz"] = s.rate_hz ? Json(*s.rate_hz) : Json(nullptr);
    timing["cycle_p99_budget_percent"] = number_or_null(p99_budget_percent(s));
    Json stages = Json::object();
    for (const StageTiming& st : s.stages) {
      stages[st.name] = {{"median_us", number_or_null(st.median_us)},
                         {"p99_us", number_or_null(st.p99_us)},
                         {"p999_us", number_or_null(st.p999_us)},
                         {"max_us", number_or_null(st.max_us)},
                         {"mean_us", number_or_null(st.mean_us)}};
    }
    timing["stages"] = stages;
    Json degraded = Json::object();
    for (const auto& [name, count] : s.degraded) degraded[name] = count;
    timing["degraded"] = degraded;
    if (s.localizer_fixes || s.localizer_unknown_place) {
      timing["localizer"] = {
          {"fixes", s.localizer_fixes ? Json(*s.localizer_fixes) : Json(nullptr)},
          {"unknown_place",
           s.localizer_unknown_place ? Json(*s.localizer_unknown_place) : Json(nullptr)}};
    }
    j["timing"] = timing;
  }
  return j.dump(2) + "\n";
}

}  // namespace harmoloc::sim_host
